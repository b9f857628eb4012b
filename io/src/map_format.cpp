#include "weighted_icp/io/map_format.h"

#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <set>
#include <string_view>
#include <vector>

#include <Eigen/Eigenvalues>

#include "text_fields.h"
#include "weighted_icp/io/atomic_file.h"
#include "weighted_icp/registration/nearest_neighbor_index.h"

namespace weighted_icp::io {

MapFormatError::MapFormatError(const std::string& source, std::size_t line, const std::string& what)
    : std::runtime_error(source + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " + what),
      source_(source),
      line_(line) {}

namespace {

/// Parses one record's fields, throwing MapFormatError with the field's name.
class FieldReader {
 public:
  FieldReader(const std::vector<std::string_view>& fields, const std::string& source, std::size_t line)
      : fields_(fields), source_(source), line_(line) {}

  double number(std::size_t i, const char* name) const {
    double value = 0.0;
    const auto text = fields_[i];
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (error != std::errc() || end != text.data() + text.size())
      fail(std::string(name) + " " + detail::quoteToken(text) + " is not a number");
    if (!std::isfinite(value)) fail(std::string(name) + " is " + detail::clipToken(text) + "; it must be finite");
    return value;
  }

  std::uint64_t id(std::size_t i, const char* name) const {
    std::uint64_t value = 0;
    const auto text = fields_[i];
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (error != std::errc() || end != text.data() + text.size())
      fail(std::string(name) + " " + detail::quoteToken(text) + " is not a non-negative integer");
    return value;
  }

  [[noreturn]] void fail(const std::string& what) const { throw MapFormatError(source_, line_, what); }

 private:
  const std::vector<std::string_view>& fields_;
  const std::string& source_;
  std::size_t line_;
};

constexpr std::size_t kFrameFields = 9;
constexpr std::size_t kLandmarkFixedFields = 15;

Eigen::Isometry3d parseFrame(const FieldReader& f) {
  const Eigen::Vector3d t(f.number(2, "tx"), f.number(3, "ty"), f.number(4, "tz"));
  Eigen::Quaterniond q(f.number(5, "qw"), f.number(6, "qx"), f.number(7, "qy"), f.number(8, "qz"));
  const double norm = q.norm();
  // Quaternions written with 6 decimals are unit to ~1e-6; far from unit means
  // a wrong record, not rounding.
  if (std::abs(norm - 1.0) > 1e-2)
    f.fail("quaternion (qw qx qy qz) has norm " + std::to_string(norm) + "; expected a unit quaternion");
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = q.normalized().toRotationMatrix();
  pose.translation() = t;
  return pose;
}

/// Why a landmark cannot be used (empty when it can): a position the search
/// index cannot hold, or a covariance that is not one (not symmetric, or with a
/// negative eigenvalue). Tolerances absorb the rounding of a printed matrix.
std::string landmarkProblem(const Landmark& landmark) {
  const Eigen::Vector3d& p = landmark.position;
  if (p.cwiseAbs().maxCoeff() > NearestNeighborIndex::kMaxCoordinate)
    return "position has a coordinate beyond ±1e18, more than the search index can hold";
  const Eigen::Matrix3d& c = landmark.covariance;
  const double norm = c.norm();
  if ((c - c.transpose()).norm() > 1e-9 * norm) return "covariance is not symmetric";
  const Eigen::Matrix3d symmetric = 0.5 * (c + c.transpose());
  const double smallest =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(symmetric, Eigen::EigenvaluesOnly).eigenvalues().minCoeff();
  if (smallest < -1e-12 * norm)
    return "covariance is not positive semi-definite (eigenvalue " + std::to_string(smallest) + ")";
  return {};
}

Landmark parseLandmark(const std::vector<std::string_view>& fields, const FieldReader& f) {
  Landmark landmark;
  landmark.id = f.id(1, "landmark id");
  landmark.position = Eigen::Vector3d(f.number(2, "x"), f.number(3, "y"), f.number(4, "z"));
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) landmark.covariance(r, c) = f.number(5 + 3 * r + c, "covariance entry");
  const std::uint64_t n = f.id(14, "observation count n");
  // Compared as a count of triples, not as 15 + 3n: a huge n would wrap 3n
  // around and could match, then ask for an impossible allocation.
  const std::size_t extra_fields = fields.size() - kLandmarkFixedFields;
  if (extra_fields % 3 != 0 || n != extra_fields / 3)
    f.fail("LANDMARK with n = " + std::to_string(n) + " observations needs 15 + 3n fields, found " +
           std::to_string(fields.size()) + " (" + std::to_string(extra_fields) + " after n)");
  landmark.observations.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t at = kLandmarkFixedFields + 3 * i;
    landmark.observations[i] = {f.id(at, "observation frame id"), f.number(at + 1, "observation u"),
                                f.number(at + 2, "observation v")};
  }
  const std::string problem = landmarkProblem(landmark);
  if (!problem.empty()) f.fail("landmark " + std::to_string(landmark.id) + ": " + problem);
  return landmark;
}

}  // namespace

LandmarkMap parseLandmarkMap(std::istream& in, const std::string& source) {
  LandmarkMap map;
  std::set<LandmarkId> landmark_ids;
  std::vector<std::size_t> landmark_lines;
  std::string line;
  std::size_t line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const auto fields = detail::splitFields(line);
    if (fields.empty() || fields[0].front() == '#') continue;
    const FieldReader f(fields, source, line_number);
    if (fields[0] == "FRAME") {
      if (fields.size() != kFrameFields)
        f.fail("FRAME needs 9 fields (FRAME id tx ty tz qw qx qy qz), found " + std::to_string(fields.size()));
      const FrameId id = f.id(1, "frame id");
      if (!map.frames.emplace(id, parseFrame(f)).second) f.fail("frame " + std::to_string(id) + " is defined twice");
    } else if (fields[0] == "LANDMARK") {
      if (fields.size() < kLandmarkFixedFields)
        f.fail("LANDMARK needs at least 15 fields (LANDMARK id x y z c00..c22 n), found " +
               std::to_string(fields.size()));
      Landmark landmark = parseLandmark(fields, f);
      if (!landmark_ids.insert(landmark.id).second)
        f.fail("landmark " + std::to_string(landmark.id) + " is defined twice");
      map.landmarks.push_back(std::move(landmark));
      landmark_lines.push_back(line_number);
    } else {
      f.fail("unknown record " + detail::quoteToken(fields[0]) + " (expected FRAME or LANDMARK)");
    }
  }
  if (in.bad()) throw MapFormatError(source, line_number, "read error");
  // Frames may come after the landmarks that refer to them, so check at the end.
  for (std::size_t i = 0; i < map.landmarks.size(); ++i)
    for (const auto& observation : map.landmarks[i].observations)
      if (!map.frames.count(observation.frame_id))
        throw MapFormatError(source, landmark_lines[i],
                             "landmark " + std::to_string(map.landmarks[i].id) + " is observed by frame " +
                                 std::to_string(observation.frame_id) + ", which has no FRAME record");
  return map;
}

LandmarkMap readLandmarkMap(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw MapFormatError(path, 0, "cannot open the file");
  return parseLandmarkMap(in, path);
}

namespace {
using detail::exact;

/// Refuses, before anything is written, a map the reader would refuse, so a
/// written map always reads back.
void requireWritable(const LandmarkMap& map) {
  const auto finite = [](const auto& matrix) { return matrix.allFinite(); };
  for (const auto& [id, pose] : map.frames) {
    const Eigen::Matrix3d rotation = pose.linear();
    // The format stores a unit quaternion: a scaling or a reflection would be written as some other pose. Rounding
    // is not (poses composed over a long run drift from orthonormal by ~1e-8): the nearest rotation is written, as
    // io::writeTrajectory accepts the same tolerance.
    if (!finite(pose.matrix()) || !rotation.isUnitary(1e-6) || rotation.determinant() < 0.0)
      throw std::invalid_argument("frame " + std::to_string(id) + " has a pose that is not a finite rigid motion");
  }
  std::set<LandmarkId> ids;
  for (const auto& landmark : map.landmarks) {
    const std::string name = "landmark " + std::to_string(landmark.id);
    if (!ids.insert(landmark.id).second) throw std::invalid_argument(name + " appears twice");
    if (!finite(landmark.position) || !finite(landmark.covariance))
      throw std::invalid_argument(name + " has a non-finite position or covariance");
    const std::string problem = landmarkProblem(landmark);
    if (!problem.empty()) throw std::invalid_argument(name + ": " + problem);
    for (const auto& o : landmark.observations) {
      if (!map.frames.count(o.frame_id))
        throw std::invalid_argument(name + " is observed by frame " + std::to_string(o.frame_id) +
                                    ", which the map does not have");
      if (!std::isfinite(o.u) || !std::isfinite(o.v))
        throw std::invalid_argument(name + " has a non-finite observation in frame " + std::to_string(o.frame_id));
    }
  }
}
}  // namespace

void writeLandmarkMap(const LandmarkMap& map, std::ostream& out) {
  requireWritable(map);
  for (const auto& [id, pose] : map.frames) {
    const Eigen::Quaterniond q = Eigen::Quaterniond(Eigen::Matrix3d(pose.linear())).normalized();
    const Eigen::Vector3d& t = pose.translation();
    out << "FRAME " << id << ' ' << exact(t.x()) << ' ' << exact(t.y()) << ' ' << exact(t.z()) << ' ' << exact(q.w())
        << ' ' << exact(q.x()) << ' ' << exact(q.y()) << ' ' << exact(q.z()) << '\n';
  }
  for (const auto& landmark : map.landmarks) {
    out << "LANDMARK " << landmark.id;
    for (int i = 0; i < 3; ++i) out << ' ' << exact(landmark.position[i]);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) out << ' ' << exact(landmark.covariance(r, c));
    out << ' ' << landmark.observations.size();
    for (const auto& o : landmark.observations) out << ' ' << o.frame_id << ' ' << exact(o.u) << ' ' << exact(o.v);
    out << '\n';
  }
}

void writeLandmarkMap(const LandmarkMap& map, const std::string& path) {
  try {
    writeAtomically(path, [&](const std::string& temporary) {
      std::ofstream out(temporary);
      if (!out) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
      writeLandmarkMap(map, out);
      out.close();
      if (!out) throw std::runtime_error("cannot write " + path + " (disk full?)");
    });
  } catch (const std::invalid_argument& e) {  // the map itself cannot be written
    throw std::runtime_error("cannot write " + path + ": " + e.what());
  }
}

}  // namespace weighted_icp::io
