#include "tests/support/temp_dir.h"

#include <unistd.h>

#include <atomic>
#include <fstream>
#include <stdexcept>

namespace graspbed::test_support {

TempDir::TempDir(const std::string& tag) {
  // pid + counter: unique across the test executables ctest runs in parallel and within one of them.
  static std::atomic<int> counter{0};
  path_ = std::filesystem::temp_directory_path() /
          ("graspbed_" + tag + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  // A crashed earlier process with a recycled pid may have left one behind.
  std::filesystem::remove_all(path_);
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

std::string TempDir::Write(const std::string& name, const std::string& text) const {
  const std::filesystem::path full = path_ / name;
  std::filesystem::create_directories(full.parent_path());
  std::ofstream out(full);
  if (!out) throw std::runtime_error("cannot write " + full.string());
  out << text;
  return full.string();
}

}  // namespace graspbed::test_support
