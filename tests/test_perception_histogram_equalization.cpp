// Equalisation methods for frames with too few corners: the paper's global
// histogram equalisation spreads a dim image over the whole grey range, none
// leaves it alone, and the feature extractor applies the method it is given.

#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "weighted_icp/frontend/perception/feature_extractor.h"
#include "weighted_icp/frontend/perception/histogram_equalization.h"

namespace {

using namespace weighted_icp::frontend;

/// A dim, low-contrast textured image (grey levels about 40 to 60).
cv::Mat dimTexture() {
  cv::Mat image(240, 320, CV_8U);
  cv::RNG(3).fill(image, cv::RNG::UNIFORM, 40, 60);
  cv::GaussianBlur(image, image, cv::Size(7, 7), 2.0);
  return image;
}

double range(const cv::Mat& gray) {
  double low = 0, high = 0;
  cv::minMaxLoc(gray, &low, &high);
  return high - low;
}

TEST(HistogramEqualization, GlobalSpreadsADimImageOverTheGreyRange) {
  const cv::Mat dim = dimTexture();
  const cv::Mat equalized = equalizeHistogram(dim, EqualizationMethod::Global);
  EXPECT_EQ(equalized.size(), dim.size());
  EXPECT_EQ(equalized.type(), CV_8UC1);
  EXPECT_LT(range(dim), 30.0);
  EXPECT_GT(range(equalized), 240.0);
  // One histogram for the whole image: a grey level maps to the same output wherever it is.
  cv::Mat expected;
  cv::equalizeHist(dim, expected);
  EXPECT_EQ(cv::norm(equalized, expected, cv::NORM_INF), 0.0);
}

TEST(HistogramEqualization, NoneReturnsTheImageAndClaheMatchesEqualizeClahe) {
  const cv::Mat dim = dimTexture();
  EXPECT_EQ(cv::norm(equalizeHistogram(dim, EqualizationMethod::None), dim, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(equalizeHistogram(dim, EqualizationMethod::Clahe), equalizeClahe(dim), cv::NORM_INF), 0.0);
}

TEST(HistogramEqualization, RefusesBadImagesAndUnknownNames) {
  EXPECT_THROW(equalizeHistogram(cv::Mat(), EqualizationMethod::Global), std::invalid_argument);
  EXPECT_THROW(equalizeHistogram(cv::Mat(10, 10, CV_8UC3), EqualizationMethod::Global), std::invalid_argument);
  for (const auto method : {EqualizationMethod::Clahe, EqualizationMethod::Global, EqualizationMethod::None})
    EXPECT_EQ(parseEqualizationMethod(toString(method)), method);
  EXPECT_THROW(parseEqualizationMethod("adaptive"), std::invalid_argument);
}

TEST(HistogramEqualization, TheExtractorEqualisesOnlyWhenTheMethodIsNotNone) {
  // Random rectangles (many corners) at grey levels 2 to 10: corners below the absolute response floor.
  cv::Mat scene(240, 320, CV_8U, cv::Scalar(0));
  cv::RNG rng(5);
  for (int i = 0; i < 60; ++i) {
    const cv::Point corner(rng.uniform(0, 300), rng.uniform(0, 220));
    cv::rectangle(scene, cv::Rect(corner, cv::Size(rng.uniform(10, 40), rng.uniform(10, 40))),
                  cv::Scalar(rng.uniform(0, 256)), cv::FILLED);
  }
  cv::Mat dark;
  scene.convertTo(dark, CV_8U, 8.0 / 255.0, 2.0);
  FeatureExtractorOptions options;
  options.equalization = EqualizationMethod::None;
  const ExtractedFeatures none = FeatureExtractor(options).extract(dark);
  EXPECT_FALSE(none.used_clahe);
  options.equalization = EqualizationMethod::Global;
  const ExtractedFeatures global = FeatureExtractor(options).extract(dark);
  EXPECT_TRUE(global.used_clahe);
  EXPECT_GT(global.keypoints.size(), none.keypoints.size());
}

}  // namespace
