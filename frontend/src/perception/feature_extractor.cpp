#include "weighted_icp/frontend/perception/feature_extractor.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>

#include <opencv2/imgproc.hpp>

#include "weighted_icp/core/parallel_for.h"

namespace weighted_icp::frontend {
namespace {

constexpr int kOrbPatchSize = 31;
constexpr int kOrbHalfPatch = kOrbPatchSize / 2;
// ORB describes keypoints at least its edgeThreshold from the border; corners
// are only sought inside that margin so that none is detected in vain.
constexpr int kOrbBorder = kOrbPatchSize;
constexpr double kMaxSubpixelShift = 0.5;  // pixels

void requireOption(bool valid, const std::string& what) {
  if (!valid) throw std::invalid_argument("FeatureExtractor: " + what);
}

void validate(const FeatureExtractorOptions& o) {
  requireOption(o.max_features >= 1, "max_features must be >= 1");
  requireOption(o.grid_cols >= 1 && o.grid_rows >= 1, "grid_cols and grid_rows must be >= 1");
  requireOption(o.quality_level > 0.0 && o.quality_level < 1.0, "quality_level must be in (0, 1)");
  requireOption(o.min_distance_px >= 0.0, "min_distance_px must be >= 0");
  requireOption(o.min_features_before_clahe >= 0, "min_features_before_clahe must be >= 0");
  requireOption(o.clahe.clip_limit > 0.0 && o.clahe.tile_grid >= 1, "clahe needs clip_limit > 0 and tile_grid >= 1");
  requireOption(o.min_corner_response >= 0.0, "min_corner_response must be >= 0");
  requireOption(o.max_working_width == 0 || o.max_working_width >= 64,
                "max_working_width must be 0 (the input's size) or >= 64 pixels");
  requireOption(o.min_working_width >= 0 && o.min_working_width <= 100000,
                "min_working_width must be 0 (the input's size) to 100000 pixels");
  requireOption(o.min_working_width == 0 || o.max_working_width == 0 || 2 * o.min_working_width <= o.max_working_width,
                "min_working_width must be at most half max_working_width (a width between them is reached by "
                "halving or doubling)");
  requireOption(
      std::isfinite(o.smoothing_sigma) && o.smoothing_sigma >= 0.0 &&
          o.smoothing_sigma <= FeatureExtractorOptions::kMaxSmoothingSigma,
      cv::format("smoothing_sigma must be 0 (no blur) to %g pixels", FeatureExtractorOptions::kMaxSmoothingSigma));
}

/// ORB's orientation (Rublee et al. 2011): the direction from the keypoint to
/// the intensity centroid of the circular patch the descriptor samples.
/// cv::ORB computes it only for keypoints it detects itself; without it the
/// descriptors would be unrotated BRIEF.
void assignOrientation(const cv::Mat& image, std::vector<cv::KeyPoint>& keypoints) {
  // The disc as cv::circle rasterises it, one span of columns per row: the
  // sums below are then exactly cv::moments of the masked patch (integers),
  // without a masked copy and a general moments pass per keypoint (issue #11:
  // that pair was about 3 % of the tracking time).
  static const std::vector<std::pair<int, int>> spans = [] {
    cv::Mat mask = cv::Mat::zeros(kOrbPatchSize, kOrbPatchSize, CV_8U);
    cv::circle(mask, {kOrbHalfPatch, kOrbHalfPatch}, kOrbHalfPatch, 255, cv::FILLED);
    std::vector<std::pair<int, int>> rows(kOrbPatchSize, {0, -1});
    for (int y = 0; y < kOrbPatchSize; ++y)
      for (int x = 0; x < kOrbPatchSize; ++x)
        if (mask.at<std::uint8_t>(y, x)) rows[y] = {rows[y].second < 0 ? x : rows[y].first, x};
    return rows;
  }();
  for (cv::KeyPoint& keypoint : keypoints) {
    const int left = cvRound(keypoint.pt.x) - kOrbHalfPatch, top = cvRound(keypoint.pt.y) - kOrbHalfPatch;
    std::int64_t m00 = 0, m10 = 0, m01 = 0;
    for (int y = 0; y < kOrbPatchSize; ++y) {
      const std::uint8_t* row = image.ptr<std::uint8_t>(top + y) + left;
      std::int64_t row_sum = 0, row_x = 0;
      for (int x = spans[y].first; x <= spans[y].second; ++x) {
        row_sum += row[x];
        row_x += static_cast<std::int64_t>(x) * row[x];
      }
      m00 += row_sum;
      m10 += row_x;
      m01 += static_cast<std::int64_t>(y) * row_sum;
    }
    const double d00 = static_cast<double>(m00);
    keypoint.angle = cv::fastAtan2(static_cast<float>(static_cast<double>(m01) - kOrbHalfPatch * d00),
                                   static_cast<float>(static_cast<double>(m10) - kOrbHalfPatch * d00));
  }
}

/// How much a Gaussian blur of `sigma` pixels lowers corner responses: a response is a squared gradient, and the
/// Sobel derivative already smooths across by [1 2 1] / 4 (variance 0.5), so an edge's gradient falls by
/// sqrt(0.5 / (0.5 + sigma^2)) and its response by the square. The response floor follows (as it does for a doubled
/// frame): without it the floor cut a quarter of a clean frame's corners at sigma 1 (fr3: 646 -> 483; 612 with it).
double smoothedResponseScale(double sigma) {
  constexpr double kSobelSmoothingVariance = 0.5;
  return kSobelSmoothingVariance / (kSobelSmoothingVariance + sigma * sigma);
}

/// A GFTT corner with its response and the grid cell it was found in.
struct Corner {
  cv::Point2f pt;
  float response;
  int cell;
};

/// GFTT in each cell of the grid over interior on its own, so that quality_level is relative to the cell's strongest
/// corner: weakly textured parts of the frame keep their corners instead of losing them to one bright, busy region.
/// Strongest first over the whole frame; ties in the order found (cells in order), whatever the number of threads.
std::vector<Corner> cornersPerCell(const cv::Mat& gray, const cv::Rect& interior, const FeatureExtractorOptions& o) {
  // The cells on OpenCV's thread pool, each into its own list, joined in cell order.
  const int cells = o.grid_rows * o.grid_cols;
  std::vector<std::vector<Corner>> found(static_cast<std::size_t>(cells));
  parallelFor(cv::Range(0, cells), [&](const cv::Range& range) {
    std::vector<cv::Point2f> corners;
    std::vector<float> responses;
    for (int cell = range.start; cell < range.end; ++cell) {
      const int row = cell / o.grid_cols, col = cell % o.grid_cols;
      const int x0 = interior.x + col * interior.width / o.grid_cols;
      const int y0 = interior.y + row * interior.height / o.grid_rows;
      const int x1 = interior.x + (col + 1) * interior.width / o.grid_cols;
      const int y1 = interior.y + (row + 1) * interior.height / o.grid_rows;
      if (x1 <= x0 || y1 <= y0) continue;
      // Pixels outside the cell still feed its gradients (no isolated border).
      cv::goodFeaturesToTrack(gray(cv::Rect(x0, y0, x1 - x0, y1 - y0)), corners, 0, o.quality_level, o.min_distance_px,
                              cv::noArray(), responses);
      for (std::size_t i = 0; i < corners.size() && responses[i] >= o.min_corner_response; ++i)
        found[static_cast<std::size_t>(cell)].push_back(
            {corners[i] + cv::Point2f(static_cast<float>(x0), static_cast<float>(y0)), responses[i], cell});
    }
  });
  std::vector<Corner> candidates;
  for (const auto& in_cell : found) candidates.insert(candidates.end(), in_cell.begin(), in_cell.end());
  // Stable: the result does not depend on the sort implementation.
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Corner& a, const Corner& b) { return a.response > b.response; });
  return candidates;
}

/// Up to max_features of the candidates (strongest first), at least min_distance_px apart across cell borders too
/// (GFTT keeps it within a cell only): first up to an equal share per cell, then the budget weak cells left goes to
/// the strongest corners not yet taken. Returned in the candidates' order.
std::vector<Corner> spreadCorners(const std::vector<Corner>& candidates, const cv::Size& image,
                                  const FeatureExtractorOptions& o) {
  // An occupancy grid with bins of min_distance_px: a corner is compared with those in the 3x3 bins around it.
  const double min_distance_sq = o.min_distance_px * o.min_distance_px;
  const int bin = std::max(1, static_cast<int>(std::ceil(o.min_distance_px)));
  const int bins_x = image.width / bin + 1, bins_y = image.height / bin + 1;
  std::vector<std::vector<cv::Point2f>> occupied(static_cast<std::size_t>(bins_x * bins_y));
  const auto farFromTaken = [&](const cv::Point2f& p) {
    const int bx = static_cast<int>(p.x) / bin, by = static_cast<int>(p.y) / bin;
    for (int y = std::max(0, by - 1); y <= std::min(bins_y - 1, by + 1); ++y)
      for (int x = std::max(0, bx - 1); x <= std::min(bins_x - 1, bx + 1); ++x)
        for (const cv::Point2f& q : occupied[static_cast<std::size_t>(y * bins_x + x)])
          if ((p.x - q.x) * (p.x - q.x) + (p.y - q.y) * (p.y - q.y) < min_distance_sq) return false;
    return true;
  };
  std::vector<bool> taken(candidates.size(), false);
  int total = 0;
  const auto take = [&](std::size_t i) {
    const cv::Point2f& p = candidates[i].pt;
    occupied[static_cast<std::size_t>(static_cast<int>(p.y) / bin * bins_x + static_cast<int>(p.x) / bin)].push_back(p);
    taken[i] = true;
    ++total;
  };
  const int per_cell = o.max_features / (o.grid_cols * o.grid_rows);
  std::vector<int> taken_in_cell(static_cast<std::size_t>(o.grid_cols * o.grid_rows), 0);
  for (std::size_t i = 0; i < candidates.size() && total < o.max_features; ++i) {
    int& in_cell = taken_in_cell[static_cast<std::size_t>(candidates[i].cell)];
    if (in_cell < per_cell && farFromTaken(candidates[i].pt)) {
      ++in_cell;
      take(i);
    }
  }
  for (std::size_t i = 0; i < candidates.size() && total < o.max_features; ++i)
    if (!taken[i] && farFromTaken(candidates[i].pt)) take(i);
  std::vector<Corner> spread;
  for (std::size_t i = 0; i < candidates.size(); ++i)
    if (taken[i]) spread.push_back(candidates[i]);
  return spread;
}

/// Each corner refined to a fraction of a pixel (on its own, so in chunks on the thread pool with the same result).
/// A corner refinement would move further than kMaxSubpixelShift is not a clean corner and keeps its detected
/// position, so the minimum distance holds to within 2 x kMaxSubpixelShift.
void refineToSubpixel(const cv::Mat& gray, std::vector<cv::Point2f>& points) {
  if (points.empty()) return;
  std::vector<cv::Point2f> refined = points;
  constexpr int kChunk = 64;
  const int chunks = (static_cast<int>(refined.size()) + kChunk - 1) / kChunk;
  parallelFor(cv::Range(0, chunks), [&](const cv::Range& range) {
    for (int chunk = range.start; chunk < range.end; ++chunk) {
      const auto first = refined.begin() + chunk * kChunk;
      const auto last = refined.begin() + std::min<std::ptrdiff_t>((chunk + 1) * kChunk, refined.size());
      std::vector<cv::Point2f> part(first, last);
      cv::cornerSubPix(gray, part, cv::Size(3, 3), cv::Size(-1, -1),
                       cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 10, 0.01));
      std::copy(part.begin(), part.end(), first);
    }
  });
  for (std::size_t i = 0; i < points.size(); ++i)
    if (cv::norm(refined[i] - points[i]) <= kMaxSubpixelShift) points[i] = refined[i];
}

}  // namespace

FeatureExtractor::FeatureExtractor(FeatureExtractorOptions options) : options_(options) {
  validate(options_);
  // One pyramid level: GFTT corners are single-scale.
  orb_ = cv::ORB::create(options_.max_features, 1.2f, 1, kOrbBorder, 0, 2, cv::ORB::HARRIS_SCORE, kOrbPatchSize);
}

std::vector<cv::KeyPoint> FeatureExtractor::detectBucketed(const cv::Mat& gray, double response_scale) const {
  const cv::Rect interior(kOrbBorder, kOrbBorder, gray.cols - 2 * kOrbBorder, gray.rows - 2 * kOrbBorder);
  if (interior.width <= 0 || interior.height <= 0) return {};
  FeatureExtractorOptions options = options_;
  options.min_corner_response *= response_scale;
  const std::vector<Corner> spread = spreadCorners(cornersPerCell(gray, interior, options), gray.size(), options);
  std::vector<cv::Point2f> points;
  points.reserve(spread.size());
  for (const Corner& corner : spread) points.push_back(corner.pt);
  if (options_.subpixel) refineToSubpixel(gray, points);
  std::vector<cv::KeyPoint> keypoints;
  keypoints.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    keypoints.emplace_back(points[i], static_cast<float>(kOrbPatchSize), -1.0f, spread[i].response);
  return keypoints;
}

int FeatureExtractor::workingWidth(int width) const {
  if (width < 1) throw std::invalid_argument("FeatureExtractor::workingWidth: width must be >= 1");
  const int min_width = options_.min_working_width, max_width = options_.max_working_width;
  while (min_width > 0 && width < min_width) width *= 2;
  while (max_width > 0 && width > max_width && width >= 2) width /= 2;
  return width;
}

ExtractedFeatures FeatureExtractor::extract(const cv::Mat& gray) const {
  if (gray.empty()) throw std::invalid_argument("FeatureExtractor::extract: empty image");
  if (gray.type() != CV_8UC1)
    throw std::invalid_argument("FeatureExtractor::extract: needs an 8-bit single-channel image, got type " +
                                cv::typeToString(gray.type()));
  const int working_width = workingWidth(gray.cols);
  if (working_width == gray.cols) return extractAtWorkingSize(gray);
  cv::Mat working = gray;
  // Enlarged bilinearly: no detail made up, none lost, but every gradient halved, so each corner's response (the
  // gradient matrix's smaller eigenvalue) quartered: the response floor follows, or the corners of a 640x480 frame
  // would not be found in a 320x240 one's enlargement (and the frames would hover at the equalisation threshold).
  double response_scale = 1.0;
  while (working.cols < working_width) {
    cv::resize(working, working, cv::Size(working.cols * 2, working.rows * 2), 0.0, 0.0, cv::INTER_LINEAR);
    response_scale *= 0.25;
  }
  while (working.cols > working_width && working.rows >= 2)
    cv::resize(working, working, cv::Size(working.cols / 2, working.rows / 2), 0.0, 0.0, cv::INTER_AREA);
  ExtractedFeatures features = extractAtWorkingSize(working, response_scale);
  // Working pixel u spans input pixels [u s, (u + 1) s): its centre is (u + 0.5) s - 0.5.
  const float sx = static_cast<float>(gray.cols) / static_cast<float>(working.cols);
  const float sy = static_cast<float>(gray.rows) / static_cast<float>(working.rows);
  for (cv::KeyPoint& keypoint : features.keypoints) {
    keypoint.pt.x = (keypoint.pt.x + 0.5f) * sx - 0.5f;
    keypoint.pt.y = (keypoint.pt.y + 0.5f) * sy - 0.5f;
    keypoint.size *= sx;
  }
  return features;
}

ExtractedFeatures FeatureExtractor::extractAtWorkingSize(const cv::Mat& frame, double response_scale) const {
  ExtractedFeatures features;
  // The frame blurred (into an image of its own: the caller's stays as it is), the corners then found, refined and
  // described there; the response floor lowered as much as the blur lowers an edge's response.
  cv::Mat gray = frame;
  if (options_.smoothing_sigma > 0.0) {
    gray = cv::Mat();
    cv::GaussianBlur(frame, gray, cv::Size(0, 0), options_.smoothing_sigma);
    response_scale *= smoothedResponseScale(options_.smoothing_sigma);
  }
  cv::Mat image = gray;
  features.keypoints = detectBucketed(image, response_scale);
  if (options_.equalization != EqualizationMethod::None &&
      static_cast<int>(features.keypoints.size()) < options_.min_features_before_clahe) {
    image = equalizeHistogram(gray, options_.equalization, options_.clahe);
    features.keypoints = detectBucketed(image, response_scale);
    features.used_clahe = true;
  }
  // Equalisation finds corners; descriptors compare with the map's, so by default they see the frame as it is.
  if (!options_.describe_equalized) image = gray;
  assignOrientation(image, features.keypoints);
  // Feature2D::compute removes the keypoints it cannot describe, so the rows
  // stay aligned with the keypoints that remain.
  if (options_.descriptor == DescriptorKind::ModifiedBrief)
    computeModifiedBrief(image, features.keypoints, features.descriptors);
  else
    orb_->compute(image, features.keypoints, features.descriptors);
  if (features.descriptors.empty()) features.descriptors.create(0, orb_->descriptorSize(), CV_8U);
  return features;
}

}  // namespace weighted_icp::frontend
