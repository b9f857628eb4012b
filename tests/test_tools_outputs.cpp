// wicp_rgbd_slam's outputs are all or nothing (#10): a failed, refused or
// interrupted run exits non-zero with an error line and leaves --out as it
// was; a re-run publishes a whole folder, never a mix of two runs.

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "test_support.h"
#include "tool_runner.h"

namespace {

namespace fs = std::filesystem;
using weighted_icp::testing::binaryDir;
using weighted_icp::testing::readFile;
using weighted_icp::testing::runBuiltTool;
using weighted_icp::testing::scratchDir;
using weighted_icp::testing::ToolRun;
using weighted_icp::testing::writeFile;

fs::path tool(const std::string& name) { return binaryDir() / "examples" / name; }

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

/// Every name in `dir`.
std::vector<std::string> entries(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

/// Waits until a tool writing its stderr to `err` shows a progress line ("... (N%)"), so that a signal sent
/// now reaches the running work, not a process still loading its libraries (seconds on a loaded machine,
/// before the handlers are installed); gives up after a minute.
void waitForProgress(const fs::path& err) {
  for (int i = 0; i < 3000 && !contains(readFile(err), "%)"); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
}

/// A short synthetic sequence in the TUM layout, which wicp_rgbd_slam tracks
/// completely with the fr1 camera; the tests spoil one part of it.
fs::path exportSequence(const fs::path& scratch, int frames) {
  const fs::path dir = scratch / "seq";
  const ToolRun r = runBuiltTool("wicp_synthetic_rgbd",
                                 "--frames " + std::to_string(frames) + " --out '" + dir.string() + "'", scratch);
  EXPECT_EQ(r.status, 0) << r.err;
  return dir;
}

/// Replaces every image in `folder` by a black one of the same size and type.
void blankImages(const fs::path& folder) {
  for (const auto& entry : fs::directory_iterator(folder)) {
    const cv::Mat image = cv::imread(entry.path().string(), cv::IMREAD_UNCHANGED);
    ASSERT_TRUE(cv::imwrite(entry.path().string(), cv::Mat::zeros(image.size(), image.type())));
  }
}

std::string slamArgs(const fs::path& seq, const fs::path& out, const std::string& extra = "") {
  return "--dataset '" + seq.string() + "' --camera fr1 --deterministic --out '" + out.string() + "' " + extra;
}

/// The error line, and nothing at all in the folder that holds --out but
/// what was there before (no output, no temporary folder).
void expectFailedWithNothingWritten(const ToolRun& r, const fs::path& parent, const std::vector<std::string>& before,
                                    const std::string& message) {
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_TRUE(contains(r.err, "wicp_rgbd_slam: error: ")) << r.err;
  EXPECT_TRUE(contains(r.err, message)) << r.err;
  EXPECT_EQ(entries(parent), before);
}

TEST(WicpRgbdSlamFailures, UnusableInputFailsWithAnErrorLineAndWritesNothing) {
  const fs::path scratch = scratchDir("slam_failures");
  const fs::path seq = exportSequence(scratch, 4);
  const fs::path parent = scratch / "outputs";
  fs::create_directories(parent);
  const auto before = entries(parent);  // empty

  blankImages(seq / "rgb");  // all-black RGB: no features
  ToolRun r = runBuiltTool("wicp_rgbd_slam", slamArgs(seq, parent / "out"), scratch);
  expectFailedWithNothingWritten(r, parent, before, "no frame was tracked");

  const fs::path seq2 = exportSequence(scratchDir("slam_failures_depth"), 4);
  blankImages(seq2 / "depth");  // all-zero depth: nothing to map
  r = runBuiltTool("wicp_rgbd_slam", slamArgs(seq2, parent / "out"), scratch);
  expectFailedWithNothingWritten(r, parent, before, "no frame was tracked");  // every frame lost

  // An absurd depth factor is refused when the camera is read, by key.
  const fs::path camera = scratch / "camera.yaml";
  writeFile(camera,
            "%YAML:1.0\nfx: 517.3\nfy: 516.5\ncx: 318.6\ncy: 255.3\nk1: 0\nk2: 0\np1: 0\np2: 0\nk3: 0\n"
            "width: 640\nheight: 480\ndepth_factor: 0.005\n");
  r = runBuiltTool(
      "wicp_rgbd_slam",
      "--dataset '" + seq2.string() + "' --camera '" + camera.string() + "' --out '" + (parent / "out").string() + "'",
      scratch);
  expectFailedWithNothingWritten(r, parent, before, "depth_factor must be between");
}

TEST(WicpRgbdSlamFailures, GroundTruthWithoutCommonTimestampsIsAWarningAndTheReportSaysWhy) {
  const fs::path scratch = scratchDir("slam_no_ate");
  const fs::path seq = exportSequence(scratch, 4);
  writeFile(seq / "groundtruth.txt",
            "# far from every frame\n1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1\n3.0 0 0 0 0 0 0 1\n");
  const fs::path out = scratch / "out";
  const ToolRun r = runBuiltTool("wicp_rgbd_slam", slamArgs(seq, out), scratch);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "wicp_rgbd_slam: warning: no ATE")) << r.err;
  const std::string report = readFile(out / "report.json");
  EXPECT_TRUE(contains(report, "\"ate_unavailable\":\"")) << report;
  EXPECT_FALSE(contains(report, "ate_rmse_m")) << report;
  // Without an ATE the picture is the camera path itself (and its loops), not nothing.
  if (!contains(r.err, "matplotlib is not installed"))
    EXPECT_TRUE(weighted_icp::testing::isPng(out / "trajectory.png"));
}

TEST(WicpRgbdSlamOutputs, FramesTxtSaysHowEveryFrameWasTrackedAndWhyOneWasNot) {
  const fs::path scratch = scratchDir("slam_frames_txt");
  const fs::path seq = exportSequence(scratch, 12);
  // Frame 6's colour image black: no corners, so it cannot be tracked.
  std::vector<fs::path> images;
  for (const auto& entry : fs::directory_iterator(seq / "rgb")) images.push_back(entry.path());
  std::sort(images.begin(), images.end());
  ASSERT_EQ(images.size(), 12u);
  const cv::Mat image = cv::imread(images[6].string(), cv::IMREAD_UNCHANGED);
  ASSERT_TRUE(cv::imwrite(images[6].string(), cv::Mat::zeros(image.size(), image.type())));
  const fs::path out = scratch / "out";
  const ToolRun r = runBuiltTool("wicp_rgbd_slam", slamArgs(seq, out, "--no-loop-closure"), scratch);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "why: frames.txt")) << r.out;
  std::ifstream in(out / "frames.txt");
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  EXPECT_EQ(line,
            "# index timestamp status predicted keyframe features matches inliers dynamic quality_score tracking_ms "
            "reason");
  std::vector<std::string> statuses, reasons;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::size_t index = 0, features = 0, matches = 0, inliers = 0, dynamic = 0;
    int predicted = 0, keyframe = 0;
    double timestamp = 0.0, score = 0.0, ms = 0.0;
    std::string status, reason;
    ASSERT_TRUE(fields >> index >> timestamp >> status >> predicted >> keyframe >> features >> matches >> inliers >>
                dynamic >> score >> ms)
        << line;
    std::getline(fields, reason);
    EXPECT_EQ(index, statuses.size()) << line;
    EXPECT_GT(ms, 0.0) << line;
    if (status == "tracked") {
      EXPECT_GT(inliers, 0u) << line;
      EXPECT_EQ(reason, " -") << line;
    }
    statuses.push_back(status);
    reasons.push_back(reason);
  }
  ASSERT_EQ(statuses.size(), 12u);
  EXPECT_EQ(statuses[0], "initialized");
  EXPECT_NE(statuses[6], "tracked");
  EXPECT_NE(reasons[6], " -");  // why, in words
  EXPECT_EQ(statuses[5], "tracked");
}

TEST(WicpRgbdSlamOutputs, AReRunReplacesTheWholeFolderOnlyWithOverwrite) {
  const fs::path scratch = scratchDir("slam_rerun");
  const fs::path seq = exportSequence(scratch, 4);
  const fs::path out = scratch / "out";
  ASSERT_EQ(runBuiltTool("wicp_rgbd_slam", slamArgs(seq, out), scratch).status, 0);
  // An older run's file the new run will not write, as a longer run's mini-map.
  writeFile(out / "minimaps" / "minimap_007.txt", "stale");
  const std::string trajectory = readFile(out / "trajectory.txt");

  ToolRun r = runBuiltTool("wicp_rgbd_slam", slamArgs(seq, out), scratch);
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(contains(r.err, "not empty")) << r.err;
  EXPECT_TRUE(contains(r.err, "--overwrite")) << r.err;
  EXPECT_TRUE(fs::exists(out / "minimaps" / "minimap_007.txt")) << "refused, yet changed";

  blankImages(seq / "rgb");  // a failed re-run, even with --overwrite, keeps the old folder whole
  r = runBuiltTool("wicp_rgbd_slam", slamArgs(seq, out, "--overwrite"), scratch);
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(readFile(out / "trajectory.txt"), trajectory);
  EXPECT_TRUE(fs::exists(out / "map.ply"));

  const fs::path seq2 = exportSequence(scratchDir("slam_rerun_2"), 4);
  r = runBuiltTool("wicp_rgbd_slam", slamArgs(seq2, out, "--overwrite"), scratch);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_FALSE(fs::exists(out / "minimaps" / "minimap_007.txt")) << "an older run's file survived the re-run";
  EXPECT_EQ(readFile(out / "trajectory.txt"), trajectory) << "the same frames, deterministic: the same trajectory";
  EXPECT_EQ(entries(scratch), (std::vector<std::string>{"out", "seq"}));
}

/// Ctrl-C a second into a run on the synthetic sequence (150 frames, several
/// seconds): it stops between frames, joins the bundle-adjustment thread, says
/// so and writes nothing.
TEST(WicpRgbdSlamOutputs, SigintStopsCleanlyAndWritesNothing) {
  for (const int signal : {SIGINT, SIGTERM}) {
    const fs::path scratch = scratchDir(signal == SIGINT ? "slam_sigint" : "slam_sigterm");
    const fs::path out = scratch / "out", err = scratch / "err.txt";
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      std::freopen(err.c_str(), "w", stderr);
      std::freopen("/dev/null", "w", stdout);
      const std::string path = tool("wicp_rgbd_slam").string(), out_text = out.string();
      ::execl(path.c_str(), path.c_str(), "--out", out_text.c_str(), static_cast<char*>(nullptr));
      std::_Exit(127);
    }
    waitForProgress(err);
    ::kill(pid, signal);
    int status = 0;
    ::waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFEXITED(status)) << "killed by the signal instead of stopping";
    EXPECT_EQ(WEXITSTATUS(status), 128 + signal);
    const std::string message = readFile(err);
    EXPECT_TRUE(contains(message, signal == SIGINT ? "interrupted by SIGINT" : "interrupted by SIGTERM")) << message;
    EXPECT_TRUE(contains(message, "no outputs written")) << message;
    EXPECT_EQ(entries(scratch), std::vector<std::string>{"err.txt"}) << "partial outputs left";
  }
}

/// wicp_demo stopped by Ctrl-C: exit 130, says so, leaves no --out folder.
TEST(WicpDemo, SigintStopsCleanlyAndWritesNothing) {
  const fs::path scratch = scratchDir("demo_sigint");
  const fs::path out = scratch / "out", err = scratch / "err.txt";
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    std::freopen(err.c_str(), "w", stderr);
    std::freopen("/dev/null", "w", stdout);
    const std::string path = tool("wicp_demo").string(), out_text = out.string();
    // A session larger than the default, so that its first progress line is surely mid-run.
    ::execl(path.c_str(), path.c_str(), "--frames", "1200", "--landmarks", "20000", "--out", out_text.c_str(),
            static_cast<char*>(nullptr));
    std::_Exit(127);
  }
  waitForProgress(err);
  ::kill(pid, SIGINT);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by the signal instead of stopping";
  EXPECT_EQ(WEXITSTATUS(status), 130);
  EXPECT_TRUE(contains(readFile(err), "wicp_demo: interrupted by SIGINT")) << readFile(err);
  EXPECT_EQ(entries(scratch), std::vector<std::string>{"err.txt"}) << "partial outputs left";
}

/// A small demo run (4 mini-maps of 20 frames), with `extra` options.
std::string demoArgs(const fs::path& out, const std::string& extra) {
  return "--frames 80 --landmarks 2000 --out '" + out.string() + "' " + extra;
}

TEST(WicpDemoOutputs, AReRunNeedsOverwriteAndLeavesNoStaleFile) {
  const fs::path scratch = scratchDir("demo_rerun");
  const fs::path out = scratch / "out";
  ASSERT_EQ(runBuiltTool("wicp_demo", demoArgs(out, "--frames-per-minimap 20"), scratch).status, 0);
  ASSERT_EQ(entries(out / "minimaps").size(), 4u);

  ToolRun r = runBuiltTool("wicp_demo", demoArgs(out, "--frames-per-minimap 40"), scratch);
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(contains(r.err, "not empty") && contains(r.err, "--overwrite")) << r.err;
  EXPECT_EQ(entries(out / "minimaps").size(), 4u) << "refused, yet changed";

  r = runBuiltTool("wicp_demo", demoArgs(out, "--frames-per-minimap 40 --overwrite"), scratch);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(entries(out / "minimaps"), (std::vector<std::string>{"minimap_000.txt", "minimap_001.txt"}));
  EXPECT_EQ(entries(scratch), std::vector<std::string>{"out"}) << "a temporary folder was left";
}

TEST(WicpDemoOutputs, AFailedRunLeavesTheEarlierOutputWhole) {
  const fs::path scratch = scratchDir("demo_failed");
  const fs::path out = scratch / "out";
  ASSERT_EQ(runBuiltTool("wicp_demo", demoArgs(out, "--frames-per-minimap 20"), scratch).status, 0);
  const std::string results = readFile(out / "results.csv");
  // Fails after the session is generated: no mini-map has a landmark seen that often.
  const ToolRun r = runBuiltTool("wicp_demo", demoArgs(out, "--min-observations 1000000 --overwrite"), scratch);
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(contains(r.err, "wicp_demo: error: ")) << r.err;
  EXPECT_EQ(readFile(out / "results.csv"), results);
  EXPECT_EQ(entries(out / "minimaps").size(), 4u);
  EXPECT_EQ(entries(scratch), std::vector<std::string>{"out"}) << "a temporary folder was left";
}

/// A sweep stopped by Ctrl-C publishes nothing: an earlier sweep's folder stays whole even with --overwrite.
TEST(WicpSweepOutputs, SigintLeavesTheEarlierSweepWhole) {
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::realMapPath());
  const fs::path scratch = scratchDir("sweep_sigint");
  const fs::path out = scratch / "out", err = scratch / "err.txt";
  fs::create_directories(out);
  writeFile(out / "results.csv", "an earlier sweep\n");
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    std::freopen(err.c_str(), "w", stderr);
    std::freopen("/dev/null", "w", stdout);
    const std::string path = tool("wicp_sweep_k").string(), map = weighted_icp::testing::realMapPath().string(),
                      out_text = out.string();
    // 110 runs on the real map: many seconds, so the first progress line is surely before the end.
    ::execl(path.c_str(), path.c_str(), "--map", map.c_str(), "--threads", "1", "--no-plot", "--overwrite", "--out",
            out_text.c_str(), static_cast<char*>(nullptr));
    std::_Exit(127);
  }
  waitForProgress(err);
  ::kill(pid, SIGINT);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by the signal instead of stopping";
  EXPECT_EQ(WEXITSTATUS(status), 130) << readFile(err);
  EXPECT_TRUE(contains(readFile(err), "interrupted by SIGINT") && contains(readFile(err), "no outputs written"))
      << readFile(err);
  EXPECT_EQ(entries(out), std::vector<std::string>{"results.csv"});
  EXPECT_EQ(readFile(out / "results.csv"), "an earlier sweep\n");
  EXPECT_EQ(entries(scratch), (std::vector<std::string>{"err.txt", "out"})) << "a temporary folder was left";
}

/// A sweep re-run with --overwrite leaves no file of the earlier one (here a plot the new run does not draw).
TEST(WicpSweepOutputs, AReRunWithOverwriteLeavesNoStaleFile) {
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::realMapPath());
  const fs::path scratch = scratchDir("sweep_rerun");
  const fs::path out = scratch / "out";
  fs::create_directories(out);
  writeFile(out / "violin.png", "an earlier sweep's plot");
  const std::string args = "--map '" + weighted_icp::testing::realMapPath().string() +
                           "' --source-frames 0-59 --target-frames 40-99 --max-iterations 3 --threads 1 --no-plot "
                           "--out '" +
                           out.string() + "'";
  ToolRun r = runBuiltTool("wicp_sweep_yaw", args, scratch);
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(contains(r.err, "--overwrite")) << r.err;
  r = runBuiltTool("wicp_sweep_yaw", args + " --overwrite", scratch);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(entries(out), (std::vector<std::string>{"results.csv", "run.json"}));
}

}  // namespace
