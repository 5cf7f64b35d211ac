#include "tests/support/files.h"

#include <fstream>
#include <sstream>

namespace graspbed::test_support {

std::string ReadText(const std::string& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) return "";
  std::stringstream text;
  text << stream.rdbuf();
  return text.str();
}

std::string SourcePath(const std::string& relative) {
  return std::string(GRASPBED_SOURCE_DIR) + "/" + relative;
}

}  // namespace graspbed::test_support
