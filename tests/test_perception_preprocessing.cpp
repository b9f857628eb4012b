// CLAHE: more contrast for a dark frame, same size and type, clear errors.

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "test_perception_support.h"
#include "test_support.h"
#include "weighted_icp/frontend/perception/image_preprocessor.h"

namespace {

using weighted_icp::frontend::ClaheOptions;
using weighted_icp::frontend::equalizeClahe;

double contrast(const cv::Mat& gray) {
  cv::Scalar mean, stddev;
  cv::meanStdDev(gray, mean, stddev);
  return stddev[0];
}

TEST(Clahe, RaisesTheContrastOfADarkRealFrame) {
  const auto dir = weighted_icp::testing::dataDir() / "tum_fr3_teddy_head";
  WEIGHTED_ICP_REQUIRE_FILE(dir / "rgb.txt");
  const cv::Mat gray = weighted_icp::testing::RealSequence::open(dir, 3).frame(0).gray();
  cv::Mat dark;
  gray.convertTo(dark, CV_8U, 0.2, 20.0);
  const cv::Mat equalized = equalizeClahe(dark);
  EXPECT_EQ(equalized.size(), dark.size());
  EXPECT_EQ(equalized.type(), CV_8UC1);
  EXPECT_GT(contrast(equalized), 2.0 * contrast(dark));
  // A lower clip limit stretches less.
  EXPECT_LT(contrast(equalizeClahe(dark, ClaheOptions{1.0, 8})), contrast(equalized));
}

TEST(Clahe, StretchesASyntheticLowContrastImage) {
  cv::Mat image(120, 160, CV_8U);
  cv::RNG(7).fill(image, cv::RNG::UNIFORM, 40, 56);
  cv::GaussianBlur(image, image, cv::Size(5, 5), 1.5);
  const cv::Mat equalized = equalizeClahe(image, ClaheOptions{4.0, 4});
  EXPECT_EQ(equalized.size(), image.size());
  EXPECT_EQ(equalized.type(), CV_8UC1);
  EXPECT_GT(contrast(equalized), 2.0 * contrast(image));
}

TEST(Clahe, RefusesBadInputAndOptions) {
  const cv::Mat gray(48, 64, CV_8U, cv::Scalar(100));
  EXPECT_THROW(equalizeClahe(cv::Mat()), std::invalid_argument);
  EXPECT_THROW(equalizeClahe(cv::Mat(48, 64, CV_8UC3, cv::Scalar::all(0))), std::invalid_argument);
  EXPECT_THROW(equalizeClahe(cv::Mat(48, 64, CV_32F, cv::Scalar(0))), std::invalid_argument);
  EXPECT_THROW(equalizeClahe(gray, ClaheOptions{0.0, 8}), std::invalid_argument);
  EXPECT_THROW(equalizeClahe(gray, ClaheOptions{3.0, 0}), std::invalid_argument);
}

}  // namespace
