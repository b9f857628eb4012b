// wicp_rgbd_slam's issue #11 options (--descriptor, --match-region,
// --dynamic-distance, --matcher kd-tree, --kd-backtracks, --lsh-seed): a bad value, or a
// matcher's own option given with another matcher, is refused with exit 2, named in the
// error, and nothing is written.

#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "test_support.h"
#include "tool_runner.h"

namespace {

TEST(MatchingOptionsTool, BadValuesAreRefusedWithExitTwo) {
  const auto scratch = weighted_icp::testing::scratchDir("ablation_bad_values");
  const auto out = scratch / "out";
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"--descriptor surf", "surf"},
      {"--match-region nowhere", "nowhere"},
      {"--dynamic-distance speed", "speed"},
      {"--matcher kdtree", "kdtree"},
      {"--kd-backtracks -3", "--kd-backtracks"},
      {"--lsh-seed -1", "--lsh-seed"},
      // a matcher's own option with another matcher
      {"--kd-backtracks 4", "--matcher kd-tree"},
      {"--matcher brute-force --lsh-seed 3", "--matcher lsh or flann"}};
  for (const auto& [arguments, named] : bad) {
    const auto run = weighted_icp::testing::runBuiltTool(
        "wicp_rgbd_slam", arguments + " --synthetic-frames 2 --out " + out.string(), scratch);
    EXPECT_EQ(run.status, 2) << arguments << ": " << run.err;
    EXPECT_NE(run.err.find(named), std::string::npos) << arguments << ": " << run.err;
    EXPECT_FALSE(std::filesystem::exists(out)) << arguments;
  }
}

}  // namespace
