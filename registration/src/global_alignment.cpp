// Global registration: rotation hypotheses about the up axis, a translation
// vote per rotation, trimmed ICP with a shrinking distance limit, inlier count.
#include "weighted_icp/registration/global_alignment.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <thread>
#include <unordered_set>
#include <utility>

#include <Eigen/Geometry>

#include "weighted_icp/core/statistics.h"
#include "weighted_icp/registration/nearest_neighbor_index.h"
#include "weighted_icp/registration/rigid_motion.h"
#include "weighted_icp/registration/worker_pool.h"

namespace weighted_icp {

namespace {

using Points = std::vector<Eigen::Vector3f>;

/// Dense vote grids larger than this are coarsened (a 30 m map at 15 cm is 8e6 cells).
constexpr std::size_t kMaxVoteCells = std::size_t{1} << 24;

Points finitePoints(const GlobalAlignment::Cloud& cloud, const char* what) {
  NearestNeighborIndex::requireIndexable(cloud, what);
  Points points;
  points.reserve(cloud.size());
  for (const auto& p : cloud)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) points.emplace_back(p.x, p.y, p.z);
  if (points.size() < 3)
    throw std::invalid_argument(std::string("GlobalAlignment: the ") + what + " has " + std::to_string(points.size()) +
                                " finite points, fewer than 3");
  return points;
}

/// One point (the first seen, a real point: its residuals are those of the
/// cloud) per occupied voxel, in input order so the sample does not depend on
/// hashing.
Points voxelFirsts(const Points& points, double cell) {
  std::unordered_set<std::int64_t> occupied;
  Points firsts;
  for (const auto& p : points) {
    const auto key = [&](int axis) { return static_cast<std::int64_t>(std::floor(p[axis] / cell)) & 0x1fffff; };
    if (occupied.insert(key(0) | (key(1) << 21) | (key(2) << 42)).second) firsts.push_back(p);
  }
  return firsts;
}

/// Every n-th of `firsts` (voxelFirsts) to stay within `max_points`.
Points strided(const Points& firsts, std::size_t max_points) {
  const std::size_t stride = (firsts.size() + max_points - 1) / max_points;
  Points sample;
  for (std::size_t i = 0; i < firsts.size(); i += stride) sample.push_back(firsts[i]);
  return sample;
}

/// voxelFirsts, then every n-th to stay within `max_points`.
Points voxelSample(const Points& points, double cell, std::size_t max_points) {
  return strided(voxelFirsts(points, cell), max_points);
}

/// The vote's sample cell (GlobalAlignmentSettings::sample_cell, 0: a third of the vote cell).
double sampleCell(const GlobalAlignmentSettings& s) { return s.sample_cell > 0.0 ? s.sample_cell : s.vote_cell / 3.0; }

/// Whether the search runs the other way, the target onto the source, its result inverted. The vote's evidence is the
/// pairs of sample points that both lie where the maps overlap; the source's sample is capped lower than the target's
/// (the vote costs their product), so a source with many more sample voxels than the target (a whole map aligned
/// onto one of its mini-maps) has few of its samples where the target is, and the vote starves. Reversed when that
/// at least doubles the sample pairs: below, the two ways are close and the caller's way is kept (mini-maps of a like
/// size are searched as before). Reversing whenever the source has twice the target's points was measured and not
/// kept: it lost maps in their first camera's frame (docs/global_alignment.md).
bool searchesReversed(std::size_t source_voxels, std::size_t target_voxels, const GlobalAlignmentSettings& s) {
  const auto pairs = [&](std::size_t from, std::size_t onto) {
    return static_cast<double>(std::min(from, s.max_source_samples)) *
           static_cast<double>(std::min(onto, s.max_target_samples));
  };
  return pairs(target_voxels, source_voxels) >= 2.0 * pairs(source_voxels, target_voxels);
}

/// The inlier radius: the settings' (GlobalAlignmentSettings::inlier_distance), or 2 target spacings.
double inlierDistance(const GlobalAlignmentSettings& s, double spacing) {
  return s.inlier_distance > 0.0 ? s.inlier_distance : 2.0 * spacing;
}

/// The trimmed ICP's floor: the settings' (GlobalAlignmentSettings::min_distance), or 2 target spacings.
double minDistance(const GlobalAlignmentSettings& s, double spacing) {
  return s.min_distance > 0.0 ? s.min_distance : 2.0 * spacing;
}

pcl::PointCloud<pcl::PointXYZ> toCloud(const Points& points) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  for (const auto& p : points) cloud.push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  return cloud;
}

Eigen::Vector3f apply(const Eigen::Matrix4d& t, const Eigen::Vector3f& p) {
  return (t.topLeftCorner<3, 3>() * p.cast<double>() + t.topRightCorner<3, 1>()).cast<float>();
}

/// A rotation with a translation from the vote, and how many votes it got.
struct Hypothesis {
  double yaw;                   // radians about the up axis, about the sample's centroid
  Eigen::Vector3d translation;  // where the centroid goes
  std::size_t votes;
};

/// The result of a trimmed ICP run.
struct TrimmedFit {
  Eigen::Matrix4d transformation;
  double distance_limit;
  double median_residual;
};

}  // namespace

struct GlobalAlignment::Target {
  Points points;
  Points sample;
  /// Voxels of the sample cell the points occupy (the sample's size before its cap).
  std::size_t voxels = 0;
  NearestNeighborIndex index;
  double spacing = 0.0;
  /// Target point indices by bucket of bucket_size (the fine window): the
  /// points within a window of p are in the 27 buckets around p's.
  std::unordered_map<std::int64_t, std::vector<std::uint32_t>> buckets, small_buckets;
  double bucket_size = 1.0, small_bucket_size = 1.0;

  static std::int64_t bucketKey(const Eigen::Vector3i& c) {
    return (static_cast<std::int64_t>(c.x()) & 0x1fffff) | ((static_cast<std::int64_t>(c.y()) & 0x1fffff) << 21) |
           ((static_cast<std::int64_t>(c.z()) & 0x1fffff) << 42);
  }
  static Eigen::Vector3i bucketOf(const Eigen::Vector3f& p, double size) {
    return (p.cast<double>() / size).array().floor().cast<int>();
  }

  /// Distance from `p` to its nearest target point.
  double nearest(const Eigen::Vector3f& p, NearestNeighborIndex::Scratch& scratch) const {
    if (index.knn(p.data(), scratch) == 0) return std::numeric_limits<double>::infinity();
    return std::sqrt(static_cast<double>(scratch.squaredDistances()[0]));
  }
};

namespace {

/// Median distance from a target point to its nearest other target point, over
/// at most 2000 evenly strided points.
double medianSpacing(const Points& points, const NearestNeighborIndex& index) {
  NearestNeighborIndex::Scratch scratch(2);
  std::vector<double> distances;
  const std::size_t stride = std::max<std::size_t>(1, points.size() / 2000);
  for (std::size_t i = 0; i < points.size(); i += stride)
    if (index.knn(points[i].data(), scratch) == 2) distances.push_back(std::sqrt(scratch.squaredDistances()[1]));
  return distances.empty() ? 0.0 : median(distances);
}

/// Translations that bring many (rotated) source samples onto target samples:
/// every source-target pair votes for their difference in a dense grid; the
/// `peaks` fullest cells, each at least 2 cells from the others, win.
std::vector<std::pair<Eigen::Vector3d, std::size_t>> voteTranslations(const Points& source, const Points& target,
                                                                      double cell, unsigned int peaks) {
  Eigen::Vector3f smin = source[0], smax = source[0], tmin = target[0], tmax = target[0];
  for (const auto& p : source) smin = smin.cwiseMin(p), smax = smax.cwiseMax(p);
  for (const auto& p : target) tmin = tmin.cwiseMin(p), tmax = tmax.cwiseMax(p);
  const Eigen::Vector3d origin = (tmin - smax).cast<double>();
  const Eigen::Vector3d extent = (tmax - smin).cast<double>() - origin;
  while ((extent / cell).prod() > static_cast<double>(kMaxVoteCells)) cell *= 2.0;
  const Eigen::Vector3i size = (extent / cell).array().floor().cast<int>() + 1;
  std::vector<std::uint32_t> grid(static_cast<std::size_t>(size.prod()), 0);
  const auto cellIndex = [&](const Eigen::Vector3d& t) {
    const Eigen::Vector3i c = ((t - origin) / cell).array().floor().cast<int>().cwiseMax(0).cwiseMin(size.array() - 1);
    return (static_cast<std::size_t>(c.z()) * size.y() + c.y()) * size.x() + c.x();
  };
  for (const auto& s : source)
    for (const auto& t : target) ++grid[cellIndex((t - s).cast<double>())];

  std::vector<std::pair<Eigen::Vector3d, std::size_t>> found;
  for (unsigned int n = 0; n < peaks; ++n) {
    const auto best = std::max_element(grid.begin(), grid.end());
    if (*best == 0) break;
    const std::size_t i = static_cast<std::size_t>(best - grid.begin());
    const Eigen::Vector3i c(static_cast<int>(i % size.x()), static_cast<int>(i / size.x() % size.y()),
                            static_cast<int>(i / size.x() / size.y()));
    found.emplace_back(origin + (c.cast<double>().array() + 0.5).matrix() * cell, *best);
    // Suppress the neighbourhood so the next peak is a different translation.
    for (int z = std::max(0, c.z() - 2); z <= std::min(size.z() - 1, c.z() + 2); ++z)
      for (int y = std::max(0, c.y() - 2); y <= std::min(size.y() - 1, c.y() + 2); ++y)
        for (int x = std::max(0, c.x() - 2); x <= std::min(size.x() - 1, c.x() + 2); ++x)
          grid[(static_cast<std::size_t>(z) * size.y() + y) * size.x() + x] = 0;
  }
  return found;
}

/// Point-to-point ICP on the pairs closer than a limit that starts at
/// `distance` and then follows shrink_factor x the median residual (never
/// growing, never below min_distance): parts of the source with no
/// counterpart in the target fall outside it and do not pull.
TrimmedFit trimmedIcp(const Points& source, const GlobalAlignment::Target& target, Eigen::Matrix4d transformation,
                      double distance, double min_distance, double shrink_factor, int iterations) {
  NearestNeighborIndex::Scratch scratch(1);
  // A start below the floor (a sparse target, spacing above the fine cell) would leave too few pairs.
  TrimmedFit fit{transformation, std::max(distance, min_distance), std::numeric_limits<double>::infinity()};
  Eigen::Matrix3Xd from(3, source.size()), to(3, source.size());
  std::vector<double> residuals;
  for (int iteration = 0; iteration < iterations; ++iteration) {
    residuals.clear();
    Eigen::Index pairs = 0;
    for (const auto& p : source) {
      const Eigen::Vector3f moved = apply(fit.transformation, p);
      if (target.index.knn(moved.data(), scratch) == 0) continue;
      const double d = std::sqrt(static_cast<double>(scratch.squaredDistances()[0]));
      if (d > fit.distance_limit) continue;
      from.col(pairs) = moved.cast<double>();
      to.col(pairs) = target.points[static_cast<std::size_t>(scratch.indices()[0])].cast<double>();
      residuals.push_back(d);
      ++pairs;
    }
    if (pairs < 3) break;
    const Eigen::Matrix4d step = Eigen::umeyama(from.leftCols(pairs), to.leftCols(pairs), false);
    fit.transformation = step * fit.transformation;
    fit.median_residual = median(residuals);
    const double next = std::clamp(shrink_factor * fit.median_residual, min_distance, fit.distance_limit);
    const bool settled = (step - Eigen::Matrix4d::Identity()).norm() < 1e-7 && next == fit.distance_limit;
    fit.distance_limit = next;
    if (settled) break;
  }
  return fit;
}

/// A yaw about `axis` (about `centroid`) and a translation: x -> R (x - centroid) + t.
Eigen::Matrix4d yawPose(const Eigen::Vector3d& axis, double yaw, const Eigen::Vector3d& centroid,
                        const Eigen::Vector3d& t) {
  Eigen::Matrix4d pose = Eigen::Matrix4d::Identity();
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(yaw, axis).toRotationMatrix();
  pose.topLeftCorner<3, 3>() = rotation;
  pose.topRightCorner<3, 1>() = t - rotation * centroid;
  return pose;
}

/// The fine search around (yaw, t): per rotation, every pair of a sample point
/// and a target point within the window votes for the translation correction
/// in fine cells; the fullest cell over all rotations wins. Returns the pose and its votes.
/// The search box: yaw range and step (degrees), translation window and cell (metres), and the target buckets
/// (as large as the window) to look in.
struct VoteBox {
  double yaw_range_deg, yaw_step_deg, window, cell;
  const std::unordered_map<std::int64_t, std::vector<std::uint32_t>>* buckets;
  double bucket_size;
};

std::pair<Eigen::Matrix4d, std::size_t> fineVote(const Points& sample, const GlobalAlignment::Target& target,
                                                 const VoteBox& box, const Eigen::Vector3d& axis, double yaw,
                                                 const Eigen::Vector3d& centroid, const Eigen::Vector3d& t,
                                                 double* refine_yaw = nullptr, Eigen::Vector3d* refine_t = nullptr) {
  const double window = box.window, cell = box.cell;
  const int side = static_cast<int>(std::ceil(2.0 * window / cell));
  std::vector<std::uint16_t> grid(static_cast<std::size_t>(side) * side * side);
  const int steps = static_cast<int>(std::floor(box.yaw_range_deg / box.yaw_step_deg + 1e-9));
  std::pair<Eigen::Matrix4d, std::size_t> best{yawPose(axis, yaw, centroid, t), 0};
  double best_yaw = yaw;
  Eigen::Vector3d best_t = t;
  for (int step = -steps; step <= steps; ++step) {
    const double angle = yaw + step * box.yaw_step_deg * M_PI / 180.0;
    const Eigen::Matrix3d rotation = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    std::fill(grid.begin(), grid.end(), 0);
    for (const auto& p : sample) {
      const Eigen::Vector3f moved = (rotation * (p.cast<double>() - centroid) + t).cast<float>();
      const Eigen::Vector3i home = GlobalAlignment::Target::bucketOf(moved, box.bucket_size);
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const auto bucket =
                box.buckets->find(GlobalAlignment::Target::bucketKey(home + Eigen::Vector3i(dx, dy, dz)));
            if (bucket == box.buckets->end()) continue;
            for (const std::uint32_t i : bucket->second) {
              const Eigen::Vector3f d = target.points[i] - moved;
              if (d.cwiseAbs().maxCoeff() >= window) continue;
              const Eigen::Vector3i c = ((d.cast<double>().array() + window) / cell).floor().cast<int>().min(side - 1);
              std::uint16_t& votes = grid[(static_cast<std::size_t>(c.z()) * side + c.y()) * side + c.x()];
              if (votes < 0xffff) ++votes;
            }
          }
    }
    const auto peak = std::max_element(grid.begin(), grid.end());
    if (*peak <= best.second) continue;
    const std::size_t i = static_cast<std::size_t>(peak - grid.begin());
    const Eigen::Vector3d offset = (Eigen::Vector3d(static_cast<double>(i % side), static_cast<double>(i / side % side),
                                                    static_cast<double>(i / side / side))
                                        .array() +
                                    0.5) *
                                       cell -
                                   window;
    best = {yawPose(axis, angle, centroid, t + offset), *peak};
    best_yaw = angle;
    best_t = t + offset;
  }
  if (refine_yaw) {
    *refine_yaw = best_yaw;
    *refine_t = best_t;
  }
  return best;
}

/// The source points with a target point within `radius` of where `transformation` puts them, and their MSAC
/// score (Torr and Zisserman's): each such point counts 1 - (d / radius)^2, so that of two poses with as many
/// inliers the tighter fit ranks higher. Their centroid (in the source's coordinates; zero when none) is the part
/// of the source that overlaps the target, about which the final pass tilts.
struct Inliers {
  std::size_t count = 0;
  double score = 0.0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
};

Inliers countInliers(const Points& source, const GlobalAlignment::Target& target, const Eigen::Matrix4d& transformation,
                     double radius) {
  NearestNeighborIndex::Scratch scratch(1);
  Inliers inliers;
  for (const auto& p : source) {
    const double d = target.nearest(apply(transformation, p), scratch) / radius;
    if (d > 1.0) continue;
    ++inliers.count;
    inliers.score += 1.0 - d * d;
    inliers.centroid += p.cast<double>();
  }
  if (inliers.count > 0) inliers.centroid /= static_cast<double>(inliers.count);
  return inliers;
}

/// A hypothesis after the fine search and the trimmed ICP: where its yaw and centroid went, and its inliers
/// (countInliers), ranked by their score.
struct Refined {
  Eigen::Matrix4d transformation = Eigen::Matrix4d::Identity();
  double yaw = 0.0;
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Inliers inliers;
};

/// The trimmed ICP's start distance, floor, shrink factor and iterations.
struct TrimmedIcpLimits {
  double start_distance, min_distance, shrink_factor;
  int iterations;
};

/// A rotation about `centroid` as a 4x4 transformation.
Eigen::Matrix4d aboutCentroid(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& centroid) {
  Eigen::Matrix4d pose = Eigen::Matrix4d::Identity();
  pose.topLeftCorner<3, 3>() = rotation;
  pose.topRightCorner<3, 1>() = centroid - rotation * centroid;
  return pose;
}

/// What refining a hypothesis needs: the source (its vote sample and every point, levelled), the target, the
/// medium and fine vote boxes, the up axis, the sample's centroid, the trimmed ICP's limits and the inlier radius.
struct Search {
  const Points& sample;
  const Points& source;
  const GlobalAlignment::Target& target;
  VoteBox medium, fine;
  Eigen::Vector3d axis, centroid;
  TrimmedIcpLimits icp;
  double inlier_distance;
};

/// The search around hypotheses of `sample` (of the levelled `source`, centred at `centroid`) against `target` about
/// `axis`, with the settings' vote boxes and the trimmed ICP's limits (`min_distance` its floor).
Search searchFor(const Points& sample, const Points& source, const GlobalAlignment::Target& target,
                 const Eigen::Vector3d& axis, const Eigen::Vector3d& centroid, const GlobalAlignmentSettings& s,
                 double min_distance, double inlier_distance) {
  return {
      sample,
      source,
      target,
      {s.fine_yaw_range_deg, s.medium_yaw_step_deg, s.fine_window, s.medium_cell, &target.buckets, target.bucket_size},
      {s.medium_yaw_step_deg, s.fine_yaw_step_deg, 2.0 * s.medium_cell, s.fine_cell, &target.small_buckets,
       target.small_bucket_size},
      axis,
      centroid,
      {2.0 * s.fine_cell, min_distance, s.shrink_factor, s.hypothesis_iterations},
      inlier_distance};
}

/// One hypothesis (yaw, centroid translation) of the source first moved by `tilt`: the medium then the fine vote
/// around it, the trimmed ICP from there on every source point, and the inlier score of the result.
Refined refineHypothesis(const Search& search, const Eigen::Matrix4d& tilt, double yaw, Eigen::Vector3d t) {
  Points tilted;
  tilted.reserve(search.sample.size());
  for (const auto& p : search.sample) tilted.push_back(apply(tilt, p));
  fineVote(tilted, search.target, search.medium, search.axis, yaw, search.centroid, t, &yaw, &t);
  const Eigen::Matrix4d pose =
      fineVote(tilted, search.target, search.fine, search.axis, yaw, search.centroid, t, &yaw, &t).first;
  const TrimmedIcpLimits& icp = search.icp;
  const TrimmedFit fit = trimmedIcp(search.source, search.target, pose * tilt, icp.start_distance, icp.min_distance,
                                    icp.shrink_factor, icp.iterations);
  return {fit.transformation, yaw, t,
          countInliers(search.source, search.target, fit.transformation, search.inlier_distance)};
}

/// `refined` searched again from where its trimmed ICP ended (its yaw about the up axis and where it put the
/// sample's centroid), at most `rounds` times while its inlier score grows.
Refined climb(const Search& search, Refined refined, unsigned int rounds) {
  const Eigen::Vector3d e1 = search.axis.unitOrthogonal(), e2 = search.axis.cross(e1);
  for (unsigned int round = 0; round < rounds; ++round) {
    const Eigen::Matrix3d rotation = refined.transformation.topLeftCorner<3, 3>();
    const Eigen::Vector3d x = rotation * e1;
    const double yaw = std::atan2(x.dot(e2), x.dot(e1));  // AngleAxis(yaw, axis) turns e1 towards e2
    const Eigen::Vector3d t = rotation * search.centroid + refined.transformation.topRightCorner<3, 1>();
    Refined again = refineHypothesis(search, Eigen::Matrix4d::Identity(), yaw, t);
    if (again.inliers.score <= refined.inliers.score) break;
    refined = std::move(again);
  }
  return refined;
}

/// The tilts within ±`range_deg` about the two axes perpendicular to `axis` (e1 = axis.unitOrthogonal(), e2 =
/// axis × e1) in `step_deg` steps, each a rotation about `pivot`: AngleAxis(i step, e1) · AngleAxis(j step, e2) for
/// i, j in [-steps, steps], i major. The grid's centre (the identity) is at size() / 2.
std::vector<Eigen::Matrix4d> tiltGrid(const Eigen::Vector3d& axis, double range_deg, double step_deg,
                                      const Eigen::Vector3d& pivot) {
  const Eigen::Vector3d e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
  const int steps = static_cast<int>(std::floor(range_deg / step_deg + 1e-9));
  std::vector<Eigen::Matrix4d> tilts;
  tilts.reserve(static_cast<std::size_t>((2 * steps + 1) * (2 * steps + 1)));
  for (int i = -steps; i <= steps; ++i)
    for (int j = -steps; j <= steps; ++j) {
      const Eigen::Matrix3d rotation =
          (Eigen::AngleAxisd(i * step_deg * M_PI / 180.0, e1) * Eigen::AngleAxisd(j * step_deg * M_PI / 180.0, e2))
              .toRotationMatrix();
      tilts.push_back(aboutCentroid(rotation, pivot));
    }
  return tilts;
}

/// The tilt (tiltGrid about the sample's centroid) under which the sample, at the refined hypothesis's yaw and
/// translation, fills one fine vote cell (yaw not searched) most.
Eigen::Matrix4d bestTilt(const Search& search, const Refined& around, double range_deg, double step_deg,
                         WorkerPool& pool, unsigned threads) {
  const VoteBox box{0.0,
                    search.fine.yaw_step_deg,
                    search.fine.window,
                    search.fine.cell,
                    search.fine.buckets,
                    search.fine.bucket_size};
  const std::vector<Eigen::Matrix4d> tilts = tiltGrid(search.axis, range_deg, step_deg, search.centroid);
  std::vector<std::size_t> votes(tilts.size(), 0);
  pool.run(tilts.size(), 1, threads, [&](std::size_t begin, std::size_t end, unsigned) {
    Points tilted(search.sample.size());
    for (std::size_t t = begin; t < end; ++t) {
      for (std::size_t k = 0; k < search.sample.size(); ++k) tilted[k] = apply(tilts[t], search.sample[k]);
      votes[t] =
          fineVote(tilted, search.target, box, search.axis, around.yaw, search.centroid, around.translation).second;
    }
  });
  // The first fullest in grid order, whichever thread voted it.
  const std::size_t best = static_cast<std::size_t>(std::max_element(votes.begin(), votes.end()) - votes.begin());
  return votes[best] > 0 ? tilts[best] : Eigen::Matrix4d::Identity();
}

/// Rotations about the up axis (about the sample's centroid), each with its voted translations, best voted first
/// (stable: ties keep rotation order).
std::vector<Hypothesis> voteRotations(const Points& sample, const Eigen::Vector3f& centroid,
                                      const GlobalAlignment::Target& target, const Eigen::Vector3d& axis,
                                      const GlobalAlignmentSettings& s, WorkerPool& pool, unsigned threads) {
  std::vector<std::vector<Hypothesis>> per_rotation(s.yaw_hypotheses);
  pool.run(s.yaw_hypotheses, 1, threads, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t r = begin; r < end; ++r) {
      const double yaw = 2.0 * M_PI * static_cast<double>(r) / s.yaw_hypotheses;
      const Eigen::Matrix3d rotation = Eigen::AngleAxisd(yaw, axis).toRotationMatrix();
      Points rotated;
      rotated.reserve(sample.size());
      for (const auto& p : sample) rotated.push_back((rotation * (p - centroid).cast<double>()).cast<float>());
      for (const auto& [translation, votes] :
           voteTranslations(rotated, target.sample, s.vote_cell, s.peaks_per_rotation))
        per_rotation[r].push_back({yaw, translation, votes});
    }
  });
  std::vector<Hypothesis> hypotheses;
  for (const auto& found : per_rotation) hypotheses.insert(hypotheses.end(), found.begin(), found.end());
  std::stable_sort(hypotheses.begin(), hypotheses.end(),
                   [](const Hypothesis& a, const Hypothesis& b) { return a.votes > b.votes; });
  return hypotheses;
}

/// Around the `s.tilted_hypotheses` best refined hypotheses (`results`, best first), the tilt whose fine vote is
/// fullest, each refined again; the result with the highest inlier score, `best` unless one scores higher.
Refined bestTilted(const Search& search, const std::vector<Refined>& results, Refined best, double range_deg,
                   const GlobalAlignmentSettings& s, WorkerPool& pool, unsigned threads) {
  const std::size_t count = std::min<std::size_t>(results.size(), s.tilted_hypotheses);
  std::vector<Eigen::Matrix4d> tilts;
  for (std::size_t h = 0; h < count; ++h)
    tilts.push_back(bestTilt(search, results[h], range_deg, s.tilt_step_deg, pool, threads));
  std::vector<Refined> tilted(count);
  pool.run(count, 1, std::max<unsigned>(1, std::min<unsigned>(threads, static_cast<unsigned>(count))),
           [&](std::size_t begin, std::size_t end, unsigned) {
             for (std::size_t h = begin; h < end; ++h)
               tilted[h] = refineHypothesis(search, tilts[h], results[h].yaw, results[h].translation);
           });
  for (const Refined& t : tilted)
    if (t.inliers.score > best.inliers.score) best = t;
  return best;
}

/// The `count` best-voted hypotheses, each searched finely around and refined with the tight pass on every source
/// point (in parallel), ranked by inlier score, best first (ties keep the vote's order).
std::vector<Refined> refineBestVoted(const Search& search, const std::vector<Hypothesis>& hypotheses, std::size_t count,
                                     WorkerPool& pool, unsigned threads) {
  std::vector<Refined> results(count);
  pool.run(count, 1, threads, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t h = begin; h < end; ++h)
      results[h] = refineHypothesis(search, Eigen::Matrix4d::Identity(), hypotheses[h].yaw, hypotheses[h].translation);
  });
  std::stable_sort(results.begin(), results.end(),
                   [](const Refined& a, const Refined& b) { return a.inliers.score > b.inliers.score; });
  return results;
}

/// The best of the `count` first of `results` (best first) each climbed (climb(), in parallel): the highest inlier
/// score, ties to the earlier; results.front() when none is climbed. `results` stay as they were (the tilts start from
/// them).
Refined bestClimbed(const Search& search, const std::vector<Refined>& results, std::size_t count, unsigned int rounds,
                    WorkerPool& pool, unsigned threads) {
  if (results.empty()) return Refined{};
  count = std::min(count, results.size());
  if (count == 0 || rounds == 0) return results.front();
  std::vector<Refined> climbed(results.begin(), results.begin() + static_cast<std::ptrdiff_t>(count));
  pool.run(count, 1, threads, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t h = begin; h < end; ++h) climbed[h] = climb(search, climbed[h], rounds);
  });
  Refined best = climbed.front();
  for (const Refined& c : climbed)
    if (c.inliers.score > best.inliers.score) best = c;
  return best;
}

/// The most tilt steps each way the search's tilts (tilt_range_deg / tilt_step_deg) and the final pass's may take: the
/// search votes (2 n + 1)^2 tilts per hypothesis, the final pass runs a trimmed ICP from each of its own.
constexpr double kMaxSearchTiltSteps = 20.0;
constexpr double kMaxFinalTiltSteps = 10.0;

/// Whether a tilt range is finite and in [0, 30] degrees.
bool tiltRangeValid(double tilt_range_deg) {
  return std::isfinite(tilt_range_deg) && tilt_range_deg >= 0.0 && tilt_range_deg <= kMaxTiltRangeDeg;
}

/// Whether a tilt range can be searched: valid (tiltRangeValid) and at most `max_steps` steps of a finite positive
/// `tilt_step_deg` each way (the settings' checks and align's per-call argument share it).
bool tiltRangeFits(double tilt_range_deg, double tilt_step_deg, double max_steps) {
  return tiltRangeValid(tilt_range_deg) && std::isfinite(tilt_step_deg) && tilt_step_deg > 0.0 &&
         tilt_range_deg / tilt_step_deg <= max_steps + 1e-9;
}

/// Refuses what GlobalAlignment::align cannot use, naming it.
void checkAlignArguments(const Eigen::Vector3d& source_up_axis, const Eigen::Vector3d& up_axis, double tilt_range_deg,
                         double tilt_step_deg) {
  if (!source_up_axis.allFinite())
    throw std::invalid_argument("GlobalAlignment::align: the source's up axis must be finite (zero: the target's)");
  if (!up_axis.allFinite() || !(up_axis.norm() > 0.0))
    throw std::invalid_argument("GlobalAlignment::align: the up axis must be a finite non-zero vector");
  if (!tiltRangeFits(tilt_range_deg, tilt_step_deg, kMaxSearchTiltSteps))
    throw std::invalid_argument(
        "GlobalAlignment::align: the tilt range must be in [0, 30] degrees and at most 20 "
        "tilt steps");
}

/// The rotation that turns the source's up axis onto `axis` (the identity for a zero source axis: the target's).
Eigen::Matrix3d levellingRotation(const Eigen::Vector3d& source_up_axis, const Eigen::Vector3d& axis) {
  return source_up_axis.norm() > 0.0
             ? Eigen::Quaterniond::FromTwoVectors(source_up_axis.normalized(), axis).toRotationMatrix()
             : Eigen::Matrix3d::Identity();
}

}  // namespace

GlobalAlignment::GlobalAlignment(GlobalAlignmentSettings settings)
    : settings_(std::move(settings)), target_(std::make_shared<Target>()), pool_(std::make_unique<WorkerPool>()) {
  const auto& s = settings_;
  const auto require = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("GlobalAlignmentSettings::") + what);
  };
  require(s.yaw_hypotheses >= 1 && s.yaw_hypotheses <= 3600, "yaw_hypotheses must be in 1-3600");
  require(s.up_axis.allFinite() && s.up_axis.norm() > 0.0, "up_axis must be a finite non-zero vector");
  require(std::isfinite(s.vote_cell) && s.vote_cell > 0.0, "vote_cell must be > 0");
  for (const auto& [value, name] : {std::pair{s.sample_cell, "sample_cell must be >= 0"},
                                    {s.initial_distance, "initial_distance must be >= 0"},
                                    {s.min_distance, "min_distance must be >= 0"},
                                    {s.inlier_distance, "inlier_distance must be >= 0"}})
    require(std::isfinite(value) && value >= 0.0, name);
  for (const auto& [value, name] : {std::pair{s.fine_yaw_range_deg, "fine_yaw_range_deg must be > 0"},
                                    {s.medium_yaw_step_deg, "medium_yaw_step_deg must be > 0"},
                                    {s.fine_yaw_step_deg, "fine_yaw_step_deg must be > 0"},
                                    {s.fine_window, "fine_window must be > 0"},
                                    {s.medium_cell, "medium_cell must be > 0"},
                                    {s.fine_cell, "fine_cell must be > 0"}})
    require(std::isfinite(value) && value > 0.0, name);
  require(s.fine_window / s.medium_cell <= 200 && 2.0 * s.medium_cell / s.fine_cell <= 200,
          "fine vote grids may have at most 200 cells a side");
  require(s.max_source_samples >= 3 && s.max_target_samples >= 3, "sample caps must be >= 3");
  require(s.peaks_per_rotation >= 1 && s.refined_hypotheses >= 1, "peaks and refined hypotheses must be >= 1");
  require(s.climb_rounds <= 100, "climb_rounds must be at most 100");
  require(tiltRangeValid(s.tilt_range_deg), "tilt_range_deg must be in [0, 30]");
  require(tiltRangeFits(s.tilt_range_deg, s.tilt_step_deg, kMaxSearchTiltSteps),
          "tilt_step_deg must be > 0 and at least tilt_range_deg / 20");
  require(tiltRangeValid(s.final_tilt_range_deg), "final_tilt_range_deg must be in [0, 30]");
  require(tiltRangeFits(s.final_tilt_range_deg, s.final_tilt_step_deg, kMaxFinalTiltSteps),
          "final_tilt_step_deg must be > 0 and at least final_tilt_range_deg / 10");
  require(s.final_tilt_rounds >= 1 && s.final_tilt_rounds <= 10, "final_tilt_rounds must be in 1-10");
  require(s.threads <= 1024, "threads must be at most 1024 (0: every hardware thread)");
  require(s.hypothesis_iterations >= 1 && s.final_iterations >= 1, "iteration counts must be >= 1");
  require(std::isfinite(s.shrink_factor) && s.shrink_factor > 0.0, "shrink_factor must be > 0");
}

GlobalAlignment::~GlobalAlignment() = default;
GlobalAlignment::GlobalAlignment(GlobalAlignment&&) noexcept = default;
GlobalAlignment& GlobalAlignment::operator=(GlobalAlignment&&) noexcept = default;

void GlobalAlignment::setTarget(const Cloud& target) {
  auto fresh = std::make_shared<Target>();
  fresh->points = finitePoints(target, "target");
  fresh->index.build(toCloud(fresh->points));
  fresh->spacing = medianSpacing(fresh->points, fresh->index);
  if (!(fresh->spacing > 0.0)) {
    // Half the points or more sit on top of each other; use the extent instead.
    Eigen::Vector3f lo = fresh->points[0], hi = lo;
    for (const auto& p : fresh->points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    fresh->spacing = 1e-3 * static_cast<double>((hi - lo).norm());
    if (!(fresh->spacing > 0.0)) throw std::invalid_argument("GlobalAlignment: all finite target points are identical");
  }
  fresh->bucket_size = settings_.fine_window;
  fresh->small_bucket_size = 2.0 * settings_.medium_cell;
  for (std::size_t i = 0; i < fresh->points.size(); ++i) {
    const auto index = static_cast<std::uint32_t>(i);
    fresh->buckets[Target::bucketKey(Target::bucketOf(fresh->points[i], fresh->bucket_size))].push_back(index);
    fresh->small_buckets[Target::bucketKey(Target::bucketOf(fresh->points[i], fresh->small_bucket_size))].push_back(
        index);
  }
  const Points firsts = voxelFirsts(fresh->points, sampleCell(settings_));
  fresh->voxels = firsts.size();
  fresh->sample = strided(firsts, settings_.max_target_samples);
  target_ = std::move(fresh);
}

GlobalAlignment GlobalAlignment::withSearchSettings(GlobalAlignmentSettings settings) const {
  // Exact comparisons: the target is built from these values, and a copy of them compares equal.
  for (const auto& [same, name] : {std::pair{settings.sample_cell == settings_.sample_cell, "sample_cell"},
                                   {settings.max_target_samples == settings_.max_target_samples, "max_target_samples"},
                                   {settings.fine_window == settings_.fine_window, "fine_window"},
                                   {settings.medium_cell == settings_.medium_cell, "medium_cell"}})
    if (!same)
      throw std::invalid_argument(std::string("GlobalAlignment::withSearchSettings: ") + name +
                                  " shapes the target and must equal this aligner's");
  GlobalAlignment other(std::move(settings));
  other.target_ = target_;
  return other;
}

GlobalAlignmentResult GlobalAlignment::align(const Cloud& source_cloud, const Eigen::Vector3d& source_up_axis) const {
  return align(source_cloud, source_up_axis, settings_.up_axis, settings_.tilt_range_deg);
}

GlobalAlignmentResult GlobalAlignment::align(const Cloud& source_cloud, const Eigen::Vector3d& source_up_axis,
                                             const Eigen::Vector3d& up_axis, double tilt_range_deg) const {
  if (target_->points.empty()) throw std::invalid_argument("GlobalAlignment::align: no target set");
  checkAlignArguments(source_up_axis, up_axis, tilt_range_deg, settings_.tilt_step_deg);
  const auto start = std::chrono::steady_clock::now();
  Points source = finitePoints(source_cloud, "source");
  GlobalAlignmentResult result =
      settings_.reverse_larger_source &&
              searchesReversed(voxelFirsts(source, sampleCell(settings_)).size(), target_->voxels, settings_)
          ? alignReversed(source, source_up_axis, up_axis, tilt_range_deg)
          : alignAsGiven(std::move(source), source_up_axis, up_axis, tilt_range_deg);
  result.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

GlobalAlignmentResult GlobalAlignment::alignReversed(const std::vector<Eigen::Vector3f>& source,
                                                     const Eigen::Vector3d& source_up_axis,
                                                     const Eigen::Vector3d& up_axis, double tilt_range_deg) const {
  GlobalAlignment reversed(settings_);
  reversed.setTarget(toCloud(source));
  const Eigen::Vector3d source_up = source_up_axis.norm() > 0.0 ? source_up_axis : up_axis;
  GlobalAlignmentResult result = reversed.align(toCloud(target_->points), up_axis, source_up, tilt_range_deg);
  result.transformation = inverseRigid(result.transformation);
  // The inlier figures the caller's way: of the source's points, against this target.
  result.target_spacing = target_->spacing;
  result.inlier_distance = inlierDistance(settings_, target_->spacing);
  const Inliers inliers = countInliers(source, *target_, result.transformation, result.inlier_distance);
  result.inliers = inliers.count;
  result.inlier_score = inliers.score;
  result.inlier_fraction = static_cast<double>(inliers.count) / static_cast<double>(source.size());
  result.reversed = true;
  return result;
}

GlobalAlignmentResult GlobalAlignment::alignAsGiven(std::vector<Eigen::Vector3f> source,
                                                    const Eigen::Vector3d& source_up_axis,
                                                    const Eigen::Vector3d& up_axis, double tilt_range_deg) const {
  const GlobalAlignmentSettings& s = settings_;
  // The source levelled: its own up axis turned onto the target's, so one axis serves both.
  const Eigen::Vector3d axis = up_axis.normalized();
  const Eigen::Matrix3d level = levellingRotation(source_up_axis, axis);
  for (auto& p : source) p = (level * p.cast<double>()).cast<float>();
  const double spacing = target_->spacing;
  const double min_distance = minDistance(s, spacing);
  const double inlier_distance = inlierDistance(s, spacing);
  const Points sample = voxelSample(source, sampleCell(s), s.max_source_samples);

  // 1. Rotations about the up axis, each with its voted translations.
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
  for (const auto& p : sample) centroid += p;
  centroid /= static_cast<float>(sample.size());
  const std::vector<Hypothesis> hypotheses =
      voteRotations(sample, centroid, *target_, axis, s, *pool_, threadsFor(s.yaw_hypotheses));

  // 2. The best-voted hypotheses, each searched finely around, refined with the tight pass on every source
  // point and ranked by inlier score.
  const Search search =
      searchFor(sample, source, *target_, axis, centroid.cast<double>(), s, min_distance, inlier_distance);
  const std::size_t refined = std::min<std::size_t>(hypotheses.size(), s.refined_hypotheses);
  const std::vector<Refined> results = refineBestVoted(search, hypotheses, refined, *pool_, threadsFor(refined));
  // 2a. The best of them searched again from where they ended while their inlier score grows. The tilts below start
  // from the results as refined: starting them from the climbed ones was as good over the sweeps but not case for
  // case (docs/global_alignment.md, "The climb").
  Refined best =
      bestClimbed(search, results, s.climbed_hypotheses, s.climb_rounds, *pool_, threadsFor(s.climbed_hypotheses));
  // 2b. Tilts, when the up axes may disagree by a few degrees (each estimated from its map's cameras).
  if (tilt_range_deg > 0.0)
    best = bestTilted(search, results, best, tilt_range_deg, s, *pool_,
                      threadsFor(std::numeric_limits<std::size_t>::max()));

  // 3. The winner refined on every source point, from where it is and tilted a little about the part of the source
  // that overlaps the target (a tilt about a centre away from it would move that part out of the ICP's reach).
  const Eigen::Vector3d pivot = best.inliers.count > 0 ? best.inliers.centroid : centroid.cast<double>();
  GlobalAlignmentResult result = finishTilted(source, best.transformation, 2.0 * s.fine_cell, axis, pivot);
  Eigen::Matrix4d levelling = Eigen::Matrix4d::Identity();
  levelling.topLeftCorner<3, 3>() = level;
  result.transformation = result.transformation * levelling;  // maps the source as given
  result.hypotheses_voted = hypotheses.size();
  result.hypotheses_refined = refined;
  return result;
}

unsigned GlobalAlignment::threadsFor(std::size_t n) const {
  unsigned threads = settings_.threads;
  if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
  return static_cast<unsigned>(std::max<std::size_t>(1, std::min<std::size_t>(threads, n)));
}

GlobalAlignmentResult GlobalAlignment::refine(const Cloud& source_cloud, const Eigen::Matrix4d& guess) const {
  if (target_->points.empty()) throw std::invalid_argument("GlobalAlignment::refine: no target set");
  const Points source = finitePoints(source_cloud, "source");
  const auto start = std::chrono::steady_clock::now();
  GlobalAlignmentResult result =
      finish(source, guess, settings_.initial_distance > 0.0 ? settings_.initial_distance : 2.0 * settings_.vote_cell);
  result.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

GlobalAlignmentResult GlobalAlignment::finishTilted(const Points& source, const Eigen::Matrix4d& start,
                                                    double start_distance, const Eigen::Vector3d& axis,
                                                    const Eigen::Vector3d& pivot) const {
  TiltedFinish best = finishTiltedOnce(source, start, start_distance, axis, pivot);
  // A winner in another basin than the untilted start's (turned from where that one ended by a quarter of a step or
  // more): the tilts about it reach further on (the truth's basin, a few degrees on at a fifth of overlap, is narrow).
  for (unsigned int round = 1; round < settings_.final_tilt_rounds && best.other_basin; ++round) {
    TiltedFinish again = finishTiltedOnce(source, best.result.transformation, start_distance, axis,
                                          best.result.inliers > 0 ? best.inlier_centroid : pivot);
    if (!(again.result.inlier_score > best.result.inlier_score)) break;
    best = std::move(again);
  }
  return best.result;
}

GlobalAlignment::TiltedFinish GlobalAlignment::finishTiltedOnce(const Points& source, const Eigen::Matrix4d& start,
                                                                double start_distance, const Eigen::Vector3d& axis,
                                                                const Eigen::Vector3d& pivot) const {
  const std::vector<Eigen::Matrix4d> tilts =
      tiltGrid(axis, settings_.final_tilt_range_deg, settings_.final_tilt_step_deg, pivot);
  std::vector<GlobalAlignmentResult> finished(tilts.size());
  std::vector<Eigen::Vector3d> centroids(tilts.size());
  pool_->run(finished.size(), 1, threadsFor(finished.size()), [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t k = begin; k < end; ++k)
      finished[k] = finish(source, start * tilts[k], start_distance, &centroids[k]);
  });
  // The untilted start (the grid's centre) wins ties; then the first in grid order, whichever thread finished it.
  const std::size_t centre = finished.size() / 2;
  std::size_t best = centre;
  for (std::size_t k = 0; k < finished.size(); ++k)
    if (k != centre && finished[k].inlier_score > finished[best].inlier_score) best = k;
  const bool other_basin =
      rotationErrorDeg(Eigen::Isometry3d(finished[best].transformation),
                       Eigen::Isometry3d(finished[centre].transformation)) >= settings_.final_tilt_step_deg / 4.0;
  return {std::move(finished[best]), centroids[best], other_basin};
}

GlobalAlignmentResult GlobalAlignment::finish(const Points& source, const Eigen::Matrix4d& start, double start_distance,
                                              Eigen::Vector3d* inlier_centroid) const {
  const GlobalAlignmentSettings& s = settings_;
  const double spacing = target_->spacing;
  const double min_distance = minDistance(s, spacing);
  const double inlier_distance = inlierDistance(s, spacing);
  const TrimmedFit fit =
      trimmedIcp(source, *target_, start, start_distance, min_distance, s.shrink_factor, s.final_iterations);
  GlobalAlignmentResult result;
  result.transformation = fit.transformation;
  const Inliers inliers = countInliers(source, *target_, fit.transformation, inlier_distance);
  result.inliers = inliers.count;
  result.inlier_score = inliers.score;
  if (inlier_centroid) *inlier_centroid = inliers.centroid;
  result.inlier_fraction = static_cast<double>(result.inliers) / static_cast<double>(source.size());
  result.distance_limit = fit.distance_limit;
  result.median_residual = fit.median_residual;
  result.target_spacing = spacing;
  result.inlier_distance = inlier_distance;
  return result;
}

}  // namespace weighted_icp
