// Camera files: the TUM presets by name, YAML read and written, bad files named.
#include <cmath>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "test_support.h"
#include "weighted_icp/io/camera.h"

using namespace weighted_icp;
namespace fs = std::filesystem;
using weighted_icp::testing::writeFile;

namespace {

std::string errorOf(const std::string& preset_or_path) {
  try {
    io::loadCamera(preset_or_path);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return {};
}

const char* const kCompleteYaml =
    "%YAML:1.0\n"
    "fx: 500.5\nfy: 501.25\ncx: 320.0\ncy: 240.0\n"
    "k1: 0.1\nk2: -0.2\np1: 0.001\np2: -0.002\nk3: 0.3\n"
    "width: 640\nheight: 480\ndepth_factor: 1000.0\n";

}  // namespace

TEST(Camera, PresetNamesLoadThePresets) {
  for (int freiburg = 1; freiburg <= 3; ++freiburg) {
    const PinholeCamera preset = tumCamera(freiburg);
    const PinholeCamera loaded = io::loadCamera("fr" + std::to_string(freiburg));
    EXPECT_EQ(loaded.fx, preset.fx);
    EXPECT_EQ(loaded.cy, preset.cy);
    EXPECT_EQ(loaded.distortion, preset.distortion);
  }
}

TEST(Camera, YamlRoundTripKeepsEveryValue) {
  const auto dir = weighted_icp::testing::scratchDir("camera_round_trip");
  PinholeCamera camera = tumCamera(1);
  camera.fx = 1.0 / 3.0 + 500.0;  // not exactly representable in decimal
  camera.width = 1280;
  camera.height = 720;
  camera.depth_factor = 1000.0;
  const std::string path = (dir / "camera.yaml").string();
  io::saveCamera(camera, path);
  const PinholeCamera loaded = io::loadCamera(path);
  EXPECT_EQ(loaded.fx, camera.fx);
  EXPECT_EQ(loaded.fy, camera.fy);
  EXPECT_EQ(loaded.cx, camera.cx);
  EXPECT_EQ(loaded.cy, camera.cy);
  EXPECT_EQ(loaded.distortion, camera.distortion);
  EXPECT_EQ(loaded.width, camera.width);
  EXPECT_EQ(loaded.height, camera.height);
  EXPECT_EQ(loaded.depth_factor, camera.depth_factor);
  // Atomic write: nothing but the camera file is left in the folder.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

TEST(Camera, AnUnregisteredDepthCameraRoundTripsAndNeedsAllItsKeys) {
  const auto dir = weighted_icp::testing::scratchDir("camera_depth_camera");
  PinholeCamera camera = tumCamera(1);
  camera.unregistered_depth = DepthCamera{580.5, 581.25, 314.0, 236.0, {0.025, -0.001, 0.002}, {0.001, 0.0087, -0.002}};
  const std::string path = (dir / "camera.yaml").string();
  io::saveCamera(camera, path);
  const PinholeCamera loaded = io::loadCamera(path);
  ASSERT_TRUE(loaded.unregistered_depth.has_value());
  EXPECT_EQ(loaded.unregistered_depth->fx, 580.5);
  EXPECT_EQ(loaded.unregistered_depth->cy, 236.0);
  EXPECT_EQ(loaded.unregistered_depth->translation_m, camera.unregistered_depth->translation_m);
  EXPECT_EQ(loaded.unregistered_depth->rotation_rad, camera.unregistered_depth->rotation_rad);
  // Without the keys, none.
  writeFile(dir / "plain.yaml", kCompleteYaml);
  EXPECT_FALSE(io::loadCamera((dir / "plain.yaml").string()).unregistered_depth.has_value());
  // Some of them: every missing one named.
  writeFile(dir / "partial.yaml", std::string(kCompleteYaml) + "depth_fx: 580\ndepth_tx: 0.025\n");
  const std::string partial = errorOf((dir / "partial.yaml").string());
  for (const char* key :
       {"depth_fy", "depth_cx", "depth_cy", "depth_ty", "depth_tz", "depth_rx", "depth_ry", "depth_rz"})
    EXPECT_NE(partial.find(std::string(key) + " is missing"), std::string::npos) << key << ": " << partial;
  EXPECT_EQ(partial.find("depth_fx is"), std::string::npos) << partial;
  // Out of range: a depth camera 2 m away, a rotation beyond pi.
  writeFile(dir / "far.yaml", std::string(kCompleteYaml) +
                                  "depth_fx: 580\ndepth_fy: 580\ndepth_cx: 320\ndepth_cy: 240\ndepth_tx: 2.0\n"
                                  "depth_ty: 0\ndepth_tz: 0\ndepth_rx: 0\ndepth_ry: 4.0\ndepth_rz: 0\n");
  const std::string far = errorOf((dir / "far.yaml").string());
  EXPECT_NE(far.find("depth_tx"), std::string::npos) << far;
  EXPECT_NE(far.find("depth_ry"), std::string::npos) << far;
  EXPECT_EQ(far.find("depth_fx"), std::string::npos) << far;
}

// A depth camera of its own resolution (an Azure Kinect's 640x576 depth beside 1280x720 colour): both sizes or
// neither, only with the depth camera, never 0.
TEST(Camera, ADepthCameraOfItsOwnSizeRoundTripsAndNeedsBothSides) {
  const auto dir = weighted_icp::testing::scratchDir("camera_depth_size");
  PinholeCamera camera = tumCamera(1);
  camera.unregistered_depth = DepthCamera{290.0, 290.5, 157.0, 118.0, {0.025, 0.0, 0.0}, {}, 320, 240};
  EXPECT_EQ(camera.depthImageSize(), cv::Size(320, 240));
  const std::string path = (dir / "camera.yaml").string();
  io::saveCamera(camera, path);
  const PinholeCamera loaded = io::loadCamera(path);
  ASSERT_TRUE(loaded.unregistered_depth.has_value());
  EXPECT_EQ(loaded.depthImageSize(), cv::Size(320, 240));
  EXPECT_EQ(loaded.unregistered_depth->cx, 157.0);
  // Without the sizes, the colour image's.
  camera.unregistered_depth->width = camera.unregistered_depth->height = 0;
  io::saveCamera(camera, path);
  EXPECT_EQ(io::loadCamera(path).depthImageSize(), cv::Size(640, 480));
  const std::string depth_camera =
      "depth_fx: 290\ndepth_fy: 290\ndepth_cx: 157\ndepth_cy: 118\ndepth_tx: 0.025\n"
      "depth_ty: 0\ndepth_tz: 0\ndepth_rx: 0\ndepth_ry: 0\ndepth_rz: 0\n";
  const auto error = [&](const std::string& name, const std::string& extra) {
    writeFile(dir / name, std::string(kCompleteYaml) + extra);
    return errorOf((dir / name).string());
  };
  const std::string one_side = error("one_side.yaml", depth_camera + "depth_width: 320\n");
  EXPECT_NE(one_side.find("depth_height is missing"), std::string::npos) << one_side;
  const std::string alone = error("alone.yaml", "depth_width: 320\ndepth_height: 240\n");
  EXPECT_NE(alone.find("depth_width and depth_height need the depth camera's keys"), std::string::npos) << alone;
  const std::string zero = error("zero.yaml", depth_camera + "depth_width: 0\ndepth_height: 240\n");
  EXPECT_NE(zero.find("depth_width must be between 1"), std::string::npos) << zero;
  EXPECT_EQ(zero.find("depth_height"), std::string::npos) << zero;
  // The depth camera's principal point is judged against its own image: 157 is far outside a 64-pixel-wide one.
  const std::string outside = error("outside.yaml", depth_camera + "depth_width: 64\ndepth_height: 240\n");
  EXPECT_NE(outside.find("depth_cx must be between"), std::string::npos) << outside;
}

TEST(Camera, HandWrittenYamlLoads) {
  const auto dir = weighted_icp::testing::scratchDir("camera_hand_written");
  writeFile(dir / "camera.yaml", kCompleteYaml);
  const PinholeCamera camera = io::loadCamera((dir / "camera.yaml").string());
  EXPECT_EQ(camera.fx, 500.5);
  EXPECT_EQ(camera.fy, 501.25);
  EXPECT_EQ(camera.distortion[1], -0.2);
  EXPECT_EQ(camera.distortion[4], 0.3);
  EXPECT_EQ(camera.depth_factor, 1000.0);
}

TEST(Camera, EveryMissingKeyIsNamedAtOnce) {
  const auto dir = weighted_icp::testing::scratchDir("camera_missing_keys");
  const fs::path path = dir / "partial.yaml";
  writeFile(path, "%YAML:1.0\nfx: 500.0\ncx: 320.0\ncy: 240.0\nk1: 0\nk2: 0\np1: 0\np2: 0\nwidth: 640\nheight: 480\n");
  const std::string error = errorOf(path.string());
  EXPECT_NE(error.find(path.string()), std::string::npos) << error;
  for (const char* key : {"fy", "k3", "depth_factor"})
    EXPECT_NE(error.find(std::string(key) + " is missing"), std::string::npos) << key << ": " << error;
  for (const char* key : {"fx ", "cx ", "width "}) EXPECT_EQ(error.find(key), std::string::npos) << error;
}

TEST(Camera, InvalidValuesAreRefusedWithTheirKeys) {
  const auto dir = weighted_icp::testing::scratchDir("camera_invalid");
  const fs::path path = dir / "invalid.yaml";
  writeFile(path,
            "%YAML:1.0\nfx: -500.0\nfy: 0\ncx: .nan\ncy: 240.0\nk1: 0\nk2: 0\np1: 0\np2: 0\nk3: 0\n"
            "width: 640.5\nheight: -480\ndepth_factor: \"many\"\n");
  const std::string error = errorOf(path.string());
  EXPECT_NE(error.find(path.string()), std::string::npos) << error;
  for (const char* key : {"fx", "fy", "cx", "width", "height", "depth_factor"})
    EXPECT_NE(error.find(std::string(key) + " "), std::string::npos) << key << ": " << error;
  EXPECT_EQ(error.find("cy "), std::string::npos) << error;
}

TEST(Camera, UnreadableFilesAreNamed) {
  const auto dir = weighted_icp::testing::scratchDir("camera_unreadable");
  const std::string missing = (dir / "absent.yaml").string();
  EXPECT_NE(errorOf(missing).find(missing), std::string::npos);
  EXPECT_NE(errorOf("fr4").find("fr4"), std::string::npos);
  const fs::path garbage = dir / "garbage.yaml";
  writeFile(garbage, "%YAML:1.0\nfx: [1, 2\n  : : }\n");
  EXPECT_NE(errorOf(garbage.string()).find(garbage.string()), std::string::npos);
  const fs::path list = dir / "list.yaml";  // valid YAML, but no keys
  writeFile(list, "%YAML:1.0\n- 1\n- 2\n");
  EXPECT_NE(errorOf(list.string()).find(list.string()), std::string::npos);
  const fs::path empty = dir / "empty.yaml";
  writeFile(empty, "");
  EXPECT_NE(errorOf(empty.string()).find(empty.string()), std::string::npos);
}

// Found by fuzz/fuzz_camera: OpenCV's YAML parser loops forever on this text; it is refused by line first.
TEST(Camera, TextOpenCvCannotParseIsRefusedByLine) {
  const auto dir = weighted_icp::testing::scratchDir("camera_layout");
  const fs::path hang = dir / "hang.yaml";
  writeFile(hang, "%YAML:1.0\n---<:p\na: -\n");
  const std::string error = errorOf(hang.string());
  EXPECT_NE(error.find(hang.string() + ":2: not a camera file"), std::string::npos) << error;
  EXPECT_NE(error.find("'---<:p'"), std::string::npos) << error;
  // An indented line not below a key (fuzz/fuzz_camera, 2026-11-25: OpenCV looped forever on it).
  const fs::path orphan = dir / "orphan.yaml";
  writeFile(orphan, "%YAML:1.0\n\n yyyyyyyyyyyyyyyyyy0.9:3104\np1: -0.005358\n");
  const std::string orphan_error = errorOf(orphan.string());
  EXPECT_NE(orphan_error.find(orphan.string() + ":3: not a camera file: an indented line not below a key"),
            std::string::npos)
      << orphan_error;
  // XML with NUL bytes in an attribute (fuzz/fuzz_camera, 2026-11-26: OpenCV's parser dereferenced null on it).
  const fs::path binary = dir / "binary.xml";
  writeFile(binary, std::string("<?xml veRsion=\0\0\0\"0.1\"?>\n<opencv_storage>\n</opencv_storage>\n", 60));
  const std::string binary_error = errorOf(binary.string());
  EXPECT_NE(binary_error.find(binary.string() + ":1: not a camera file: a NUL byte"), std::string::npos)
      << binary_error;
  // What OpenCV writes is of the plain layout, indented matrices of other keys included.
  const fs::path opencv = dir / "opencv.yaml";
  writeFile(opencv,
            "%YAML:1.0\n---\n# calibration\nfx: 517.3\nfy: 516.5\ncx: 318.6\ncy: 255.3\nk1: 0\nk2: 0\np1: 0\n"
            "p2: 0\nk3: 0\nwidth: 640\nheight: 480\ndepth_factor: 5000.\nK: !!opencv-matrix\n   rows: 1\n   cols: 1\n"
            "   dt: d\n   data: [ 1. ]\n");
  EXPECT_EQ(io::loadCamera(opencv.string()).fx, 517.3);
}

TEST(Camera, InvalidCamerasAreNotSaved) {
  const auto dir = weighted_icp::testing::scratchDir("camera_save_invalid");
  PinholeCamera camera = tumCamera(3);
  camera.depth_factor = 0.0;
  const std::string path = (dir / "camera.yaml").string();
  EXPECT_THROW(io::saveCamera(camera, path), std::runtime_error);
  EXPECT_FALSE(fs::exists(path));
  camera = tumCamera(3);
  camera.fy = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(io::saveCamera(camera, path), std::runtime_error);
  EXPECT_FALSE(fs::exists(path));
}

/// Implausible but finite values (a focal length in millimetres, a principal
/// point far outside the image, a depth factor of 0.001) are refused by key.
TEST(Camera, ImplausibleValuesAreRefusedWithTheirKeysAndRanges) {
  const auto dir = weighted_icp::testing::scratchDir("camera_implausible");
  const fs::path path = dir / "implausible.yaml";
  writeFile(path,
            "%YAML:1.0\nfx: 0.5\nfy: 2e6\ncx: 5000\ncy: -300\nk1: 0\nk2: 0\np1: 0\np2: 0\nk3: 0\n"
            "width: 640\nheight: 480\ndepth_factor: 0.001\n");
  const std::string error = errorOf(path.string());
  for (const char* key : {"fx", "fy", "cx", "cy", "depth_factor"})
    EXPECT_NE(error.find(std::string(key) + " must be between"), std::string::npos) << key << ": " << error;
  EXPECT_EQ(error.find("width "), std::string::npos) << error;
  // Each with the line it is on.
  EXPECT_NE(error.find("line 2: fx must be between"), std::string::npos) << error;
  EXPECT_NE(error.find("line 13: depth_factor must be between"), std::string::npos) << error;

  // The edges of the ranges are accepted: a principal point just outside the
  // image, a 1 px focal length, a depth factor of 1e6.
  writeFile(path,
            "%YAML:1.0\nfx: 1\nfy: 1e5\ncx: -100\ncy: 700\nk1: 0\nk2: 0\np1: 0\np2: 0\nk3: 0\n"
            "width: 640\nheight: 480\ndepth_factor: 1e6\n");
  EXPECT_EQ(errorOf(path.string()), "") << "a plausible camera was refused";

  PinholeCamera camera = tumCamera(1);
  camera.depth_factor = 1e7;  // refused when saving too, so a saved camera loads back
  EXPECT_THROW(io::saveCamera(camera, (dir / "saved.yaml").string()), std::runtime_error);
}

// The camera a TUM folder is read with: the one asked for, else its camera.yaml, else its name; a folder that does
// not exist is named as such (not as a camera the tools cannot guess).
TEST(Camera, ADatasetsCameraIsAskedForOrItsOwnOrNamedByTheFolder) {
  const auto dir = weighted_icp::testing::scratchDir("camera_of_dataset");
  const fs::path named = dir / "rgbd_dataset_freiburg3_teddy", own = dir / "recording", plain = dir / "plain";
  for (const fs::path& folder : {named, own, plain}) fs::create_directories(folder);
  writeFile((own / "camera.yaml").string(), kCompleteYaml);

  EXPECT_EQ(io::datasetCamera(named.string(), "").fx, tumCamera(3).fx);
  EXPECT_EQ(io::datasetCamera(own.string(), "").fx, 500.5);
  EXPECT_EQ(io::datasetCamera(own.string(), "fr2").fx, tumCamera(2).fx);  // asked for: before the folder's own
  EXPECT_EQ(io::datasetCamera(named.string() + "/", "").fx, tumCamera(3).fx);

  const auto error = [](const std::string& dataset, const std::string& how) {
    try {
      io::datasetCamera(dataset, "", how);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string unnamed = error(plain.string(), "--camera");
  EXPECT_NE(unnamed.find(plain.string()), std::string::npos) << unnamed;
  EXPECT_NE(unnamed.find("--camera fr1|fr2|fr3|FILE.yaml"), std::string::npos) << unnamed;
  EXPECT_NE(error(plain.string(), "camera=").find("pass camera="), std::string::npos);
  const std::string missing = error((dir / "tum_fr1_xyz_hed").string(), "--camera");  // a typo, named like fr1
  EXPECT_NE(missing.find("tum_fr1_xyz_hed: no such folder"), std::string::npos) << missing;
  EXPECT_NE(error((dir / "kinn").string(), "--camera").find("kinn: no such folder"), std::string::npos);
}
