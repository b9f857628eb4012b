// The front end's named choices by wicp_rgbd_slam's option names: each key sets its option through the
// library's parser, and a wrong key or value is refused naming it.

#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "weighted_icp/frontend/slam/frontend_choices.h"

namespace {

using namespace weighted_icp::frontend;

TEST(FrontendChoices, EachKeySetsItsOption) {
  FrontendOptions options;
  setFrontendChoice(options, "pnp", "iterative");
  setFrontendChoice(options, "quality-measure", "brisque");
  setFrontendChoice(options, "descriptor", "modified-brief");
  setFrontendChoice(options, "match-region", "homography");
  setFrontendChoice(options, "dynamic-distance", "both");
  setFrontendChoice(options, "equalization", "global");
  setFrontendChoice(options, "dense-odometry", "prior");
  setFrontendChoice(options, "dense-odometry-kind", "icp");
  setFrontendChoice(options, "quality-gate", "absolute");
  setFrontendChoice(options, "matcher", "kd-tree");
  EXPECT_FALSE(options.features.describe_equalized);
  setFrontendChoice(options, "describe", "equalized");
  EXPECT_TRUE(options.features.describe_equalized);
  EXPECT_THROW(setFrontendChoice(options, "describe", "clahe"), std::invalid_argument);
  // Choices of two words: each word sets its value, anything else is refused.
  struct TwoWords {
    const char *key, *off, *on;
    bool FrontendOptions::*flag;
  };
  for (const TwoWords& choice :
       {TwoWords{"gate-free-retry", "off", "on", &FrontendOptions::gate_free_retry},
        TwoWords{"motion-timing", "frame", "period", &FrontendOptions::motion_per_period},
        TwoWords{"keyframe-before-loss", "off", "on", &FrontendOptions::keyframe_before_loss},
        TwoWords{"pnp-thresholds", "frame", "working", &FrontendOptions::pnp_thresholds_in_working_pixels}}) {
    setFrontendChoice(options, choice.key, choice.on);
    EXPECT_TRUE(options.*choice.flag) << choice.key;
    setFrontendChoice(options, choice.key, choice.off);
    EXPECT_FALSE(options.*choice.flag) << choice.key;
    EXPECT_THROW(setFrontendChoice(options, choice.key, "yes"), std::invalid_argument) << choice.key;
  }
  // The PnP prediction's word sets a nested option.
  setFrontendChoice(options, "pnp-prediction", "candidate");
  EXPECT_TRUE(options.pnp.refine_guess);
  EXPECT_EQ(frontendChoiceWord(options, "pnp-prediction"), "candidate");
  setFrontendChoice(options, "pnp-prediction", "start");
  EXPECT_FALSE(options.pnp.refine_guess);
  EXPECT_THROW(setFrontendChoice(options, "pnp-prediction", "guess"), std::invalid_argument);
  EXPECT_TRUE(FrontendOptions{}.gate_free_retry);  // the defaults
  EXPECT_FALSE(FrontendOptions{}.motion_per_period);
  EXPECT_TRUE(FrontendOptions{}.keyframe_before_loss);
  EXPECT_TRUE(FrontendOptions{}.pnp_thresholds_in_working_pixels);
  EXPECT_EQ(options.pnp.method, PnpMethod::Iterative);
  EXPECT_EQ(options.quality.measure, QualityMeasure::Brisque);
  EXPECT_EQ(options.features.descriptor, DescriptorKind::ModifiedBrief);
  EXPECT_EQ(options.match_region, MatchRegion::Homography);
  EXPECT_EQ(options.dynamic_distance, DynamicDistanceKind::Both);
  EXPECT_EQ(options.features.equalization, EqualizationMethod::Global);
  EXPECT_EQ(options.dense_odometry.use, DenseOdometryUse::Prior);
  EXPECT_EQ(options.dense_odometry.kind, DenseOdometryKind::Icp);
  EXPECT_EQ(options.quality.mode, QualityGateMode::Absolute);
  EXPECT_EQ(options.matcher.kind, MatcherKind::KdTree);
  EXPECT_EQ(frontendChoiceKeys().size(), 18u);
  // The widths features are found at: full, or MIN-MAX pixels.
  EXPECT_EQ(FrontendOptions{}.features.min_working_width, 427);
  EXPECT_EQ(FrontendOptions{}.features.max_working_width, 960);
  setFrontendChoice(options, "feature-width", "full");
  EXPECT_EQ(options.features.min_working_width, 0);
  EXPECT_EQ(options.features.max_working_width, 0);
  setFrontendChoice(options, "feature-width", "400-800");
  EXPECT_EQ(options.features.min_working_width, 400);
  EXPECT_EQ(options.features.max_working_width, 800);
  setFrontendChoice(options, "feature-width", "0-960");  // halved, never doubled
  EXPECT_EQ(options.features.min_working_width, 0);
  EXPECT_EQ(options.features.max_working_width, 960);
  setFrontendChoice(options, "feature-width", "427-0");  // doubled, never halved
  EXPECT_EQ(options.features.min_working_width, 427);
  EXPECT_EQ(options.features.max_working_width, 0);
  setFrontendChoice(options, "feature-width", "400-800");
  for (const char* wrong :
       {"800", "500-800", "10-800", "0-40", "400-800px", "", "half", "-960", "400--800", "+400-800"})
    EXPECT_THROW(setFrontendChoice(options, "feature-width", wrong), std::invalid_argument) << wrong;
  EXPECT_EQ(options.features.max_working_width, 800);
  // The feature blur: off, or a Gaussian sigma in pixels in [0, 5].
  EXPECT_EQ(FrontendOptions{}.features.smoothing_sigma, 0.0);
  setFrontendChoice(options, "feature-smoothing", "0.8");
  EXPECT_EQ(options.features.smoothing_sigma, 0.8);
  setFrontendChoice(options, "feature-smoothing", "off");
  EXPECT_EQ(options.features.smoothing_sigma, 0.0);
  setFrontendChoice(options, "feature-smoothing", "1");
  setFrontendChoice(options, "feature-smoothing", "0");  // no blur, as off
  EXPECT_EQ(frontendChoiceWord(options, "feature-smoothing"), "off");
  setFrontendChoice(options, "feature-smoothing", "1");
  for (const char* wrong : {"-0.5", "-1", "5.5", "1px", "nan", "inf", "", "on"})
    EXPECT_THROW(setFrontendChoice(options, "feature-smoothing", wrong), std::invalid_argument) << wrong;
  EXPECT_EQ(options.features.smoothing_sigma, 1.0);
}

TEST(FrontendChoices, EachKeysWordSetsBackTheSameChoice) {
  // The word read for a key, set again on the defaults, gives back the options it was read from: the two directions
  // of the table agree for every key, on the defaults and on a changed value.
  FrontendOptions changed;
  setFrontendChoice(changed, "pnp", "iterative");
  setFrontendChoice(changed, "descriptor", "modified-brief");
  setFrontendChoice(changed, "gate-free-retry", "off");
  setFrontendChoice(changed, "feature-width", "400-800");
  setFrontendChoice(changed, "dense-odometry", "prior");
  setFrontendChoice(changed, "feature-smoothing", "0.8");
  for (const FrontendOptions& source : {FrontendOptions{}, changed}) {
    FrontendOptions copy;
    for (const std::string& key : frontendChoiceKeys()) setFrontendChoice(copy, key, frontendChoiceWord(source, key));
    for (const std::string& key : frontendChoiceKeys())
      EXPECT_EQ(frontendChoiceWord(copy, key), frontendChoiceWord(source, key)) << key;
  }
  EXPECT_EQ(frontendChoiceWord(changed, "pnp"), "iterative");
  EXPECT_EQ(frontendChoiceWord(changed, "feature-width"), "400-800");
  EXPECT_EQ(frontendChoiceWord(changed, "gate-free-retry"), "off");
  EXPECT_EQ(frontendChoiceWord(FrontendOptions{}, "gate-free-retry"), "on");
  EXPECT_EQ(frontendChoiceWord(changed, "feature-smoothing"), "0.8");
  FrontendOptions fine;  // a sigma six digits do not hold reads back exactly
  setFrontendChoice(fine, "feature-smoothing", "1.23456789012");
  FrontendOptions read_back;
  setFrontendChoice(read_back, "feature-smoothing", frontendChoiceWord(fine, "feature-smoothing"));
  EXPECT_EQ(read_back.features.smoothing_sigma, 1.23456789012);
  EXPECT_EQ(frontendChoiceWord(FrontendOptions{}, "feature-smoothing"), "off");
  EXPECT_THROW(frontendChoiceWord(changed, "pnp-method"), std::invalid_argument);
}

TEST(FrontendChoices, AWrongKeyOrValueIsNamed) {
  FrontendOptions options;
  try {
    setFrontendChoice(options, "pnp", "epnp");
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "pnp: unknown PnP method 'epnp' (expected ap3p or iterative)");
  }
  try {
    setFrontendChoice(options, "pnp-method", "ap3p");
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("unknown front-end option 'pnp-method' (expected matcher, quality-gate, "),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(options.pnp.method, PnpMethod::Ap3p);  // a refused value changes nothing
}

// PnP's pixel thresholds follow the grid keypoints are found on: twice the frame's pixels for a frame halved for
// its features, the frame's own for one found at its size or doubled (enlarging adds no detail).
TEST(FrontendChoices, PnpThresholdsAreInPixelsOfTheImageFeaturesAreFoundAt) {
  FrontendOptions options;
  const FeatureExtractor extractor(options.features);
  EXPECT_EQ(extractor.workingWidth(640), 640);
  EXPECT_EQ(extractor.workingWidth(1280), 640);
  EXPECT_EQ(extractor.workingWidth(1920), 960);
  EXPECT_EQ(extractor.workingWidth(2560), 640);
  EXPECT_EQ(extractor.workingWidth(320), 640);
  EXPECT_EQ(extractor.workingWidth(100), 800);
  EXPECT_THROW(extractor.workingWidth(0), std::invalid_argument);
  const double ransac = options.pnp.ransac_reprojection_px, huber = options.pnp.huber_px;
  for (const int width : {320, 640, 960}) {
    EXPECT_EQ(pnpOptionsFor(options, width).ransac_reprojection_px, ransac) << width;
    EXPECT_EQ(pnpOptionsFor(options, width).huber_px, huber) << width;
  }
  EXPECT_EQ(pnpOptionsFor(options, 1280).ransac_reprojection_px, 2.0 * ransac);
  EXPECT_EQ(pnpOptionsFor(options, 1280).huber_px, 2.0 * huber);
  EXPECT_DOUBLE_EQ(pnpOptionsFor(options, 2000).ransac_reprojection_px, 4.0 * ransac);  // 2000 -> 1000 -> 500
  options.pnp_thresholds_in_working_pixels = false;
  EXPECT_EQ(pnpOptionsFor(options, 1280).ransac_reprojection_px, ransac);
}

}  // namespace
