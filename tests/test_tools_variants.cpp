// wicp_make_variant end to end: a variant is written with its camera.yaml and
// wicp_rgbd_slam runs on it as it is; a bad camera file, images of another size
// than the camera's and a bad command line give clear errors and no output.

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "test_support.h"
#include "tool_runner.h"

namespace {

using weighted_icp::testing::dataDir;
using weighted_icp::testing::runBuiltTool;
using weighted_icp::testing::scratchDir;
namespace fs = std::filesystem;

TEST(MakeVariant, WritesAVariantThatWicpRgbdSlamRunsWithItsOwnCamera) {
  const fs::path scratch = scratchDir("variant");
  const auto made = runBuiltTool(
      "wicp_make_variant", "--synthetic-frames 12 --variant mm-depth,jpeg --out " + (scratch / "v").string(), scratch);
  ASSERT_EQ(made.status, 0) << made.err;
  EXPECT_TRUE(fs::exists(scratch / "v" / "camera.yaml"));
  EXPECT_NE(made.out.find("depth factor 1000"), std::string::npos) << made.out;
  // No --camera: the folder's camera.yaml (depth factor 1000) is what makes the depth metric.
  const auto slam = runBuiltTool(
      "wicp_rgbd_slam",
      "--dataset " + (scratch / "v").string() + " --deterministic --out " + (scratch / "run").string(), scratch);
  ASSERT_EQ(slam.status, 0) << slam.err;
  EXPECT_NE(slam.out.find("ATE RMSE"), std::string::npos) << slam.out;
}

TEST(MakeVariant, NamesABadCameraFileAndWritesNothing) {
  const fs::path scratch = scratchDir("variant");
  const fs::path camera = scratch / "camera.yaml";
  std::ofstream(camera) << "%YAML:1.0\n---\nfx: 517.3\nfy: -1\n";
  const auto run = runBuiltTool("wicp_make_variant",
                                "--dataset " + (dataDir() / "tum_fr1_xyz_head").string() + " --camera " +
                                    camera.string() + " --variant jpeg --out " + (scratch / "v").string(),
                                scratch);
  EXPECT_EQ(run.status, 1);
  EXPECT_NE(run.err.find(camera.string()), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(scratch / "v"));
}

TEST(MakeVariant, NamesAnImageOfAnotherSizeThanTheCamerasAndWritesNothing) {
  const fs::path scratch = scratchDir("variant");
  const auto made = runBuiltTool("wicp_make_variant",
                                 "--synthetic-frames 2 --variant jpeg --out " + (scratch / "v").string(), scratch);
  ASSERT_EQ(made.status, 0) << made.err;
  // A camera of half the size: the first image read is named, with both sizes.
  std::ifstream in(scratch / "v" / "camera.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), {}), replaced;
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"width: 640", "width: 320"},
                                 std::pair<std::string, std::string>{"height: 480", "height: 240"}})
    text.replace(text.find(from), from.size(), to);
  std::ofstream(scratch / "half.yaml") << text;
  const auto run =
      runBuiltTool("wicp_make_variant",
                   "--dataset " + (scratch / "v").string() + " --camera " + (scratch / "half.yaml").string() +
                       " --variant blur --out " + (scratch / "w").string(),
                   scratch);
  EXPECT_EQ(run.status, 1);
  EXPECT_NE(run.err.find("rgb/"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("640"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(scratch / "w"));
}

TEST(MakeVariant, RefusesABadCommandLine) {
  const fs::path scratch = scratchDir("variant");
  const std::string out = " --out " + (scratch / "v").string();
  for (const std::string& args :
       {"--variant sepia" + out, "--variant jpeg,jpeg" + out, "--variant jpeg --jpeg-quality 0" + out,
        "--variant burst --burst-length 5 --burst-period 2" + out, std::string("--variant jpeg")}) {
    const auto run = runBuiltTool("wicp_make_variant", args, scratch);
    EXPECT_EQ(run.status, 2) << args << ": " << run.err;
    EXPECT_FALSE(run.err.empty()) << args;
  }
  EXPECT_FALSE(fs::exists(scratch / "v"));
}

}  // namespace
