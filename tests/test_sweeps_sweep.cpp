// The sweep library behind the wicp_sweep_* tools, on a small map made here:
// landmarks on three planes, seen by a varying number of six cameras.

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "sweep.h"
#include "test_support.h"
#include "weighted_icp/io/map_format.h"

namespace weighted_icp::sweep {
namespace {

namespace fs = std::filesystem;
using weighted_icp::testing::readFile;

/// Three perpendicular planes (floor and two walls) of jittered 7x7 grids,
/// so ICP has a unique optimum. Landmark i is seen by 1 + i % 6 consecutive
/// frames and has its own covariance, so every strategy ranks differently.
LandmarkMap planesMap() {
  LandmarkMap map;
  for (FrameId f = 0; f < 6; ++f) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(-0.5 + 0.3 * f, -1.5, 1.2);
    map.frames[f] = pose;
  }
  LandmarkId id = 0;
  for (int plane = 0; plane < 3; ++plane)
    for (int i = 0; i < 7; ++i)
      for (int j = 0; j < 7; ++j, ++id) {
        const double u = 0.15 * i + 0.02 * std::sin(1.7 * id), v = 0.15 * j + 0.02 * std::cos(2.3 * id);
        Landmark landmark;
        landmark.id = id;
        landmark.position = plane == 0   ? Eigen::Vector3d(u, v, 0.0)
                            : plane == 1 ? Eigen::Vector3d(u, 1.0, v)
                                         : Eigen::Vector3d(-0.1, v, u);
        landmark.covariance = Eigen::Matrix3d::Identity() * 1e-4 * (1 + (id * 7) % 5);
        for (std::size_t n = 0; n <= id % 6; ++n) landmark.observations.push_back({(id + n) % 6, 100.0 + n, 200.0});
        map.landmarks.push_back(landmark);
      }
  return map;
}

MapPair sameMapPair(bool truth_known = true) {
  MapPair pair;
  pair.source = pair.target = planesMap().withMinObservations(2);
  pair.description = "planes";
  pair.truth_known = truth_known;
  return pair;
}

std::vector<std::vector<std::string>> parseCsv(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream fields(line);
    while (std::getline(fields, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.push_back("");  // getline drops a trailing empty cell
    rows.push_back(cells);
  }
  return rows;
}

/// Runs a sweep tool the way main() does; returns its exit status and stderr.
std::pair<int, std::string> runTool(const SweepDefinition& sweep, std::vector<std::string> args) {
  args.insert(args.begin(), "wicp_sweep_test");
  std::vector<const char*> argv;
  for (const std::string& a : args) argv.push_back(a.c_str());
  ::testing::internal::CaptureStderr();
  const int status = runSweepTool("wicp_sweep_test", sweep, static_cast<int>(argv.size()), argv.data());
  return {status, ::testing::internal::GetCapturedStderr()};
}

// ---------------------------------------------------------------------------
// The generated cases

TEST(SweepCases, KSweepCrossesEveryKWithTheFiveDisplacements) {
  const std::vector<SweepCase> cases = kSweep().cases(0);
  ASSERT_EQ(cases.size(), 7u * 5u);
  std::multiset<unsigned int> ks;
  for (const SweepCase& c : cases) ks.insert(c.k);
  for (const unsigned int k : {1u, 3u, 5u, 7u, 10u, 15u, 20u}) EXPECT_EQ(ks.count(k), 5u) << "k " << k;
  const Displacement paper = kSweepDisplacements().front();  // the paper's config.yaml
  EXPECT_EQ(paper.toString(), "0 1 0.4 10 0 22.5");
  EXPECT_TRUE(kSweep().sweeps_k);
}

TEST(SweepCases, YawSweepGoesFrom0To70InBothDirectionsWithTheGivenK) {
  const std::vector<SweepCase> cases = yawSweep().cases(7);
  std::multiset<double> yaws;
  for (const SweepCase& c : cases) {
    EXPECT_EQ(c.k, 7u);
    EXPECT_EQ(c.displacement.x, 0.0);
    EXPECT_EQ(c.displacement.y, 0.0);
    EXPECT_EQ(c.displacement.roll_deg, 0.0);
    yaws.insert(c.displacement.yaw_deg);
  }
  EXPECT_EQ(yaws, (std::multiset<double>{-70, -60, -50, -40, -30, -20, -10, 0, 10, 20, 30, 40, 50, 60, 70}));
}

TEST(SweepCases, XySweepHasFourQuadrantsPerMagnitude) {
  const std::vector<SweepCase> cases = xySweep().cases(5);
  ASSERT_EQ(cases.size(), 4 * xySweepMagnitudes.size());
  for (const double a : xySweepMagnitudes) {
    std::set<std::pair<double, double>> quadrants;
    for (const SweepCase& c : cases)
      if (std::abs(c.displacement.x) == a) {
        EXPECT_EQ(std::abs(c.displacement.y), a);
        EXPECT_EQ(c.displacement.yaw_deg, 0.0);
        quadrants.insert({c.displacement.x, c.displacement.y});
      }
    EXPECT_EQ(quadrants.size(), 4u) << "magnitude " << a;
  }
}

TEST(SweepCases, XyYawSweepHasTheHalfMetreQuadrantsAtFourYaws) {
  const std::vector<SweepCase> cases = xyYawSweep().cases(5);
  ASSERT_EQ(cases.size(), 16u);
  std::set<std::tuple<double, double, double>> distinct;
  for (const SweepCase& c : cases) {
    EXPECT_EQ(std::abs(c.displacement.x), 0.5);
    EXPECT_EQ(std::abs(c.displacement.y), 0.5);
    distinct.insert({c.displacement.x, c.displacement.y, c.displacement.yaw_deg});
  }
  EXPECT_EQ(distinct.size(), 16u);
  std::set<double> yaws;
  for (const auto& [x, y, yaw] : distinct) yaws.insert(yaw);
  EXPECT_EQ(yaws, (std::set<double>{-30, -10, 10, 30}));
}

TEST(SweepCases, BaseRunsOncePerDisplacementInTheKSweep) {
  // Base ignores k, so only the weighted strategies repeat per k.
  EXPECT_EQ(countRuns(kSweep().cases(0)), 3u * 35u + 5u);
  EXPECT_EQ(countRuns(yawSweep().cases(5)), 4u * 15u);
}

// ---------------------------------------------------------------------------
// The paper's preset

TEST(SweepPresets, PaperGridsAreTheOnesItsSectionFourDescribes) {
  // Table 1: every k at the one config.yaml displacement.
  const auto k_cases = kSweep().paper_cases(5);
  ASSERT_EQ(k_cases.size(), kSweepValues.size());
  for (const SweepCase& c : k_cases) EXPECT_EQ(c.displacement.toString(), kSweepDisplacements().front().toString());
  // Yaw 0..70 in steps of 10, one direction.
  const auto yaw_cases = yawSweep().paper_cases(5);
  ASSERT_EQ(yaw_cases.size(), 8u);
  for (std::size_t i = 0; i < yaw_cases.size(); ++i) EXPECT_EQ(yaw_cases[i].displacement.yaw_deg, 10.0 * i);
  // XY: quadrants at 0.25 and 0.5 m, then growing by kPaperXyStep.
  const auto xy_cases = xySweep().paper_cases(5);
  ASSERT_EQ(xy_cases.size(), 8u);
  EXPECT_EQ(std::abs(xy_cases.back().displacement.x), 0.5);
  ASSERT_TRUE(xySweep().paper_extension);
  const auto step2 = xySweep().paper_extension(5, 2);
  ASSERT_EQ(step2.size(), 4u);
  EXPECT_EQ(std::abs(step2[0].displacement.x), 0.5 + 2 * kPaperXyStep);
  EXPECT_FALSE(yawSweep().paper_extension);
}

// Running and the CSV

TEST(SweepRunning, CsvHasOneRowPerRunWithTheDocumentedColumns) {
  AlignmentSettings settings;
  settings.threads = 1;
  const std::vector<SweepCase> cases = yawSweep().cases(5);
  const std::vector<SweepRun> runs = runSweep(cases, sameMapPair(), settings);
  ASSERT_EQ(runs.size(), 60u);
  const auto rows = parseCsv(formatResultsCsv("yaw", runs));
  ASSERT_EQ(rows.size(), 61u);
  EXPECT_EQ(rows[0],
            (std::vector<std::string>{"sweep", "strategy", "k", "x", "y", "z", "roll", "pitch", "yaw", "fitness_score",
                                      "iterations", "refine_iterations", "converged", "time_ms", "rotation_error_deg",
                                      "translation_error_m", "paper_success", "truth_success"}));
  std::set<std::pair<std::string, std::string>> strategy_yaw;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    ASSERT_EQ(rows[i].size(), 18u) << "row " << i;
    // Both verdicts, each following its own rule.
    EXPECT_EQ(rows[i][16], std::stod(rows[i][9]) < kPaperSuccessFitness ? "1" : "0") << "row " << i;
    EXPECT_EQ(rows[i][17],
              std::stod(rows[i][14]) <= kTruthSuccessRotationDeg && std::stod(rows[i][15]) <= kTruthSuccessTranslationM
                  ? "1"
                  : "0")
        << "row " << i;
    EXPECT_EQ(rows[i][0], "yaw");
    EXPECT_EQ(rows[i][2], rows[i][1] == "base" ? "1" : "5");
    EXPECT_FALSE(rows[i][14].empty());
    EXPECT_FALSE(rows[i][15].empty());
    strategy_yaw.insert({rows[i][1], rows[i][8]});
  }
  EXPECT_EQ(strategy_yaw.size(), 60u);  // every strategy x displacement, once
}

/// A Ctrl-C between runs: the sweep ends early with the runs made so far.
TEST(SweepRunning, StopsBeforeTheNextRunWhenAsked) {
  AlignmentSettings settings;
  settings.threads = 1;
  std::size_t asked = 0;
  const auto runs = runSweep(yawSweep().cases(5), sameMapPair(), settings, {}, [&] { return ++asked > 3; });
  EXPECT_EQ(runs.size(), 3u);
  EXPECT_EQ(asked, 4u);
}

TEST(SweepRunning, ErrorsAreMeasuredAgainstTheInverseDisplacement) {
  // With k = 1 every strategy is nearest-neighbour ICP, which recovers this
  // small motion exactly: the error is ~0 only if the truth is D^-1.
  AlignmentSettings settings;
  settings.threads = 1;
  const Displacement small{0.05, -0.04, 0.03, 2.0, -1.0, 6.0};
  const std::vector<SweepRun> runs = runSweep({{1, small}}, sameMapPair(), settings);
  ASSERT_EQ(runs.size(), 4u);
  for (const SweepRun& run : runs) {
    ASSERT_TRUE(run.rotation_error_deg && run.translation_error_m);
    EXPECT_LT(*run.rotation_error_deg, 1e-3) << toString(run.strategy);
    EXPECT_LT(*run.translation_error_m, 1e-4) << toString(run.strategy);
  }
}

TEST(SweepRunning, ZeroDisplacementGivesZeroErrorWithRefinement) {
  AlignmentSettings settings;
  settings.threads = 1;
  settings.refine = true;
  for (const SweepRun& run : runSweep({{5, Displacement{}}}, sameMapPair(), settings)) {
    EXPECT_LT(*run.rotation_error_deg, 1e-3) << toString(run.strategy);
    EXPECT_LT(*run.translation_error_m, 1e-4) << toString(run.strategy);
  }
}

TEST(SweepRunning, ErrorCellsAreEmptyWhenTheTruthIsUnknown) {
  AlignmentSettings settings;
  settings.threads = 1;
  const auto runs = runSweep({{5, Displacement{0, 0, 0, 0, 0, 10}}}, sameMapPair(false), settings);
  const auto rows = parseCsv(formatResultsCsv("yaw", runs));
  ASSERT_EQ(rows.size(), 5u);
  for (std::size_t i = 1; i < rows.size(); ++i) {
    ASSERT_EQ(rows[i].size(), 18u);
    EXPECT_EQ(rows[i][14], "");
    EXPECT_EQ(rows[i][15], "");
    EXPECT_FALSE(rows[i][16].empty());  // the paper's verdict needs no truth
    EXPECT_EQ(rows[i][17], "");         // ours does
  }
}

TEST(SweepRunning, ResultsDoNotDependOnTheThreadCount) {
  AlignmentSettings one, two;
  one.threads = 1;
  two.threads = 2;
  const std::vector<SweepCase> cases = xyYawSweep().cases(5);
  const auto a = runSweep(cases, sameMapPair(), one), b = runSweep(cases, sameMapPair(), two);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].result.transformation, b[i].result.transformation) << "run " << i;
    EXPECT_EQ(a[i].result.iterations, b[i].result.iterations) << "run " << i;
  }
}

// ---------------------------------------------------------------------------
// The tool: maps, options, outputs

class SweepTool : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = weighted_icp::testing::scratchDir("sweep_tool");
    map_path_ = (dir_ / "planes.txt").string();
    io::writeLandmarkMap(planesMap(), map_path_);
  }
  fs::path dir_;
  std::string map_path_;
};

TEST_F(SweepTool, WritesTheCsvAndRunInfoFromASessionMap) {
  const auto [status, errors] =
      runTool(xyYawSweep(), {"--map", map_path_, "--source-frames", "0-5", "--target-frames", "0-5", "--threads", "1",
                             "--no-plot", "--out", (dir_ / "out").string()});
  ASSERT_EQ(status, 0) << errors;
  const auto rows = parseCsv(readFile(dir_ / "out" / "results.csv"));
  EXPECT_EQ(rows.size(), 1u + 64u);
  EXPECT_EQ(rows[1][0], "xy_yaw");
  EXPECT_FALSE(rows[1][14].empty());  // one session map: the truth is known
  EXPECT_NE(readFile(dir_ / "out" / "run.json").find("\"truth_known\":true"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir_ / "out" / "violin.png"));  // --no-plot
}

TEST_F(SweepTool, TruthIsKnownForOneFileAndUnknownForTwo) {
  const std::string copy = (dir_ / "copy.txt").string();
  fs::copy_file(map_path_, copy);
  const auto errorCell = [&](const std::string& target, const std::string& out) {
    const auto [status, errors] =
        runTool(xyYawSweep(), {"--source", map_path_, "--target", target, "--threads", "1", "--no-plot",
                               "--max-iterations", "5", "--out", (dir_ / out).string()});
    EXPECT_EQ(status, 0) << errors;
    return parseCsv(readFile(dir_ / out / "results.csv")).at(1).at(14);
  };
  EXPECT_FALSE(errorCell(map_path_, "same").empty());
  EXPECT_TRUE(errorCell(copy, "two").empty());
}

TEST_F(SweepTool, WithoutFrameRangesTheSessionIsSplitIntoAlternateLandmarks) {
  const auto [status, errors] = runTool(yawSweep(), {"--map", map_path_, "--threads", "1", "--no-plot",
                                                     "--max-iterations", "5", "--out", (dir_ / "out").string()});
  ASSERT_EQ(status, 0) << errors;
  const std::string run = readFile(dir_ / "out" / "run.json");
  EXPECT_NE(run.find("odd landmarks onto even landmarks"), std::string::npos) << run;
  EXPECT_NE(run.find("\"truth_known\":true"), std::string::npos) << run;
  const auto rows = parseCsv(readFile(dir_ / "out" / "results.csv"));
  ASSERT_GT(rows.size(), 1u);
  EXPECT_FALSE(rows[1][14].empty());
}

TEST_F(SweepTool, AMissingMapFailsNamingTheFile) {
  const std::string missing = (dir_ / "no_such_map.txt").string();
  const auto [status, errors] = runTool(yawSweep(), {"--map", missing, "--no-plot", "--out", dir_.string()});
  EXPECT_EQ(status, 1);
  EXPECT_NE(errors.find(missing), std::string::npos) << errors;
  EXPECT_FALSE(fs::exists(dir_ / "results.csv"));
}

TEST_F(SweepTool, BadOptionValuesFailSayingWhich) {
  const auto fails = [&](std::vector<std::string> args, const std::string& expected) {
    args.insert(args.end(), {"--map", map_path_, "--no-plot", "--out", (dir_ / "out").string()});
    const auto [status, errors] = runTool(yawSweep(), args);
    EXPECT_NE(status, 0) << expected;
    EXPECT_NE(errors.find(expected), std::string::npos) << errors;
  };
  fails({"--k", "0"}, "--k must be between 1 and 1000 (got 0)");
  fails({"--max-iterations", "-3"}, "--max-iterations must be between 1 and 1000000 (got -3)");
  fails({"--source-frames", "5-2", "--target-frames", "6-9"}, "--source-frames \"5-2\"");
  fails({"--source-frames", "0-4", "--target-frames", "x"}, "--target-frames \"x\"");
  fails({"--source-frames", "0-4"}, "give both --source-frames and --target-frames");
  fails({"--source-frames", "0-4", "--target-frames", "100-200"}, "frames 100-200");  // no frame of the map
  fails({"--source", map_path_}, "either --map or --source/--target");
  fails({"--bogus"}, "bogus");
  EXPECT_FALSE(fs::exists(dir_ / "out" / "results.csv"));
}

TEST_F(SweepTool, TheKSweepHasNoKOption) {
  const auto [status, errors] = runTool(kSweep(), {"--map", map_path_, "--k", "3", "--no-plot"});
  EXPECT_EQ(status, 2);
  EXPECT_NE(errors.find("'--k'"), std::string::npos) << errors;
}

TEST_F(SweepTool, WithoutMapsTheDefaultSessionMapIsRequired) {
  // Run from a folder nested in the test's own scratch folder, so that ".." is the test's too and
  // ../shared/data cannot exist, whatever lies beside the temporary folder.
  const fs::path nested = dir_ / "cwd";
  fs::create_directories(nested);
  // Restores the working folder however the test ends (its scratch folder is removed afterwards).
  struct WorkingFolder {
    fs::path previous = fs::current_path();
    explicit WorkingFolder(const fs::path& path) { fs::current_path(path); }
    ~WorkingFolder() { fs::current_path(previous); }
  } working_folder(nested);
  ASSERT_FALSE(fs::exists("../shared/data/map_fr1_desk.txt"));
  const auto [status, errors] = runTool(yawSweep(), {"--no-plot"});
  EXPECT_EQ(status, 1);
  EXPECT_NE(errors.find("default --map ../shared/data/map_fr1_desk.txt"), std::string::npos) << errors;
}

}  // namespace
}  // namespace weighted_icp::sweep
