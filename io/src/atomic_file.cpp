// Atomic single-file writes (atomic_file.h): temporary file, fsync, rename.
#include "weighted_icp/io/atomic_file.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include <fcntl.h>
#include <unistd.h>

namespace weighted_icp::io {

void syncToDisk(const std::filesystem::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error("cannot open " + path.string() + ": " + std::strerror(errno));
  const int status = ::fsync(fd);
  const int fsync_errno = errno;
  ::close(fd);
  // Some file systems cannot sync a folder (EINVAL): nothing was lost there.
  if (status != 0 && fsync_errno != EINVAL)
    throw std::runtime_error("cannot write " + path.string() + ": " + std::strerror(fsync_errno));
}

void writeAtomically(const std::string& path, const std::function<void(const std::string&)>& write) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const fs::path temporary =
      target.parent_path() / ("." + target.filename().string() + ".tmp" + std::to_string(::getpid()));
  try {
    write(temporary.string());
    // A full disk may only show when the data is flushed: before the rename,
    // so a failed write never replaces `path`.
    syncToDisk(temporary);
    std::error_code error;
    fs::rename(temporary, target, error);
    if (error) throw std::runtime_error("cannot write " + path + ": " + error.message());
  } catch (...) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw;
  }
}

}  // namespace weighted_icp::io
