#include "weighted_icp/frontend/perception/image_preprocessor.h"

#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

namespace weighted_icp::frontend {

cv::Mat equalizeClahe(const cv::Mat& gray, const ClaheOptions& options) {
  if (gray.empty()) throw std::invalid_argument("equalizeClahe: empty image");
  if (gray.type() != CV_8UC1)
    throw std::invalid_argument("equalizeClahe: needs an 8-bit single-channel image, got type " +
                                cv::typeToString(gray.type()));
  if (!(options.clip_limit > 0.0))
    throw std::invalid_argument("equalizeClahe: clip_limit must be > 0, got " + std::to_string(options.clip_limit));
  if (options.tile_grid < 1)
    throw std::invalid_argument("equalizeClahe: tile_grid must be >= 1, got " + std::to_string(options.tile_grid));
  // A fresh CLAHE object per call: cv::CLAHE keeps scratch buffers, so a shared
  // one would not be safe to use from several threads.
  const cv::Ptr<cv::CLAHE> clahe = cv::createCLAHE(options.clip_limit, cv::Size(options.tile_grid, options.tile_grid));
  cv::Mat equalized;
  clahe->apply(gray, equalized);
  return equalized;
}

}  // namespace weighted_icp::frontend
