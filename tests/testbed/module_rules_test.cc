// The module boundaries of DESIGN.md, read from the sources: testbed/ (what runs a scenario on any
// backend and scores it) sits above sim/ and hardware/, so no module below it includes it; MuJoCo
// stays inside sim/ (tests and benchmarks of sim/ may use it directly).
#include <filesystem>
#include <fstream>
#include <utility>
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace graspbed::testbed {
namespace {

namespace fs = std::filesystem;

struct Include {
  std::string file;  ///< path from the repository root
  int line = 0;
  std::string target;  ///< what is included, as written between the quotes or angle brackets
};

// Every #include of the C++ sources under `dir` (relative to the repository root).
std::vector<Include> IncludesUnder(const std::string& dir) {
  static const std::regex kInclude(R"(^\s*#\s*include\s*[<"]([^>"]+)[>"])");
  std::vector<Include> found;
  const fs::path root(GRASPBED_SOURCE_DIR);
  for (const auto& entry : fs::recursive_directory_iterator(root / dir)) {
    const std::string extension = entry.path().extension().string();
    if (!entry.is_regular_file() || (extension != ".h" && extension != ".cc")) continue;
    std::ifstream file(entry.path());
    std::string text;
    for (int line = 1; std::getline(file, text); ++line) {
      std::smatch match;
      if (std::regex_search(text, match, kInclude)) {
        found.push_back({fs::relative(entry.path(), root).string(), line, match[1].str()});
      }
    }
  }
  return found;
}

TEST(ModuleRulesTest, NoModuleBelowTheTestbedIncludesIt) {
  size_t scanned = 0;
  for (const char* module : {"common", "hand", "sensor", "controller", "sim", "hardware"}) {
    for (const Include& include : IncludesUnder(module)) {
      ++scanned;
      EXPECT_NE(include.target.rfind("testbed/", 0), 0u)
          << include.file << ":" << include.line << " includes " << include.target
          << ": testbed/ sits above " << module << "/, which must not depend on it";
    }
  }
  EXPECT_GT(scanned, 100u) << "the scan found almost no includes: wrong source directory?";
}

TEST(ModuleRulesTest, TheSimulationAndTheSerialLinkDoNotKnowEachOther) {
  for (const auto& [module, other] : {std::pair{"sim", "hardware/"}, std::pair{"hardware", "sim/"}}) {
    for (const Include& include : IncludesUnder(module)) {
      EXPECT_NE(include.target.rfind(other, 0), 0u)
          << include.file << ":" << include.line << " includes " << include.target << ": the simulated and the "
          << "serial backend meet only in testbed/";
    }
  }
}

TEST(ModuleRulesTest, MujocoIsIncludedOnlyInsideSim) {
  size_t mujoco_in_sim = 0;
  for (const Include& include : IncludesUnder("sim")) mujoco_in_sim += include.target.rfind("mujoco/", 0) == 0;
  EXPECT_GT(mujoco_in_sim, 0u) << "sim/ includes no MuJoCo header: wrong source directory?";
  for (const char* module : {"common", "hand", "sensor", "controller", "hardware", "testbed", "app", "python"}) {
    for (const Include& include : IncludesUnder(module)) {
      EXPECT_NE(include.target.rfind("mujoco/", 0), 0u)
          << include.file << ":" << include.line << " includes " << include.target
          << ": MuJoCo belongs to sim/ alone";
    }
  }
}

}  // namespace
}  // namespace graspbed::testbed
