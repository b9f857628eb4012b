// The command-line contracts other tools rely on: wicp_align's JSON line and
// exit codes, wicp_rgbd_slam's output folder.

#include <array>
#include <cstdio>
#include <fstream>
#include <regex>
#include <sstream>

#include <gtest/gtest.h>

#include "test_support.h"
#include "tool_runner.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/io/trajectory.h"
#include "weighted_icp/registration/rigid_motion.h"

namespace {

namespace fs = std::filesystem;
using weighted_icp::testing::binaryDir;

using weighted_icp::testing::ToolRun;

ToolRun run(const std::string& tool, const std::string& args, const fs::path& scratch) {
  return weighted_icp::testing::runBuiltTool(tool, args, scratch);
}

using weighted_icp::testing::lastLine;

double numberAfter(const std::string& json, const std::string& key) {
  const std::regex pattern("\"" + key + "\":(-?[0-9.eE+-]+)");
  std::smatch match;
  if (!std::regex_search(json, match, pattern)) throw std::runtime_error("no number for " + key + " in " + json);
  return std::stod(match[1]);
}

TEST(WicpAlign, JsonLineRecoversTheDisplacementOnTheRealMap) {
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::realMapPath());
  const fs::path scratch = weighted_icp::testing::scratchDir("wicp_align_json");
  const std::string map = weighted_icp::testing::realMapPath().string();
  const ToolRun r = run("wicp_align",
                        "--source " + map + " --target " + map +
                            " --strategy observations --displace \"0.1 0.05 0 0 0 8\" --refine --json",
                        scratch);
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string json = lastLine(r.out);
  ASSERT_EQ(json.front(), '{');
  for (const char* key : {"\"transformation\":[[", "\"fitness_score\":", "\"iterations\":", "\"converged\":true",
                          "\"correspondences\":", "\"time_ms\":"})
    EXPECT_NE(json.find(key), std::string::npos) << key << " missing from " << json;
  // The transformation, row-major as 4 rows, must undo the displacement.
  const Eigen::Matrix4d t = weighted_icp::testing::alignTransformation(json);
  const Eigen::Isometry3d truth = weighted_icp::Displacement{0.1, 0.05, 0, 0, 0, 8}.toIsometry().inverse();
  EXPECT_LT(weighted_icp::rotationErrorDeg(Eigen::Isometry3d(t), truth), 0.01);
  EXPECT_LT(weighted_icp::translationError(Eigen::Isometry3d(t), truth), 0.001);
  EXPECT_EQ(numberAfter(json, "correspondences"), 6081);
  EXPECT_GT(numberAfter(json, "time_ms"), 0.0);
}

TEST(WicpAlign, NoStopRuleRunsLongerToTheSamePose) {
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::realMapPath());
  const fs::path scratch = weighted_icp::testing::scratchDir("wicp_align_stop_rule");
  const std::string map = weighted_icp::testing::realMapPath().string();
  const std::string args = "--source " + map + " --target " + map +
                           " --strategy covariance --displace \"0.1 0.05 0.02 2 1 10\" --threads 1 --json";
  const ToolRun with = run("wicp_align", args, scratch);
  const ToolRun without = run("wicp_align", args + " --no-stop-rule", scratch);
  ASSERT_EQ(with.status, 0) << with.err;
  ASSERT_EQ(without.status, 0) << without.err;
  const std::string a = lastLine(with.out), b = lastLine(without.out);
  EXPECT_LT(numberAfter(a, "iterations"), numberAfter(b, "iterations"));
  const Eigen::Matrix4d difference =
      weighted_icp::testing::alignTransformation(a) - weighted_icp::testing::alignTransformation(b);
  // The run without the rule repeats its pose 78 more times (96 against 18 iterations), drifting by float
  // rounding of the moved points each time: measured 1.9e-6 in a matrix entry.
  EXPECT_LT(difference.cwiseAbs().maxCoeff(), 1e-5);
}

// PCL counts reaching the iteration limit as converged; wicp_align does not: exit 3, and the JSON says why.
TEST(WicpAlign, StoppingAtTheIterationLimitIsNotConvergence) {
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::realMapPath());
  const fs::path scratch = weighted_icp::testing::scratchDir("wicp_align_iteration_limit");
  const std::string map = weighted_icp::testing::realMapPath().string();
  const std::string args = "--source " + map + " --target " + map + " --displace \"0.3 0.2 0 0 0 30\" --json";
  const ToolRun cut = run("wicp_align", args + " --max-iterations 2", scratch);
  EXPECT_EQ(cut.status, 3) << cut.out << cut.err;
  EXPECT_NE(lastLine(cut.out).find("\"stopped_at_iteration_limit\":true"), std::string::npos) << cut.out;
  EXPECT_NE(cut.out.find("converged no after 2 iterations (stopped at the iteration limit"), std::string::npos)
      << cut.out;
  const ToolRun full = run("wicp_align", args, scratch);
  EXPECT_EQ(full.status, 0) << full.out << full.err;
  EXPECT_NE(lastLine(full.out).find("\"stopped_at_iteration_limit\":false"), std::string::npos) << full.out;
}

TEST(WicpAlign, BadInputGivesAClearErrorAndANonZeroExit) {
  const fs::path scratch = weighted_icp::testing::scratchDir("wicp_align_errors");
  const fs::path bad = scratch / "bad.txt";
  std::ofstream(bad) << "FRAME 0 0 0 0 1 0 0 0\nLANDMARK 1 0 0 nan\n";
  ToolRun r = run("wicp_align", "--source " + bad.string() + " --target " + bad.string(), scratch);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find(bad.string() + ":2"), std::string::npos) << r.err;
  r = run("wicp_align", "--source " + bad.string(), scratch);  // no --target
  EXPECT_EQ(r.status, 2) << r.err;
  // A bad value is a bad command line (exit 2), as in every other tool, refused before any file is read.
  r = run("wicp_align", "--source a --target b --strategy bogus", scratch);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--strategy: unknown strategy 'bogus'"), std::string::npos) << r.err;
  r = run("wicp_align", "--source a --target b --displace \"1 2 3\"", scratch);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--displace: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("expected 6"), std::string::npos) << r.err;
}

TEST(WicpRgbdSlam, WritesEveryOutputOnTheSyntheticSequence) {
  const fs::path out = weighted_icp::testing::scratchDir("wicp_rgbd_slam") / "out";
  const ToolRun r =
      run("wicp_rgbd_slam", "--synthetic-frames 45 --deterministic --minimap-keyframes 3 --out " + out.string(),
          out.parent_path());
  ASSERT_EQ(r.status, 0) << r.err;
  const auto trajectory = weighted_icp::io::readTrajectory((out / "trajectory.txt").string());
  EXPECT_EQ(trajectory.size(), 45u);
  std::ifstream report_file(out / "report.json");
  const std::string report((std::istreambuf_iterator<char>(report_file)), {});
  for (const char* key :
       {"frames", "tracked_frames", "keyframes", "landmarks", "median_ms_per_frame", "p90_ms_per_frame",
        "skipped_frames", "predicted_frames", "coasted_frames", "lost_frames", "ate_rmse_m"})
    EXPECT_NE(report.find(std::string("\"") + key + "\":"), std::string::npos) << key << " missing: " << report;
  EXPECT_LT(numberAfter(report, "ate_rmse_m"), 0.01);
  EXPECT_EQ(numberAfter(report, "tracked_frames"), 45);
  EXPECT_EQ(numberAfter(report, "coasted_frames"), 0);  // every frame of the synthetic sequence is measured
  std::size_t minimaps = 0;
  for (const auto& entry : fs::directory_iterator(out / "minimaps")) {
    const auto map = weighted_icp::io::readLandmarkMap(entry.path().string());
    EXPECT_FALSE(map.landmarks.empty()) << entry.path();
    EXPECT_LE(map.frames.size(), 3u);
    ++minimaps;
  }
  EXPECT_EQ(static_cast<double>(minimaps), numberAfter(report, "minimaps"));
  EXPECT_GE(minimaps, 2u);
  EXPECT_TRUE(fs::exists(out / "map.ply"));
  EXPECT_FALSE(weighted_icp::io::readLandmarkMap((out / "session.txt").string()).landmarks.empty());
}

TEST(WicpRgbdSlam, AMissingDatasetOrCameraFileFailsClearly) {
  const fs::path scratch = weighted_icp::testing::scratchDir("wicp_rgbd_slam_errors");
  ToolRun r =
      run("wicp_rgbd_slam",
          "--dataset " + (scratch / "nothing").string() + " --camera fr1 --out " + (scratch / "out").string(), scratch);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("nothing"), std::string::npos) << r.err;
  const fs::path camera = scratch / "camera.yaml";
  std::ofstream(camera) << "%YAML:1.0\n---\nfx: 500\nfy: 500\n";
  r = run("wicp_rgbd_slam",
          "--camera " + camera.string() + " --dataset " + scratch.string() + " --out " + (scratch / "out").string(),
          scratch);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("cx"), std::string::npos) << r.err;  // names a missing key
  r = run("wicp_rgbd_slam", "", scratch);                   // --out is required
  EXPECT_EQ(r.status, 2);
}

}  // namespace
