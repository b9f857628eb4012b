// AtomicFolder (atomic_folder.h): a temporary folder beside the target, one
// rename to publish it, and fsync so that what is published is on the disk.

#include "weighted_icp/io/atomic_folder.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <system_error>

#include <fcntl.h>
#include <unistd.h>

namespace weighted_icp::io {

namespace fs = std::filesystem;

namespace {

/// `dir` as a folder path ("out/" names "out"), checked: absent, empty or
/// (with `overwrite`) a folder; its parent is created.
fs::path checkedTarget(const std::string& dir, bool overwrite) {
  fs::path target = fs::path(dir).lexically_normal();
  if (!target.has_filename()) target = target.parent_path();
  if (target.empty()) throw std::runtime_error("no output folder given");
  std::error_code error;
  if (fs::exists(target, error)) {
    if (!fs::is_directory(target)) throw std::runtime_error(target.string() + " exists and is not a folder");
    if (!fs::is_empty(target) && !overwrite) throw FolderNotEmptyError(target);
  }
  const fs::path parent = target.has_parent_path() ? target.parent_path() : fs::path(".");
  fs::create_directories(parent, error);
  if (error) throw std::runtime_error("cannot create " + parent.string() + ": " + error.message());
  return target;
}

/// A new folder beside the target, so the final rename stays on one file system.
fs::path makeTemporaryFolder(const fs::path& target) {
  const fs::path parent = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code error;
  for (int attempt = 0;; ++attempt) {
    const fs::path temporary = parent / ("." + target.filename().string() + ".tmp-" + std::to_string(::getpid()) + "-" +
                                         std::to_string(attempt));
    if (fs::create_directory(temporary, error)) return temporary;
    if (error) throw std::runtime_error("cannot write in " + parent.string() + ": " + error.message());
  }
}

/// Swaps two names in one step (Linux renameat2); false where the file system
/// or kernel cannot, so the caller falls back to two renames.
bool exchange(const fs::path& a, const fs::path& b) {
#ifdef RENAME_EXCHANGE
  if (::renameat2(AT_FDCWD, a.c_str(), AT_FDCWD, b.c_str(), RENAME_EXCHANGE) == 0) return true;
  if (errno != EINVAL && errno != ENOSYS && errno != ENOTSUP)
    throw std::runtime_error("cannot replace " + b.string() + ": " + std::strerror(errno));
#endif
  (void)a;
  (void)b;
  return false;
}

/// Renames `temporary` to `target`. A non-empty target is swapped with it and
/// deleted after; without the swap, moved aside first and put back if the
/// second rename fails.
void moveIntoPlace(const fs::path& temporary, const fs::path& target) {
  if (!fs::exists(target) || fs::is_empty(target)) {
    fs::rename(temporary, target);  // replaces an empty folder
    return;
  }
  std::error_code error;
  if (exchange(temporary, target)) {
    fs::remove_all(temporary, error);  // now the old folder
    return;
  }
  const fs::path old = temporary.string() + ".old";
  fs::rename(target, old);
  fs::rename(temporary, target, error);
  if (error) {
    fs::rename(old, target);
    throw fs::filesystem_error("rename", temporary, target, error);
  }
  fs::remove_all(old, error);
}

}  // namespace

AtomicFolder::AtomicFolder(const std::string& target, bool overwrite)
    : target_(checkedTarget(target, overwrite)), temporary_(makeTemporaryFolder(target_)) {}

AtomicFolder::~AtomicFolder() { discard(); }

void AtomicFolder::publish() {
  if (done_) throw std::logic_error("AtomicFolder::publish: " + target_.string() + " already published or discarded");
  try {
    syncToDisk(temporary_);
    moveIntoPlace(temporary_, target_);
    done_ = true;
  } catch (const fs::filesystem_error& e) {
    discard();
    throw std::runtime_error("cannot write " + target_.string() + ": " + e.code().message());
  } catch (...) {
    discard();
    throw;
  }
  // The rename itself, for durability after a crash; the folder is already
  // complete and published, so a failure here loses nothing to report.
  try {
    syncToDisk(target_.has_parent_path() ? target_.parent_path() : fs::path("."));
  } catch (const std::exception&) {
  }
}

void AtomicFolder::discard() noexcept {
  if (done_) return;
  done_ = true;
  std::error_code ignored;
  fs::remove_all(temporary_, ignored);
}

}  // namespace weighted_icp::io
