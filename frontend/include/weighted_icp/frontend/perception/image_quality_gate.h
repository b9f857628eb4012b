#pragma once
// No-reference image quality (BRISQUE, OpenCV contrib's quality module) to
// keep blurred or noisy frames out of tracking. OpenCV's scale runs from 0
// (best) to 100 (worst).

#include <string>

#include <opencv2/core.hpp>
#include <opencv2/ml.hpp>

namespace weighted_icp::frontend {

struct ImageQualityGateOptions {
  // Tuned on the real TUM frames: all 37 of fr1/xyz head score 8.0 to 44.0
  // (44.0 is a visibly motion-blurred frame) and all 200 of fr3/teddy head
  // 4.8 to 38.9. Degraded copies of frames 0 and 10 of each score higher: Gaussian
  // blur sigma 1.5 48.4 to 58.8, sigma 3 66.6 to 71.4, noise sigma 15 49.6 to
  // 53.7, blur sigma 3 plus that noise 50.0 to 54.2. 47 passes every real
  // frame and rejects every degraded one; the margins are small both ways
  // (3 and 1.4), as BRISQUE's scale, trained on LIVE photographs, does not
  // separate these wider. Score dark frames after CLAHE: darkening to 0.2x
  // lifts a frame to 50 to 59, equalising brings it back to 24 to 26.
  double max_brisque_score = 47.0;
  // Holds brisque_model_live.yml and brisque_range_live.yml (Debian: opencv-data).
  std::string model_dir = "/usr/share/opencv4/quality";
};

class ImageQualityGate {
 public:
  /// Loads the BRISQUE model once. Throws std::runtime_error naming a model
  /// file that is missing or unreadable.
  explicit ImageQualityGate(ImageQualityGateOptions options = {});

  /// BRISQUE score of an 8-bit gray, BGR or BGRA image (lower is better).
  /// Throws std::invalid_argument for an empty image or another type.
  /// About 25 ms on a 640x480 frame here: too slow for every frame within a
  /// 33 ms tracking budget, so gate keyframe candidates or run it aside.
  double score(const cv::Mat& image) const;
  /// score(image) <= max_brisque_score.
  bool accept(const cv::Mat& image) const;

  const ImageQualityGateOptions& options() const { return options_; }

 private:
  ImageQualityGateOptions options_;
  cv::Ptr<cv::ml::SVM> model_;
  cv::Mat range_;
};

}  // namespace weighted_icp::frontend
