// wicp_rgbd_slam's issue #11 ablation options (--quality-measure, --dense-odometry,
// --dense-odometry-kind, --equalization, --pnp): a name outside the list is a
// command-line error naming the option and the accepted names; accepted names run.

#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "test_support.h"
#include "tool_runner.h"

namespace {

namespace fs = std::filesystem;
using weighted_icp::testing::scratchDir;
using weighted_icp::testing::ToolRun;

ToolRun run(const std::string& args, const fs::path& scratch) {
  return weighted_icp::testing::runBuiltTool("wicp_rgbd_slam", args, scratch, 60);
}

TEST(AblationOptions, UnknownNamesAreCommandLineErrorsListingTheChoices) {
  const fs::path scratch = scratchDir("ablation_bad_names");
  const std::pair<const char*, const char*> cases[] = {
      {"--quality-measure niqe", "--quality-measure must be one of sharpness, brisque (got niqe)"},
      {"--dense-odometry always", "--dense-odometry must be one of off, prior, fallback, prior+fallback (got always)"},
      {"--dense-odometry-kind fast", "--dense-odometry-kind must be one of rgbd, icp, rgbd-icp (got fast)"},
      {"--equalization CLAHE", "--equalization must be one of clahe, global, none (got CLAHE)"},
      {"--pnp epnp", "--pnp must be one of ap3p, iterative (got epnp)"},
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
  std::ifstream report(out / "report.json");
  std::stringstream text;
  text << report.rdbuf();
  EXPECT_NE(text.str().find("\"tracked_frames\":5"), std::string::npos) << text.str();
}

}  // namespace
