#pragma once
// Descriptor matching restricted to regions of interest: a query feature is
// compared only with the reference descriptors predicted to appear near it
// (the KD-tree paper's ROI, Sec. 3.2, with the prediction of its Eq. 8 or a
// projection), instead of with every reference descriptor.

#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

namespace weighted_icp::frontend {

/// @brief Where descriptors are searched (issue #11 ablation).
enum class MatchRegion {
  Everywhere,  // the whole reference (DescriptorMatcher), today
  Projection,  // regions of interest around each point's projection with the predicted pose
  Homography   // around the keyframe-to-frame homography's prediction (KD-tree paper, Eq. 8)
};

/// @brief "everywhere", "projection", "homography"; throws std::invalid_argument otherwise.
/// @param name the command-line spelling.
MatchRegion parseMatchRegion(const std::string& name);
/// @brief The name parseMatchRegion reads. @param region the region.
std::string matchRegionName(MatchRegion region);

/// @brief Acceptance rules of matchInRegionsOfInterest (those of DescriptorMatcherOptions).
struct RoiMatchOptions {
  /// A reference row is a candidate for a query feature when its predicted
  /// pixel lies within this distance of the feature.
  double radius_px = 40.0;
  float ratio = 0.9f;              // best < ratio * second best among the candidates
  int max_hamming_distance = 64;   // bits
  bool cross_check_unique = true;  // at most one query per reference: the best
};

/// @brief For each query feature, its nearest candidate reference row.
///
/// The candidates of a query feature are the reference rows whose predicted
/// pixel is within radius_px of it (rows with a non-finite prediction are
/// never candidates). The best candidate is kept if it passes the ratio test
/// against the second best candidate (a lone candidate has no second and
/// passes) and the distance cap; then at most one query per reference row
/// (smallest distance, then smallest query index). Sorted by queryIdx;
/// deterministic. The candidates are found with a grid of radius-sized cells.
/// @param query_descriptors CV_8UC1, one row per query feature.
/// @param query_pixels the pixel of each query row.
/// @param reference_descriptors CV_8UC1 rows of the same length.
/// @param predicted_pixels where each reference row is expected in the query image.
/// @param options acceptance rules; radius_px > 0, ratio in (0, 1], cap >= 0.
/// Throws std::invalid_argument for mismatched sizes, types or options out of range.
std::vector<cv::DMatch> matchInRegionsOfInterest(const cv::Mat& query_descriptors,
                                                 const std::vector<Eigen::Vector2d>& query_pixels,
                                                 const cv::Mat& reference_descriptors,
                                                 const std::vector<Eigen::Vector2d>& predicted_pixels,
                                                 const RoiMatchOptions& options);

}  // namespace weighted_icp::frontend
