// The wicp_vocabulary tool as a user runs it: training writes a loadable
// vocabulary; bad command lines exit 2, bad files exit 1 naming file and line,
// and nothing is written on failure.

#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "test_support.h"
#include "tool_runner.h"
#include "weighted_icp/mapping/binary_vocabulary.h"

namespace weighted_icp::testing {
namespace {

TEST(WicpVocabulary, TrainsALoadableVocabulary) {
  const auto dir = scratchDir("train");
  const auto out = dir / "vocabulary.txt";
  const ToolRun run = runBuiltTool(
      "wicp_vocabulary",
      "train --synthetic 5 --synthetic-frames 21 --every 10 --branching 4 --depth 3 --out " + out.string(), dir);
  ASSERT_EQ(run.status, 0) << run.err;
  const mapping::BinaryVocabulary vocabulary = mapping::BinaryVocabulary::load(out.string());
  EXPECT_GT(vocabulary.wordCount(), 4u);
  EXPECT_NE(run.out.find("\"words\":" + std::to_string(vocabulary.wordCount())), std::string::npos) << run.out;
}

TEST(WicpVocabulary, BadCommandLinesAndFilesFailCleanly) {
  const auto dir = scratchDir("bad");
  const auto out = dir / "vocabulary.txt";
  EXPECT_EQ(runBuiltTool("wicp_vocabulary", "", dir).status, 2);
  EXPECT_EQ(runBuiltTool("wicp_vocabulary", "cluster --out " + out.string(), dir).status, 2);
  EXPECT_EQ(runBuiltTool("wicp_vocabulary", "train --out " + out.string(), dir).status, 2);  // no data
  EXPECT_EQ(runBuiltTool("wicp_vocabulary", "train --synthetic 5 --branching 1 --out " + out.string(), dir).status, 2);
  const ToolRun missing =
      runBuiltTool("wicp_vocabulary", "train --dataset " + (dir / "absent").string() + " --out " + out.string(), dir);
  EXPECT_EQ(missing.status, 1);
  EXPECT_NE(missing.err.find("absent"), std::string::npos) << missing.err;
  EXPECT_FALSE(std::filesystem::exists(out));

  const auto corrupt = dir / "corrupt.txt";
  writeFile(corrupt, "wicp_vocabulary 1\nbranching 4\ndepth x\n");
  const ToolRun bad = runBuiltTool(
      "wicp_vocabulary", "evaluate --vocabulary " + corrupt.string() + " --synthetic 5 --synthetic-frames 2", dir);
  EXPECT_EQ(bad.status, 1);
  EXPECT_NE(bad.err.find(corrupt.string() + ":3:"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace weighted_icp::testing
