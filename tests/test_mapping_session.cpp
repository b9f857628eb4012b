// Session folders: a round trip keeps everything, corrupt files fail naming file and line, failures leave nothing.
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

#include "test_support.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/mapping/session.h"

namespace weighted_icp::testing {
namespace {

namespace fs = std::filesystem;

Eigen::Isometry3d randomPose(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
  pose.translation() = Eigen::Vector3d(u(rng), u(rng), u(rng)) * 3.0;
  return pose;
}

/// Three keyframes with ORB-like features, landmarks observed by them, frames tracked from them.
mapping::Session makeSession() {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  mapping::Session session;
  session.camera = tumCamera(1);
  for (std::size_t k = 0; k < 3; ++k) {
    frontend::Keyframe keyframe;
    keyframe.id = 2 * k;  // ids need not be contiguous
    keyframe.frame_id = 10 * k;
    keyframe.timestamp = 1305031102.175304 + 0.1 * static_cast<double>(k);
    keyframe.segment = k / 2;
    keyframe.pose_wc = randomPose(rng);
    const int features = 5 + static_cast<int>(k);
    keyframe.descriptors = cv::Mat(features, 32, CV_8U);
    cv::randu(keyframe.descriptors, 0, 256);
    for (int i = 0; i < features; ++i) {
      cv::KeyPoint point(static_cast<float>(640 * u(rng)), static_cast<float>(480 * u(rng)), 31.0f,
                         static_cast<float>(360 * u(rng)), static_cast<float>(u(rng)), i % 8, -1);
      keyframe.keypoints.push_back(point);
      keyframe.pixels.emplace_back(point.pt.x + 0.25, point.pt.y - 0.5);
      keyframe.depths.push_back(i % 3 == 0 ? 0.0 : 0.5 + 3 * u(rng));
    }
    session.keyframes.push_back(keyframe);
  }
  for (std::size_t j = 0; j < 6; ++j) {
    frontend::MapPoint point;
    point.id = 3 * j + 1;
    point.position = Eigen::Vector3d(u(rng), u(rng), u(rng));
    Eigen::Matrix3d a = Eigen::Matrix3d::Random();
    point.covariance = a * a.transpose() * 1e-4;
    if (j != 4) {
      point.descriptor = cv::Mat(1, 32, CV_8U);
      cv::randu(point.descriptor, 0, 256);
    }
    for (std::size_t k = 0; k <= j % 3; ++k) {
      point.observations.push_back({2 * k, Eigen::Vector2d(640 * u(rng), 480 * u(rng)), k == 1 ? 0.0 : 1.5});
      session.keyframes[k].observed_points.push_back(point.id);
    }
    session.points.push_back(point);
  }
  for (std::size_t f = 0; f < 7; ++f)
    session.frames.push_back({1305031102.2 + 0.033 * static_cast<double>(f), 2 * (f % 3), randomPose(rng)});
  return session;
}

void expectSameMat(const cv::Mat& a, const cv::Mat& b) {
  ASSERT_EQ(a.empty(), b.empty());
  if (a.empty()) return;
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(cv::norm(a, b, cv::NORM_HAMMING), 0.0);
}

TEST(Session, SaveLoadRoundTripKeepsEverything) {
  const mapping::Session session = makeSession();
  const fs::path folder = scratchDir("round_trip") / "session";
  mapping::saveSession(session, folder.string());
  const mapping::Session loaded = mapping::loadSession(folder.string());

  EXPECT_DOUBLE_EQ(loaded.camera.fx, session.camera.fx);
  EXPECT_EQ(loaded.camera.distortion, session.camera.distortion);
  ASSERT_EQ(loaded.keyframes.size(), session.keyframes.size());
  for (std::size_t k = 0; k < session.keyframes.size(); ++k) {
    const auto& a = session.keyframes[k];
    const auto& b = loaded.keyframes[k];
    EXPECT_EQ(b.id, a.id);
    EXPECT_EQ(b.frame_id, a.frame_id);
    EXPECT_EQ(b.timestamp, a.timestamp);
    EXPECT_EQ(b.segment, a.segment);
    EXPECT_TRUE(b.pose_wc.isApprox(a.pose_wc, 1e-12));
    EXPECT_EQ(b.observed_points, a.observed_points);
    ASSERT_EQ(b.keypoints.size(), a.keypoints.size());
    for (std::size_t i = 0; i < a.keypoints.size(); ++i) {
      EXPECT_EQ(b.keypoints[i].pt, a.keypoints[i].pt);
      EXPECT_EQ(b.keypoints[i].size, a.keypoints[i].size);
      EXPECT_EQ(b.keypoints[i].angle, a.keypoints[i].angle);
      EXPECT_EQ(b.keypoints[i].response, a.keypoints[i].response);
      EXPECT_EQ(b.keypoints[i].octave, a.keypoints[i].octave);
      EXPECT_EQ(b.pixels[i], a.pixels[i]);
      EXPECT_EQ(b.depths[i], a.depths[i]);
    }
    expectSameMat(a.descriptors, b.descriptors);
  }
  ASSERT_EQ(loaded.points.size(), session.points.size());
  for (std::size_t j = 0; j < session.points.size(); ++j) {
    const auto& a = session.points[j];
    const auto& b = loaded.points[j];
    EXPECT_EQ(b.id, a.id);
    EXPECT_EQ(b.position, a.position);
    EXPECT_EQ(b.covariance, a.covariance);
    expectSameMat(a.descriptor, b.descriptor);
    ASSERT_EQ(b.observations.size(), a.observations.size());
    for (std::size_t o = 0; o < a.observations.size(); ++o) {
      EXPECT_EQ(b.observations[o].keyframe, a.observations[o].keyframe);
      EXPECT_EQ(b.observations[o].pixel, a.observations[o].pixel);
      EXPECT_EQ(b.observations[o].depth, a.observations[o].depth);
    }
  }
  ASSERT_EQ(loaded.frames.size(), session.frames.size());
  const Trajectory before = session.trajectory(), after = loaded.trajectory();
  for (std::size_t f = 0; f < before.size(); ++f) {
    EXPECT_EQ(after[f].timestamp, before[f].timestamp);
    EXPECT_EQ(loaded.frames[f].reference_keyframe, session.frames[f].reference_keyframe);
    EXPECT_TRUE(after[f].pose.isApprox(before[f].pose, 1e-12));
  }
}

/// Replaces line `line` (1-based) of a file.
void replaceLine(const fs::path& path, std::size_t line, const std::string& text) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  in.close();
  lines.at(line - 1) = text;
  std::ofstream out(path);
  for (const auto& l : lines) out << l << '\n';
}

/// Line number (1-based) of the first line starting with `prefix`.
std::size_t lineStarting(const fs::path& path, const std::string& prefix, std::size_t nth = 0) {
  std::ifstream in(path);
  std::size_t number = 0;
  for (std::string l; std::getline(in, l);) {
    ++number;
    if (l.rfind(prefix, 0) == 0 && nth-- == 0) return number;
  }
  ADD_FAILURE() << "no line starting with " << prefix << " in " << path;
  return 0;
}

void expectErrorAt(const fs::path& folder, const fs::path& file, std::size_t line, const std::string& what) {
  try {
    mapping::loadSession(folder.string());
    ADD_FAILURE() << "a corrupt " << file << " must be refused";
  } catch (const io::MapFormatError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(file.string() + ":" + std::to_string(line) + ":"), std::string::npos) << message;
    EXPECT_NE(message.find(what), std::string::npos) << message;
  }
}

TEST(Session, RebuildsTheFrontEndMap) {
  mapping::Session session = makeSession();
  EXPECT_THROW(session.toMap(), std::invalid_argument) << "keyframe ids 0, 2, 4 cannot be a run's";
  for (auto& keyframe : session.keyframes) keyframe.id /= 2;
  for (auto& point : session.points)
    for (auto& observation : point.observations) observation.keyframe /= 2;
  for (auto& frame : session.frames) frame.reference_keyframe /= 2;
  const auto map = session.toMap();
  ASSERT_EQ(map->keyframeCount(), session.keyframes.size());
  ASSERT_EQ(map->mapPointCount(), session.points.size());
  const auto points = map->mapPoints();
  for (std::size_t j = 0; j < points.size(); ++j) {
    EXPECT_EQ(points[j].id, j);
    EXPECT_EQ(points[j].position, session.points[j].position);
    EXPECT_EQ(points[j].observations.size(), session.points[j].observations.size());
  }
  const auto keyframes = map->keyframes();
  for (std::size_t k = 0; k < keyframes.size(); ++k) {
    EXPECT_TRUE(keyframes[k].pose_wc.isApprox(session.keyframes[k].pose_wc));
    EXPECT_EQ(keyframes[k].observed_points.size(), session.keyframes[k].observed_points.size());
    EXPECT_EQ(keyframes[k].keypoints.size(), session.keyframes[k].keypoints.size());
  }
}

TEST(Session, CorruptFilesFailNamingFileAndLine) {
  const mapping::Session session = makeSession();
  const fs::path root = scratchDir("corrupt");
  const auto fresh = [&](const std::string& name) {
    const fs::path folder = root / name;
    mapping::saveSession(session, folder.string());
    return folder;
  };
  {
    const fs::path folder = fresh("bad_descriptor");
    const fs::path file = folder / "keyframes.txt";
    const std::size_t line = lineStarting(file, "FEATURE", 3);
    replaceLine(file, line, "FEATURE 1 2 31 0 0.5 0 -1 1 2 1.5 zz00");
    expectErrorAt(folder, file, line, "descriptor");
  }
  {
    const fs::path folder = fresh("unknown_keyframe");
    const fs::path file = folder / "landmarks.txt";
    const std::size_t line = lineStarting(file, "LANDMARK", 2);
    replaceLine(file, line, "LANDMARK 99 0 0 1 1 0 0 0 1 0 0 0 1 - 1 7 320 240 1.5");
    expectErrorAt(folder, file, line, "keyframe 7");
  }
  {
    const fs::path folder = fresh("nan");
    const fs::path file = folder / "frames.txt";
    const std::size_t line = lineStarting(file, "FRAME", 1);
    replaceLine(file, line, "FRAME nan 0 0 0 0 1 0 0 0");
    expectErrorAt(folder, file, line, "timestamp");
  }
  {
    const fs::path folder = fresh("truncated");
    const fs::path file = folder / "frames.txt";
    replaceLine(file, lineStarting(file, "FRAME", 6), "");
    expectErrorAt(folder, folder / "session.txt", lineStarting(folder / "session.txt", "FRAMES"), "declared");
  }
  {
    const fs::path folder = fresh("short_feature_list");
    const fs::path file = folder / "keyframes.txt";
    const std::size_t line = lineStarting(file, "KEYFRAME", 1);
    replaceLine(file, lineStarting(file, "FEATURE", 5), "KEYFRAME_OOPS");
    expectErrorAt(folder, file, line + 1, "expected a FEATURE record");  // the second keyframe's first feature
  }
  {
    // A feature count of 2^40 with 32-byte descriptors: read feature by feature, never allocated up front.
    const fs::path folder = fresh("huge_feature_count");
    const fs::path file = folder / "keyframes.txt";
    replaceLine(file, lineStarting(file, "KEYFRAME", 0), "KEYFRAME 0 0 0 0 0 0 0 1 0 0 0 1099511627776 32");
    expectErrorAt(folder, file, lineStarting(file, "KEYFRAME", 1), "expected a FEATURE record");
  }
  {
    // 16 + 4 n wraps round to 20 fields for n = 2^62 + 1: refused for the count, not read past the record.
    const fs::path folder = fresh("wrapping_count");
    const fs::path file = folder / "landmarks.txt";
    const std::size_t line = lineStarting(file, "LANDMARK", 0);
    replaceLine(file, line, "LANDMARK 0 0 0 1 1 0 0 0 1 0 0 0 1 - 4611686018427387905 0 320 240 1.5");
    expectErrorAt(folder, file, line, "does not match");
  }
}

TEST(Session, AMissingFolderOrFileIsAClearError) {
  const fs::path root = scratchDir("missing");
  try {
    mapping::loadSession((root / "nowhere").string());
    FAIL() << "a missing folder must be refused";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("nowhere"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("does not exist"), std::string::npos) << error.what();
  }
  mapping::saveSession(makeSession(), (root / "partial").string());
  fs::remove(root / "partial" / "landmarks.txt");
  try {
    mapping::loadSession((root / "partial").string());
    FAIL() << "a folder without landmarks.txt must be refused";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("landmarks.txt"), std::string::npos) << error.what();
  }
}

TEST(Session, AFailedSaveLeavesNothingBehind) {
  const fs::path root = scratchDir("failed_save");
  mapping::Session session = makeSession();
  session.camera.fx = 0.0;  // refused when camera.yaml is written, after the folder was started
  EXPECT_THROW(mapping::saveSession(session, (root / "session").string()), std::runtime_error);
  EXPECT_TRUE(fs::is_empty(root)) << "a failed save must leave neither the folder nor a temporary";

  session = makeSession();
  session.frames[2].reference_keyframe = 5;  // no such keyframe: refused before anything is written
  EXPECT_THROW(mapping::saveSession(session, (root / "session").string()), std::invalid_argument);
  EXPECT_TRUE(fs::is_empty(root));

  // An existing session is kept when the new one cannot be written.
  mapping::saveSession(makeSession(), (root / "session").string());
  session = makeSession();
  session.camera.fx = 0.0;
  EXPECT_THROW(mapping::saveSession(session, (root / "session").string(), true), std::runtime_error);
  EXPECT_EQ(mapping::loadSession((root / "session").string()).keyframes.size(), 3u);
}

}  // namespace
}  // namespace weighted_icp::testing
