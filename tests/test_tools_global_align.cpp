// wicp_align --global: the JSON contract of wicp_align, with the start found
// from geometry alone (a yaw of 180° no local ICP recovers); maps written in
// their first camera's frame, levelled by their cameras (--up-axis auto).

#include <cmath>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "test_landmark_pairs.h"
#include "test_support.h"
#include "tool_runner.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/registration/rigid_motion.h"

namespace {

namespace fs = std::filesystem;

/// The real map as a SLAM without gravity writes it: in its first camera's frame, where up is near -y. `up` is the
/// true up (the world's z) in that frame.
struct CameraFrameMap {
  weighted_icp::LandmarkMap map;
  Eigen::Vector3d up;
};
CameraFrameMap realMapInItsFirstCamerasFrame() {
  weighted_icp::LandmarkMap map = weighted_icp::io::readLandmarkMap(weighted_icp::testing::realMapPath().string());
  const Eigen::Isometry3d first = map.toFirstCameraFrame();
  return {map, first.linear().transpose() * Eigen::Vector3d::UnitZ()};
}

/// The transformation of wicp_align's JSON line within 2° and 5 cm of `truth`.
void expectWithinTarget(const std::string& json, const Eigen::Isometry3d& truth) {
  const Eigen::Isometry3d t(weighted_icp::testing::alignTransformation(json));
  EXPECT_LT(weighted_icp::rotationErrorDeg(t, truth), 2.0) << json;
  EXPECT_LT(weighted_icp::translationError(t, truth), 0.05) << json;
}

TEST(WicpAlignGlobal, RecoversYaw180AndKeepsTheJsonContract) {
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::realMapPath());
  const fs::path scratch = weighted_icp::testing::scratchDir("wicp_align_global");
  const std::string map = weighted_icp::testing::realMapPath().string();
  const auto r = weighted_icp::testing::runBuiltTool(
      "wicp_align", "--source " + map + " --target " + map + " --displace \"1 -1.5 0 0 0 180\" --global --json",
      scratch);
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string json = weighted_icp::testing::lastLine(r.out);
  for (const char* key : {"\"transformation\":[[", "\"fitness_score\":", "\"iterations\":", "\"converged\":true",
                          "\"correspondences\":", "\"time_ms\":", "\"reversed\":false"})
    EXPECT_NE(json.find(key), std::string::npos) << key << " missing from " << json;
  expectWithinTarget(json, weighted_icp::Displacement{1, -1.5, 0, 0, 0, 180}.toIsometry().inverse());
}

TEST(WicpAlignGlobal, LevelsMapsWrittenInTheirFirstCamerasFrameByTheirCameras) {
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::realMapPath());
  const fs::path scratch = weighted_icp::testing::scratchDir("wicp_align_global_camera_frame");
  const auto [map, up] = realMapInItsFirstCamerasFrame();
  const std::string path = (scratch / "camera_frame.txt").string();
  weighted_icp::io::writeLandmarkMap(map, path);
  // A turn of 120° about the true up and 1.5 m across it.
  Eigen::Isometry3d moved = Eigen::Isometry3d::Identity();
  moved.linear() = Eigen::AngleAxisd(120.0 * M_PI / 180.0, up).toRotationMatrix();
  moved.translation() = 1.5 * up.unitOrthogonal();
  weighted_icp::LandmarkMap source = map;
  source.transform(moved);
  const std::string source_path = (scratch / "moved.txt").string();
  weighted_icp::io::writeLandmarkMap(source, source_path);

  const auto r = weighted_icp::testing::runBuiltTool(
      "wicp_align", "--source " + source_path + " --target " + path + " --global --json", scratch);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("each map levelled by its cameras"), std::string::npos) << r.out;
  const std::string json = weighted_icp::testing::lastLine(r.out);
  EXPECT_NE(json.find("\"up_axis_target\":["), std::string::npos) << json;
  expectWithinTarget(json, moved.inverse());

  // Searched about z, as before the up axis was estimated, the same pair is not recovered.
  const auto z = weighted_icp::testing::runBuiltTool(
      "wicp_align", "--source " + source_path + " --target " + path + " --global --up-axis z --json", scratch);
  const Eigen::Matrix4d tz = weighted_icp::testing::alignTransformation(weighted_icp::testing::lastLine(z.out));
  EXPECT_GT(weighted_icp::rotationErrorDeg(Eigen::Isometry3d(tz), moved.inverse()), 2.0);
}

// A mini-map whose cameras face about one way (the real map's frames 150-189, in its first camera's frame, turned 90°
// about up) onto the whole map: its pitched levellings are looked at first, the tool says how many it searched, and
// the pose is recovered.
TEST(WicpAlignGlobal, SaysHowManyPitchedLevellingsOfAOneHeadingMiniMapItSearched) {
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::realMapPath());
  const fs::path scratch = weighted_icp::testing::scratchDir("wicp_align_global_one_heading");
  const auto [map, up] = realMapInItsFirstCamerasFrame();
  auto [whole, mini] = weighted_icp::testing::mapAndMiniMap(map, 150, 189);
  Eigen::Isometry3d moved = Eigen::Isometry3d::Identity();
  moved.linear() = Eigen::AngleAxisd(M_PI / 2.0, up).toRotationMatrix();
  mini.transform(moved);
  const std::string whole_path = (scratch / "whole.txt").string(), mini_path = (scratch / "mini.txt").string();
  weighted_icp::io::writeLandmarkMap(whole, whole_path);
  weighted_icp::io::writeLandmarkMap(mini, mini_path);

  const auto r = weighted_icp::testing::runBuiltTool(
      "wicp_align", "--source " + mini_path + " --target " + whole_path + " --global --json", scratch);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("about its cameras' rows (they face about one way)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("6 pitched levellings looked at first, "), std::string::npos) << r.out;
  expectWithinTarget(weighted_icp::testing::lastLine(r.out), moved.inverse());
}

}  // namespace
