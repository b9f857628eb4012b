// matchInRegionsOfInterest: a grid over the predicted pixels, Hamming search in the cells around each feature.

#include "weighted_icp/frontend/perception/roi_matcher.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

#include "weighted_icp/core/binary_descriptor.h"
#include "weighted_icp/core/named_values.h"
#include "weighted_icp/frontend/perception/descriptor_matcher.h"

namespace weighted_icp::frontend {
namespace {

void check(const cv::Mat& query, const std::vector<Eigen::Vector2d>& query_pixels, const cv::Mat& reference,
           const std::vector<Eigen::Vector2d>& predicted, const RoiMatchOptions& o) {
  const auto fail = [](const std::string& what) { throw std::invalid_argument("matchInRegionsOfInterest: " + what); };
  if (!(o.radius_px > 0.0) || !std::isfinite(o.radius_px)) fail("radius_px must be > 0");
  if (!(o.ratio > 0.0f && o.ratio <= 1.0f)) fail("ratio must be in (0, 1]");
  if (o.max_hamming_distance < 0) fail("max_hamming_distance must be >= 0");
  if ((!query.empty() && query.type() != CV_8UC1) || (!reference.empty() && reference.type() != CV_8UC1))
    fail("descriptors must be CV_8UC1");
  if (static_cast<std::size_t>(query.rows) != query_pixels.size())
    fail(std::to_string(query.rows) + " query rows but " + std::to_string(query_pixels.size()) + " pixels");
  if (static_cast<std::size_t>(reference.rows) != predicted.size())
    fail(std::to_string(reference.rows) + " reference rows but " + std::to_string(predicted.size()) + " predictions");
  if (!query.empty() && !reference.empty() && query.cols != reference.cols)
    fail("query rows have " + std::to_string(query.cols) + " bytes, reference rows " + std::to_string(reference.cols));
}

/// Reference rows bucketed by predicted pixel in square cells of the radius, over the features' extent widened by the
/// radius: a prediction outside it is farther than the radius from every feature and cannot match (a map point
/// almost in the camera's plane projects millions of pixels away; bucketing it would size the grid by it).
struct PredictionGrid {
  double cell;
  int x0 = 0, y0 = 0, cols = 0, rows = 0;
  std::vector<std::vector<int>> buckets;

  PredictionGrid(const std::vector<Eigen::Vector2d>& predicted, const std::vector<Eigen::Vector2d>& query_pixels,
                 double radius)
      : cell(radius) {
    Eigen::AlignedBox2d features;
    for (const Eigen::Vector2d& p : query_pixels)
      if (p.allFinite()) features.extend(p);
    if (features.isEmpty()) return;
    const Eigen::AlignedBox2d reach(features.min().array() - radius, features.max().array() + radius);
    x0 = static_cast<int>(std::floor(reach.min().x() / cell));
    y0 = static_cast<int>(std::floor(reach.min().y() / cell));
    cols = static_cast<int>(std::floor(reach.max().x() / cell)) - x0 + 1;
    rows = static_cast<int>(std::floor(reach.max().y() / cell)) - y0 + 1;
    if (static_cast<double>(cols) * rows > 4e6)
      throw std::invalid_argument("matchInRegionsOfInterest: radius too small for the spread of the query pixels");
    buckets.resize(static_cast<std::size_t>(cols) * rows);
    for (std::size_t i = 0; i < predicted.size(); ++i)
      if (predicted[i].allFinite() && reach.contains(predicted[i]))
        buckets[index(cellX(predicted[i].x()), cellY(predicted[i].y()))].push_back(static_cast<int>(i));
  }
  int cellX(double x) const { return static_cast<int>(std::floor(x / cell)) - x0; }
  int cellY(double y) const { return static_cast<int>(std::floor(y / cell)) - y0; }
  std::size_t index(int cx, int cy) const { return static_cast<std::size_t>(cy) * cols + cx; }
};

}  // namespace

MatchRegion parseMatchRegion(const std::string& name) {
  return parseNamedValue(name, {MatchRegion::Everywhere, MatchRegion::Projection, MatchRegion::Homography},
                         matchRegionName, "match region");
}

std::string matchRegionName(MatchRegion region) {
  switch (region) {
    case MatchRegion::Everywhere: return "everywhere";
    case MatchRegion::Projection: return "projection";
    case MatchRegion::Homography: return "homography";
  }
  return "unknown";
}

std::vector<cv::DMatch> matchInRegionsOfInterest(const cv::Mat& query, const std::vector<Eigen::Vector2d>& query_pixels,
                                                 const cv::Mat& reference,
                                                 const std::vector<Eigen::Vector2d>& predicted,
                                                 const RoiMatchOptions& options) {
  check(query, query_pixels, reference, predicted, options);
  if (query.empty() || reference.empty()) return {};
  const PredictionGrid grid(predicted, query_pixels, options.radius_px);
  if (grid.cols == 0) return {};
  const double radius_sq = options.radius_px * options.radius_px;
  std::vector<cv::DMatch> matches;
  for (int q = 0; q < query.rows; ++q) {
    const Eigen::Vector2d& pixel = query_pixels[static_cast<std::size_t>(q)];
    if (!pixel.allFinite()) continue;
    const int cx = grid.cellX(pixel.x()), cy = grid.cellY(pixel.y());
    int best = -1, best_d = 1 << 30, second_d = 1 << 30;
    for (int y = std::max(0, cy - 1); y <= std::min(grid.rows - 1, cy + 1); ++y)
      for (int x = std::max(0, cx - 1); x <= std::min(grid.cols - 1, cx + 1); ++x)
        for (const int r : grid.buckets[grid.index(x, y)]) {
          if ((predicted[static_cast<std::size_t>(r)] - pixel).squaredNorm() > radius_sq) continue;
          const int d = hammingDistance(query.ptr<std::uint8_t>(q), reference.ptr<std::uint8_t>(r), query.cols);
          // Rows are visited in bucket order; ties go to the smaller row index.
          if (d < best_d || (d == best_d && r < best)) {
            second_d = best_d;
            best_d = d;
            best = r;
          } else if (d < second_d) {
            second_d = d;
          }
        }
    if (best < 0 || best_d > options.max_hamming_distance) continue;
    if (second_d < (1 << 30) && !(best_d < options.ratio * second_d)) continue;
    matches.emplace_back(q, best, static_cast<float>(best_d));
  }
  if (!options.cross_check_unique) return matches;
  return keepBestMatchPerReference(matches, reference.rows);
}

}  // namespace weighted_icp::frontend
