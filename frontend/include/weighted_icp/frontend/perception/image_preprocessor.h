#pragma once
// Contrast-limited adaptive histogram equalisation (CLAHE) for poorly lit
// frames: it stretches local contrast so that a dark image yields corners
// again, while the clip limit keeps sensor noise from being amplified.

#include <opencv2/core.hpp>

namespace weighted_icp::frontend {

struct ClaheOptions {
  double clip_limit = 3.0;  // histogram clip per tile, in multiples of the mean bin
  int tile_grid = 8;        // tiles per image side
};

/// CLAHE of a CV_8UC1 image; same size and type. Throws std::invalid_argument
/// for an empty image, another type, clip_limit <= 0 or tile_grid < 1.
cv::Mat equalizeClahe(const cv::Mat& gray, const ClaheOptions& options = {});

}  // namespace weighted_icp::frontend
