// The proof of the reference controller on the shipped scenario suite, through the real `graspbed
// suite` command: grip_slip passes every scenario but those listed in kNotYetPassed (each with its
// reason, printed; the reference controller's next issue empties the list); the blind open-loop
// baseline, at an effort that holds the light objects, loses the objects of the slip scenarios.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "tests/support/cli_runner.h"
#include "tests/support/temp_dir.h"

namespace graspbed::controller {
namespace {

namespace fs = std::filesystem;
using graspbed::test_support::CliBinary;
using graspbed::test_support::CliResult;
using graspbed::test_support::RunCli;
using graspbed::test_support::TempDir;

/// Open-loop effort of the baseline run: about 3 N of pinch, 4x what the 100 g boxes need.
constexpr double kBaselineEffort = 0.15;

/// Scenarios whose load grows past what a fixed 3 N grip carries.
const std::set<std::string> kSlipScenarios = {"added_mass_step", "pull_ramp", "pouring_cup", "low_friction"};
/// Light-object scenarios the baseline's effort must hold (so its failures above are not a weak grip).
const std::set<std::string> kLightScenarios = {"default", "static_hold", "lift_unknown_mass"};

/// Scenarios strengthened by the honest verdicts (max_grip_efficiency, gross slips) and the object
/// library's tasks that grip_slip does not pass yet, with the expectations it fails (comma separated,
/// before the colon) and why, as measured. Do not loosen a scenario to empty it.
const std::map<std::string, std::string> kNotYetPassed = {
    {"low_friction",
     "max_grip_efficiency: with the soft finger's spin friction (physics.condim 4) the lift of the "
     "mu 0.2 box raises the vibration and centroid cues at 0.84-0.97 s with no contact sliding (27.8 "
     "false flags a minute), and each flag steps the target to the 10 N ceiling: mean 8.29 N against "
     "the oracle's 3.85 N (2.15); at point contacts it held 3.5 N (0.91)"},
    {"lift_mug",
     "max_grip_efficiency: the wrapped mug's oracle fell to 3.97 N (the pad meets it at its first "
     "mesa row, the soft finger's spin friction holds the handle's torque), while the reference "
     "still climbs to its ceiling on the lift's cues: mean 9.61 N (2.42)"},
    {"pour_bottle",
     "max_slip_mm: the wrapped full bottle (470 g, mu 0.45) slides 3.2 mm through the lift, flagged "
     "once of two gross slips; its oracle is 11.64 N, above the reference's 10 N ceiling"},
    {"hold_foam_brick",
     "not_dropped, max_slip_mm: the 500 N/m foam brick is held by a constant 0.27 to 2 N (its oracle "
     "0.26 N) and dropped from 4 N, where the pads sink deep and squeeze it out: the reference's "
     "vibration cue rises with the slide at the lift and its flags take the target to the 10 N "
     "ceiling (dropped at 1.65 s)"},
};

/// Number of shipped scenario files.
size_t ShippedScenarioCount() {
  size_t count = 0;
  for (const auto& entry : fs::directory_iterator(std::string(GRASPBED_SOURCE_DIR) + "/scenarios")) {
    if (entry.path().extension() == ".yaml") ++count;
  }
  return count;
}

struct SuiteRun {
  int exit_code = -1;
  std::map<std::string, nlohmann::json> runs;  ///< scenario name -> its summary
};

class ReferenceSuiteTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (CliBinary().empty()) GTEST_FAIL() << "GRASPBED_BINARY not set (run through ctest)";
  }

  SuiteRun RunSuite(const std::string& extra_arguments) {
    const CliResult cli = RunCli("suite scenarios -j 2 --no-plots --json --out " + (dir_ / "out").string() +
                                 " " + extra_arguments);
    SuiteRun result;
    result.exit_code = cli.exit_code;
    const nlohmann::json suite = nlohmann::json::parse(cli.out, nullptr, /*allow_exceptions=*/false);
    if (suite.is_discarded() || !suite.contains("runs")) return result;
    for (const nlohmann::json& run : suite["runs"]) result.runs[run["scenario"].get<std::string>()] = run;
    return result;
  }

  const TempDir temp_dir_{"reference_suite"};
  const fs::path dir_ = temp_dir_.path();
};

/// The expectations a kNotYetPassed reason names: "a, b: why" -> {a, b}.
std::set<std::string> ListedExpectations(const std::string& reason) {
  std::set<std::string> names;
  std::stringstream list(reason.substr(0, reason.find(':')));
  for (std::string name; std::getline(list, name, ',');)
    names.insert(name.substr(name.find_first_not_of(' ')));
  return names;
}

/// Names of the failed expectations of one run.
std::set<std::string> FailedExpectations(const nlohmann::json& run) {
  std::set<std::string> failed;
  for (const nlohmann::json& expectation : run["expectations"]) {
    if (!expectation["passed"].get<bool>()) failed.insert(expectation["name"].get<std::string>());
  }
  return failed;
}

TEST_F(ReferenceSuiteTest, GripSlipPassesEveryShippedScenarioButTheListedAndOpenLoopLosesTheSlipScenarios) {
  const SuiteRun reference = RunSuite("");
  ASSERT_EQ(reference.runs.size(), ShippedScenarioCount());
  EXPECT_EQ(reference.exit_code, kNotYetPassed.empty() ? 0 : 1);
  for (const auto& [name, run] : reference.runs) {
    SCOPED_TRACE(name);
    EXPECT_EQ(run["controller"], "grip_slip");
    const std::set<std::string> failed = FailedExpectations(run);
    const auto listed = kNotYetPassed.find(name);
    const std::set<std::string> listed_failures =
        listed == kNotYetPassed.end() ? std::set<std::string>{} : ListedExpectations(listed->second);
    if (!listed_failures.count("not_dropped")) {
      EXPECT_FALSE(run["metrics"]["dropped"].get<bool>());
    }
    if (listed == kNotYetPassed.end()) {
      EXPECT_TRUE(run["passed"].get<bool>()) << ::testing::PrintToString(failed);
      continue;
    }
    // Listed: it fails, and for the reason given (the expectation named first), nothing else.
    std::printf("[ not yet ] %s: %s; fails %s\n", name.c_str(), listed->second.c_str(),
                ::testing::PrintToString(failed).c_str());
    EXPECT_EQ(failed, listed_failures) << "listed in kNotYetPassed for " << listed->second;
  }

  const SuiteRun baseline = RunSuite("--controller open_loop --set controller.params.close_effort=" +
                                     std::to_string(kBaselineEffort));
  ASSERT_EQ(baseline.runs.size(), reference.runs.size());
  EXPECT_EQ(baseline.exit_code, 1);
  for (const std::string& name : kLightScenarios) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(baseline.runs.count(name));
    EXPECT_FALSE(baseline.runs.at(name)["metrics"]["dropped"].get<bool>());
  }
  for (const std::string& name : kSlipScenarios) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(baseline.runs.count(name));
    const nlohmann::json& run = baseline.runs.at(name);
    EXPECT_FALSE(run["passed"].get<bool>());
    // Lost for physical reasons, not only for not flagging slip (which a blind controller cannot).
    const std::set<std::string> failed = FailedExpectations(run);
    EXPECT_TRUE(failed.count("not_dropped") || failed.count("max_slip_mm"))
        << ::testing::PrintToString(failed);
    // The reference controller held the same object with less slip than the baseline allowed.
    EXPECT_LT(reference.runs.at(name)["metrics"]["max_slip_mm"].get<double>(),
              run["metrics"]["max_slip_mm"].get<double>());
  }
}

}  // namespace
}  // namespace graspbed::controller
