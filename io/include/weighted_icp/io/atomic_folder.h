#pragma once
// Writing a whole output folder so that readers see the old folder or the
// complete new one, never a mix: the folder is built under a temporary name
// beside its target and published by one rename. atomic_file.h does the same
// for single files.

#include <filesystem>
#include <stdexcept>
#include <string>

#include "weighted_icp/io/atomic_file.h"

namespace weighted_icp::io {

/// @brief The refusal of an existing, non-empty target when overwriting was not asked for: its own type, so that a
/// tool can add how to overwrite without reading the message.
class FolderNotEmptyError : public std::runtime_error {
 public:
  /// @param folder the target refused
  explicit FolderNotEmptyError(const std::filesystem::path& folder)
      : std::runtime_error(folder.string() + " exists and is not empty; not overwriting it"), folder_(folder) {}
  /// @brief The target refused.
  const std::filesystem::path& folder() const { return folder_; }

 private:
  std::filesystem::path folder_;
};

/// @brief A folder under construction: files go into path(); publish() renames
/// it to the target, and a folder never published is deleted with this object
/// (so an exception or an interrupted run leaves no partial output).
class AtomicFolder {
 public:
  /// @brief Checks the target and creates the temporary folder beside it.
  /// @param target the folder to publish ("out/" names "out"); its parent is created
  /// @param overwrite replace an existing non-empty target; without it such a
  ///        target is refused (FolderNotEmptyError) before anything is written
  AtomicFolder(const std::string& target, bool overwrite);
  /// @brief Deletes the temporary folder unless it was published.
  ~AtomicFolder();
  AtomicFolder(const AtomicFolder&) = delete;
  AtomicFolder& operator=(const AtomicFolder&) = delete;

  /// @brief The temporary folder to write into.
  const std::filesystem::path& path() const { return temporary_; }
  /// @brief The folder publish() creates or replaces.
  const std::filesystem::path& target() const { return target_; }
  /// @brief Renames the temporary folder to the target in one step (replacing
  /// an old target atomically where the kernel can swap two names); throws
  /// std::runtime_error naming the target on failure, the old target intact.
  void publish();
  /// @brief Deletes the temporary folder now; the target is untouched.
  void discard() noexcept;

 private:
  std::filesystem::path target_;
  std::filesystem::path temporary_;
  bool done_ = false;
};

}  // namespace weighted_icp::io
