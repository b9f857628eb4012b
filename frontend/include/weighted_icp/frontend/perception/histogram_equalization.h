#pragma once
// How a frame with too few corners is equalised before features are detected
// again: CLAHE (the default before issue #11), global histogram equalisation
// as the front-end paper describes it, or not at all (for the ablation).

#include <string>

#include <opencv2/core.hpp>

#include "weighted_icp/frontend/perception/image_preprocessor.h"

namespace weighted_icp::frontend {

/// @brief The equalisation applied to a frame with too few corners.
enum class EqualizationMethod {
  /// Contrast-limited adaptive equalisation (tiles, clipped histograms): equalizeClahe().
  Clahe,
  /// The front-end paper (Section 2, step 1, and its pre-processing paragraph): "The histogram
  /// of frames with insufficient features has been equalized", which "distributes the image's
  /// most frequent pixel intensity values": one histogram over the whole grey image
  /// (cv::equalizeHist), no tiles, no clip limit.
  Global,
  /// Never equalise: the frame's corners are what they are.
  None
};

/// @brief "clahe", "global" or "none".
/// @param method the method to name
std::string toString(EqualizationMethod method);
/// @brief The method named by toString; std::invalid_argument listing the names otherwise.
/// @param name the name
EqualizationMethod parseEqualizationMethod(const std::string& name);

/// @brief The equalised image (same size and type); None returns `gray` itself.
/// Throws std::invalid_argument for an empty image or one that is not CV_8UC1.
/// @param gray 8-bit grey image
/// @param method how to equalise
/// @param clahe CLAHE's parameters (Clahe only)
cv::Mat equalizeHistogram(const cv::Mat& gray, EqualizationMethod method, const ClaheOptions& clahe = {});

}  // namespace weighted_icp::frontend
