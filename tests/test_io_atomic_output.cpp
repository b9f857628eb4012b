// Outputs appear complete or not at all: io::AtomicFolder's publish and
// discard, and writes on a full disk (simulated with RLIMIT_FSIZE, which needs
// no root: a write past the limit fails with EFBIG as it would with ENOSPC).

#include <sys/resource.h>

#include <algorithm>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "test_support.h"
#include "weighted_icp/io/atomic_folder.h"
#include "weighted_icp/io/cloud_io.h"
#include "weighted_icp/io/map_format.h"

namespace {

using namespace weighted_icp;
namespace fs = std::filesystem;
using weighted_icp::testing::readFile;
using weighted_icp::testing::scratchDir;
using weighted_icp::testing::writeFile;

/// Every name in `dir`, to see that nothing temporary is left behind.
std::vector<std::string> entries(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

TEST(AtomicFolder, PublishesInOneRenameAndLeavesNothingBeside) {
  const fs::path scratch = scratchDir("atomic_folder_publish");
  const fs::path target = scratch / "out";
  {
    io::AtomicFolder folder(target.string() + "/", false);
    writeFile(folder.path() / "a.txt", "new");
    EXPECT_FALSE(fs::exists(target)) << "visible before publish";
    folder.publish();
  }
  EXPECT_EQ(readFile(target / "a.txt"), "new");
  EXPECT_EQ(entries(scratch), std::vector<std::string>{"out"});
}

TEST(AtomicFolder, RefusesANonEmptyTargetWithoutOverwrite) {
  const fs::path scratch = scratchDir("atomic_folder_refuse");
  const fs::path target = scratch / "out";
  fs::create_directories(target);
  writeFile(target / "old.txt", "old");
  try {
    io::AtomicFolder folder(target.string(), false);
    FAIL() << "a non-empty folder was accepted";
  } catch (const io::FolderNotEmptyError& e) {  // its own type, so tools can add how to overwrite
    EXPECT_NE(std::string(e.what()).find("not empty"), std::string::npos) << e.what();
    EXPECT_EQ(e.folder(), target);
  }
  EXPECT_EQ(readFile(target / "old.txt"), "old");
  EXPECT_EQ(entries(scratch), std::vector<std::string>{"out"});
  writeFile(scratch / "file", "x");  // a file is not a folder, even with overwrite
  EXPECT_THROW(io::AtomicFolder((scratch / "file").string(), true), std::runtime_error);
}

TEST(AtomicFolder, OverwriteReplacesTheWholeFolder) {
  const fs::path scratch = scratchDir("atomic_folder_overwrite");
  const fs::path target = scratch / "out";
  fs::create_directories(target / "minimaps");
  writeFile(target / "minimaps" / "minimap_005.txt", "stale");
  io::AtomicFolder folder(target.string(), true);
  writeFile(folder.path() / "new.txt", "new");
  folder.publish();
  EXPECT_FALSE(fs::exists(target / "minimaps")) << "an older file the new run did not write survived";
  EXPECT_EQ(readFile(target / "new.txt"), "new");
  EXPECT_EQ(entries(scratch), std::vector<std::string>{"out"});
}

TEST(AtomicFolder, AFolderNeverPublishedIsDiscardedAndTheOldOneKept) {
  const fs::path scratch = scratchDir("atomic_folder_discard");
  const fs::path target = scratch / "out";
  fs::create_directories(target);
  writeFile(target / "map.ply", "old");
  try {
    io::AtomicFolder folder(target.string(), true);
    writeFile(folder.path() / "trajectory.txt", "partial");
    throw std::runtime_error("the run failed");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(entries(target), std::vector<std::string>{"map.ply"});
  EXPECT_EQ(entries(scratch), std::vector<std::string>{"out"});
}

/// Limits the size of any file this process writes, for one scope.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    ::getrlimit(RLIMIT_FSIZE, &saved_);
    previous_handler_ = std::signal(SIGXFSZ, SIG_IGN);  // else the process is killed, not the write refused
    rlimit limit = saved_;
    limit.rlim_cur = bytes;
    ok_ = ::setrlimit(RLIMIT_FSIZE, &limit) == 0;
  }
  ~FileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &saved_);
    std::signal(SIGXFSZ, previous_handler_);
  }
  bool ok() const { return ok_; }

 private:
  rlimit saved_{};
  void (*previous_handler_)(int) = nullptr;
  bool ok_ = false;
};

LandmarkCloud manyPoints(std::size_t n) {
  LandmarkCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    LandmarkPoint p;
    p.x = static_cast<float>(i);
    p.y = p.z = 1.0f;
    p.weight = 1.0;
    cloud.push_back(p);
  }
  return cloud;
}

TEST(FullDisk, ATruncatedCloudIsNeverRenamedIntoPlace) {
  const fs::path scratch = scratchDir("full_disk_cloud");
  const LandmarkCloud cloud = manyPoints(5000);  // about 200 kB, past the limit below
  for (const char* name : {"map.ply", "map.pcd"}) {
    const fs::path path = scratch / name;
    {
      FileSizeLimit limit(64 * 1024);
      ASSERT_TRUE(limit.ok());
      try {
        io::saveLandmarkCloud(cloud, path.string());
        ADD_FAILURE() << name << ": a write past the disk's end reported success";
      } catch (const std::exception& e) {
        EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
      }
    }
    EXPECT_FALSE(fs::exists(path)) << name;
    EXPECT_TRUE(entries(scratch).empty()) << "a temporary file was left: " << entries(scratch).front();
    io::saveLandmarkCloud(cloud, path.string());  // without the limit: the check passes a complete file
    EXPECT_EQ(io::loadLandmarkCloud(path.string())->size(), cloud.size()) << name;
    fs::remove(path);
  }
}

/// A real full file system where one can be made: a small tmpfs (mounting
/// needs root, as CI has); skipped, saying why, elsewhere.
TEST(FullDisk, ARealFullFileSystemFailsTheWriteAndLeavesNothing) {
  const fs::path dir = scratchDir("full_tmpfs") / "mnt";
  fs::create_directories(dir);
  if (std::system(("mount -t tmpfs -o size=128k tmpfs '" + dir.string() + "' 2>/dev/null").c_str()) != 0)
    GTEST_SKIP() << "cannot mount a 128 kB tmpfs here (needs root); the RLIMIT_FSIZE tests cover the same paths";
  struct Unmount {
    fs::path dir;
    ~Unmount() { (void)std::system(("umount '" + dir.string() + "'").c_str()); }
  } unmount{dir};
  const LandmarkCloud cloud = manyPoints(5000);  // about 200 kB
  for (const char* name : {"map.ply", "map.pcd"}) {
    EXPECT_THROW(io::saveLandmarkCloud(cloud, (dir / name).string()), std::runtime_error) << name;
    EXPECT_TRUE(entries(dir).empty()) << name << ": left " << entries(dir).front();
  }
  io::saveLandmarkCloud(manyPoints(100), (dir / "small.ply").string());  // what fits is written
  EXPECT_EQ(io::loadLandmarkCloud((dir / "small.ply").string())->size(), 100u);
}

TEST(FullDisk, ATruncatedMapFileKeepsTheOldOne) {
  const fs::path scratch = scratchDir("full_disk_map");
  LandmarkMap map;
  map.frames[0] = Eigen::Isometry3d::Identity();
  for (LandmarkId id = 0; id < 3000; ++id) {
    Landmark landmark;
    landmark.id = id;
    landmark.position = Eigen::Vector3d(id, 1, 2);
    landmark.observations.push_back({0, 1.0, 2.0});
    map.landmarks.push_back(landmark);
  }
  const fs::path path = scratch / "session.txt";
  writeFile(path, "old");
  {
    FileSizeLimit limit(16 * 1024);
    ASSERT_TRUE(limit.ok());
    EXPECT_THROW(io::writeLandmarkMap(map, path.string()), std::runtime_error);
  }
  EXPECT_EQ(readFile(path), "old");
  EXPECT_EQ(entries(scratch), std::vector<std::string>{"session.txt"});
}

TEST(CloudRoundTrip, APointThatWouldNotLoadBackIsRefusedAtWriteTime) {
  const fs::path scratch = scratchDir("cloud_round_trip");
  LandmarkCloud cloud = manyPoints(4);
  cloud[2].y = std::numeric_limits<float>::infinity();  // what 1e200 becomes as a float
  for (const char* name : {"cloud.ply", "cloud.pcd"}) {
    const fs::path path = scratch / name;
    try {
      io::saveLandmarkCloud(cloud, path.string());
      ADD_FAILURE() << name << " was written with an infinite coordinate";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("point 2 "), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(path));
  }
  cloud[2].y = 1.0f;
  cloud[1].weight = -1.0;
  EXPECT_THROW(io::saveLandmarkCloud(cloud, (scratch / "cloud.ply").string()), std::runtime_error);
}

}  // namespace
