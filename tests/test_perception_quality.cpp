// The BRISQUE quality gate on real TUM frames: sharp frames pass, blurred and
// noisy copies do not; a missing model is reported with its path.

#include <algorithm>
#include <iostream>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "test_perception_support.h"
#include "test_support.h"
#include "weighted_icp/frontend/perception/image_quality_gate.h"

namespace {

using weighted_icp::frontend::ImageQualityGate;
using weighted_icp::frontend::ImageQualityGateOptions;
using weighted_icp::testing::RealSequence;

const std::string kModelDir = ImageQualityGateOptions{}.model_dir;

/// Heavy Gaussian blur (sigma 3) plus sensor-like noise (sigma 15), seeded.
cv::Mat blurredAndNoisy(const cv::Mat& gray) {
  cv::Mat blurred, noise(gray.size(), CV_32F), degraded;
  cv::GaussianBlur(gray, blurred, cv::Size(), 3.0);
  cv::RNG(42).fill(noise, cv::RNG::NORMAL, 0.0, 15.0);
  blurred.convertTo(degraded, CV_32F);
  degraded += noise;
  degraded.convertTo(degraded, CV_8U);
  return degraded;
}

class RealFrameQuality : public ::testing::TestWithParam<int> {};

TEST_P(RealFrameQuality, ScoresASharpFrameBetterThanItsBlurredNoisyCopy) {
  WEIGHTED_ICP_REQUIRE_FILE(kModelDir);
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::tumHeadDir(GetParam()) / "rgb.txt");
  const ImageQualityGate gate;
  const weighted_icp::RgbdFrame frame =
      RealSequence::open(weighted_icp::testing::tumHeadDir(GetParam()), GetParam()).frame(0);
  const double sharp = gate.score(frame.gray());
  const double degraded = gate.score(blurredAndNoisy(frame.gray()));
  std::cout << "fr" << GetParam() << " frame 0: BRISQUE " << sharp << ", blurred and noisy " << degraded << "\n";
  EXPECT_LT(sharp + 20.0, degraded);
  EXPECT_TRUE(gate.accept(frame.gray()));
  EXPECT_FALSE(gate.accept(blurredAndNoisy(frame.gray())));
  // The colour image is scored on its gray levels.
  EXPECT_NEAR(gate.score(frame.color), sharp, 0.5);
}

TEST_P(RealFrameQuality, PassesEveryRealFrameWithTheDefaultThreshold) {
  WEIGHTED_ICP_REQUIRE_FILE(kModelDir);
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::tumHeadDir(GetParam()) / "rgb.txt");
  const ImageQualityGate gate;
  const RealSequence data = RealSequence::open(weighted_icp::testing::tumHeadDir(GetParam()), GetParam());
  const std::size_t step = GetParam() == 1 ? 1 : 4;  // fr3: every 4th of 200 frames, to keep the test short
  double worst = 0.0;
  for (std::size_t i = 0; i < data.sequence.size(); i += step) {
    const double score = gate.score(data.frame(i).gray());
    worst = std::max(worst, score);
    EXPECT_LE(score, gate.options().max_brisque_score) << "frame " << i;
  }
  std::cout << "fr" << GetParam() << ": worst BRISQUE " << worst << "\n";
}

INSTANTIATE_TEST_SUITE_P(Tum, RealFrameQuality, ::testing::Values(1, 3),
                         [](const auto& info) { return "fr" + std::to_string(info.param); });

TEST(ImageQualityGate, NamesAMissingModelFile) {
  ImageQualityGateOptions options;
  options.model_dir = "/nonexistent/brisque_models";
  try {
    ImageQualityGate gate(options);
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/brisque_models/brisque_model_live.yml"), std::string::npos)
        << e.what();
  }

  // The model is there, its range file is not.
  WEIGHTED_ICP_REQUIRE_FILE(kModelDir);
  const auto dir = weighted_icp::testing::scratchDir("perception_brisque_model_only");
  std::filesystem::create_symlink(std::filesystem::path(kModelDir) / "brisque_model_live.yml",
                                  dir / "brisque_model_live.yml");
  options.model_dir = dir.string();
  try {
    ImageQualityGate gate(options);
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find((dir / "brisque_range_live.yml").string()), std::string::npos) << e.what();
  }
}

TEST(ImageQualityGate, RefusesEmptyAndNonEightBitImages) {
  WEIGHTED_ICP_REQUIRE_FILE(kModelDir);
  const ImageQualityGate gate;
  EXPECT_THROW(gate.score(cv::Mat()), std::invalid_argument);
  EXPECT_THROW(gate.score(cv::Mat(48, 64, CV_16U, cv::Scalar(0))), std::invalid_argument);
  EXPECT_THROW(gate.score(cv::Mat(48, 64, CV_8UC2, cv::Scalar::all(0))), std::invalid_argument);
}

}  // namespace
