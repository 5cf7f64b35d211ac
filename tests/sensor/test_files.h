#pragma once
// Helpers for sensor tests: real files in a per-test temporary directory, and error capture.

#include <filesystem>
#include <functional>
#include <string>

namespace graspbed::sensor::testing {

/// A fresh directory under the system temp dir, removed on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  /// Writes `text` to `name` inside the directory and returns its full path.
  std::string Write(const std::string& name, const std::string& text) const;
  std::string Path(const std::string& name) const { return (path_ / name).string(); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// what() of the std::exception `action` throws, or "(no error)".
std::string ErrorOf(const std::function<void()>& action);

/// Absolute path of a file in the source tree.
std::string SourcePath(const std::string& relative);

}  // namespace graspbed::sensor::testing
