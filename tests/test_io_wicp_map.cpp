// The wicp_map tool, run as a user would: its files, its output and its exit
// codes (0 done, 1 bad data naming file:line, 2 bad command line).

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_support.h"
#include "tool_runner.h"
#include "weighted_icp/io/cloud_io.h"
#include "weighted_icp/io/map_format.h"

namespace {

using namespace weighted_icp;
namespace fs = std::filesystem;
using weighted_icp::testing::binaryDir;
using weighted_icp::testing::readFile;
using weighted_icp::testing::scratchDir;
using weighted_icp::testing::writeFile;

using weighted_icp::testing::ToolRun;

/// Runs wicp_map with `arguments` (shell syntax).
ToolRun wicpMap(const std::string& arguments, const fs::path& scratch) {
  return weighted_icp::testing::runBuiltTool("wicp_map", arguments, scratch);
}

std::string quoted(const fs::path& path) { return "'" + path.string() + "'"; }

/// Frames 0..4 at x = id. Observation counts: 10 -> 2 (frames 0, 1),
/// 11 -> 3 (0, 2, 4), 12 -> 1 (3), 13 -> 0, 14 -> 2 (3, 4).
const char* const kSmallMap =
    "FRAME 0  0 0 0  1 0 0 0\n"
    "FRAME 1  1 0 0  1 0 0 0\n"
    "FRAME 2  2 0 0  1 0 0 0\n"
    "FRAME 3  3 0 0  1 0 0 0\n"
    "FRAME 4  4 0 0  1 0 0 0\n"
    "LANDMARK 10  0 0 1  0.001 0 0 0 0.001 0 0 0 0.001  2  0 300 200  1 310 200\n"
    "LANDMARK 11  2 0 1  0.0004 0 0 0 0.0001 0 0 0 0.0001  3  0 400 200  2 300 200  4 200 200\n"
    "LANDMARK 12  3 1 1  0.001 0 0 0 0.001 0 0 0 0.001  1  3 320 300\n"
    "LANDMARK 13  9 9 9  0.01 0 0 0 0.01 0 0 0 0.01  0\n"
    "LANDMARK 14  4 0 2  0.003 0 0 0 0.004 0 0 0 0  2  3 400 250  4 320 250\n";

fs::path smallMap(const fs::path& scratch) {
  writeFile(scratch / "small.txt", kSmallMap);
  return scratch / "small.txt";
}

std::vector<FrameId> frameIds(const LandmarkMap& map) {
  std::vector<FrameId> ids;
  for (const auto& [id, pose] : map.frames) ids.push_back(id);
  return ids;
}

/// (landmark id, observation count) in file order.
std::vector<std::pair<LandmarkId, std::size_t>> landmarkCounts(const LandmarkMap& map) {
  std::vector<std::pair<LandmarkId, std::size_t>> counts;
  for (const auto& landmark : map.landmarks) counts.emplace_back(landmark.id, landmark.observations.size());
  return counts;
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> result;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) result.push_back(line);
  return result;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TEST(WicpMapCut, ByFrameCount) {
  const fs::path scratch = scratchDir("wicp_map_cut_count");
  const fs::path out = scratch / "minis";  // does not exist yet
  const ToolRun run =
      wicpMap("cut " + quoted(smallMap(scratch)) + " --out " + quoted(out) + " --frames-per-minimap 2", scratch);
  ASSERT_EQ(run.status, 0) << run.err;

  const LandmarkMap first = io::readLandmarkMap((out / "minimap_000.txt").string());
  const LandmarkMap second = io::readLandmarkMap((out / "minimap_001.txt").string());
  const LandmarkMap third = io::readLandmarkMap((out / "minimap_002.txt").string());
  EXPECT_FALSE(fs::exists(out / "minimap_003.txt"));
  using Counts = std::vector<std::pair<LandmarkId, std::size_t>>;
  EXPECT_EQ(frameIds(first), (std::vector<FrameId>{0, 1}));
  EXPECT_EQ(landmarkCounts(first), (Counts{{10, 2}, {11, 1}}));
  EXPECT_EQ(frameIds(second), (std::vector<FrameId>{2, 3}));
  EXPECT_EQ(landmarkCounts(second), (Counts{{11, 1}, {12, 1}, {14, 1}}));
  EXPECT_EQ(frameIds(third), (std::vector<FrameId>{4}));
  EXPECT_EQ(landmarkCounts(third), (Counts{{11, 1}, {14, 1}}));

  const std::vector<std::string> printed = lines(run.out);
  ASSERT_EQ(printed.size(), 3u) << run.out;
  EXPECT_TRUE(contains(printed[0], "minimap_000.txt") && contains(printed[0], "(2 frames)") &&
              contains(printed[0], " 2 landmarks"))
      << printed[0];
  EXPECT_TRUE(contains(printed[1], "minimap_001.txt") && contains(printed[1], "(2 frames)") &&
              contains(printed[1], " 3 landmarks"))
      << printed[1];
  EXPECT_TRUE(contains(printed[2], "minimap_002.txt") && contains(printed[2], "(1 frames)") &&
              contains(printed[2], " 2 landmarks"))
      << printed[2];
}

TEST(WicpMapCut, ByRangesWithMinObservations) {
  const fs::path scratch = scratchDir("wicp_map_cut_ranges");
  const fs::path out = scratch / "minis";
  const ToolRun run = wicpMap(
      "cut " + quoted(smallMap(scratch)) + " --out " + quoted(out) + " --ranges 0-2,2-4 --min-observations 2", scratch);
  ASSERT_EQ(run.status, 0) << run.err;
  const LandmarkMap first = io::readLandmarkMap((out / "minimap_000.txt").string());
  const LandmarkMap second = io::readLandmarkMap((out / "minimap_001.txt").string());
  EXPECT_FALSE(fs::exists(out / "minimap_002.txt"));
  using Counts = std::vector<std::pair<LandmarkId, std::size_t>>;
  EXPECT_EQ(frameIds(first), (std::vector<FrameId>{0, 1, 2}));
  EXPECT_EQ(landmarkCounts(first), (Counts{{10, 2}, {11, 2}}));
  EXPECT_EQ(frameIds(second), (std::vector<FrameId>{2, 3, 4}));
  EXPECT_EQ(landmarkCounts(second), (Counts{{11, 2}, {14, 2}}));  // 12 is seen once only
}

/// Every name in `dir`, sorted.
std::vector<std::string> entries(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

TEST(WicpMapCut, ANonEmptyOutIsRefusedWithoutOverwrite) {
  const fs::path scratch = scratchDir("wicp_map_cut_non_empty");
  const fs::path out = scratch / "minis";
  fs::create_directories(out);
  writeFile(out / "minimap_007.txt", "FRAME 0  0 0 0  1 0 0 0\n");
  const ToolRun run =
      wicpMap("cut " + quoted(smallMap(scratch)) + " --out " + quoted(out) + " --frames-per-minimap 2", scratch);
  EXPECT_EQ(run.status, 1);
  EXPECT_TRUE(contains(run.err, "not empty") && contains(run.err, "--overwrite")) << run.err;
  EXPECT_EQ(entries(out), std::vector<std::string>{"minimap_007.txt"});
  EXPECT_EQ(entries(scratch), (std::vector<std::string>{"minis", "small.txt"})) << "temporary left";
}

// A re-run into the same folder holds this cut's mini-maps only, whatever the earlier one wrote.
TEST(WicpMapCut, ARerunWithOverwriteLeavesNoStaleMiniMap) {
  const fs::path scratch = scratchDir("wicp_map_cut_rerun");
  const fs::path out = scratch / "minis";
  const std::string cut = "cut " + quoted(smallMap(scratch)) + " --out " + quoted(out);
  ASSERT_EQ(wicpMap(cut + " --frames-per-minimap 1", scratch).status, 0);
  ASSERT_EQ(entries(out).size(), 5u);
  const ToolRun rerun = wicpMap(cut + " --frames-per-minimap 2 --overwrite", scratch);
  ASSERT_EQ(rerun.status, 0) << rerun.err;
  EXPECT_EQ(entries(out), (std::vector<std::string>{"minimap_000.txt", "minimap_001.txt", "minimap_002.txt"}));
  EXPECT_EQ(frameIds(io::readLandmarkMap((out / "minimap_001.txt").string())), (std::vector<FrameId>{2, 3}));
}

// A cut that fails after reading the map leaves the earlier cut whole, even with --overwrite.
TEST(WicpMapCut, AFailedCutLeavesTheEarlierOneWhole) {
  const fs::path scratch = scratchDir("wicp_map_cut_failed");
  const fs::path out = scratch / "minis";
  const std::string cut = "cut " + quoted(smallMap(scratch)) + " --out " + quoted(out);
  ASSERT_EQ(wicpMap(cut + " --frames-per-minimap 2", scratch).status, 0);
  const std::string before = readFile(out / "minimap_000.txt");
  const ToolRun failed = wicpMap(cut + " --ranges 0-1,7-9 --overwrite", scratch);
  EXPECT_EQ(failed.status, 1);
  EXPECT_EQ(entries(out), (std::vector<std::string>{"minimap_000.txt", "minimap_001.txt", "minimap_002.txt"}));
  EXPECT_EQ(readFile(out / "minimap_000.txt"), before);
  EXPECT_EQ(entries(scratch), (std::vector<std::string>{"minis", "small.txt"})) << "temporary left";
}

TEST(WicpMapCut, RangeWithoutFramesIsAnError) {
  const fs::path scratch = scratchDir("wicp_map_cut_empty_range");
  const ToolRun run =
      wicpMap("cut " + quoted(smallMap(scratch)) + " --out " + quoted(scratch) + " --ranges 0-1,7-9", scratch);
  EXPECT_EQ(run.status, 1);
  EXPECT_TRUE(contains(run.err, "7-9")) << run.err;
  EXPECT_FALSE(fs::exists(scratch / "minimap_000.txt"));
}

TEST(WicpMapConvert, WritesALoadableWeightedPcd) {
  const fs::path scratch = scratchDir("wicp_map_convert_pcd");
  const fs::path cloud_path = scratch / "cloud.pcd";
  const ToolRun run = wicpMap("convert " + quoted(smallMap(scratch)) + " " + quoted(cloud_path), scratch);
  ASSERT_EQ(run.status, 0) << run.err;
  // Defaults: landmarks with >= 2 observations (10, 11, 14), covariance weights 1 / (1 + ||C||_F).
  const LandmarkCloud::Ptr cloud = io::loadLandmarkCloud(cloud_path.string());
  ASSERT_EQ(cloud->size(), 3u);
  const double frobenius[] = {1e-3 * std::sqrt(3.0), 1e-4 * std::sqrt(18.0), 5e-3};
  const std::uint32_t observations[] = {2, 3, 2};
  const float x[] = {0.0f, 2.0f, 4.0f};
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ((*cloud)[i].x, x[i]) << i;
    EXPECT_NEAR((*cloud)[i].weight, 1.0 / (1.0 + frobenius[i]), 1e-15) << i;
    EXPECT_EQ((*cloud)[i].num_observations, observations[i]) << i;
  }
  EXPECT_TRUE(contains(run.out, "3 landmarks")) << run.out;
}

TEST(WicpMapConvert, PlyWithAnotherStrategyAndThreshold) {
  const fs::path scratch = scratchDir("wicp_map_convert_ply");
  const fs::path cloud_path = scratch / "cloud.ply";
  const ToolRun run = wicpMap("convert " + quoted(smallMap(scratch)) + " " + quoted(cloud_path) +
                                  " --strategy observations --min-observations 0",
                              scratch);
  ASSERT_EQ(run.status, 0) << run.err;
  const LandmarkCloud::Ptr cloud = io::loadLandmarkCloud(cloud_path.string());
  ASSERT_EQ(cloud->size(), 5u);
  const double counts[] = {2, 3, 1, 0, 2};
  for (std::size_t i = 0; i < 5; ++i) EXPECT_EQ((*cloud)[i].weight, counts[i]) << i;
}

/// A PLY of infinities would not load back: such a map is refused, naming the
/// landmark, before anything is written (the map reader already refuses
/// coordinates beyond what the float index holds; the cloud writer checks
/// again for maps built in code, see test_io_atomic_output.cpp).
TEST(WicpMapConvert, RefusesCoordinatesBeyondFloatNamingTheLandmark) {
  const fs::path scratch = scratchDir("wicp_map_convert_huge");
  std::string map = kSmallMap;
  map.replace(map.find("LANDMARK 11  2 0 1"), 18, "LANDMARK 11  2 1e200 1");
  writeFile(scratch / "huge.txt", map);
  const fs::path cloud_path = scratch / "cloud.ply";
  const ToolRun run = wicpMap("convert " + quoted(scratch / "huge.txt") + " " + quoted(cloud_path), scratch);
  EXPECT_EQ(run.status, 1);
  EXPECT_TRUE(contains(run.err, "wicp_map: error: ")) << run.err;
  EXPECT_TRUE(contains(run.err, "huge.txt:")) << run.err;
  EXPECT_TRUE(contains(run.err, "landmark 11")) << run.err;
  EXPECT_FALSE(fs::exists(cloud_path));
}

/// A full disk (a file-size limit, which needs no root) must fail the run and
/// leave no truncated PLY; PCL's PLY writer itself reports nothing.
TEST(WicpMapConvert, AFullDiskFailsAndLeavesNoTruncatedFile) {
  const fs::path scratch = scratchDir("wicp_map_convert_full");
  std::string map = "FRAME 0  0 0 0  1 0 0 0\n";
  for (int id = 0; id < 4000; ++id)
    map += "LANDMARK " + std::to_string(id) + "  " + std::to_string(id) +
           " 0 1  0.001 0 0 0 0.001 0 0 0 0.001  2  0 1 1  0 2 2\n";
  writeFile(scratch / "big.txt", map);
  const fs::path cloud_path = scratch / "cloud.ply";
  // 64 kB: the map is read in full, the cloud (about 150 kB) cannot be written.
  const ToolRun run = wicpMap("convert " + quoted(scratch / "big.txt") + " " + quoted(cloud_path), scratch);
  ASSERT_EQ(run.status, 0) << "without the limit the conversion works: " << run.err;
  fs::remove(cloud_path);
  const fs::path tool = binaryDir() / "examples" / "wicp_map";
  const std::string command = "ulimit -f 64; trap '' XFSZ; exec '" + tool.string() + "' convert " +
                              quoted(scratch / "big.txt") + " " + quoted(cloud_path) + " >/dev/null 2>" +
                              quoted(scratch / "err.txt");
  const int status = std::system(("bash -c \"" + command + "\"").c_str());
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1) << status;
  EXPECT_TRUE(contains(readFile(scratch / "err.txt"), "cannot write " + cloud_path.string()))
      << readFile(scratch / "err.txt");
  EXPECT_FALSE(fs::exists(cloud_path)) << "a truncated cloud was left";
  for (const auto& entry : fs::directory_iterator(scratch))
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
}

/// The four numbers (min, median, p90, max) printed after `label`.
std::vector<double> statsRow(const std::string& output, const std::string& label) {
  std::vector<double> values;
  for (const std::string& line : lines(output))
    if (contains(line, label)) {
      std::istringstream numbers(line.substr(line.find(label) + label.size()));
      for (double value; numbers >> value;) values.push_back(value);
    }
  return values;
}

TEST(WicpMapStats, CountsHistogramAndDistributions) {
  const fs::path scratch = scratchDir("wicp_map_stats");
  const ToolRun run = wicpMap("stats " + quoted(smallMap(scratch)), scratch);
  ASSERT_EQ(run.status, 0) << run.err;
  EXPECT_TRUE(contains(run.out, "frames      5 (ids 0-4)")) << run.out;
  EXPECT_TRUE(contains(run.out, "landmarks   5\n")) << run.out;
  EXPECT_TRUE(contains(run.out, "0: 1  1: 1  2: 2  3: 1  4: 0  5-9: 0  10+: 0")) << run.out;
  EXPECT_TRUE(contains(run.out, "landmarks with >= 2 observations: 3")) << run.out;
  // Bounding box of landmarks 10, 11 and 14.
  EXPECT_TRUE(contains(run.out, "min (0 0 1)  max (4 0 2)")) << run.out;
  // Counts 2, 3, 2: median 2, 90th percentile 2 + 0.8 (3 - 2).
  EXPECT_EQ(statsRow(run.out, "weight observations"), (std::vector<double>{2, 2, 2.8, 3}));
  const std::vector<double> norms = statsRow(run.out, "covariance norm (Frobenius)");
  ASSERT_EQ(norms.size(), 4u) << run.out;
  EXPECT_NEAR(norms[0], 1e-4 * std::sqrt(18.0), 1e-9);
  EXPECT_NEAR(norms[1], 1e-3 * std::sqrt(3.0), 1e-8);
  EXPECT_NEAR(norms[3], 5e-3, 1e-8);
  // Landmark 10 at (0,0,1) seen from x = 0 and x = 1: mean distance (1 + sqrt 2) / 2; the smallest.
  EXPECT_NEAR(statsRow(run.out, "mean observation distance (m)").at(0), (1.0 + std::sqrt(2.0)) / 2.0, 1e-5);
  EXPECT_EQ(statsRow(run.out, "weight base"), (std::vector<double>{1, 1, 1, 1}));

  const ToolRun all = wicpMap("stats " + quoted(smallMap(scratch)) + " --min-observations 0", scratch);
  ASSERT_EQ(all.status, 0) << all.err;
  // Counts 0, 1, 2, 2, 3: the 90th percentile lies at 3.6 of 4 gaps, 2 + 0.6 (3 - 2).
  EXPECT_EQ(statsRow(all.out, "weight observations"), (std::vector<double>{0, 2, 2.6, 3}));
}

TEST(WicpMapEmptyMaps, FramesWithoutLandmarks) {
  const fs::path scratch = scratchDir("wicp_map_no_landmarks");
  writeFile(scratch / "frames_only.txt", "FRAME 0  0 0 0  1 0 0 0\nFRAME 1  1 0 0  1 0 0 0\n");
  const std::string map = quoted(scratch / "frames_only.txt");

  const ToolRun stats = wicpMap("stats " + map, scratch);
  EXPECT_EQ(stats.status, 0) << stats.err;
  EXPECT_TRUE(contains(stats.out, "landmarks   0\n")) << stats.out;
  EXPECT_TRUE(contains(stats.out, "landmarks with >= 2 observations: 0")) << stats.out;

  const ToolRun cut =
      wicpMap("cut " + map + " --out " + quoted(scratch / "minis") + " --frames-per-minimap 1", scratch);
  ASSERT_EQ(cut.status, 0) << cut.err;
  for (const char* name : {"minimap_000.txt", "minimap_001.txt"}) {
    const LandmarkMap mini = io::readLandmarkMap((scratch / "minis" / name).string());
    EXPECT_EQ(mini.frames.size(), 1u) << name;
    EXPECT_TRUE(mini.landmarks.empty()) << name;
  }

  const ToolRun pcd = wicpMap("convert " + map + " " + quoted(scratch / "empty.pcd"), scratch);
  ASSERT_EQ(pcd.status, 0) << pcd.err;
  EXPECT_TRUE(io::loadLandmarkCloud((scratch / "empty.pcd").string())->empty());
  // PCL cannot write a PLY without points: a clear error, no file.
  const ToolRun ply = wicpMap("convert " + map + " " + quoted(scratch / "empty.ply"), scratch);
  EXPECT_EQ(ply.status, 1);
  EXPECT_TRUE(contains(ply.err, "empty.ply")) << ply.err;
  EXPECT_FALSE(fs::exists(scratch / "empty.ply"));
}

TEST(WicpMapEmptyMaps, NoFramesAtAll) {
  const fs::path scratch = scratchDir("wicp_map_no_frames");
  writeFile(scratch / "empty.txt", "");
  const std::string map = quoted(scratch / "empty.txt");
  const ToolRun stats = wicpMap("stats " + map, scratch);
  EXPECT_EQ(stats.status, 0) << stats.err;
  EXPECT_TRUE(contains(stats.out, "frames      0\n")) << stats.out;
  const ToolRun cut =
      wicpMap("cut " + map + " --out " + quoted(scratch / "minis") + " --frames-per-minimap 3", scratch);
  EXPECT_EQ(cut.status, 0) << cut.err;
  EXPECT_FALSE(fs::exists(scratch / "minis" / "minimap_000.txt"));
}

TEST(WicpMapErrors, MalformedMapNamesFileAndLine) {
  const fs::path scratch = scratchDir("wicp_map_malformed");
  const fs::path bad = scratch / "bad_map.txt";
  writeFile(bad, "FRAME 0  0 0 0  1 0 0 0\n# comment\nLANDMARK 1  0 0 1  1 0 0 0 1 0 0 0 1  2  0 1 2\n");
  for (const std::string& command :
       {"stats " + quoted(bad),
        "cut " + quoted(bad) + " --out " + quoted(scratch / "minis") + " --frames-per-minimap 1",
        "convert " + quoted(bad) + " " + quoted(scratch / "cloud.pcd")}) {
    const ToolRun run = wicpMap(command, scratch);
    EXPECT_EQ(run.status, 1) << command;
    EXPECT_TRUE(contains(run.err, bad.string() + ":3:")) << command << ": " << run.err;
  }
  EXPECT_FALSE(fs::exists(scratch / "minis"));
  EXPECT_FALSE(fs::exists(scratch / "cloud.pcd"));

  const ToolRun missing = wicpMap("stats " + quoted(scratch / "absent.txt"), scratch);
  EXPECT_EQ(missing.status, 1);
  EXPECT_TRUE(contains(missing.err, (scratch / "absent.txt").string())) << missing.err;
}

TEST(WicpMapErrors, BadCommandLinesExitWithTwo) {
  const fs::path scratch = scratchDir("wicp_map_command_line");
  const std::string map = quoted(smallMap(scratch));
  const std::string out = " --out " + quoted(scratch / "minis");
  for (const std::string& arguments : {
           std::string(),
           std::string("frobnicate ") + map,
           std::string("stats"),
           "stats " + map + " extra",
           "stats " + map + " --min-observations=-1",
           "cut " + map + " --frames-per-minimap 2",
           "cut " + map + out,
           "cut " + map + out + " --frames-per-minimap 2 --ranges 0-1",
           "cut " + map + out + " --frames-per-minimap 0",
           "cut " + map + out + " --ranges 3-1",
           "cut " + map + out + " --ranges 0-x",
           "cut " + map + out + " --ranges 0-1,",
           "convert " + map,
           "convert " + map + " " + quoted(scratch / "c.pcd") + " --strategy frobenius",
           "convert " + map + " " + quoted(scratch / "c.pcd") + " --no-such-option",
       }) {
    const ToolRun run = wicpMap(arguments, scratch);
    EXPECT_EQ(run.status, 2) << "wicp_map " << arguments << "\n" << run.err;
    EXPECT_TRUE(contains(run.err, "wicp_map: error: ")) << "wicp_map " << arguments << "\n" << run.err;
  }
  EXPECT_FALSE(fs::exists(scratch / "minis"));
  EXPECT_FALSE(fs::exists(scratch / "c.pcd"));
}

TEST(WicpMapHelp, EachCommandHasHelp) {
  const fs::path scratch = scratchDir("wicp_map_help");
  for (const std::string command : {"stats", "cut", "convert"}) {
    const ToolRun run = wicpMap(command + " --help", scratch);
    EXPECT_EQ(run.status, 0) << command;
    EXPECT_TRUE(contains(run.out, "wicp_map " + command + " MAP")) << run.out;
    EXPECT_TRUE(contains(run.out, "--min-observations")) << run.out;
  }
  const ToolRun run = wicpMap("--help", scratch);
  EXPECT_EQ(run.status, 0);
  EXPECT_TRUE(contains(run.out, "stats|cut|convert")) << run.out;
}

}  // namespace
