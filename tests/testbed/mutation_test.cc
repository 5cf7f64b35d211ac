// Every run ends, whatever the numbers in the file: the shipped scenarios with numeric values replaced
// at random (seeded) by huge, tiny, negative, zero, NaN and infinite ones or by the file's value
// scaled (x1e-6 .. x1e6, negated), each run through the real
// `graspbed run`. Each must end within a wall-time bound with exit 0 or 1 (it ran: summary.json
// written) or 2 (refused: a one-line message, nothing written) -- never hang, never crash.
//
// A longer campaign: GRASPBED_BINARY=build/graspbed GRASPBED_MUTATION_RUNS=2000 GRASPBED_MUTATION_SEED=7
//   [GRASPBED_MUTATION_LIMIT_S=20] [GRASPBED_MUTATION_SCENARIOS=dir] build/tests/testbed/scenario_tests
//   --gtest_filter='Mutation*'.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/cli_runner.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"

namespace graspbed::testbed {
namespace {

namespace fs = std::filesystem;
using graspbed::test_support::CliBinary;
using graspbed::test_support::CliResult;
using graspbed::test_support::RunCliWithin;
using graspbed::test_support::SourcePath;
using graspbed::test_support::TempDir;

constexpr uint64_t kDefaultSeed = 20261123;
// Enough runs to reach every shipped file and many keys, few enough for about 20 s on 2 busy cores.
constexpr int kDefaultRuns = 48;
constexpr int kMaxMutationsPerRun = 3;
// A shipped scenario runs in at most ~3 s here (static_hold, 20 s simulated); a refused one in
// ~0.05 s. A run still going after this long is taken for a hang.
constexpr double kRunLimitS = 60.0;

// Values a typo, a unit mix-up or a bad generator puts into a file.
const std::vector<std::string> kValues = {
    "1.0e+308", "-1.0e+308", "1.0e-308", "-1.0e-308", "1.0e+9", "-1.0e+9", "1.0e-9", "-1.0e-9", "0",
    "-0.0",     "-1",        "nan",      ".nan",      ".inf",   "-.inf",   "1e999",  "3600",    "0.3"};

// Factors applied to the file's own value.
constexpr double kScales[] = {1e3, 1e-3, -1.0, 1e6, 1e-6, 10.0, 0.1};

int EnvInt(const char* name, int fallback) {
  const char* text = std::getenv(name);
  return text == nullptr ? fallback : std::atoi(text);
}

// A number std::stod reads whole (YAML's .nan/.inf and overflowing values are not).
bool IsNumber(const std::string& text) {
  if (text.empty()) return false;
  try {
    size_t consumed = 0;
    std::stod(text, &consumed);
    return consumed == text.size();
  } catch (const std::exception&) {
    return false;
  }
}

// Every numeric scalar below `node`, with its dotted path (for the report).
void CollectNumbers(YAML::Node node, const std::string& path,
                    std::vector<std::pair<std::string, YAML::Node>>* out) {
  if (node.IsScalar()) {
    if (IsNumber(node.Scalar())) out->emplace_back(path, node);
  } else if (node.IsSequence()) {
    for (size_t i = 0; i < node.size(); ++i)
      CollectNumbers(node[i], path + "[" + std::to_string(i) + "]", out);
  } else if (node.IsMap()) {
    for (auto entry : node) {
      CollectNumbers(entry.second, (path.empty() ? "" : path + ".") + entry.first.Scalar(), out);
    }
  }
}

// The shipped scenarios, or the *.yaml of $GRASPBED_MUTATION_SCENARIOS (another library, or an older
// checkout's against its own binary).
std::vector<std::string> ShippedScenarios() {
  const char* dir = std::getenv("GRASPBED_MUTATION_SCENARIOS");
  std::vector<std::string> files;
  for (const auto& entry :
       fs::directory_iterator(dir != nullptr ? std::string(dir) : SourcePath("scenarios"))) {
    if (entry.path().extension() == ".yaml") files.push_back(entry.path().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

TEST(MutationTest, EveryMutatedShippedScenarioEndsWithExitZeroOneOrTwo) {
  if (CliBinary().empty()) GTEST_FAIL() << "GRASPBED_BINARY must point at the CLI";
  const uint64_t seed =
      static_cast<uint64_t>(EnvInt("GRASPBED_MUTATION_SEED", static_cast<int>(kDefaultSeed)));
  const int runs = EnvInt("GRASPBED_MUTATION_RUNS", kDefaultRuns);
  const double limit_s = EnvInt("GRASPBED_MUTATION_LIMIT_S", static_cast<int>(kRunLimitS));
  const std::vector<std::string> files = ShippedScenarios();
  ASSERT_FALSE(files.empty());
  std::mt19937_64 rng(seed);
  const TempDir dir("mutation");
  int counts[3] = {0, 0, 0};
  for (int run = 0; run < runs; ++run) {
    // Every file in turn, so a short campaign still reaches each of them.
    const std::string& file = files[static_cast<size_t>(run) % files.size()];
    YAML::Node root = YAML::LoadFile(file);
    std::vector<std::pair<std::string, YAML::Node>> numbers;
    CollectNumbers(root, "", &numbers);
    ASSERT_FALSE(numbers.empty()) << file;
    const int mutations = std::uniform_int_distribution<int>(1, kMaxMutationsPerRun)(rng);
    std::ostringstream what;
    what << "seed " << seed << ", run " << run << ": " << fs::path(file).filename().string();
    for (int m = 0; m < mutations; ++m) {
      auto& [path, node] = numbers[std::uniform_int_distribution<size_t>(0, numbers.size() - 1)(rng)];
      // Half absolute values, half the file's value scaled (values just inside or outside a range).
      std::string value;
      const int pick = std::uniform_int_distribution<int>(0, 2 * static_cast<int>(kValues.size()) - 1)(rng);
      if (pick < static_cast<int>(kValues.size())) {
        value = kValues[static_cast<size_t>(pick)];
      } else {
        const double factor = kScales[static_cast<size_t>(pick) % std::size(kScales)];
        if (!IsNumber(node.Scalar())) continue;  // already mutated to ".nan" or "1e999"
        std::ostringstream scaled;
        scaled.precision(17);
        scaled << std::stod(node.Scalar()) * factor;
        value = scaled.str();
      }
      // A longer duration_s is only a longer run, not a hang: never lengthened.
      if (path == "duration_s" && IsNumber(value) && IsNumber(node.Scalar()) &&
          std::stod(value) > std::stod(node.Scalar())) {
        continue;
      }
      node = value;
      what << " " << path << "=" << value;
    }
    YAML::Emitter emitter;
    emitter << root;
    const std::string mutated =
        dir.Write("run" + std::to_string(run) + ".yaml", std::string(emitter.c_str()) + "\n");
    const std::string out = dir.Path("out" + std::to_string(run));

    const auto start = std::chrono::steady_clock::now();
    const CliResult result = RunCliWithin("run " + mutated + " --no-plots --out " + out, limit_s);
    const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    SCOPED_TRACE(what.str() + " (" + std::to_string(wall_s) + " s)");
    if (result.timed_out) {
      ADD_FAILURE() << "still running after " << limit_s << " s";
      continue;
    }
    if (result.exit_code < 0 || result.exit_code > 2) {
      ADD_FAILURE() << "exit " << result.exit_code << "\n" << result.err;
      continue;
    }
    ++counts[result.exit_code];
    if (result.exit_code == 2) {
      // Refused: one line naming the problem, nothing written.
      EXPECT_EQ(result.err.rfind("graspbed: error: ", 0), 0u) << result.err;
      EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
      EXPECT_FALSE(fs::exists(out)) << result.err;
    } else {
      // It ran: exit 1 is a failed expectation or a physics fault, never an error without a result.
      EXPECT_TRUE(fs::exists(out + "/summary.json")) << result.err;
      EXPECT_EQ(result.err.find("graspbed: error"), std::string::npos) << result.err;
    }
  }
  std::printf("%d mutated runs: %d passed, %d failed, %d refused\n", runs, counts[0], counts[1], counts[2]);
}

}  // namespace
}  // namespace graspbed::testbed
