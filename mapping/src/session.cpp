// Session folders: capture from a SLAM run, save atomically, load with errors naming file and line.
#include "weighted_icp/mapping/session.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>

#include "text_records.h"
#include "weighted_icp/io/atomic_folder.h"
#include "weighted_icp/io/camera.h"

namespace weighted_icp::mapping {

namespace fs = std::filesystem;

namespace {

constexpr int kFormatVersion = 1;

/// Hex of one descriptor row, "-" for none.
std::string descriptorHex(const cv::Mat& descriptors, int row) {
  if (descriptors.empty()) return "-";
  return detail::toHex(descriptors.ptr<unsigned char>(row), static_cast<std::size_t>(descriptors.cols));
}

/// A descriptor row read from hex into `descriptors` (allocated with `bytes` columns); "-" only when bytes is 0.
void readDescriptor(const detail::RecordReader& in, std::size_t field, std::size_t bytes, cv::Mat& descriptors,
                    int row) {
  const std::string_view text = in.field(field);
  if (bytes == 0) {
    if (text != "-") in.fail("descriptor " + detail::echo(text) + " given where none was declared");
    return;
  }
  if (!detail::fromHex(text, descriptors.ptr<unsigned char>(row), bytes))
    in.fail("descriptor " + detail::echo(text) + " is not " + std::to_string(bytes) + " bytes of hex");
}

std::ofstream openForWriting(const fs::path& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path.string());
  return out;
}

void finishWriting(std::ofstream& out, const fs::path& path) {
  out.close();
  if (!out) throw std::runtime_error("error writing " + path.string());
}

void writeKeyframes(const Session& session, const fs::path& path) {
  std::ofstream out = openForWriting(path);
  out << "# KEYFRAME id frame_id timestamp segment tx ty tz qw qx qy qz features descriptor_bytes\n"
         "# FEATURE x y size angle response octave class_id u v depth descriptor_hex  (one per feature)\n";
  for (const auto& keyframe : session.keyframes) {
    const std::size_t bytes = keyframe.descriptors.empty() ? 0 : static_cast<std::size_t>(keyframe.descriptors.cols);
    out << "KEYFRAME " << keyframe.id << ' ' << keyframe.frame_id << ' ' << detail::exact(keyframe.timestamp) << ' '
        << keyframe.segment << ' ' << detail::poseFields(keyframe.pose_wc) << ' ' << keyframe.keypoints.size() << ' '
        << bytes << '\n';
    for (std::size_t i = 0; i < keyframe.keypoints.size(); ++i) {
      const cv::KeyPoint& k = keyframe.keypoints[i];
      out << "FEATURE " << detail::exact(k.pt.x) << ' ' << detail::exact(k.pt.y) << ' ' << detail::exact(k.size) << ' '
          << detail::exact(k.angle) << ' ' << detail::exact(k.response) << ' ' << k.octave << ' ' << k.class_id << ' '
          << detail::exact(keyframe.pixels[i].x()) << ' ' << detail::exact(keyframe.pixels[i].y()) << ' '
          << detail::exact(keyframe.depths[i]) << ' ' << descriptorHex(keyframe.descriptors, static_cast<int>(i))
          << '\n';
    }
  }
  finishWriting(out, path);
}

void writeLandmarks(const Session& session, const fs::path& path) {
  std::ofstream out = openForWriting(path);
  out << "# LANDMARK id x y z c00 c01 c02 c10 c11 c12 c20 c21 c22 descriptor_hex n (keyframe u v depth) x n\n";
  for (const auto& point : session.points) {
    out << "LANDMARK " << point.id;
    for (int i = 0; i < 3; ++i) out << ' ' << detail::exact(point.position[i]);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) out << ' ' << detail::exact(point.covariance(r, c));
    out << ' ' << descriptorHex(point.descriptor, 0) << ' ' << point.observations.size();
    for (const auto& observation : point.observations)
      out << ' ' << observation.keyframe << ' ' << detail::exact(observation.pixel.x()) << ' '
          << detail::exact(observation.pixel.y()) << ' ' << detail::exact(observation.depth);
    out << '\n';
  }
  finishWriting(out, path);
}

void writeFrames(const Session& session, const fs::path& path) {
  std::ofstream out = openForWriting(path);
  out << "# FRAME timestamp reference_keyframe tx ty tz qw qx qy qz  (pose in the reference keyframe's frame)\n";
  for (const auto& frame : session.frames)
    out << "FRAME " << detail::exact(frame.timestamp) << ' ' << frame.reference_keyframe << ' '
        << detail::poseFields(frame.pose_in_reference) << '\n';
  finishWriting(out, path);
}

void writeManifest(const Session& session, const fs::path& path) {
  std::ofstream out = openForWriting(path);
  out << "# A weighted_icp SLAM session (docs/mapping.md)\n"
      << "WICP_SESSION " << kFormatVersion << '\n'
      << "KEYFRAMES " << session.keyframes.size() << '\n'
      << "LANDMARKS " << session.points.size() << '\n'
      << "FRAMES " << session.frames.size() << '\n';
  finishWriting(out, path);
}

/// The record counts session.txt declares, with the lines they are on.
struct Manifest {
  std::map<std::string, std::pair<std::size_t, std::size_t>> counts;  // keyword -> (count, line)
  std::string path;
};

Manifest readManifest(const fs::path& path) {
  detail::RecordReader in(path.string());
  Manifest manifest;
  manifest.path = path.string();
  in.expect("WICP_SESSION");
  in.expectFields(2);
  if (in.count(1, "version") != kFormatVersion)
    in.fail("format version " + std::string(in.field(1)) + " is not " + std::to_string(kFormatVersion));
  for (const char* keyword : {"KEYFRAMES", "LANDMARKS", "FRAMES"}) {
    in.expect(keyword);
    in.expectFields(2);
    manifest.counts[keyword] = {in.count(1, keyword), in.line()};
  }
  if (in.next()) in.fail("unexpected record " + detail::echo(in.field(0)));
  return manifest;
}

void checkCount(const Manifest& manifest, const std::string& keyword, std::size_t found, const fs::path& file) {
  const auto [declared, line] = manifest.counts.at(keyword);
  if (declared != found)
    throw io::MapFormatError(manifest.path, line,
                             std::to_string(declared) + " declared, but " + file.string() + " has " +
                                 std::to_string(found) + " (truncated or mixed-up files)");
}

/// One keyframe record and its features.
frontend::Keyframe readKeyframe(detail::RecordReader& in) {
  in.expectFields(14);
  frontend::Keyframe keyframe;
  keyframe.id = in.count(1, "id");
  keyframe.frame_id = in.count(2, "frame_id");
  keyframe.timestamp = in.number(3, "timestamp");
  keyframe.segment = in.count(4, "segment");
  keyframe.pose_wc = in.pose(5);
  const std::size_t features = in.count(12, "features");
  const std::size_t bytes = in.count(13, "descriptor_bytes");
  if (bytes > 4096) in.fail("descriptor_bytes " + std::to_string(bytes) + " is implausible");
  // Rows are added as FEATURE records are read, never allocated from the declared count: a corrupt count then
  // ends in "the file ends where a FEATURE record was expected", not in an allocation of its size.
  cv::Mat row(1, static_cast<int>(bytes), CV_8U);
  for (std::size_t i = 0; i < features; ++i) {
    in.expect("FEATURE");
    in.expectFields(12);
    cv::KeyPoint k;
    k.pt = cv::Point2f(static_cast<float>(in.number(1, "x")), static_cast<float>(in.number(2, "y")));
    k.size = static_cast<float>(in.number(3, "size"));
    k.angle = static_cast<float>(in.number(4, "angle"));
    k.response = static_cast<float>(in.number(5, "response"));
    k.octave = in.integer(6, "octave");
    k.class_id = in.integer(7, "class_id");
    keyframe.keypoints.push_back(k);
    keyframe.pixels.emplace_back(in.number(8, "u"), in.number(9, "v"));
    const double depth = in.number(10, "depth");
    if (depth < 0.0) in.fail("depth must not be negative");
    keyframe.depths.push_back(depth);
    readDescriptor(in, 11, bytes, row, 0);
    if (bytes > 0) keyframe.descriptors.push_back(row);
  }
  return keyframe;
}

std::vector<frontend::Keyframe> readKeyframes(const fs::path& path) {
  detail::RecordReader in(path.string());
  std::vector<frontend::Keyframe> keyframes;
  while (in.next()) {
    if (in.field(0) != "KEYFRAME") in.fail("expected a KEYFRAME record, found " + detail::echo(in.field(0)));
    const std::size_t line = in.line();
    frontend::Keyframe keyframe = readKeyframe(in);
    if (!keyframes.empty() && keyframe.id <= keyframes.back().id)
      throw io::MapFormatError(in.path(), line,
                               "keyframe ids must ascend (" + std::to_string(keyframe.id) + " after " +
                                   std::to_string(keyframes.back().id) + ")");
    keyframes.push_back(std::move(keyframe));
  }
  return keyframes;
}

std::vector<frontend::MapPoint> readLandmarks(const fs::path& path, std::map<frontend::KeyframeId, std::size_t>& index,
                                              std::vector<frontend::Keyframe>& keyframes) {
  detail::RecordReader in(path.string());
  std::vector<frontend::MapPoint> points;
  while (in.next()) {
    if (in.field(0) != "LANDMARK") in.fail("expected a LANDMARK record, found " + detail::echo(in.field(0)));
    in.expectAtLeast(16);
    frontend::MapPoint point;
    point.id = in.count(1, "id");
    if (!points.empty() && point.id <= points.back().id) in.fail("landmark ids must ascend");
    point.position = Eigen::Vector3d(in.number(2, "x"), in.number(3, "y"), in.number(4, "z"));
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        point.covariance(r, c) = in.number(5 + 3 * r + c, "c" + std::to_string(r) + std::to_string(c));
    const std::string_view hex = in.field(14);
    if (hex != "-") {
      point.descriptor = cv::Mat(1, static_cast<int>(hex.size() / 2), CV_8U);
      readDescriptor(in, 14, hex.size() / 2, point.descriptor, 0);
    }
    const std::size_t n = in.count(15, "n");
    // Compared by division: 16 + 4 n can wrap round for a corrupt n and match the record's length.
    if (n != (in.size() - 16) / 4) in.fail("n = " + std::to_string(n) + " does not match the record's fields");
    in.expectFields(16 + 4 * n);
    for (std::size_t o = 0; o < n; ++o) {
      const std::size_t f = 16 + 4 * o;
      frontend::MapPointObservation observation;
      observation.keyframe = in.count(f, "keyframe");
      const auto keyframe = index.find(observation.keyframe);
      if (keyframe == index.end())
        in.fail("observation by keyframe " + std::to_string(observation.keyframe) + ", which the session lacks");
      observation.pixel = Eigen::Vector2d(in.number(f + 1, "u"), in.number(f + 2, "v"));
      observation.depth = in.number(f + 3, "depth");
      point.observations.push_back(observation);
      keyframes[keyframe->second].observed_points.push_back(point.id);
    }
    points.push_back(std::move(point));
  }
  return points;
}

std::vector<SessionFrame> readFrames(const fs::path& path, const std::map<frontend::KeyframeId, std::size_t>& index) {
  detail::RecordReader in(path.string());
  std::vector<SessionFrame> frames;
  while (in.next()) {
    if (in.field(0) != "FRAME") in.fail("expected a FRAME record, found " + detail::echo(in.field(0)));
    in.expectFields(10);
    SessionFrame frame;
    frame.timestamp = in.number(1, "timestamp");
    frame.reference_keyframe = in.count(2, "reference_keyframe");
    if (!index.count(frame.reference_keyframe))
      in.fail("reference keyframe " + std::to_string(frame.reference_keyframe) + " is not in the session");
    frame.pose_in_reference = in.pose(3);
    frames.push_back(frame);
  }
  return frames;
}

}  // namespace

Trajectory Session::trajectory() const {
  std::map<frontend::KeyframeId, Eigen::Isometry3d> poses;
  for (const auto& keyframe : keyframes) poses[keyframe.id] = keyframe.pose_wc;
  Trajectory trajectory;
  for (const auto& frame : frames)
    trajectory.push_back({frame.timestamp, poses.at(frame.reference_keyframe) * frame.pose_in_reference});
  return trajectory;
}

void Session::validate() const {
  const auto fail = [](const std::string& what) { throw std::invalid_argument("session: " + what); };
  std::set<frontend::KeyframeId> ids;
  for (const auto& keyframe : keyframes) {
    const std::string name = "keyframe " + std::to_string(keyframe.id);
    if (!ids.empty() && keyframe.id <= *ids.rbegin()) fail(name + ": keyframe ids must ascend");
    ids.insert(keyframe.id);
    if (!keyframe.pose_wc.matrix().allFinite()) fail(name + ": pose is not finite");
    if (keyframe.pixels.size() != keyframe.keypoints.size() || keyframe.depths.size() != keyframe.keypoints.size())
      fail(name + ": keypoints, pixels and depths differ in number");
    if (!keyframe.descriptors.empty() && (keyframe.descriptors.type() != CV_8U ||
                                          keyframe.descriptors.rows != static_cast<int>(keyframe.keypoints.size())))
      fail(name + ": descriptors must be one CV_8U row per keypoint");
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto& point = points[i];
    const std::string name = "landmark " + std::to_string(point.id);
    if (i > 0 && point.id <= points[i - 1].id) fail(name + ": landmark ids must ascend");
    if (!point.position.allFinite() || !point.covariance.allFinite()) fail(name + ": not finite");
    if (!point.descriptor.empty() && (point.descriptor.type() != CV_8U || point.descriptor.rows != 1))
      fail(name + ": the descriptor must be one CV_8U row");
    for (const auto& observation : point.observations)
      if (!ids.count(observation.keyframe))
        fail(name + ": observed by keyframe " + std::to_string(observation.keyframe) + ", not in the session");
  }
  for (const auto& frame : frames)
    if (!ids.count(frame.reference_keyframe) || !frame.pose_in_reference.matrix().allFinite())
      fail("frame at " + detail::exact(frame.timestamp) + ": unknown reference keyframe or non-finite pose");
}

std::unique_ptr<frontend::Map> Session::toMap() const {
  validate();
  auto map = std::make_unique<frontend::Map>();
  for (std::size_t i = 0; i < keyframes.size(); ++i) {
    if (keyframes[i].id != i)
      throw std::invalid_argument("session: keyframe ids must be 0, 1, 2, ... to rebuild a map (found " +
                                  std::to_string(keyframes[i].id) + " at position " + std::to_string(i) + ")");
    map->addKeyframe(keyframes[i]);
  }
  for (const auto& point : points) map->addMapPoint(point);
  return map;
}

Session captureSession(const frontend::RgbdSlam& slam, const PinholeCamera& camera) {
  Session session;
  session.camera = camera;
  session.keyframes = slam.map().keyframes();
  session.points = slam.map().mapPoints();
  // observed_points is rebuilt from the landmarks on load, in id order: store it that way.
  for (auto& keyframe : session.keyframes) std::sort(keyframe.observed_points.begin(), keyframe.observed_points.end());
  for (const auto& record : slam.frames())
    if (record.result.hasPose())
      session.frames.push_back({record.timestamp, record.result.reference_keyframe, record.result.pose_in_reference});
  return session;
}

void saveSession(const Session& session, const std::string& folder, bool overwrite) {
  session.validate();
  io::AtomicFolder out(folder, overwrite);
  io::saveCamera(session.camera, (out.path() / "camera.yaml").string());
  writeKeyframes(session, out.path() / "keyframes.txt");
  writeLandmarks(session, out.path() / "landmarks.txt");
  writeFrames(session, out.path() / "frames.txt");
  writeManifest(session, out.path() / "session.txt");
  out.publish();
}

Session loadSession(const std::string& folder) {
  const fs::path root(folder);
  if (!fs::is_directory(root)) throw std::runtime_error("session folder " + folder + " does not exist");
  for (const char* file : {"session.txt", "camera.yaml", "keyframes.txt", "landmarks.txt", "frames.txt"})
    if (!fs::is_regular_file(root / file))
      throw std::runtime_error("session folder " + folder + " has no " + file + " (not a session, or incomplete)");
  const Manifest manifest = readManifest(root / "session.txt");
  Session session;
  session.camera = io::loadCamera((root / "camera.yaml").string());
  session.keyframes = readKeyframes(root / "keyframes.txt");
  checkCount(manifest, "KEYFRAMES", session.keyframes.size(), root / "keyframes.txt");
  std::map<frontend::KeyframeId, std::size_t> index;
  for (std::size_t i = 0; i < session.keyframes.size(); ++i) index[session.keyframes[i].id] = i;
  session.points = readLandmarks(root / "landmarks.txt", index, session.keyframes);
  checkCount(manifest, "LANDMARKS", session.points.size(), root / "landmarks.txt");
  for (auto& keyframe : session.keyframes) std::sort(keyframe.observed_points.begin(), keyframe.observed_points.end());
  session.frames = readFrames(root / "frames.txt", index);
  checkCount(manifest, "FRAMES", session.frames.size(), root / "frames.txt");
  return session;
}

}  // namespace weighted_icp::mapping
