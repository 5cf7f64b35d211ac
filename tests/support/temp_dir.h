#pragma once
// A per-test temporary directory for tests that write real files.

#include <filesystem>
#include <string>

namespace graspbed::test_support {

/// A fresh, empty directory under the system temp dir (graspbed_<tag>_<pid>_<n>), removed with
/// everything in it on destruction.
class TempDir {
 public:
  /// `tag` names the directory so a leftover one says which tests made it.
  explicit TempDir(const std::string& tag = "test");
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  /// Writes `text` to `name` inside the directory (sub-directories created) and returns its full path;
  /// throws std::runtime_error when the file cannot be written.
  std::string Write(const std::string& name, const std::string& text) const;
  /// Full path of `name` inside the directory (nothing is created).
  std::string Path(const std::string& name) const { return (path_ / name).string(); }
  /// The directory itself.
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace graspbed::test_support
