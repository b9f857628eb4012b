// The paper's landmark map format: exact round trip, the real map, and every
// kind of malformed input refused with the file and line.

#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "landmark_map_expectations.h"
#include "test_support.h"
#include "weighted_icp/io/map_format.h"

namespace {

using namespace weighted_icp;
namespace fs = std::filesystem;
using weighted_icp::testing::readFile;
using weighted_icp::testing::realMapPath;
using weighted_icp::testing::scratchDir;
using weighted_icp::testing::writeFile;

std::size_t filesIn(const fs::path& folder) {
  return static_cast<std::size_t>(std::distance(fs::directory_iterator(folder), fs::directory_iterator()));
}

/// Awkward values on purpose: non-terminating binary fractions, tiny and huge
/// magnitudes, non-contiguous ids, a landmark without observations.
LandmarkMap awkwardMap() {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> uniform(-3.0, 3.0);
  LandmarkMap map;
  for (const FrameId id : {0u, 3u, 17u, 1000u}) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = Eigen::AngleAxisd(uniform(random),
                                      Eigen::Vector3d(uniform(random), uniform(random), uniform(random)).normalized())
                        .toRotationMatrix();
    pose.translation() = Eigen::Vector3d(uniform(random), 1.0 / 3.0, -2.5e17);
    map.frames[id] = pose;
  }
  for (const LandmarkId id : {42u, 7u, 99999u}) {
    Landmark landmark;
    landmark.id = id;
    landmark.position = Eigen::Vector3d(uniform(random), 0.1, 1e-300);
    const Eigen::Matrix3d a = Eigen::Matrix3d::NullaryExpr([&] { return uniform(random); });
    landmark.covariance = a * a.transpose() * 1e-4;
    map.landmarks.push_back(landmark);
  }
  map.landmarks[0].observations = {{0, 318.123456789, 255.3}, {17, 1.0 / 7.0, 479.999999}};
  map.landmarks[2].observations = {{1000, 0.0, 0.0}, {3, 640.0, 2.0 / 3.0}, {0, 12.5, 99.25}};
  return map;
}

TEST(MapFormat, WriteThenReadGivesTheSameMap) {
  const LandmarkMap map = awkwardMap();
  const fs::path path = scratchDir("map_round_trip") / "map.txt";
  io::writeLandmarkMap(map, path.string());
  const LandmarkMap read = io::readLandmarkMap(path.string());

  ASSERT_EQ(read.frames.size(), map.frames.size());
  for (const auto& [id, pose] : map.frames) {
    ASSERT_TRUE(read.frames.count(id)) << "frame " << id;
    EXPECT_EQ(read.frames.at(id).translation(), pose.translation()) << "frame " << id;
    EXPECT_LT((read.frames.at(id).linear() - pose.linear()).cwiseAbs().maxCoeff(), 1e-12) << "frame " << id;
  }
  weighted_icp::testing::expectSameLandmarks(map, read);
}

TEST(MapFormat, AcceptsCrlfCommentsAndBlankLines) {
  const fs::path path = scratchDir("map_crlf") / "map.txt";
  writeFile(path,
            "# exported on Windows\r\n"
            "\r\n"
            "FRAME 5  1 2 3  1 0 0 0\r\n"
            "   \t\r\n"
            "  # indented comment\r\n"
            "LANDMARK 8  0.5 -0.5 2  0.01 0 0 0 0.02 0 0 0 0.03  1  5 320.5 240.25\r\n");
  const LandmarkMap map = io::readLandmarkMap(path.string());
  ASSERT_EQ(map.frames.size(), 1u);
  EXPECT_EQ(map.frames.at(5).translation(), Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(map.frames.at(5).linear().isIdentity(0.0));
  ASSERT_EQ(map.landmarks.size(), 1u);
  EXPECT_EQ(map.landmarks[0].position, Eigen::Vector3d(0.5, -0.5, 2));
  EXPECT_EQ(map.landmarks[0].covariance.diagonal(), Eigen::Vector3d(0.01, 0.02, 0.03));
  ASSERT_EQ(map.landmarks[0].observations.size(), 1u);
  EXPECT_EQ(map.landmarks[0].observations[0].frame_id, 5u);
  EXPECT_EQ(map.landmarks[0].observations[0].u, 320.5);
  EXPECT_EQ(map.landmarks[0].observations[0].v, 240.25);  // not "240.25\r"
}

TEST(MapFormat, EmptyFileIsAnEmptyMap) {
  const fs::path path = scratchDir("map_empty") / "map.txt";
  writeFile(path, "# nothing yet\n");
  const LandmarkMap map = io::readLandmarkMap(path.string());
  EXPECT_TRUE(map.frames.empty());
  EXPECT_TRUE(map.landmarks.empty());
}

// ---- malformed input --------------------------------------------------------

const char* const kTwoFrames =
    "FRAME 0  0 0 0  1 0 0 0\n"
    "FRAME 1  1 0 0  1 0 0 0\n";

/// Writes `text` to a file and checks that reading it fails at `line` with a
/// message naming the file, the line and containing `what`.
void expectRefused(const std::string& text, std::size_t line, const std::string& what) {
  // One folder per test: ctest runs tests in parallel.
  const fs::path path =
      scratchDir(std::string("map_malformed_") + ::testing::UnitTest::GetInstance()->current_test_info()->name()) /
      "bad_map.txt";
  writeFile(path, text);
  try {
    io::readLandmarkMap(path.string());
    ADD_FAILURE() << "accepted:\n" << text;
  } catch (const io::MapFormatError& e) {
    EXPECT_EQ(e.source(), path.string());
    EXPECT_EQ(e.line(), line) << e.what();
    const std::string message = e.what();
    EXPECT_NE(message.find(path.string() + ":" + std::to_string(line) + ": "), std::string::npos) << message;
    EXPECT_NE(message.find(what), std::string::npos) << "'" << what << "' not in: " << message;
  }
}

TEST(MapFormatErrors, UnknownRecordType) {
  expectRefused(std::string(kTwoFrames) + "POINT 1 2 3\n", 3, "unknown record 'POINT'");
}

TEST(MapFormatErrors, FrameWithWrongFieldCount) {
  expectRefused(std::string(kTwoFrames) + "FRAME 2  0 0 0  1 0 0\n", 3, "FRAME needs 9 fields");
  expectRefused(std::string(kTwoFrames) + "FRAME 2  0 0 0  1 0 0 0 7\n", 3, "found 10");
}

TEST(MapFormatErrors, LandmarkWhoseCountDoesNotMatchItsFields) {
  const std::string head = std::string(kTwoFrames) + "LANDMARK 1  0 0 1  1 0 0 0 1 0 0 0 1  ";
  expectRefused(head + "2  0 10 20\n", 3, "n = 2");
  expectRefused(head + "1  0 10 20  1\n", 3, "n = 1");
  expectRefused(head + "0  0 10 20\n", 3, "n = 0");
  expectRefused(std::string(kTwoFrames) + "LANDMARK 1  0 0 1  1 0 0 0 1 0 0 0 1\n", 3, "at least 15 fields");
  // 15 + 3n wraps around to 16 for this n: it must not pass for one extra field.
  expectRefused(head + "12297829382473034411  0\n", 3, "n = 12297829382473034411");
}

TEST(MapFormatErrors, NonNumbers) {
  expectRefused(std::string(kTwoFrames) + "FRAME 2  0 0 zero  1 0 0 0\n", 3, "tz 'zero' is not a number");
  expectRefused(std::string(kTwoFrames) + "FRAME 2  0 0 1.5e  1 0 0 0\n", 3, "tz '1.5e' is not a number");
  expectRefused(std::string(kTwoFrames) + "FRAME two  0 0 0  1 0 0 0\n", 3, "frame id 'two'");
  expectRefused(std::string(kTwoFrames) + "LANDMARK 1  0 0 1  1 0 0 0 1 0 0 0 1  1  0 1O 20\n", 3,
                "observation u '1O' is not a number");
}

/// The message of reading `text` as a map; empty if it was read.
std::string refusal(const std::string& text) {
  const fs::path path =
      scratchDir(std::string("map_token_") + ::testing::UnitTest::GetInstance()->current_test_info()->name()) /
      "bad_map.txt";
  writeFile(path, text);
  try {
    io::readLandmarkMap(path.string());
  } catch (const io::MapFormatError& e) {
    return e.what();
  }
  return {};
}

// Issue #10: a bad token is echoed clipped and escaped, whatever the file holds.
TEST(MapFormatErrors, HugeTokenIsClipped) {
  const std::string message =
      refusal(std::string(kTwoFrames) + "FRAME 2  0 0 " + std::string(1 << 20, '7') + "x  1 0 0 0\n");
  EXPECT_LT(message.size(), 200u + scratchDir("map_token_HugeTokenIsClipped").string().size()) << message;
  EXPECT_NE(message.find("tz '7777"), std::string::npos) << message;
  EXPECT_NE(message.find("(1048577 bytes) is not a number"), std::string::npos) << message;
}

TEST(MapFormatErrors, NulAndBinaryBytesAreEscaped) {
  const std::string nul = refusal(std::string(kTwoFrames) + "FRAME 2  0 0 1" + std::string(1, '\0') + "2  1 0 0 0\n");
  EXPECT_NE(nul.find("tz '1\\x002' is not a number"), std::string::npos) << nul;
  const std::string binary = refusal(std::string(kTwoFrames) + "\x01\xff\x1b[31m 2\n");
  EXPECT_NE(binary.find("unknown record '\\x01\\xff\\x1b[31m'"), std::string::npos) << binary;
  for (const char c : binary) EXPECT_TRUE(c >= 0x20 && c < 0x7f) << binary;
}

TEST(MapFormatErrors, NanAndInfinity) {
  expectRefused(std::string(kTwoFrames) + "LANDMARK 1  nan 0 1  1 0 0 0 1 0 0 0 1  0\n", 3, "x is nan");
  expectRefused(std::string(kTwoFrames) + "LANDMARK 1  0 0 1  1 0 0 0 inf 0 0 0 1  0\n", 3, "covariance entry is inf");
  expectRefused(std::string(kTwoFrames) + "FRAME 2  0 0 0  1 0 0 -infinity\n", 3, "qz is -infinity");
  expectRefused(std::string(kTwoFrames) + "LANDMARK 1  0 0 1  1 0 0 0 1 0 0 0 1  1  0 NaN 20\n", 3,
                "observation u is NaN");
}

TEST(MapFormatErrors, NegativeObservationCount) {
  expectRefused(std::string(kTwoFrames) + "LANDMARK 1  0 0 1  1 0 0 0 1 0 0 0 1  -1\n", 3,
                "observation count n '-1' is not a non-negative integer");
}

TEST(MapFormatErrors, PositionBeyondWhatTheSearchIndexHolds) {
  // 1.8e38 is a valid double but overflows the float kd-tree's split: it crashed wicp_align.
  expectRefused(std::string(kTwoFrames) + "LANDMARK 5  1.8e38 0 1  1 0 0 0 1 0 0 0 1  0\n", 3,
                "landmark 5: position has a coordinate beyond");
  expectRefused(std::string(kTwoFrames) + "LANDMARK 5  0 0 -2e18  1 0 0 0 1 0 0 0 1  0\n", 3, "beyond ±1e18");
}

TEST(MapFormatErrors, CovarianceThatIsNotOne) {
  expectRefused(std::string(kTwoFrames) + "LANDMARK 8  0 0 1  1 0.5 0 0 1 0 0 0 1  0\n", 3,
                "landmark 8: covariance is not symmetric");
  expectRefused(std::string(kTwoFrames) + "LANDMARK 8  0 0 1  1 0 0 0 -1 0 0 0 1  0\n", 3,
                "landmark 8: covariance is not positive semi-definite");
  expectRefused(std::string(kTwoFrames) + "LANDMARK 8  0 0 1  1 2 0 2 1 0 0 0 1  0\n", 3,
                "not positive semi-definite");  // symmetric, eigenvalues 3, -1, 1
}

TEST(MapFormat, AcceptsCovariancesWithinRoundingOfValidOnes) {
  const fs::path path = scratchDir("rounding") / "map.txt";
  // Asymmetric in the 12th digit, singular, and a -1e-20 eigenvalue from printing: all real covariances.
  writeFile(path, std::string(kTwoFrames) +
                      "LANDMARK 1  0 0 1  1e-4 2.0000000000001e-5 0 2e-5 1e-4 0 0 0 1e-4  0\n"
                      "LANDMARK 2  0 0 1  1 1 0 1 1 0 0 0 0  0\n"
                      "LANDMARK 3  0 0 1  1 0 0 0 -1e-20 0 0 0 1  0\n"
                      "LANDMARK 4  1e18 -1e18 1  0 0 0 0 0 0 0 0 0  0\n");
  EXPECT_EQ(io::readLandmarkMap(path.string()).landmarks.size(), 4u);
}

TEST(MapFormatErrors, DuplicateFrameId) {
  expectRefused(std::string(kTwoFrames) + "FRAME 1  5 5 5  1 0 0 0\n", 3, "frame 1 is defined twice");
}

TEST(MapFormatErrors, DuplicateLandmarkId) {
  expectRefused(std::string(kTwoFrames) +
                    "LANDMARK 4  0 0 1  1 0 0 0 1 0 0 0 1  0\n"
                    "LANDMARK 5  0 0 1  1 0 0 0 1 0 0 0 1  0\n"
                    "LANDMARK 4  0 0 2  1 0 0 0 1 0 0 0 1  0\n",
                5, "landmark 4 is defined twice");
}

TEST(MapFormatErrors, ObservationOfAFrameWithoutRecordNamesTheLandmarkLine) {
  // Checked after the whole file (frames may follow landmarks), yet reported at the landmark's line.
  expectRefused(std::string(kTwoFrames) +
                    "LANDMARK 4  0 0 1  1 0 0 0 1 0 0 0 1  2  0 1 2  7 3 4\n"
                    "FRAME 2  0 0 0  1 0 0 0\n",
                3, "landmark 4 is observed by frame 7, which has no FRAME record");
}

TEST(MapFormatErrors, FarFromUnitQuaternion) {
  expectRefused(std::string(kTwoFrames) + "FRAME 2  0 0 0  2 0 0 0\n", 3, "norm");
  expectRefused(std::string(kTwoFrames) + "FRAME 2  0 0 0  0 0 0 0\n", 3, "expected a unit quaternion");
}

TEST(MapFormatErrors, MissingFileIsNamed) {
  const fs::path path = scratchDir("map_missing") / "no_such_map.txt";
  try {
    io::readLandmarkMap(path.string());
    FAIL() << "read a missing file";
  } catch (const io::MapFormatError& e) {
    EXPECT_EQ(e.source(), path.string());
    EXPECT_EQ(e.line(), 0u);
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
}

// ---- writing ------------------------------------------------------------------

TEST(MapFormatWrite, IntoAMissingFolderThrowsAndLeavesNothing) {
  const fs::path scratch = scratchDir("map_write_missing_folder");
  const fs::path path = scratch / "absent" / "map.txt";
  try {
    io::writeLandmarkMap(awkwardMap(), path.string());
    FAIL() << "wrote into a missing folder";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(scratch / "absent"));
  EXPECT_EQ(filesIn(scratch), 0u);
}

TEST(MapFormatWrite, AFailedWriteKeepsTheExistingFile) {
  const fs::path scratch = scratchDir("map_write_keeps_file");
  const fs::path path = scratch / "map.txt";
  io::writeLandmarkMap(awkwardMap(), path.string());
  const std::string before = readFile(path);

  LandmarkMap unwritable = awkwardMap();
  unwritable.landmarks[1].position.y() = std::nan("");
  try {
    io::writeLandmarkMap(unwritable, path.string());
    FAIL() << "wrote a NaN position";
  } catch (const std::runtime_error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(path.string()), std::string::npos) << message;
    EXPECT_NE(message.find("landmark 7"), std::string::npos) << message;
  }
  EXPECT_EQ(readFile(path), before);
  EXPECT_EQ(filesIn(scratch), 1u) << "a temporary file was left behind";
}

/// The writer must not produce a file its own reader refuses.
// Poses composed over a long run are rigid only up to rounding: written as their nearest rotation (a unit
// quaternion), not refused; a real scaling still is (RefusesMapsTheReaderWouldRefuse).
TEST(MapFormatWrite, ARotationOffOrthonormalByRoundingIsWrittenAsTheNearestRotation) {
  LandmarkMap map;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(1.0, Eigen::Vector3d(0, 1, 1).normalized()).toRotationMatrix();
  const Eigen::Matrix3d rigid = pose.linear();
  pose.linear()(2, 0) += 5e-8;
  pose.translation() = Eigen::Vector3d(1, 2, 3);
  map.frames[7] = pose;
  std::stringstream text;
  io::writeLandmarkMap(map, text);
  const LandmarkMap back = io::parseLandmarkMap(text, "memory");
  const Eigen::Matrix3d R = back.frames.at(7).linear();
  EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((R - rigid).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_TRUE(back.frames.at(7).translation().isApprox(pose.translation()));
}

TEST(MapFormatWrite, RefusesMapsTheReaderWouldRefuse) {
  const auto refused = [](const LandmarkMap& map, const std::string& what) {
    std::ostringstream out;
    try {
      io::writeLandmarkMap(map, out);
      ADD_FAILURE() << "wrote a map with " << what;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
    EXPECT_TRUE(out.str().empty()) << "wrote part of the map before refusing it";
  };
  LandmarkMap map = awkwardMap();
  map.landmarks[2].observations[1].frame_id = 4;
  refused(map, "landmark 99999 is observed by frame 4");

  map = awkwardMap();
  map.landmarks[0].covariance(1, 2) = std::numeric_limits<double>::infinity();
  refused(map, "landmark 42 has a non-finite");

  map = awkwardMap();
  map.landmarks[0].observations[0].v = std::nan("");
  refused(map, "landmark 42 has a non-finite observation in frame 0");

  map = awkwardMap();
  map.landmarks[1].id = 42;
  refused(map, "landmark 42 appears twice");

  map = awkwardMap();
  map.landmarks[1].covariance(0, 1) += 1.0;
  refused(map, "landmark 7: covariance is not symmetric");

  map = awkwardMap();
  map.landmarks[1].position.z() = 3e38;
  refused(map, "landmark 7: position has a coordinate beyond");

  map = awkwardMap();
  map.frames[3].linear() *= 2.0;  // a scaling: no quaternion stores it
  refused(map, "frame 3 has a pose that is not a finite rigid motion");
}

// ---- the real map -----------------------------------------------------------

TEST(RealMap, HasTheDocumentedCounts) {
  WEIGHTED_ICP_REQUIRE_FILE(realMapPath());
  const LandmarkMap map = io::readLandmarkMap(realMapPath().string());
  EXPECT_EQ(map.frames.size(), 240u);
  EXPECT_EQ(map.landmarks.size(), 22338u);
  EXPECT_EQ(map.withMinObservations(2).landmarks.size(), 6081u);
  std::size_t unobserved = 0;
  for (const auto& landmark : map.landmarks) unobserved += landmark.observations.empty();
  EXPECT_EQ(unobserved, 630u);
}

struct ReprojectionError {
  double mean_px = 0.0;
  std::size_t observations = 0;
  std::size_t behind_camera = 0;
};

/// Projects every observed landmark into each frame that observed it with the
/// TUM freiburg1 pinhole (no distortion); `pose` gives a frame's camera-to-world pose.
template <typename PoseOf>
ReprojectionError reproject(const LandmarkMap& map, PoseOf pose) {
  constexpr double fx = 517.3, fy = 516.5, cx = 318.6, cy = 255.3;
  ReprojectionError result;
  double sum = 0.0;
  for (const auto& landmark : map.landmarks)
    for (const auto& o : landmark.observations) {
      const Eigen::Vector3d p = pose(map.frames.at(o.frame_id)).inverse() * landmark.position;
      result.behind_camera += p.z() <= 0.0;
      sum += std::hypot(fx * p.x() / p.z() + cx - o.u, fy * p.y() / p.z() + cy - o.v);
      ++result.observations;
    }
  result.mean_px = sum / static_cast<double>(result.observations);
  return result;
}

TEST(RealMap, LandmarksReprojectOntoTheirObservations) {
  WEIGHTED_ICP_REQUIRE_FILE(realMapPath());
  const LandmarkMap map = io::readLandmarkMap(realMapPath().string());
  const ReprojectionError error = reproject(map, [](const Eigen::Isometry3d& pose) { return pose; });
  EXPECT_GT(error.observations, map.landmarks.size() - 630);
  EXPECT_EQ(error.behind_camera, 0u);
  EXPECT_LT(error.mean_px, 1.0);
}

// Documents the pitfall: the FRAME quaternion is scalar first. Read as x y z w
// (the TUM ground-truth order) the poses are wrong by tens of pixels or more.
TEST(RealMap, QuaternionReadInTumOrderDoesNotReproject) {
  WEIGHTED_ICP_REQUIRE_FILE(realMapPath());
  const LandmarkMap map = io::readLandmarkMap(realMapPath().string());
  const ReprojectionError error = reproject(map, [](const Eigen::Isometry3d& pose) {
    // The file's "qw qx qy qz" taken as "qx qy qz qw".
    const Eigen::Quaterniond file_order(pose.linear());
    const Eigen::Quaterniond misread(file_order.z(), file_order.w(), file_order.x(), file_order.y());
    Eigen::Isometry3d wrong = pose;
    wrong.linear() = misread.normalized().toRotationMatrix();
    return wrong;
  });
  EXPECT_GT(error.mean_px, 50.0);
}

}  // namespace
