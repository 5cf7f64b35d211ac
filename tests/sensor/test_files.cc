#include "tests/sensor/test_files.h"

#include <unistd.h>

#include <atomic>
#include <exception>
#include <fstream>
#include <stdexcept>

namespace graspbed::sensor::testing {

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  path_ = std::filesystem::temp_directory_path() /
          ("graspbed_sensor_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

std::string TempDir::Write(const std::string& name, const std::string& text) const {
  const std::string full = Path(name);
  std::ofstream out(full);
  if (!out) throw std::runtime_error("cannot write " + full);
  out << text;
  return full;
}

std::string ErrorOf(const std::function<void()>& action) {
  try {
    action();
  } catch (const std::exception& error) {
    return error.what();
  }
  return "(no error)";
}

std::string SourcePath(const std::string& relative) { return std::string(GRASPBED_SOURCE_DIR) + "/" + relative; }

}  // namespace graspbed::sensor::testing
