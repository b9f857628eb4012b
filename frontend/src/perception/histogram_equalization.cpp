// The equalisation methods a frame with too few corners can get: CLAHE, the paper's global one, or none.
#include "weighted_icp/frontend/perception/histogram_equalization.h"

#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "weighted_icp/core/named_values.h"

namespace weighted_icp::frontend {

std::string toString(EqualizationMethod method) {
  switch (method) {
    case EqualizationMethod::Clahe: return "clahe";
    case EqualizationMethod::Global: return "global";
    case EqualizationMethod::None: return "none";
  }
  return "unknown";
}

EqualizationMethod parseEqualizationMethod(const std::string& name) {
  return parseNamedValue(
      name, {EqualizationMethod::Clahe, EqualizationMethod::Global, EqualizationMethod::None},
      [](auto value) { return toString(value); }, "equalisation");
}

cv::Mat equalizeHistogram(const cv::Mat& gray, EqualizationMethod method, const ClaheOptions& clahe) {
  if (gray.empty()) throw std::invalid_argument("equalizeHistogram: empty image");
  if (gray.type() != CV_8UC1)
    throw std::invalid_argument("equalizeHistogram: needs an 8-bit single-channel image, got type " +
                                cv::typeToString(gray.type()));
  switch (method) {
    case EqualizationMethod::Clahe: return equalizeClahe(gray, clahe);
    case EqualizationMethod::Global: {
      cv::Mat equalized;
      cv::equalizeHist(gray, equalized);
      return equalized;
    }
    case EqualizationMethod::None: return gray;
  }
  return gray;
}

}  // namespace weighted_icp::frontend
