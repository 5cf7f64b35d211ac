#include "common/data_dir.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <system_error>
#include <vector>

namespace graspbed::common {
namespace {

namespace fs = std::filesystem;

/// Directories that hold graspbed's code: the shared object this function lives in (the Python
/// module when loaded from Python) and the running executable.
std::vector<fs::path> CodeDirectories() {
  std::vector<fs::path> directories;
  std::error_code error;
  Dl_info info{};
  if (dladdr(reinterpret_cast<const void*>(&CodeDirectories), &info) != 0 && info.dli_fname != nullptr &&
      info.dli_fname[0] == '/') {
    const fs::path object = fs::canonical(info.dli_fname, error);
    if (!error) directories.push_back(object.parent_path());
  }
  const fs::path executable = fs::canonical("/proc/self/exe", error);
  if (!error) directories.push_back(executable.parent_path());
  return directories;
}

std::string FindDataDir() {
  if (const char* env = std::getenv("GRASPBED_DATA_DIR"); env != nullptr && env[0] != '\0') {
    if (!fs::is_directory(env)) {
      throw std::runtime_error(std::string("GRASPBED_DATA_DIR = ") + env + ": not a directory");
    }
    return fs::absolute(env).lexically_normal().string();
  }
  std::string tried;
  for (const fs::path& start : CodeDirectories()) {
    for (fs::path directory = start;; directory = directory.parent_path()) {
      const fs::path candidate = directory / "share" / "graspbed";
      if (fs::is_directory(candidate / "sensor" / "layouts")) return candidate.string();
      tried += (tried.empty() ? "" : ", ") + candidate.string();
      if (directory == directory.root_path() || directory.empty()) break;
    }
  }
  throw std::runtime_error("graspbed's data (share/graspbed/sensor/layouts) not found; tried " + tried +
                           "; set GRASPBED_DATA_DIR to the installed share/graspbed");
}

}  // namespace

const std::string& DataDir() {
  static const std::string data_dir = FindDataDir();
  return data_dir;
}

std::string DataPath(const std::string& relative_path) { return DataDir() + "/" + relative_path; }

std::string ProgramDir() {
  const std::vector<fs::path> directories = CodeDirectories();
  return directories.empty() ? std::string() : directories.front().string();
}

}  // namespace graspbed::common
