// Camera files: TUM presets by name, OpenCV FileStorage YAML read and written, and which one a TUM folder has.
#include "weighted_icp/io/camera.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "text_fields.h"
#include "weighted_icp/io/atomic_file.h"

namespace weighted_icp::io {

namespace {

const char* const kDistortionKeys[5] = {"k1", "k2", "p1", "p2", "k3"};
/// The unregistered depth camera's keys, all or none: intrinsics, then its pose in the colour camera's frame.
const char* const kDepthCameraKeys[10] = {"depth_fx", "depth_fy", "depth_cx", "depth_cy", "depth_tx",
                                          "depth_ty", "depth_tz", "depth_rx", "depth_ry", "depth_rz"};
/// The depth camera's values in the order of kDepthCameraKeys (pointers to const for a const DepthCamera).
template <typename Depth>
std::array<decltype(&std::declval<Depth&>().fx), 10> depthCameraValues(Depth& depth) {
  return {&depth.fx,
          &depth.fy,
          &depth.cx,
          &depth.cy,
          &depth.translation_m[0],
          &depth.translation_m[1],
          &depth.translation_m[2],
          &depth.rotation_rad[0],
          &depth.rotation_rad[1],
          &depth.rotation_rad[2]};
}
/// The depth camera may sit at most this far from the colour camera (metres) and turn at most pi.
constexpr double kMaxDepthCameraOffset = 1.0;

/// A key of the camera file and what is wrong with it.
struct KeyProblem {
  std::string key, what;
};

/// Plausible ranges. A camera file outside them is a typo or a unit mistake
/// (millimetres for metres, a focal length in mm, a swapped cx/width), and such
/// a camera does not fail loudly: the front end tracks nothing or everything
/// sits at absurd depths, and the run ends without a clue. Real RGB-D sensors
/// have focal lengths of a few hundred to a few thousand pixels and depth
/// factors of 1000 (mm) to 5000 (TUM); the bounds are far wider, to refuse only
/// nonsense.
constexpr double kMinFocal = 1.0, kMaxFocal = 1e5;
constexpr double kMinDepthFactor = 1.0, kMaxDepthFactor = 1e6;
constexpr int kMaxImageSide = 100000;
/// How far outside the image the principal point may lie, as a fraction of the
/// image side: cropped or shifted sensors put it off centre, never far outside.
constexpr double kPrincipalPointMargin = 0.5;

std::string rangeText(double low, double high) {
  std::ostringstream text;
  text << "must be between " << low << " and " << high;
  return text.str();
}

/// What makes `camera` unusable; empty when it is valid.
std::vector<KeyProblem> invalidKeys(const PinholeCamera& camera) {
  std::vector<KeyProblem> problems;
  const auto inRange = [&](const char* key, double value, double low, double high) {
    if (!(std::isfinite(value) && value >= low && value <= high)) problems.push_back({key, rangeText(low, high)});
  };
  const auto finite = [&](const char* key, double value) {
    if (!std::isfinite(value)) problems.push_back({key, "must be finite"});
  };
  inRange("fx", camera.fx, kMinFocal, kMaxFocal);
  inRange("fy", camera.fy, kMinFocal, kMaxFocal);
  for (std::size_t i = 0; i < camera.distortion.size(); ++i) finite(kDistortionKeys[i], camera.distortion[i]);
  if (camera.width <= 0 || camera.width > kMaxImageSide)
    problems.push_back({"width", "must be between 1 and " + std::to_string(kMaxImageSide)});
  if (camera.height <= 0 || camera.height > kMaxImageSide)
    problems.push_back({"height", "must be between 1 and " + std::to_string(kMaxImageSide)});
  // Checked against the image only when its size is valid, else just finite.
  const auto principal = [&](const char* key, double value, int side) {
    if (side <= 0 || side > kMaxImageSide)
      finite(key, value);
    else
      inRange(key, value, -kPrincipalPointMargin * side, (1.0 + kPrincipalPointMargin) * side);
  };
  principal("cx", camera.cx, camera.width);
  principal("cy", camera.cy, camera.height);
  inRange("depth_factor", camera.depth_factor, kMinDepthFactor, kMaxDepthFactor);
  if (const auto& depth = camera.unregistered_depth) {
    inRange("depth_fx", depth->fx, kMinFocal, kMaxFocal);
    inRange("depth_fy", depth->fy, kMinFocal, kMaxFocal);
    // Its own image size, both or neither (0 x 0: the colour image's size).
    const bool sized = depth->width != 0 || depth->height != 0;
    if (sized && (depth->width <= 0 || depth->width > kMaxImageSide))
      problems.push_back({"depth_width", "must be between 1 and " + std::to_string(kMaxImageSide)});
    if (sized && (depth->height <= 0 || depth->height > kMaxImageSide))
      problems.push_back({"depth_height", "must be between 1 and " + std::to_string(kMaxImageSide)});
    principal("depth_cx", depth->cx, sized ? depth->width : camera.width);
    principal("depth_cy", depth->cy, sized ? depth->height : camera.height);
    for (std::size_t i = 0; i < 3; ++i) {
      inRange(kDepthCameraKeys[4 + i], depth->translation_m[i], -kMaxDepthCameraOffset, kMaxDepthCameraOffset);
      inRange(kDepthCameraKeys[7 + i], depth->rotation_rad[i], -M_PI, M_PI);
    }
  }
  return problems;
}

/// "line N: key what; ..." (the line where the file has the key; none for a missing key).
std::string describe(const std::vector<KeyProblem>& problems, const std::map<std::string, std::size_t>& lines = {}) {
  std::string text;
  for (const auto& problem : problems) {
    const auto line = lines.find(problem.key);
    text += (text.empty() ? "" : "; ") +
            (line == lines.end() ? std::string() : "line " + std::to_string(line->second) + ": ") + problem.key + " " +
            problem.what;
  }
  return text;
}

/// @brief Refuses a YAML camera file whose lines are not the plain layout camera files have: directives
/// ("%YAML:1.0"), document markers ("---"), comments, "key: value" lines with a name for key, and indented
/// lines below a key (an OpenCV matrix of another key). OpenCV's YAML parser can loop forever on malformed text
/// (found by fuzz/fuzz_camera: "%YAML:1.0\n---<:p\na: -\n", and an indented line right after the directive), so
/// it is given only text of this layout. XML and JSON files (first character '<' or '{') are left to FileStorage.
/// @param path the camera file
/// @return the line each key is on (its first), so that a value out of range can be reported with its line; empty
///         for an XML or JSON file
std::map<std::string, std::size_t> requirePlainYamlLayout(const std::string& path) {
  std::map<std::string, std::size_t> key_lines;
  std::ifstream in(path, std::ios::binary);
  std::string line;
  std::size_t number = 0;
  bool first = true;
  bool below_key = false;  // an indented line belongs to the key line above it
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    // A camera file is text: OpenCV's XML parser dereferenced null on a NUL byte (fuzz/fuzz_camera, 2026-11-26).
    if (line.find('\0') != std::string::npos)
      throw std::runtime_error(path + ":" + std::to_string(number) + ": not a camera file: a NUL byte (binary data)");
    if (first) {
      const std::size_t start = line.find_first_not_of(" \t");
      if (start == std::string::npos) continue;
      if (line[start] == '<' || line[start] == '{') return key_lines;
      first = false;
    }
    if (line.empty() || line[0] == '#') continue;
    if (line[0] == '%' || line == "---" || line == "...") {
      below_key = false;
      continue;
    }
    if (line[0] == ' ' || line[0] == '\t') {
      // An indented line not below a key: OpenCV's parser looped forever on one (fuzz/fuzz_camera, 2026-11-25).
      if (!below_key)
        throw std::runtime_error(path + ":" + std::to_string(number) +
                                 ": not a camera file: an indented line not below a key, " + detail::quoteToken(line));
      continue;
    }
    const std::size_t colon = line.find(':');
    const bool named = colon != std::string::npos && colon > 0 &&
                       std::all_of(line.begin(), line.begin() + static_cast<std::ptrdiff_t>(colon),
                                   [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
    if (!named || (colon + 1 < line.size() && line[colon + 1] != ' ' && line[colon + 1] != '\t'))
      throw std::runtime_error(path + ":" + std::to_string(number) +
                               ": not a camera file: expected \"key: value\", found " + detail::quoteToken(line));
    key_lines.emplace(line.substr(0, colon), number);
    below_key = true;
  }
  return key_lines;
}

/// The optional unregistered depth camera: none of its keys, or all of them (the missing ones reported); its image
/// size (depth_width, depth_height) optional, both or neither, and only with the depth camera.
template <typename ReadReal, typename ReadInteger>
void readDepthCamera(const cv::FileStorage& storage, const ReadReal& real, const ReadInteger& integer,
                     std::vector<KeyProblem>& problems, PinholeCamera& camera) {
  bool any = false;
  for (const char* key : kDepthCameraKeys) any |= !storage[key].empty();
  const bool sized = !storage["depth_width"].empty() || !storage["depth_height"].empty();
  if (!any) {
    if (sized) problems.push_back({"depth_width", "and depth_height need the depth camera's keys (depth_fx ...)"});
    return;
  }
  DepthCamera depth;
  const auto values = depthCameraValues(depth);
  for (std::size_t i = 0; i < values.size(); ++i) real(kDepthCameraKeys[i], *values[i]);
  if (sized) {
    integer("depth_width", depth.width);
    integer("depth_height", depth.height);
    // Given as 0: not the "same as colour" default, a mistake.
    if (depth.width == 0) depth.width = -1;
    if (depth.height == 0) depth.height = -1;
  }
  camera.unregistered_depth = depth;
}

PinholeCamera readCameraFile(const std::string& path) {
  // Checked first: FileStorage would log its own error on stderr, or say just "buf".
  if (!std::filesystem::is_regular_file(path))
    throw std::runtime_error(path + ": no such file (and not a camera preset fr1, fr2 or fr3)");
  if (std::filesystem::is_empty(path)) throw std::runtime_error(path + ": empty camera file");
  const std::map<std::string, std::size_t> key_lines = requirePlainYamlLayout(path);
  cv::FileStorage storage;
  try {
    storage.open(path, cv::FileStorage::READ);
  } catch (const cv::Exception& e) {  // a file that is not YAML, XML or JSON
    throw std::runtime_error(path + ": not a camera file: " + e.err);
  }
  if (!storage.isOpened()) throw std::runtime_error(path + ": cannot open the camera file");
  if (!storage.root().isMap()) throw std::runtime_error(path + ": not a camera file: expected \"key: value\" lines");

  std::vector<KeyProblem> problems;
  const auto real = [&](const char* key, double& value) {
    const cv::FileNode node = storage[key];
    if (node.empty())
      problems.push_back({key, "is missing"});
    else if (!node.isReal() && !node.isInt())
      problems.push_back({key, "is not a number"});
    else
      value = static_cast<double>(node);
  };
  const auto integer = [&](const char* key, int& value) {
    const cv::FileNode node = storage[key];
    if (node.empty())
      problems.push_back({key, "is missing"});
    else if (!node.isInt())
      problems.push_back({key, "is not an integer"});
    else
      value = static_cast<int>(node);
  };
  PinholeCamera camera;
  real("fx", camera.fx);
  real("fy", camera.fy);
  real("cx", camera.cx);
  real("cy", camera.cy);
  for (std::size_t i = 0; i < camera.distortion.size(); ++i) real(kDistortionKeys[i], camera.distortion[i]);
  integer("width", camera.width);
  integer("height", camera.height);
  real("depth_factor", camera.depth_factor);
  readDepthCamera(storage, real, integer, problems, camera);
  // A key already reported as missing or not a number holds its default: report it once.
  const std::size_t unread = problems.size();
  for (auto& problem : invalidKeys(camera)) {
    bool reported = false;
    for (std::size_t i = 0; i < unread; ++i) reported |= problems[i].key == problem.key;
    if (!reported) problems.push_back(std::move(problem));
  }
  if (!problems.empty()) throw std::runtime_error(path + ": invalid camera: " + describe(problems, key_lines));
  return camera;
}

}  // namespace

PinholeCamera loadCamera(const std::string& preset_or_path) {
  if (preset_or_path == "fr1") return tumCamera(1);
  if (preset_or_path == "fr2") return tumCamera(2);
  if (preset_or_path == "fr3") return tumCamera(3);
  return readCameraFile(preset_or_path);
}

void saveCamera(const PinholeCamera& camera, const std::string& path) {
  // Refused before writing, so a saved camera always loads back.
  if (const auto problems = invalidKeys(camera); !problems.empty())
    throw std::runtime_error("cannot write " + path + ": invalid camera: " + describe(problems));
  cv::FileStorage storage(".yml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  storage << "fx" << camera.fx << "fy" << camera.fy << "cx" << camera.cx << "cy" << camera.cy;
  for (std::size_t i = 0; i < camera.distortion.size(); ++i) storage << kDistortionKeys[i] << camera.distortion[i];
  storage << "width" << camera.width << "height" << camera.height << "depth_factor" << camera.depth_factor;
  if (const auto& depth = camera.unregistered_depth) {
    const auto values = depthCameraValues(*depth);
    for (std::size_t i = 0; i < values.size(); ++i) storage << kDepthCameraKeys[i] << *values[i];
    if (depth->width != 0 || depth->height != 0)
      storage << "depth_width" << depth->width << "depth_height" << depth->height;
  }
  const std::string text = storage.releaseAndGetString();
  writeAtomically(path, [&](const std::string& temporary) {
    std::ofstream out(temporary);
    if (!out) throw std::runtime_error("cannot create " + temporary);
    out << text;
    out.close();
    if (!out) throw std::runtime_error("cannot write " + path);
  });
}

namespace {

/// The TUM sensor a folder is named after (rgbd_dataset_freiburg3_teddy, tum_fr1_xyz_head): its own name only
/// ("data/", "data/." and "data" alike), not its parents'. Empty when it names none.
std::string sensorOfFolderName(const std::string& dir) {
  const std::string name = std::filesystem::weakly_canonical(std::filesystem::absolute(dir)).filename().string();
  for (const char* sensor : {"1", "2", "3"})
    if (name.find(std::string("freiburg") + sensor) != std::string::npos ||
        name.find(std::string("fr") + sensor) != std::string::npos)
      return std::string("fr") + sensor;
  return {};
}

}  // namespace

PinholeCamera datasetCamera(const std::string& dataset, const std::string& spec, const std::string& how_to_pass) {
  if (!std::filesystem::is_directory(dataset)) throw std::runtime_error(dataset + ": no such folder");
  if (!spec.empty()) return loadCamera(spec);
  const std::filesystem::path own = std::filesystem::path(dataset) / "camera.yaml";
  if (std::filesystem::is_regular_file(own)) return loadCamera(own.string());
  const std::string sensor = sensorOfFolderName(dataset);
  if (sensor.empty())
    throw std::runtime_error("cannot tell the camera of " + dataset +
                             " from its name and it has no camera.yaml; pass " + how_to_pass +
                             " fr1|fr2|fr3|FILE.yaml");
  return loadCamera(sensor);
}

}  // namespace weighted_icp::io
