// The one RGB-D frame type: grey view, valid depth count, raw <-> metric depth.
#include <cstdint>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "weighted_icp/core/rgbd_frame.h"

using namespace weighted_icp;

TEST(RgbdFrame, GrayConvertsColourAndKeepsGrey) {
  RgbdFrame frame;
  frame.color = cv::Mat(4, 5, CV_8UC3, cv::Scalar(10, 200, 60));  // BGR
  const cv::Mat gray = frame.gray();
  ASSERT_EQ(gray.type(), CV_8UC1);
  ASSERT_EQ(gray.size(), frame.color.size());
  // OpenCV's weights: 0.299 R + 0.587 G + 0.114 B.
  EXPECT_NEAR(gray.at<std::uint8_t>(2, 3), 0.299 * 60 + 0.587 * 200 + 0.114 * 10, 1.0);
  frame.color = cv::Mat(4, 5, CV_8UC1, cv::Scalar(77));
  EXPECT_EQ(frame.gray().data, frame.color.data);  // already grey: no copy
}

TEST(RgbdFrame, CountsOnlyPositiveDepthReadings) {
  RgbdFrame frame;
  EXPECT_EQ(frame.validDepthPixels(), 0u);
  frame.depth = cv::Mat::zeros(3, 4, CV_32F);
  frame.depth.at<float>(0, 0) = 1.5f;
  frame.depth.at<float>(2, 3) = 0.4f;
  frame.depth.at<float>(1, 1) = -1.0f;
  frame.depth.at<float>(1, 2) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(frame.validDepthPixels(), 2u);
}

TEST(RgbdFrame, RawDepthRoundTripsThroughMetres) {
  cv::Mat raw(2, 3, CV_16UC1);
  const std::uint16_t values[6] = {0, 1, 5000, 12345, 40000, 65535};
  for (int i = 0; i < 6; ++i) raw.at<std::uint16_t>(i / 3, i % 3) = values[i];
  const cv::Mat metres = depthFromRaw(raw, 5000.0);
  ASSERT_EQ(metres.type(), CV_32FC1);
  EXPECT_EQ(metres.at<float>(0, 0), 0.0f);
  EXPECT_FLOAT_EQ(metres.at<float>(0, 2), 1.0f);
  EXPECT_EQ(cv::norm(depthToRaw(metres, 5000.0), raw, cv::NORM_INF), 0.0);  // exact, every value
}

TEST(RgbdFrame, BadDepthConversionsAreRefused) {
  EXPECT_THROW(depthFromRaw(cv::Mat::zeros(2, 2, CV_8UC1), 5000.0), std::invalid_argument);
  EXPECT_THROW(depthFromRaw(cv::Mat::zeros(2, 2, CV_16UC1), 0.0), std::invalid_argument);
  EXPECT_THROW(depthToRaw(cv::Mat::zeros(2, 2, CV_16UC1), 5000.0), std::invalid_argument);
  EXPECT_THROW(depthToRaw(cv::Mat::zeros(2, 2, CV_32FC1), -1.0), std::invalid_argument);
}
