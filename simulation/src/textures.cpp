// Random face textures for the RGB-D sequence's room, furniture and moving
// object (see textures.h). Each step draws one kind of mark; the order of the
// steps and of the draws within them fixes the textures of every seed.

#include "textures.h"

#include <cmath>
#include <string>

#include <opencv2/imgproc.hpp>

#include "random_source.h"

namespace weighted_icp::simulation {

namespace {

constexpr double kPi = 3.14159265358979323846;

/// Draws the marks of one texture: sizes in metres become texels, counts
/// scale with the area, and all choices come from one random source.
class TexturePainter {
 public:
  TexturePainter(double width_m, double height_m, double texels_per_metre, std::uint64_t seed)
      : random_(seed),
        texels_per_metre_(texels_per_metre),
        area_(width_m * height_m),
        cols_(std::max(8, static_cast<int>(std::lround(width_m * texels_per_metre)))),
        rows_(std::max(8, static_cast<int>(std::lround(height_m * texels_per_metre)))) {
    texture_ = cv::Mat(rows_, cols_, CV_8UC3, color(70, 190));
  }

  // Large panels first (posters, doors), so small marks sit on varied grounds.
  void panels() {
    for (int n = count(0.8); n > 0; --n) {
      const cv::Point corner = anywhere();
      const cv::Size size(texels(random_.uniform(0.2, 0.8)), texels(random_.uniform(0.2, 0.8)));
      cv::rectangle(texture_, cv::Rect(corner, size), color(40, 220), cv::FILLED);
    }
  }
  void rectangles() {
    for (int n = count(30.0); n > 0; --n) {
      const cv::Point corner = anywhere();
      const cv::Size size(texels(random_.uniform(0.02, 0.2)), texels(random_.uniform(0.02, 0.2)));
      const int thickness = random_.chance(0.6) ? cv::FILLED : stroke();
      cv::rectangle(texture_, cv::Rect(corner, size), color(10, 245), thickness, cv::LINE_AA);
    }
  }
  // Turned quadrilaterals: corners at all angles.
  void quadrilaterals() {
    for (int n = count(10.0); n > 0; --n) {
      const cv::Point centre = anywhere();
      const double radius = random_.uniform(0.02, 0.12) * texels_per_metre_;
      const double angle = random_.uniform(0.0, 2.0 * kPi);
      std::array<cv::Point, 4> corners;
      for (int k = 0; k < 4; ++k) {
        const double a = angle + k * kPi / 2.0 + random_.uniform(-0.3, 0.3);
        corners[k] = centre + cv::Point(static_cast<int>(radius * std::cos(a)), static_cast<int>(radius * std::sin(a)));
      }
      cv::fillConvexPoly(texture_, corners.data(), 4, color(10, 245), cv::LINE_AA);
    }
  }
  void circles() {
    for (int n = count(20.0); n > 0; --n) {
      const int thickness = random_.chance(0.75) ? cv::FILLED : stroke();
      cv::circle(texture_, anywhere(), texels(random_.uniform(0.01, 0.08)), color(10, 245), thickness, cv::LINE_AA);
    }
  }
  void lines() {
    for (int n = count(10.0); n > 0; --n) {
      const cv::Point start = anywhere();
      const double length = random_.uniform(0.05, 0.4) * texels_per_metre_;
      const double angle = random_.uniform(0.0, 2.0 * kPi);
      const cv::Point end =
          start + cv::Point(static_cast<int>(length * std::cos(angle)), static_cast<int>(length * std::sin(angle)));
      cv::line(texture_, start, end, color(10, 245), stroke(), cv::LINE_AA);
    }
  }
  // Small checkerboards, as on calibration prints.
  void checkerboards() {
    for (int n = count(2.0); n > 0; --n) {
      const cv::Point origin = anywhere();
      const int square = texels(random_.uniform(0.02, 0.04));
      const cv::Scalar dark = color(10, 80), light = color(170, 245);
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
          cv::rectangle(texture_, cv::Rect(origin + cv::Point(c * square, r * square), cv::Size(square, square)),
                        (r + c) % 2 ? dark : light, cv::FILLED);
    }
  }
  // Text-like marks: labels, signs.
  void text() {
    static const std::string kGlyphs = "ABCDEFGHJKLMNPQRSTUVWXYZ0123456789#%&";
    constexpr double kHersheyCapHeight = 22.0;  // texels at font scale 1
    for (int n = count(12.0); n > 0; --n) {
      std::string word;
      for (int k = random_.integer(2, 6); k > 0; --k)
        word += kGlyphs[random_.integer(0, static_cast<int>(kGlyphs.size()) - 1)];
      const double scale = random_.uniform(0.03, 0.12) * texels_per_metre_ / kHersheyCapHeight;
      cv::putText(texture_, word, anywhere(), random_.chance(0.5) ? cv::FONT_HERSHEY_SIMPLEX : cv::FONT_HERSHEY_DUPLEX,
                  scale, color(10, 245), stroke(), cv::LINE_AA);
    }
  }

  const cv::Mat& texture() const { return texture_; }

 private:
  int count(double per_square_metre) const { return 1 + static_cast<int>(area_ * per_square_metre); }
  int texels(double metres) const { return std::max(1, static_cast<int>(std::lround(metres * texels_per_metre_))); }
  int stroke() { return texels(random_.uniform(0.004, 0.012)); }
  cv::Point anywhere() { return cv::Point(random_.integer(0, cols_ - 1), random_.integer(0, rows_ - 1)); }
  cv::Scalar color(int low, int high) {
    return cv::Scalar(random_.integer(low, high), random_.integer(low, high), random_.integer(low, high));
  }

  RandomSource random_;
  double texels_per_metre_, area_;
  int cols_, rows_;
  cv::Mat texture_;
};

}  // namespace

cv::Mat makeTexture(double width_m, double height_m, double texels_per_metre, std::uint64_t seed) {
  TexturePainter painter(width_m, height_m, texels_per_metre, seed);
  painter.panels();
  painter.rectangles();
  painter.quadrilaterals();
  painter.circles();
  painter.lines();
  painter.checkerboards();
  painter.text();
  return painter.texture();
}

FaceTextures makeBoxTextures(const Eigen::Vector3d& size, double texels_per_metre, std::uint64_t seed) {
  FaceTextures faces;
  for (int face = 0; face < 6; ++face)
    faces[face] = makeTexture(size[faceU(face / 2)], size[faceV(face / 2)], texels_per_metre, mixBits(seed + face));
  return faces;
}

FaceTextures makeRepeatedBoxTextures(const Eigen::Vector3d& size, double texels_per_metre, const cv::Mat& tile) {
  FaceTextures faces;
  for (int face = 0; face < 6; ++face) {
    const int cols = std::max(8, static_cast<int>(std::ceil(size[faceU(face / 2)] * texels_per_metre)) + 1);
    const int rows = std::max(8, static_cast<int>(std::ceil(size[faceV(face / 2)] * texels_per_metre)) + 1);
    cv::Mat repeated;
    cv::repeat(tile, rows / tile.rows + 1, cols / tile.cols + 1, repeated);
    faces[face] = repeated(cv::Rect(0, 0, cols, rows)).clone();
  }
  return faces;
}

}  // namespace weighted_icp::simulation
