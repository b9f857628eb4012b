// GFTT + ORB extraction on real TUM frames: enough corners, spread over the
// grid, descriptors aligned with keypoints and rotated, deterministic, and the
// CLAHE fallback on a dark low-contrast frame.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <limits>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "test_perception_support.h"
#include "test_support.h"
#include "weighted_icp/frontend/perception/descriptor_matcher.h"
#include "weighted_icp/frontend/perception/feature_extractor.h"

namespace {

using namespace weighted_icp;
using frontend::ExtractedFeatures;
using frontend::FeatureExtractor;
using frontend::FeatureExtractorOptions;

std::filesystem::path fr1Dir() { return weighted_icp::testing::dataDir() / "tum_fr1_xyz_head"; }
std::filesystem::path fr3Dir() { return weighted_icp::testing::dataDir() / "tum_fr3_teddy_head"; }

cv::Mat grayFrame(const std::filesystem::path& dir, int freiburg, std::size_t index) {
  return weighted_icp::testing::RealSequence::open(dir, freiburg).frame(index).gray();
}

bool sameFeatures(const ExtractedFeatures& a, const ExtractedFeatures& b) {
  if (a.keypoints.size() != b.keypoints.size() || a.used_clahe != b.used_clahe) return false;
  for (std::size_t i = 0; i < a.keypoints.size(); ++i) {
    const cv::KeyPoint &p = a.keypoints[i], &q = b.keypoints[i];
    if (p.pt != q.pt || p.angle != q.angle || p.response != q.response) return false;
  }
  return a.descriptors.size() == b.descriptors.size() && cv::norm(a.descriptors, b.descriptors, cv::NORM_HAMMING) == 0;
}

/// Cells of an 8 x 6 grid over the part of the image ORB can describe (31 px
/// from the border) with texture, i.e. a corner response of at least 1e-3
/// (ten times the extractor's floor), and of those the cells holding a keypoint.
struct Spread {
  int textured = 0, covered = 0;
};
Spread spreadOver(const cv::Mat& gray, const std::vector<cv::KeyPoint>& keypoints) {
  constexpr int kCols = 8, kRows = 6, kBorder = 31;
  cv::Mat response;
  cv::cornerMinEigenVal(gray, response, 3);
  const cv::Rect interior(kBorder, kBorder, gray.cols - 2 * kBorder, gray.rows - 2 * kBorder);
  Spread spread;
  for (int r = 0; r < kRows; ++r) {
    for (int c = 0; c < kCols; ++c) {
      const cv::Rect cell(interior.x + c * interior.width / kCols, interior.y + r * interior.height / kRows,
                          interior.width / kCols, interior.height / kRows);
      double strongest = 0.0;
      cv::minMaxLoc(response(cell), nullptr, &strongest);
      if (strongest < 1e-3) continue;
      ++spread.textured;
      if (std::any_of(keypoints.begin(), keypoints.end(), [&](const cv::KeyPoint& k) { return cell.contains(k.pt); }))
        ++spread.covered;
    }
  }
  return spread;
}

class RealFrameExtraction : public ::testing::TestWithParam<int> {};

TEST_P(RealFrameExtraction, FindsManyCornersSpreadOverTheImageWithAlignedDescriptors) {
  const int freiburg = GetParam();
  const auto dir = freiburg == 1 ? fr1Dir() : fr3Dir();
  WEIGHTED_ICP_REQUIRE_FILE(dir / "rgb.txt");
  const cv::Mat gray = grayFrame(dir, freiburg, 0);
  const FeatureExtractor extractor;
  const ExtractedFeatures features = extractor.extract(gray);

  EXPECT_FALSE(features.used_clahe);
  EXPECT_GE(features.keypoints.size(), 500u);
  EXPECT_LE(features.keypoints.size(), 1000u);
  ASSERT_EQ(features.descriptors.rows, static_cast<int>(features.keypoints.size()));
  EXPECT_EQ(features.descriptors.cols, 32);
  EXPECT_EQ(features.descriptors.type(), CV_8UC1);

  // Every textured cell gets keypoints, also on a small budget, where
  // without bucketing (one cell) the strongest corners crowd into the busiest
  // parts of the frame.
  const Spread spread = spreadOver(gray, features.keypoints);
  FeatureExtractorOptions small;
  small.max_features = 200;
  const Spread small_spread = spreadOver(gray, FeatureExtractor(small).extract(gray).keypoints);
  small.grid_cols = small.grid_rows = 1;
  const Spread unbucketed = spreadOver(gray, FeatureExtractor(small).extract(gray).keypoints);
  std::cout << "fr" << freiburg << ": " << features.keypoints.size() << " keypoints in " << spread.covered << " of "
            << spread.textured << " textured cells; 200 keypoints in " << small_spread.covered << ", without bucketing "
            << unbucketed.covered << "\n";
  EXPECT_GE(spread.textured, 30);
  EXPECT_EQ(spread.covered, spread.textured);
  EXPECT_EQ(small_spread.covered, spread.textured);
  EXPECT_LT(unbucketed.covered, small_spread.covered);

  // Row i is the descriptor of keypoint i: describing keypoints one by one
  // with an ORB of the same settings gives the same rows.
  const cv::Ptr<cv::ORB> orb = cv::ORB::create(1000, 1.2f, 1, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31);
  for (std::size_t i = 0; i < features.keypoints.size(); i += 37) {
    std::vector<cv::KeyPoint> one{features.keypoints[i]};
    cv::Mat row;
    orb->compute(gray, one, row);
    ASSERT_EQ(one.size(), 1u);
    EXPECT_EQ(cv::norm(row, features.descriptors.row(static_cast<int>(i)), cv::NORM_HAMMING), 0) << "keypoint " << i;
  }
  for (const cv::KeyPoint& k : features.keypoints) {
    EXPECT_GE(k.angle, 0.0f);
    EXPECT_LT(k.angle, 360.0f);
  }
}

INSTANTIATE_TEST_SUITE_P(Tum, RealFrameExtraction, ::testing::Values(1, 3),
                         [](const auto& info) { return "fr" + std::to_string(info.param); });

TEST(FeatureExtractor, KeepsTheMinimumDistanceAndTheDescriptorMargin) {
  WEIGHTED_ICP_REQUIRE_FILE(fr3Dir() / "rgb.txt");
  const cv::Mat gray = grayFrame(fr3Dir(), 3, 10);
  const FeatureExtractorOptions options;
  const ExtractedFeatures features = FeatureExtractor(options).extract(gray);
  ASSERT_FALSE(features.keypoints.empty());
  for (std::size_t i = 0; i < features.keypoints.size(); ++i) {
    const cv::Point2f p = features.keypoints[i].pt;
    EXPECT_TRUE(cv::Rect(31, 31, gray.cols - 62, gray.rows - 62).contains(p)) << p;
    for (std::size_t j = i + 1; j < features.keypoints.size(); ++j)
      ASSERT_GE(cv::norm(p - features.keypoints[j].pt), options.min_distance_px - 1.0);  // sub-pixel shifts
  }
}

TEST(FeatureExtractor, IsDeterministicAndIndependentOfTheThreadCount) {
  WEIGHTED_ICP_REQUIRE_FILE(fr1Dir() / "rgb.txt");
  const cv::Mat gray = grayFrame(fr1Dir(), 1, 3);
  const FeatureExtractor extractor;
  const ExtractedFeatures first = extractor.extract(gray);
  EXPECT_TRUE(sameFeatures(first, extractor.extract(gray)));
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  const ExtractedFeatures single_thread = extractor.extract(gray);
  cv::setNumThreads(threads);
  EXPECT_TRUE(sameFeatures(first, single_thread));
}

// Rotated BRIEF: a frame turned by 90 degrees still matches itself, and the
// keypoint orientations turn with it. Unrotated BRIEF fails this.
TEST(FeatureExtractor, DescriptorsFollowTheKeypointOrientation) {
  WEIGHTED_ICP_REQUIRE_FILE(fr3Dir() / "rgb.txt");
  const cv::Mat gray = grayFrame(fr3Dir(), 3, 0);
  cv::Mat turned;
  cv::rotate(gray, turned, cv::ROTATE_90_CLOCKWISE);  // (x, y) -> (rows - 1 - y, x)
  const FeatureExtractor extractor;
  const ExtractedFeatures original = extractor.extract(gray);
  const ExtractedFeatures rotated = extractor.extract(turned);

  std::vector<std::vector<cv::DMatch>> nearest;
  cv::BFMatcher(cv::NORM_HAMMING).knnMatch(rotated.descriptors, original.descriptors, nearest, 2);
  int confident = 0, correct = 0, turned_by_90 = 0;
  for (const auto& pair : nearest) {
    if (pair.size() < 2 || !(pair[0].distance < 0.8f * pair[1].distance)) continue;
    ++confident;
    const cv::KeyPoint& o = original.keypoints[static_cast<std::size_t>(pair[0].trainIdx)];
    const cv::KeyPoint& r = rotated.keypoints[static_cast<std::size_t>(pair[0].queryIdx)];
    if (cv::norm(cv::Point2f(static_cast<float>(gray.rows - 1) - o.pt.y, o.pt.x) - r.pt) > 1.0) continue;
    ++correct;
    const float turn = std::fmod(r.angle - o.angle + 360.0f, 360.0f);
    if (std::abs(turn - 90.0f) < 10.0f) ++turned_by_90;
  }
  std::cout << confident << " confident matches, " << correct << " at the rotated position, " << turned_by_90
            << " turned by 90 +- 10 degrees\n";
  EXPECT_GE(correct, 300);
  EXPECT_GE(correct, confident * 9 / 10);
  EXPECT_GE(turned_by_90, correct * 9 / 10);
}

// A poorly lit frame: gray levels squeezed into [20, 71]. Too few corners
// clear the absolute floor, so the extractor equalises and finds more.
TEST(FeatureExtractor, EqualisesADarkLowContrastFrame) {
  WEIGHTED_ICP_REQUIRE_FILE(fr3Dir() / "rgb.txt");
  const cv::Mat gray = grayFrame(fr3Dir(), 3, 0);
  cv::Mat dark;
  gray.convertTo(dark, CV_8U, 0.2, 20.0);

  const ExtractedFeatures with_clahe = FeatureExtractor().extract(dark);
  FeatureExtractorOptions never;
  never.min_features_before_clahe = 0;
  const ExtractedFeatures without_clahe = FeatureExtractor(never).extract(dark);
  std::cout << "dark frame: " << without_clahe.keypoints.size() << " keypoints as is, " << with_clahe.keypoints.size()
            << " after CLAHE\n";
  EXPECT_FALSE(without_clahe.used_clahe);
  EXPECT_LT(without_clahe.keypoints.size(), 300u);
  EXPECT_TRUE(with_clahe.used_clahe);
  EXPECT_GE(with_clahe.keypoints.size(), 2 * without_clahe.keypoints.size());
  EXPECT_EQ(with_clahe.descriptors.rows, static_cast<int>(with_clahe.keypoints.size()));
}

// Two dark views of fr3 (frames 10 and 15, grey levels squeezed into [10, 48]), both equalised to find corners.
// CLAHE maps each tile by its own histogram, which changes with the view: described in the equalised images, the
// same corners differ more between the views than described in the frames as they are, and fewer matches agree with
// the true motion.
TEST(FeatureExtractor, DescribesAnEqualisedFrameAsItIsSoThatItsCornersMatchAcrossViews) {
  WEIGHTED_ICP_REQUIRE_FILE(fr3Dir() / "rgb.txt");
  const auto data = weighted_icp::testing::RealSequence::open(fr3Dir(), 3);
  const auto darken = [&](std::size_t index) {
    cv::Mat dark;
    data.frame(index).gray().convertTo(dark, CV_8U, 0.15, 10.0);
    return dark;
  };
  const cv::Mat reference = darken(10), query = darken(15);
  const auto verified = [&](bool describe_equalized) {
    FeatureExtractorOptions options;
    options.describe_equalized = describe_equalized;
    const FeatureExtractor extractor(options);
    const ExtractedFeatures a = extractor.extract(reference), b = extractor.extract(query);
    EXPECT_TRUE(a.used_clahe && b.used_clahe);
    frontend::DescriptorMatcherOptions matching;
    matching.kind = frontend::MatcherKind::BruteForce;
    frontend::DescriptorMatcher matcher(matching);
    matcher.setReference(a.descriptors);
    const auto check = weighted_icp::testing::checkAgainstGroundTruth(data, 10, 15, a.keypoints, b.keypoints,
                                                                      matcher.match(b.descriptors), 5.0);
    std::cout << (describe_equalized ? "described equalised: " : "described as it is: ") << check.inliers << " of "
              << check.checked << " matches with depth within 5 px\n";
    return check;
  };
  const auto as_it_is = verified(false), equalised = verified(true);
  EXPECT_GT(as_it_is.inliers, equalised.inliers + equalised.inliers / 10);
  EXPECT_GT(as_it_is.fraction(), 0.7);
}

// A frame wider than max_working_width is worked on halved: a 1280x960 image whose 2x2 blocks are the pixels of a
// 640x480 frame gives that frame's features exactly, their keypoints at the blocks' centres.
TEST(FeatureExtractor, AWideFrameIsWorkedOnHalvedAndItsKeypointsGivenInItsPixels) {
  WEIGHTED_ICP_REQUIRE_FILE(fr1Dir() / "rgb.txt");
  const cv::Mat gray = grayFrame(fr1Dir(), 1, 3);
  cv::Mat wide;
  cv::resize(gray, wide, cv::Size(2 * gray.cols, 2 * gray.rows), 0.0, 0.0, cv::INTER_NEAREST);
  FeatureExtractorOptions options;
  options.max_working_width = 960;
  const ExtractedFeatures small = FeatureExtractor(options).extract(gray);  // 640 wide: as without the option
  EXPECT_TRUE(sameFeatures(small, FeatureExtractor().extract(gray)));
  const ExtractedFeatures halved = FeatureExtractor(options).extract(wide);
  ASSERT_GT(small.keypoints.size(), 300u);
  ASSERT_EQ(halved.keypoints.size(), small.keypoints.size());
  for (std::size_t i = 0; i < small.keypoints.size(); ++i) {
    const cv::Point2f expected = 2.0f * small.keypoints[i].pt + cv::Point2f(0.5f, 0.5f);
    ASSERT_LT(cv::norm(halved.keypoints[i].pt - expected), 1e-4) << i;
    EXPECT_EQ(halved.keypoints[i].angle, small.keypoints[i].angle);
  }
  EXPECT_EQ(cv::norm(halved.descriptors, small.descriptors, cv::NORM_HAMMING), 0.0);
  EXPECT_TRUE(sameFeatures(FeatureExtractor().extract(wide), halved));  // the default: 960
  // At its own size the wide frame gives other corners (twice as many pixels per corner spacing).
  options.max_working_width = 0;
  EXPECT_FALSE(sameFeatures(FeatureExtractor(options).extract(wide), halved));
  options.max_working_width = 10;
  EXPECT_THROW(FeatureExtractor{options}, std::invalid_argument);
}

// A frame narrower than min_working_width is worked on doubled (bilinear): a 320x240 frame gives the features of its
// 640x480 enlargement, with the corner-response floor quartered as its gradients are halved, their keypoints in its
// own pixels.
TEST(FeatureExtractor, ANarrowFrameIsWorkedOnDoubledAndItsKeypointsGivenInItsPixels) {
  WEIGHTED_ICP_REQUIRE_FILE(fr3Dir() / "rgb.txt");
  cv::Mat narrow, enlarged;
  cv::resize(grayFrame(fr3Dir(), 3, 10), narrow, cv::Size(320, 240), 0.0, 0.0, cv::INTER_AREA);
  cv::resize(narrow, enlarged, cv::Size(640, 480), 0.0, 0.0, cv::INTER_LINEAR);
  FeatureExtractorOptions full;
  full.min_working_width = full.max_working_width = 0;
  FeatureExtractorOptions enlarged_floor = full;
  enlarged_floor.min_corner_response = full.min_corner_response / 4.0;
  const ExtractedFeatures doubled = FeatureExtractor().extract(narrow);
  const ExtractedFeatures expected = FeatureExtractor(enlarged_floor).extract(enlarged);
  EXPECT_FALSE(sameFeatures(FeatureExtractor(full).extract(enlarged), expected)) << "the floor decides nothing here";
  ASSERT_GT(expected.keypoints.size(), 300u);
  ASSERT_EQ(doubled.keypoints.size(), expected.keypoints.size());
  for (std::size_t i = 0; i < expected.keypoints.size(); ++i)
    ASSERT_LT(cv::norm(doubled.keypoints[i].pt - (0.5f * expected.keypoints[i].pt - cv::Point2f(0.25f, 0.25f))), 1e-4)
        << i;
  EXPECT_EQ(cv::norm(doubled.descriptors, expected.descriptors, cv::NORM_HAMMING), 0.0);
  // At its own size: fewer corners, none within ORB's 31 pixels of the border.
  const ExtractedFeatures own = FeatureExtractor(full).extract(narrow);
  EXPECT_LT(own.keypoints.size(), doubled.keypoints.size());
  FeatureExtractorOptions crossed;
  crossed.min_working_width = 600;  // more than half of 960: no width between them is sure to be reached
  EXPECT_THROW(FeatureExtractor{crossed}, std::invalid_argument);
}

TEST(FeatureExtractor, ReturnsNothingForAnImageTooSmallToDescribe) {
  const cv::Mat tiny(60, 60, CV_8U, cv::Scalar(128));
  const ExtractedFeatures features = FeatureExtractor().extract(tiny);
  EXPECT_TRUE(features.keypoints.empty());
  EXPECT_EQ(features.descriptors.rows, 0);
  EXPECT_EQ(features.descriptors.cols, 32);
  EXPECT_EQ(features.descriptors.type(), CV_8UC1);
}

TEST(FeatureExtractor, RefusesBadInputAndOptions) {
  const FeatureExtractor extractor;
  EXPECT_THROW(extractor.extract(cv::Mat()), std::invalid_argument);
  EXPECT_THROW(extractor.extract(cv::Mat(480, 640, CV_8UC3, cv::Scalar::all(0))), std::invalid_argument);
  EXPECT_THROW(extractor.extract(cv::Mat(480, 640, CV_16U, cv::Scalar(0))), std::invalid_argument);
  FeatureExtractorOptions options;
  options.grid_cols = 0;
  EXPECT_THROW(FeatureExtractor{options}, std::invalid_argument);
  options = {};
  options.quality_level = 0.0;
  EXPECT_THROW(FeatureExtractor{options}, std::invalid_argument);
  options = {};
  options.clahe.clip_limit = 0.0;
  EXPECT_THROW(FeatureExtractor{options}, std::invalid_argument);
  for (const double sigma : {-1.0, 5.5, std::numeric_limits<double>::quiet_NaN()}) {
    options = {};
    options.smoothing_sigma = sigma;
    EXPECT_THROW(FeatureExtractor{options}, std::invalid_argument) << sigma;
  }
}

/// `gray` compressed as JPEG of `quality` with its 8x8 blocks laid `dx`, `dy` pixels off: two such views of one frame
/// differ as two frames of a JPEG camera do where the scene is the same (their blocking and ringing moved).
cv::Mat jpegView(const cv::Mat& gray, int quality, int dx, int dy) {
  const cv::Mat there = (cv::Mat_<double>(2, 3) << 1, 0, dx, 0, 1, dy);
  const cv::Mat back = (cv::Mat_<double>(2, 3) << 1, 0, -dx, 0, 1, -dy);
  cv::Mat shifted, view;
  cv::warpAffine(gray, shifted, there, gray.size());
  std::vector<std::uint8_t> bytes;
  cv::imencode(".jpg", shifted, bytes, {cv::IMWRITE_JPEG_QUALITY, quality});
  cv::warpAffine(cv::imdecode(bytes, cv::IMREAD_GRAYSCALE), view, back, gray.size());
  return view;
}

/// How many of `a`'s keypoints have one of `b`'s within a pixel.
int repeated(const ExtractedFeatures& a, const ExtractedFeatures& b) {
  int count = 0;
  for (const cv::KeyPoint& k : a.keypoints)
    count += std::any_of(b.keypoints.begin(), b.keypoints.end(),
                         [&](const cv::KeyPoint& l) { return cv::norm(k.pt - l.pt) < 1.0; });
  return count;
}

// The feature blur against JPEG: corners found in the blurred views of a real frame compressed twice with their
// blocks laid differently repeat far more often (measured 190 of 661 without, 287 of 628 at sigma 1), and the
// response floor lowered with the blur keeps most of a clean frame's corners (646 without the blur: 612 with it, 483
// without the lowering).
TEST(FeatureExtractor, CornersFoundInTheBlurredFrameRepeatAcrossJpegViewsAndTheCleanFrameKeepsItsCorners) {
  WEIGHTED_ICP_REQUIRE_FILE(fr3Dir() / "rgb.txt");
  const cv::Mat frame = grayFrame(fr3Dir(), 3, 10);
  FeatureExtractorOptions unblurred, blurred;
  unblurred.smoothing_sigma = 0.0;
  blurred.smoothing_sigma = 1.0;
  const FeatureExtractor plain(unblurred), smoothing(blurred);
  const cv::Mat a = jpegView(frame, 75, 3, 2), b = jpegView(frame, 75, 6, 4);
  const ExtractedFeatures plain_a = plain.extract(a), plain_b = plain.extract(b);
  const cv::Mat a_before = a.clone();
  const ExtractedFeatures smoothed_a = smoothing.extract(a), smoothed_b = smoothing.extract(b);
  EXPECT_EQ(cv::norm(a, a_before, cv::NORM_INF), 0.0) << "the caller's frame was blurred";
  ASSERT_GT(plain_a.keypoints.size(), 300u);
  ASSERT_GT(smoothed_a.keypoints.size(), 300u);
  const double plain_share = static_cast<double>(repeated(plain_a, plain_b)) / plain_a.keypoints.size();
  const double smoothed_share = static_cast<double>(repeated(smoothed_a, smoothed_b)) / smoothed_a.keypoints.size();
  EXPECT_GT(smoothed_share, 1.3 * plain_share) << plain_share << " repeated without the blur";
  EXPECT_GT(repeated(smoothed_a, smoothed_b), repeated(plain_a, plain_b));
  // Found, refined and described in the blurred frame: ORB describes a keypoint there as the extractor did.
  ASSERT_EQ(smoothed_a.descriptors.rows, static_cast<int>(smoothed_a.keypoints.size()));
  cv::Mat blurred_a;
  cv::GaussianBlur(a, blurred_a, cv::Size(0, 0), 1.0);
  const cv::Ptr<cv::ORB> orb = cv::ORB::create(1000, 1.2f, 1, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31);
  std::vector<cv::KeyPoint> first{smoothed_a.keypoints.front()};
  cv::Mat row;
  orb->compute(blurred_a, first, row);
  ASSERT_EQ(first.size(), 1u);
  EXPECT_EQ(cv::norm(row, smoothed_a.descriptors.row(0), cv::NORM_HAMMING), 0);

  const std::size_t clean_plain = plain.extract(frame).keypoints.size();
  const std::size_t clean_smoothed = smoothing.extract(frame).keypoints.size();
  EXPECT_GT(clean_smoothed, clean_plain * 8 / 10) << clean_plain << " without the blur";
}

}  // namespace
