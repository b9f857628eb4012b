// The tools' pictures: wicp_evaluate --plot and wicp_align --plot write a PNG, and without a usable Python
// (or matplotlib) they warn and still succeed, leaving no file.

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "test_support.h"
#include "tool_runner.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/io/trajectory.h"

using namespace weighted_icp;
using weighted_icp::testing::isPng;
using weighted_icp::testing::runBuiltTool;
namespace fs = std::filesystem;

namespace {

/// A ground truth along a curve and an estimate off it by a growing error.
void writeTrajectories(const fs::path& dir) {
  Trajectory truth, estimate;
  for (int i = 0; i < 60; ++i) {
    StampedPose pose;
    pose.timestamp = 0.05 * i;
    pose.pose.translation() = Eigen::Vector3d(0.02 * i, std::sin(0.1 * i), 0.5);
    truth.push_back(pose);
    pose.pose.translation() += Eigen::Vector3d(0.0, 0.001 * i, -0.0005 * i);
    estimate.push_back(pose);
  }
  io::writeTrajectory(truth, (dir / "gt.txt").string());
  io::writeTrajectory(estimate, (dir / "est.txt").string());
}

/// A map of scattered landmarks, and the same moved a little, as the two maps of an alignment.
void writeMaps(const fs::path& dir) {
  LandmarkMap map;
  map.frames[0] = Eigen::Isometry3d::Identity();
  for (LandmarkId id = 0; id < 300; ++id) {
    Landmark landmark;
    landmark.id = id;
    landmark.position = Eigen::Vector3d(std::sin(1.3 * id), std::cos(0.7 * id), 0.01 * static_cast<double>(id % 50));
    landmark.covariance = Eigen::Matrix3d::Identity() * (1e-4 * static_cast<double>(1 + id % 7));
    landmark.observations = {{0, 1.0, 1.0}, {0, 2.0, 2.0}};
    map.landmarks.push_back(landmark);
  }
  io::writeLandmarkMap(map, (dir / "b.txt").string());
  map.transform(Eigen::Isometry3d(Eigen::Translation3d(0.03, -0.02, 0.0)));
  io::writeLandmarkMap(map, (dir / "a.txt").string());
}

/// Skips the test when the tool said matplotlib is missing: the picture cannot be checked here.
#define SKIP_WITHOUT_MATPLOTLIB(run)                                      \
  if ((run).err.find("matplotlib is not installed") != std::string::npos) \
  GTEST_SKIP() << "matplotlib is not installed for the build's Python: " << (run).err

}  // namespace

TEST(ToolsPlots, EvaluateDrawsTheTrajectoriesAndErrors) {
  const fs::path dir = weighted_icp::testing::scratchDir("evaluate");
  writeTrajectories(dir);
  const auto run = runBuiltTool(
      "wicp_evaluate",
      (dir / "gt.txt").string() + " " + (dir / "est.txt").string() + " --plot " + (dir / "ate.png").string(), dir, 120);
  EXPECT_EQ(run.status, 0) << run.err;
  SKIP_WITHOUT_MATPLOTLIB(run);
  EXPECT_EQ(run.err.find("warning"), std::string::npos) << run.err;
  EXPECT_TRUE(isPng(dir / "ate.png"));
}

TEST(ToolsPlots, AlignDrawsTheCloudsBeforeAndAfter) {
  const fs::path dir = weighted_icp::testing::scratchDir("align");
  writeMaps(dir);
  const auto run = runBuiltTool("wicp_align",
                                "--source " + (dir / "a.txt").string() + " --target " + (dir / "b.txt").string() +
                                    " --k 3 --plot " + (dir / "align.png").string(),
                                dir, 120);
  EXPECT_EQ(run.status, 0) << run.err;
  SKIP_WITHOUT_MATPLOTLIB(run);
  EXPECT_TRUE(isPng(dir / "align.png")) << run.err;
}

TEST(ToolsPlots, WithoutPythonTheToolWarnsAndSucceeds) {
  const fs::path dir = weighted_icp::testing::scratchDir("no_python");
  writeTrajectories(dir);
  ::setenv("WEIGHTED_ICP_PLOT_PYTHON", (dir / "no_such_python").c_str(), 1);
  const auto run = runBuiltTool("wicp_evaluate",
                                (dir / "gt.txt").string() + " " + (dir / "est.txt").string() + " --plot " +
                                    (dir / "ate.png").string() + " --json",
                                dir, 120);
  ::unsetenv("WEIGHTED_ICP_PLOT_PYTHON");
  EXPECT_EQ(run.status, 0) << run.err;
  EXPECT_NE(run.err.find("wicp_evaluate: warning: no plot"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("no_such_python"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(dir / "ate.png"));
  EXPECT_NE(run.out.find("\"ate_rmse_m\""), std::string::npos);  // the numbers are still there
}

// A plotting script that fails: the warning ends with what it said last (a traceback's last line), and the
// traceback itself does not reach the tool's stderr.
TEST(ToolsPlots, AFailingPlotterIsOneWarningLineNotATraceback) {
  const fs::path dir = weighted_icp::testing::scratchDir("failing_plotter");
  writeTrajectories(dir);
  const fs::path fake = dir / "failing_python";
  {
    std::ofstream script(fake);
    script << "#!/bin/sh\n"
              "echo 'Traceback (most recent call last):' >&2\n"
              "echo '  File \"plot_results.py\", line 1, in <module>' >&2\n"
              "echo 'ValueError: the plotter broke' >&2\n"
              "exit 1\n";
  }
  fs::permissions(fake, fs::perms::owner_all);
  ::setenv("WEIGHTED_ICP_PLOT_PYTHON", fake.c_str(), 1);
  const auto run = runBuiltTool(
      "wicp_evaluate",
      (dir / "gt.txt").string() + " " + (dir / "est.txt").string() + " --plot " + (dir / "ate.png").string(), dir, 120);
  ::unsetenv("WEIGHTED_ICP_PLOT_PYTHON");
  EXPECT_EQ(run.status, 0) << run.err;
  EXPECT_NE(run.err.find("wicp_evaluate: warning: no plot"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("ValueError: the plotter broke"), std::string::npos) << run.err;
  EXPECT_EQ(run.err.find("most recent call last"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(dir / "ate.png"));
}

// A picture asked for in a folder that does not exist: a warning naming the folder, the numbers still printed.
// A picture asked for in a folder that does not exist is a wrong command line: refused before the work (exit 2,
// the folder named), rather than warned about at the end of a run whose picture is then missing.
TEST(ToolsPlots, APictureInAMissingFolderIsRefusedBeforeTheWork) {
  const fs::path dir = weighted_icp::testing::scratchDir("missing_folder");
  writeMaps(dir);
  const fs::path png = dir / "no" / "such" / "align.png";
  const auto run = runBuiltTool("wicp_align",
                                "--source " + (dir / "a.txt").string() + " --target " + (dir / "b.txt").string() +
                                    " --plot " + png.string() + " --json",
                                dir, 120);
  EXPECT_EQ(run.status, 2) << run.err;
  EXPECT_NE(run.err.find("no folder " + (dir / "no" / "such").string()), std::string::npos) << run.err;
  EXPECT_EQ(run.out.find("\"fitness_score\""), std::string::npos) << "the alignment ran: " << run.out;
  EXPECT_FALSE(fs::exists(png));
}
