// Numeric options of every tool are range-checked as they are parsed (issue
// #10): a negative count must not wrap into a huge unsigned one, an absurd
// thread count must not reach libgomp; each is a command-line error (exit 2)
// naming the option, the range and the value. And wicp_align refuses maps it
// cannot index and reports degenerate problems with their own exit code.

#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include <sys/wait.h>

#include <gtest/gtest.h>

#include "test_support.h"
#include "tool_runner.h"

namespace {

namespace fs = std::filesystem;
using weighted_icp::testing::binaryDir;
using weighted_icp::testing::scratchDir;

using weighted_icp::testing::ToolRun;

/// At most 60 s: an option that makes a tool run forever fails the test.
ToolRun run(const std::string& tool, const std::string& args, const fs::path& scratch) {
  return weighted_icp::testing::runBuiltTool(tool, args, scratch, 60);
}

struct BadOption {
  const char* tool;
  const char* args;
  const char* message;  // expected in stderr
};

TEST(ToolOptions, OutOfRangeNumbersAreCommandLineErrorsNamingTheOption) {
  const fs::path scratch = scratchDir("options");
  const BadOption cases[] = {
      {"wicp_align", "--source a --target b --k -1", "--k must be between 1 and 1000 (got -1)"},
      {"wicp_align", "--source a --target b --k 4294967295", "--k must be between 1 and 1000 (got 4294967295)"},
      {"wicp_align", "--source a --target b --k 100000", "--k must be between 1 and 1000 (got 100000)"},
      {"wicp_align", "--source a --target b --threads 100000", "--threads must be between 0 and 1024 (got 100000)"},
      {"wicp_align", "--source a --target b --threads -1", "--threads must be between 0 and 1024 (got -1)"},
      {"wicp_align", "--source a --target b --min-observations -1", "--min-observations must be between 0"},
      {"wicp_align", "--source a --target b --max-iterations 0", "--max-iterations must be between 1"},
      {"wicp_align", "--source a --target b --max-correspondence-distance -2",
       "--max-correspondence-distance must be greater than 0 (got -2)"},
      {"wicp_align", "--source a --target b --k five", "--k must be an integer between 1 and 1000 (got five)"},
      {"wicp_demo", "--k 0", "--k must be between 1 and 1000 (got 0)"},
      {"wicp_demo", "--threads 2000", "--threads must be between 0 and 1024 (got 2000)"},
      {"wicp_demo", "--seed -1", "--seed must be at least 0 (got -1)"},
      {"wicp_demo", "--frames 100 --frames-per-minimap 100", "--frames-per-minimap must be between 1 and 99 (got 100)"},
      {"wicp_map", "stats a --min-observations -1", "--min-observations must be at least 0 (got -1)"},
      {"wicp_map", "cut a --out b --frames-per-minimap 0", "--frames-per-minimap must be at least 1 (got 0)"},
      {"wicp_map", "convert a b --min-observations -3", "--min-observations must be at least 0 (got -3)"},
      {"wicp_evaluate", "a b --rpe-delta -1", "--rpe-delta must be greater than 0 (got -1)"},
      {"wicp_evaluate", "a b --plot /nonexistent_wicp_dir/ate.png",
       "--plot /nonexistent_wicp_dir/ate.png: no folder /nonexistent_wicp_dir to write it in"},
      {"wicp_align", "--source a --target b --plot /nonexistent_wicp_dir/align.png",
       "--plot /nonexistent_wicp_dir/align.png: no folder /nonexistent_wicp_dir to write it in"},
      {"wicp_evaluate", "a b --max-difference nan", "--max-difference must be greater than 0 (got nan)"},
      {"wicp_rgbd_slam", "--out x --max-frames -1", "--max-frames must be at least 0 (got -1)"},
      {"wicp_rgbd_slam", "--out x --minimap-keyframes -1", "--minimap-keyframes must be between 1 and 100000"},
      {"wicp_rgbd_slam", "--out x --seed -1", "--seed must be at least 0 (got -1)"},
      {"wicp_rgbd_slam", "--out x --synthetic-frames -1", "--synthetic-frames must be between 1 and 100000 (got -1)"},
      {"wicp_rgbd_slam", "--out x --global-ba -1", "--global-ba must be between 0 and 1000 (got -1)"},
      {"wicp_rgbd_slam", "--out x --loop-closing-niceness 20", "--loop-closing-niceness must be between 0 and 19"},
      // An option the chosen source would ignore is refused, not ignored.
      {"wicp_rgbd_slam", "--out x --camera fr3", "--camera applies to --dataset only"},
      {"wicp_rgbd_slam", "--out x --dataset d --room-scale 2", "--room-scale applies to the synthetic sequence"},
      {"wicp_rgbd_slam", "--out x --dataset d --dim", "--dim applies to the synthetic sequence"},
      {"wicp_rgbd_slam", "--out x --dataset d --cy-error 3", "--cy-error applies to the synthetic sequence"},
      {"wicp_make_variant", "--out x --variant jpeg --dataset d --synthetic-seed 3",
       "--synthetic-seed applies to the synthetic sequence"},
      {"wicp_make_variant", "--out x --variant jpeg --camera fr1", "--camera applies to --dataset only"},
      {"wicp_synthetic_rgbd", "--out x --frames -3", "--frames must be between 1 and 100000 (got -3)"},
      {"wicp_synthetic_rgbd", "--out x --fps 0", "--fps must be greater than 0"},
      {"wicp_synthetic_rgbd", "--out x --depth-noise-coefficient -1", "--depth-noise-coefficient must be between 0"},
      {"wicp_sweep_k", "--threads -1", "--threads must be between 0 and 1024 (got -1)"},
      {"wicp_sweep_yaw", "--k -1", "--k must be between 1 and 1000 (got -1)"},
      {"wicp_sweep_xy", "--max-iterations -5", "--max-iterations must be between 1 and 1000000 (got -5)"},
      {"wicp_sweep_xy_yaw", "--min-observations -1", "--min-observations must be at least 0 (got -1)"},
      {"wicp_global_sweep", "--synthetic --landmarks -1", "--landmarks must be between 1 and 10000000 (got -1)"},
      {"wicp_global_sweep", "--synthetic --seed -1", "--seed must be at least 0 (got -1)"},
      {"wicp_global_sweep", "--synthetic --yaw-hypotheses 0", "--yaw-hypotheses must be between 1 and 3600 (got 0)"},
      {"wicp_global_sweep", "--synthetic --yaws 0,x", "--yaws: 'x' is not a finite number"},
      {"wicp_global_sweep", "--synthetic --xy 1", "--xy: '1' is not x:y"},
      {"wicp_global_sweep", "--synthetic --overlaps 0", "--overlaps: each must be in (0, 1]"},
      {"wicp_global_sweep", "--synthetic --method foo",
       "--method must be global, coarse, icp, truth, fpfh or fpfh-trimmed (got foo)"},
      {"wicp_global_sweep", "", "give exactly one of --map FILE and --synthetic"},
      {"wicp_align", "--source a --target b --up-axis z", "--up-axis applies only with --global"},
      {"wicp_align", "--source a --target b --global --up-axis \"0 0 0\"",
       "--up-axis: expected auto, z or \"X Y Z\" (three finite numbers, not all zero), got '0 0 0'"},
      {"wicp_global_sweep", "--synthetic --up-axis y", "--up-axis: expected auto, z or \"X Y Z\""},
      {"wicp_global_sweep", "--synthetic --map-pose \"0 0 0 0 0 0 2\"", "--map-pose: the quaternion is not a unit one"},
      {"wicp_global_sweep", "--synthetic --tilt 12 --camera-frame",
       "--tilt re-expresses the map itself: not with --camera-frame or --map-pose"},
      {"wicp_global_sweep", "--synthetic --tilt 91", "--tilt must be between -90 and 90 (got 91)"},
      {"wicp_global_sweep", "--synthetic --inside 60-9", "--inside: '60-9' is not FIRST-LAST"},
      {"wicp_global_sweep", "--synthetic --inside 60-", "--inside: '60-' is not FIRST-LAST"},
      {"wicp_make_variant", "--variant frame-step --frame-step 0 --out x",
       "--frame-step must be between 1 and 30 (got 0)"},
      {"wicp_make_variant", "--variant exposure --exposure-stops 5 --out x",
       "--exposure-stops must be between 0 and 4 (got 5)"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(std::string(c.tool) + " " + c.args);
    const ToolRun r = run(c.tool, c.args, scratch);
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << r.err;
  }
}

// Issue #10: wicp_map said "the option '--map' is required", an option it does not have.
TEST(ToolOptions, WicpMapNamesAMissingPositionalArgument) {
  const fs::path scratch = scratchDir("wicp_map_positionals");
  const std::pair<const char*, const char*> cases[] = {
      {"stats", "error: stats: a MAP file is required (usage: wicp_map stats MAP"},
      {"cut --out x --frames-per-minimap 2", "error: cut: a MAP file is required (usage: wicp_map cut MAP"},
      {"convert", "error: convert: a MAP file is required (usage: wicp_map convert MAP"},
      {"convert a.txt", "error: convert: an output cloud OUT.pcd|OUT.ply is required (usage: wicp_map convert"},
  };
  for (const auto& [args, message] : cases) {
    SCOPED_TRACE(args);
    const ToolRun r = run("wicp_map", args, scratch);
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("--map"), std::string::npos) << r.err;
  }
}

TEST(ToolOptions, BoundsThemselvesAreAccepted) {
  const fs::path scratch = scratchDir("bounds");
  // --help after the options: parsing (and so the range check) runs, then help exits 0.
  for (const char* args : {"--k 1000 --threads 1024 --help", "--k 1 --threads 0 --min-observations 0 --help",
                           "--k=+5 --max-correspondence-distance 1e-3 --help"}) {
    SCOPED_TRACE(args);
    const ToolRun r = run("wicp_align", args, scratch);
    EXPECT_EQ(r.status, 0) << r.err;
  }
}

/// A map of `positions` (one "x y z" each), every landmark seen by two frames.
fs::path writeMap(const fs::path& folder, const std::string& name, const std::vector<std::string>& positions) {
  std::ostringstream text;
  text << "FRAME 0  0 0 0  1 0 0 0\nFRAME 1  1 0 0  1 0 0 0\n";
  for (std::size_t i = 0; i < positions.size(); ++i)
    text << "LANDMARK " << i << "  " << positions[i] << "  1e-4 0 0 0 1e-4 0 0 0 1e-4  2  0 100 100  1 120 100\n";
  const fs::path path = folder / name;
  std::ofstream(path) << text.str();
  return path;
}

std::vector<std::string> grid(std::size_t n) {
  std::vector<std::string> positions;
  for (std::size_t i = 0; i < n; ++i)
    positions.push_back(std::to_string(0.3 * (i % 4)) + " " + std::to_string(0.2 * (i / 4 % 3)) + " " +
                        std::to_string(1.0 + 0.25 * (i / 12)));
  return positions;
}

TEST(WicpAlignDegenerate, ReportedInJsonWithExitCode4) {
  const fs::path scratch = scratchDir("degenerate");
  const std::string source = writeMap(scratch, "source.txt", grid(40)).string();
  const struct {
    std::vector<std::string> target;
    const char* args;
    const char* reason;
  } cases[] = {
      {grid(2), "--k 1", "only 2 finite target points, fewer than 3"},
      {{"0 0 1", "1 0 1", "0 1 1", "0 0 2"}, "", "k = 5 is at least the 4 finite target points"},
      {{"0 0 1", "0.1 0.1 1.1", "0.2 0.2 1.2", "0.3 0.3 1.3", "0.5 0.5 1.5", "0.9 0.9 1.9"}, "--k 1", "collinear"},
      {std::vector<std::string>(20, "1 2 3"), "--k 1", "identical"},
      {grid(12), "--k 12", "k = 12 is at least the 12 finite target points"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.reason);
    const std::string target = writeMap(scratch, "target.txt", c.target).string();
    const ToolRun r =
        run("wicp_align", "--source " + source + " --target " + target + " " + c.args + " --json", scratch);
    EXPECT_EQ(r.status, 4) << r.err << r.out;
    EXPECT_NE(r.out.find("\"converged\":false,\"degenerate\":true,\"reason\":\""), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(c.reason), std::string::npos) << r.out;
  }
  const std::string target = writeMap(scratch, "target.txt", grid(40)).string();
  const ToolRun fine = run("wicp_align", "--source " + source + " --target " + target + " --json", scratch);
  EXPECT_EQ(fine.status, 0) << fine.err << fine.out;
  EXPECT_NE(fine.out.find("\"degenerate\":false"), std::string::npos) << fine.out;
}

TEST(WicpAlignDegenerate, CoordinatesBeyondTheIndexAreRefusedWithFileAndLine) {
  // As target these crashed wicp_align and wicp_sweep_k (exit 139); as source they were accepted.
  const fs::path scratch = scratchDir("huge");
  const fs::path huge = writeMap(scratch, "huge.txt", std::vector<std::string>(20, "1.8e38 1.8e38 1.8e38"));
  const std::string valid = writeMap(scratch, "valid.txt", grid(40)).string();
  for (const std::string& args :
       {"--source " + valid + " --target " + huge.string(), "--source " + huge.string() + " --target " + valid}) {
    const ToolRun r = run("wicp_align", args, scratch);
    EXPECT_EQ(r.status, 1) << r.err;
    EXPECT_NE(r.err.find(huge.string() + ":3: landmark 0: position has a coordinate beyond"), std::string::npos)
        << r.err;
  }
  const ToolRun sweep = run(
      "wicp_sweep_k",
      "--source " + valid + " --target " + huge.string() + " --no-plot --out " + (scratch / "sweep").string(), scratch);
  EXPECT_EQ(sweep.status, 1) << sweep.err;
  EXPECT_NE(sweep.err.find(huge.string() + ":3"), std::string::npos) << sweep.err;
}

}  // namespace
