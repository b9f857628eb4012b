// The modified BRIEF descriptor: Eq. 7 neighbourhood averages compared by a steered Gaussian test pattern.

#include "weighted_icp/frontend/perception/modified_brief.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "weighted_icp/core/named_values.h"

namespace weighted_icp::frontend {
namespace {

constexpr int kTests = 256;
constexpr int kPatchRadius = 15;  // ORB's 31-pixel patch
constexpr int kBorder = kPatchRadius + 2;

struct TestPair {
  float x1, y1, x2, y2;
};

/// A uniform double in [0, 1) from the generator's bits (std distributions differ between libraries).
double uniform(std::mt19937_64& random) { return static_cast<double>(random() >> 11) * 0x1.0p-53; }

/// One Gaussian coordinate by Box-Muller, redrawn until inside the patch radius.
std::array<float, 2> gaussianPoint(std::mt19937_64& random, double sigma) {
  while (true) {
    const double u1 = 1.0 - uniform(random), u2 = uniform(random);
    const double r = std::sqrt(-2.0 * std::log(u1)) * sigma;
    const double x = r * std::cos(2.0 * M_PI * u2), y = r * std::sin(2.0 * M_PI * u2);
    if (x * x + y * y <= kPatchRadius * kPatchRadius) return {static_cast<float>(x), static_cast<float>(y)};
  }
}

const std::array<TestPair, kTests>& pattern() {
  static const std::array<TestPair, kTests> pairs = [] {
    std::array<TestPair, kTests> p{};
    std::mt19937_64 random(0xb41ef);
    const double sigma = (2.0 * kPatchRadius + 1.0) / 5.0;
    for (TestPair& pair : p) {
      const auto a = gaussianPoint(random, sigma), b = gaussianPoint(random, sigma);
      pair = {a[0], a[1], b[0], b[1]};
    }
    return p;
  }();
  return pairs;
}

}  // namespace

DescriptorKind parseDescriptorKind(const std::string& name) {
  return parseNamedValue(name, {DescriptorKind::Orb, DescriptorKind::ModifiedBrief}, descriptorKindName, "descriptor");
}

std::string descriptorKindName(DescriptorKind kind) { return kind == DescriptorKind::Orb ? "orb" : "modified-brief"; }

cv::Mat averageNeighbours(const cv::Mat& gray) {
  if (gray.empty() || gray.type() != CV_8UC1)
    throw std::invalid_argument("averageNeighbours: needs a non-empty CV_8UC1 image");
  // (P1 + P2 + P3) / 3 as one 3x3 kernel.
  const float a = 1.0f / 9.0f, b = 1.0f / 6.0f;
  const cv::Mat kernel = (cv::Mat_<float>(3, 3) << a, a, a, b, 0.0f, b, a, a, a);
  cv::Mat averaged;
  cv::filter2D(gray, averaged, CV_32F, kernel, cv::Point(-1, -1), 0.0, cv::BORDER_REFLECT_101);
  return averaged;
}

void computeModifiedBrief(const cv::Mat& gray, std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors) {
  const cv::Mat averaged = averageNeighbours(gray);
  const auto& tests = pattern();
  std::vector<cv::KeyPoint> kept;
  kept.reserve(keypoints.size());
  cv::Mat rows(static_cast<int>(keypoints.size()), kTests / 8, CV_8UC1, cv::Scalar(0));
  for (const cv::KeyPoint& keypoint : keypoints) {
    const int u = cvRound(keypoint.pt.x), v = cvRound(keypoint.pt.y);
    if (u < kBorder || v < kBorder || u >= gray.cols - kBorder || v >= gray.rows - kBorder) continue;
    const double angle = keypoint.angle < 0 ? 0.0 : keypoint.angle * M_PI / 180.0;
    const float c = static_cast<float>(std::cos(angle)), s = static_cast<float>(std::sin(angle));
    const auto at = [&](float x, float y) {
      return averaged.at<float>(v + cvRound(s * x + c * y), u + cvRound(c * x - s * y));
    };
    std::uint8_t* row = rows.ptr<std::uint8_t>(static_cast<int>(kept.size()));
    for (int i = 0; i < kTests; ++i) {
      const TestPair& t = tests[static_cast<std::size_t>(i)];
      if (at(t.x1, t.y1) < at(t.x2, t.y2)) row[i / 8] |= static_cast<std::uint8_t>(1u << (i % 8));
    }
    kept.push_back(keypoint);
  }
  descriptors = rows.rowRange(0, static_cast<int>(kept.size())).clone();
  keypoints.swap(kept);
}

}  // namespace weighted_icp::frontend
