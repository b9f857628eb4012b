#pragma once
// The front-end paper's modified BRIEF (its Eq. 7): a binary descriptor whose
// tests compare averages of neighbouring pixels instead of single (Gaussian-
// smoothed) pixels, steered by the keypoint's orientation as ORB steers BRIEF.

#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

namespace weighted_icp::frontend {

/// @brief Which binary descriptor describes the corners.
enum class DescriptorKind {
  Orb,           // ORB's rotated BRIEF (cv::ORB::compute), today's choice
  ModifiedBrief  // the front-end paper's Eq. 7 averages, steered BRIEF tests
};

/// @brief "orb" -> Orb, "modified-brief" -> ModifiedBrief; throws std::invalid_argument otherwise.
/// @param name the command-line spelling.
DescriptorKind parseDescriptorKind(const std::string& name);
/// @brief The name parseDescriptorKind reads. @param kind the descriptor.
std::string descriptorKindName(DescriptorKind kind);

/// @brief The Eq. 7 neighbourhood average of every pixel of an 8-bit image.
///
/// Reading of Eq. 7 (garbled in the extracted text): in the 3x3 neighbourhood
/// p1..p9 of a pixel (rows p1 p2 p3 / p4 p5 p6 / p7 p8 p9), P1 = (p1+p2+p3)/3,
/// P2 = (p4+p6)/2 and P3 = (p7+p8+p9)/3 are the averages of each row (Fig. 3:
/// "average value calculated of pixel intensities on each row"), the centre
/// left out as printed; the pixel's value becomes (P1 + P2 + P3) / 3.
/// Borders are reflected.
/// @param gray CV_8UC1. Returns CV_32FC1 of the same size.
cv::Mat averageNeighbours(const cv::Mat& gray);

/// @brief Describes keypoints with the modified BRIEF: 256 tests, 32 bytes per row, as ORB.
///
/// Test i sets bit i when A(x_i) < A(y_i), A = averageNeighbours(gray), for
/// the pair (x_i, y_i) of a fixed pattern rotated by the keypoint's angle.
/// The pattern is BRIEF's G II (Calonder et al. 2010, the paper's [22]):
/// both points i.i.d. Gaussian around the keypoint with sigma = S / 5 for the
/// 31-pixel patch S, kept within its 15-pixel radius so that every rotation
/// stays inside the patch, drawn once from a fixed seed (deterministic).
/// Keypoints closer than 17 px to the border are dropped with their rows,
/// as cv::Feature2D::compute drops those it cannot describe.
/// @param gray CV_8UC1 image.
/// @param keypoints in: corners with angle in degrees (-1: not oriented, taken as 0); out: those described.
/// @param descriptors out: CV_8UC1, one 32-byte row per remaining keypoint.
void computeModifiedBrief(const cv::Mat& gray, std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors);

}  // namespace weighted_icp::frontend
