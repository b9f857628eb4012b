// wicp_align --global: the JSON contract of wicp_align, with the start found
// from geometry alone (a yaw of 180° no local ICP recovers).

#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "test_support.h"
#include "tool_runner.h"
#include "weighted_icp/registration/rigid_motion.h"

namespace {

namespace fs = std::filesystem;

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
                          "\"correspondences\":", "\"time_ms\":"})
    EXPECT_NE(json.find(key), std::string::npos) << key << " missing from " << json;
  const Eigen::Matrix4d t = weighted_icp::testing::alignTransformation(json);
  const Eigen::Isometry3d truth = weighted_icp::Displacement{1, -1.5, 0, 0, 0, 180}.toIsometry().inverse();
  EXPECT_LT(weighted_icp::rotationErrorDeg(Eigen::Isometry3d(t), truth), 2.0);
  EXPECT_LT(weighted_icp::translationError(Eigen::Isometry3d(t), truth), 0.05);
}

}  // namespace
