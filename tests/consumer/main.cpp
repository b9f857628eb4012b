// A user's program against the installed weighted_icp: aligns a displaced copy of a small landmark map back
// onto it and writes / reads it through io, so the installed headers, libraries and dependencies all link.
#include <cmath>
#include <cstdio>
#include <random>

#include <Eigen/Geometry>

#include "weighted_icp/io/map_format.h"
#include "weighted_icp/metrics/trajectory_error.h"
#include "weighted_icp/registration/landmark_alignment.h"
#include "weighted_icp/version.h"

int main(int argc, char** argv) {
  using namespace weighted_icp;
  if (argc != 2) {
    std::fprintf(stderr, "usage: consumer SCRATCH_MAP.txt\n");
    return 2;
  }
  LandmarkMap map;
  map.frames[0] = Eigen::Isometry3d::Identity();
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coordinate(-2.0, 2.0);
  for (LandmarkId id = 0; id < 200; ++id) {
    Landmark landmark;
    landmark.id = id;
    landmark.position = Eigen::Vector3d(coordinate(random), coordinate(random), coordinate(random));
    landmark.covariance = Eigen::Matrix3d::Identity() * 1e-4;
    landmark.observations.push_back({0, 320.0, 240.0});
    map.landmarks.push_back(landmark);
  }
  io::writeLandmarkMap(map, argv[1]);
  const LandmarkMap target = io::readLandmarkMap(argv[1]);

  LandmarkMap source = target;
  const Eigen::Isometry3d displacement(Eigen::Translation3d(0.05, -0.03, 0.02) *
                                       Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitZ()));
  source.transform(displacement);
  AlignmentSettings settings;
  settings.k = 1;
  const AlignmentResult result = alignLandmarkMaps(source, target, CovarianceWeight{}, settings);
  // The alignment must undo the displacement.
  const Eigen::Matrix4d error = result.transformation * displacement.matrix() - Eigen::Matrix4d::Identity();
  std::printf("weighted_icp %s: converged %d after %d iterations, residual %.2e\n", WEIGHTED_ICP_VERSION_STRING,
              result.converged ? 1 : 0, result.iterations, error.norm());
  return result.converged && error.norm() < 1e-3 ? 0 : 1;
}
