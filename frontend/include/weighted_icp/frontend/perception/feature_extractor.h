#pragma once
// Corner features for RGB-D tracking: Shi-Tomasi (GFTT) corners spread over a
// grid, described by ORB's rotated BRIEF. Poorly lit frames are equalised
// (CLAHE) and detected again when too few corners are found.

#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "weighted_icp/frontend/perception/histogram_equalization.h"
#include "weighted_icp/frontend/perception/image_preprocessor.h"
#include "weighted_icp/frontend/perception/modified_brief.h"

namespace weighted_icp::frontend {

struct FeatureExtractorOptions {
  int max_features = 1000;
  int grid_cols = 8;            // buckets across the image ...
  int grid_rows = 6;            // ... and down it
  double quality_level = 0.01;  // GFTT: corner response relative to the frame's strongest
  double min_distance_px = 8.0;
  int min_features_before_clahe = 300;
  ClaheOptions clahe;
  // Smallest accepted corner response (the smaller eigenvalue of the gradient
  // matrix, on cv::cornerMinEigenVal's scale). quality_level alone is
  // relative, so a dark frame would yield as many corners as a bright one,
  // most of them noise, and never reach CLAHE. On TUM fr1/fr3 frame pairs five
  // frames apart, corners below 1e-4 led to a ground-truth-verified match for
  // under 5 % of them (from 1e-4 to 2e-4: 8 %, above 8e-4: 24 to 45 %).
  double min_corner_response = 1e-4;
  /// Refine corners to sub-pixel accuracy (cv::cornerSubPix, shifts up to
  /// 0.5 px): GFTT returns whole pixels, whose rounding alone is 0.3 px of
  /// noise on every pose. min_distance_px then holds to within 1 px.
  bool subpixel = true;
  /// ORB's rotated BRIEF, or the front-end paper's modified BRIEF (Eq. 7);
  /// both 32 bytes per row, steered by the same intensity-centroid angle.
  DescriptorKind descriptor = DescriptorKind::Orb;
  /// How a frame with fewer than min_features_before_clahe corners is equalised before detecting again.
  EqualizationMethod equalization = EqualizationMethod::Clahe;
  /// Describe the corners found on an equalised frame in the equalised image (true: before 2026-11-26) or in the
  /// frame as it is (false). CLAHE maps each tile by its own histogram, which changes with the view: descriptors of
  /// the same corner then differ from frame to frame and from the map's, built mostly from frames not equalised.
  /// Over sequences where equalisation triggers (fr3 blurred, with bursts, made dark; fr1 made dark), describing the
  /// frame as it is cut the worst ATE from 3.87 to 0.92 cm (docs/frontend_generalisation.md).
  bool describe_equalized = false;
  /// Images wider than this are halved (pixel areas averaged) until they are not, the features found and described
  /// there and their keypoints given in the input image's pixels: a 1280x960 sensor's frame is worked on at 640x480,
  /// the scale every other option was chosen at (the corner spacing, ORB's 31-pixel patch, the response floor);
  /// any width then works within a factor 1.5 of 640. 0: always the input image's size (before 2026-11-27). On
  /// 1280x960 variants of fr1, fr3 and the synthetic room (plain, JPEG, blurred, dark, unregistered half-resolution
  /// depth) it cut fr3 dark from 3.8 to 1.2 cm and fr3 blurred from 2.0 to 1.0 cm, fr1's rows by 0.05-0.13 cm, and
  /// the median time by a third; the synthetic rows lost 0.01-0.03 cm (docs/frontend_generalisation.md).
  int max_working_width = 960;
  /// Images narrower than this are doubled (bilinear) until they are not, alike: a 320x240 sensor's frame is worked
  /// on at 640x480, its 31-pixel ORB border taking 21 % of the image instead of 40 %, and min_corner_response is
  /// quartered per doubling (enlarging halves every gradient). 0: never enlarged (before 2026-11-27, evening). On
  /// 320x240 variants of fr1, fr3 and the synthetic room (plain, Kinect-like, dark; three draws) it cut 8 of the 9
  /// rows (synthetic 0.36 -> 0.14 cm, fr3 Kinect-like 1.91 -> 0.94, fr1 Kinect-like 0.73 -> 0.59) and left fr3 plain
  /// at 1.08 (docs/frontend_generalisation.md). At most max_working_width / 2.
  int min_working_width = 427;
  /// Gaussian sigma, in pixels of the image features are found at (after halving or doubling), of a blur applied
  /// before corners are found, refined and described there (ORB smooths for its tests on top); min_corner_response is
  /// lowered by what the blur takes from an edge's response, 0.5 / (0.5 + sigma^2). Noise and JPEG's blocks make
  /// corners of their own that move from frame to frame: on a real frame compressed twice with its blocks laid
  /// differently, 46 % of the corners found in the blurred views repeat within a pixel against 29 % without. 0: no
  /// blur, the default: at 1 px it lowered the frame-to-frame error on 26 of 31 sequences and helped most in the dark,
  /// but cost the revisits in good light that close loops (docs/frontend_generalisation.md, "Features in a blurred
  /// frame").
  double smoothing_sigma = 0.0;
  /// The largest smoothing_sigma accepted, in pixels: beyond it the corners of a 640-pixel frame blur together.
  static constexpr double kMaxSmoothingSigma = 5.0;
};

struct ExtractedFeatures {
  std::vector<cv::KeyPoint> keypoints;  // angle in degrees, response = GFTT corner response
  cv::Mat descriptors;                  // CV_8U, 32 bytes per row, row i describes keypoints[i]
  bool used_clahe = false;
};

class FeatureExtractor {
 public:
  /// Throws std::invalid_argument for options out of range.
  explicit FeatureExtractor(FeatureExtractorOptions options = {});

  /// Divides the part of the image ORB can describe (31 px from the border)
  /// into grid cells and runs GFTT in each (quality_level relative to the
  /// cell's strongest corner, min_corner_response absolute). Keeps up to
  /// max_features / (grid_cols * grid_rows) of the strongest per cell
  /// (bucketing), fills the budget weak cells leave with the strongest
  /// remaining corners, and keeps min_distance_px across cell borders too.
  /// If fewer than min_features_before_clahe are found, detects again on the
  /// CLAHE-equalised image (used_clahe) and describes the frame as it is
  /// (the equalised image with describe_equalized). Orientation
  /// is the intensity centroid angle, as ORB's own detector computes it, so
  /// the descriptors are rotated BRIEF. Keypoints ORB cannot describe are
  /// dropped with their rows. Deterministic; keypoints come strongest first.
  /// Images wider than max_working_width are worked on halved, narrower than min_working_width doubled (see there);
  /// the keypoints are in `gray`'s pixels.
  /// Throws std::invalid_argument for an empty image or one that is not CV_8UC1.
  ExtractedFeatures extract(const cv::Mat& gray) const;

  const FeatureExtractorOptions& options() const { return options_; }

  /// @brief The width extract() finds features at for a frame `width` pixels wide: doubled while narrower than
  /// min_working_width, halved while wider than max_working_width (either 0: never).
  /// @param width  the frame's width in pixels (>= 1; std::invalid_argument otherwise)
  int workingWidth(int width) const;

 private:
  /// @param response_scale min_corner_response is multiplied by it (1 / 4 per doubling of the frame)
  std::vector<cv::KeyPoint> detectBucketed(const cv::Mat& gray, double response_scale = 1.0) const;
  /// extract() on an image of the working size.
  /// @param response_scale as for detectBucketed
  ExtractedFeatures extractAtWorkingSize(const cv::Mat& gray, double response_scale = 1.0) const;

  FeatureExtractorOptions options_;
  cv::Ptr<cv::ORB> orb_;
};

}  // namespace weighted_icp::frontend
