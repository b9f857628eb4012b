// wicp_rgbd_slam's issue #11 ablation options (--quality-measure, --dense-odometry,
// --dense-odometry-kind, --equalization, --pnp) and --quality-gate: a name outside the list is a
// command-line error naming the option and the accepted names (read by the library's own parser);
// accepted names run. scripts/run_ablation.py runs option sets over variants and sums them up.

#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "test_support.h"
#include "tool_runner.h"

namespace {

namespace fs = std::filesystem;
using weighted_icp::testing::readFile;
using weighted_icp::testing::scratchDir;
using weighted_icp::testing::ToolRun;

ToolRun run(const std::string& args, const fs::path& scratch) {
  return weighted_icp::testing::runBuiltTool("wicp_rgbd_slam", args, scratch, 60);
}

TEST(AblationOptions, UnknownNamesAreCommandLineErrorsListingTheChoices) {
  const fs::path scratch = scratchDir("ablation_bad_names");
  const std::pair<const char*, const char*> cases[] = {
      {"--quality-measure niqe", "--quality-measure: unknown quality measure 'niqe' (expected sharpness or brisque)"},
      {"--dense-odometry always",
       "--dense-odometry: unknown dense odometry use 'always' (expected off, prior, "
       "fallback or prior+fallback)"},
      {"--dense-odometry-kind fast",
       "--dense-odometry-kind: unknown dense odometry kind 'fast' (expected rgbd, icp or "
       "rgbd-icp)"},
      {"--equalization CLAHE", "--equalization: unknown equalisation 'CLAHE' (expected clahe, global or none)"},
      {"--pnp epnp", "--pnp: unknown PnP method 'epnp' (expected ap3p or iterative)"},
      {"--quality-gate strict", "--quality-gate: unknown quality gate mode 'strict' (expected relative,"},
  };
  for (const auto& [args, message] : cases) {
    SCOPED_TRACE(args);
    const ToolRun r = run(std::string("--out ") + (scratch / "out").string() + " " + args, scratch);
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(scratch / "out"));
  }
}

TEST(AblationOptions, EveryOptionRunsOnAFewSyntheticFrames) {
  const fs::path scratch = scratchDir("ablation_runs");
  const fs::path out = scratch / "out";
  const std::string args =
      "--synthetic-frames 5 --deterministic --quality-measure brisque --dense-odometry "
      "prior+fallback --dense-odometry-kind rgbd-icp --equalization global --pnp iterative "
      "--overwrite --out " +
      out.string();
  const ToolRun r = run(args, scratch);
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string report = readFile(out / "report.json");
  EXPECT_NE(report.find("\"tracked_frames\":5"), std::string::npos) << report;
}

TEST(AblationRunner, WritesEveryRowAndASummaryOfEachSetAgainstTheFirst) {
  const fs::path scratch = scratchDir("ablation_runner");
  const fs::path table = scratch / "table.md";
  // Two rows (one a variant of two kinds joined by "+"), two option sets: the first is the baseline.
  const ToolRun r = weighted_icp::testing::runScript(
      "run_ablation.py",
      "--scratch '" + (scratch / "work").string() + "' --out '" + table.string() +
          "' --sequences synthetic --variants original,jpeg+blur --synthetic-frames 6 --set base= "
          "--set iterative='--pnp iterative'",
      scratch);
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string text = readFile(table);
  EXPECT_NE(text.find("| sequence | base | iterative |"), std::string::npos) << text;
  EXPECT_NE(text.find("| synthetic | "), std::string::npos) << text;
  EXPECT_NE(text.find("| synthetic, jpeg+blur | "), std::string::npos) << text;
  EXPECT_EQ(text.find("| failed |"), std::string::npos) << text;  // no run failed
  // The baseline against itself: ratio 1, nothing lower or higher, no rise; the other set has its own line.
  EXPECT_NE(text.find("| base | 1.000 | 0 / 0 | none | 1.000 | 0 | 1.000 | 0 |"), std::string::npos) << text;
  EXPECT_NE(text.find("| iterative | "), std::string::npos) << text;
  EXPECT_EQ(text, r.out.substr(r.out.size() - text.size())) << "the table printed is the one written";
  EXPECT_TRUE(fs::is_directory(scratch / "work" / "variants" / "synthetic_jpeg+blur"));
}

TEST(AblationRunner, FlagsTheToolRefusesStopTheRunNamingThem) {
  const fs::path scratch = scratchDir("ablation_runner_bad");
  const ToolRun r = weighted_icp::testing::runScript(
      "run_ablation.py",
      "--scratch '" + (scratch / "work").string() +
          "' --sequences synthetic --variants original --synthetic-frames 4 --set bad='--pnp epnp'",
      scratch);
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("refused the flags '--pnp epnp'"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(scratch / "work" / "ablation.md"));
}

}  // namespace
