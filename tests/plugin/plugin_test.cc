// Controller plugins: real shared libraries (tests/plugin/CMakeLists.txt builds them) loaded through
// the controller factory, the scenario loader and the real executable. Each way a plugin can be
// refused (missing, not a plugin, another API version, a make() that throws) gives a message naming
// the library and, on the command line, exit 2.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "controller/grasp_controller.h"
#include "controller/plugin_loader.h"
#include "testbed/scenario_config.h"
#include "tests/support/allocation_counter.h"
#include "tests/support/cli_runner.h"
#include "tests/support/error_of.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"

namespace graspbed::controller {
namespace {

using graspbed::test_support::CliBinary;
using graspbed::test_support::CliResult;
using graspbed::test_support::RunCli;
using graspbed::test_support::TempDir;
using ::testing::HasSubstr;

const std::string kPluginDir = GRASPBED_TEST_PLUGIN_DIR;
const std::string kThreshold = kPluginDir + "/libthreshold_grip.so";
const std::string kWrongVersion = kPluginDir + "/libwrong_version_plugin.so";
const std::string kApi2 = kPluginDir + "/libapi2_plugin.so";
const std::string kThrowing = kPluginDir + "/libthrowing_plugin.so";
const std::string kNotAPlugin = kPluginDir + "/libnot_a_plugin.so";
const std::string kMissing = kPluginDir + "/libno_such_plugin.so";

std::string ErrorOf(const std::function<void()>& action) {
  return graspbed::test_support::ErrorOf<std::invalid_argument>(action);
}

std::string Plugin(const std::string& library) { return "plugin:" + library; }

TEST(PluginLoaderTest, LoadsThePluginItsNameAndDeclaredParameters) {
  const LoadedPlugin& plugin = LoadPlugin(Plugin(kThreshold));
  EXPECT_EQ(plugin.name, "threshold_grip");
  EXPECT_EQ(plugin.path, kThreshold);
  const std::vector<ControllerParameter> parameters = ControllerParameters(Plugin(kThreshold));
  ASSERT_EQ(parameters.size(), 6u);
  EXPECT_EQ(parameters[0].name, "target_grip_n");
  EXPECT_DOUBLE_EQ(parameters[0].default_value, 3.0);
  EXPECT_EQ(parameters[0].unit, "N");
  // Loaded once: a second name for the same file is the same plugin.
  EXPECT_EQ(&LoadPlugin(Plugin(kPluginDir + "/../plugins/libthreshold_grip.so")), &plugin);
}

TEST(PluginLoaderTest, ParametersAreValidatedExactlyLikeABuiltIn) {
  const std::unique_ptr<GraspController> controller =
      MakeController(Plugin(kThreshold), {{"target_grip_n", 5.0}});
  EXPECT_EQ(controller->name(), "threshold_grip");
  EXPECT_THAT(ErrorOf([] {
                MakeController(Plugin(kThreshold), {{"target_grip", 5.0}});
              }),
              HasSubstr("target_grip: no such parameter; valid parameters: target_grip_n, approach_effort"));
  EXPECT_THAT(ErrorOf([] {
                MakeController(Plugin(kThreshold), {{"target_grip_n", 50.0}});
              }),
              HasSubstr("target_grip_n = 50: must be in [0.2, 10] N"));
  // The plugin's own cross-field check comes back as bad input naming the plugin.
  EXPECT_THAT(ErrorOf([] {
                MakeController(Plugin(kThreshold), {{"contact_n", 4.0}});
              }),
              HasSubstr("('threshold_grip'): contact_n = 4: must be below target_grip_n"));
}

TEST(PluginLoaderTest, TheControllerClosesHoldsAndOpensWithoutAllocating) {
  const std::unique_ptr<GraspController> controller = MakeController(Plugin(kThreshold), {});
  controller->Reset();
  controller->SetIntent(GraspIntent::kClose);
  sensor::TactileState state;
  state.unit_count = 20;
  state.valid_count = 20;
  const long before = graspbed::test_support::AllocationCount();
  EXPECT_DOUBLE_EQ(controller->Update(state, {}, 0.0).grip_effort, 0.3);  // closing at the approach effort
  state.total_fn_n = 1.0;  // in contact, below the 3 N target: the effort rises
  double effort = 0.0;
  for (int tick = 1; tick <= 100; ++tick) effort = controller->Update(state, {}, 1e-3 * tick).grip_effort;
  EXPECT_NEAR(effort, 0.3 + 0.3 * (3.0 - 1.0) * 0.1, 1e-9);  // gain x error x 100 ms
  state.stale = true;                                        // data not to be trusted: hold, never open
  const HandCommand hold = controller->Update(state, {}, 0.2);
  EXPECT_TRUE(hold.brake);
  EXPECT_TRUE(controller->telemetry().safe_hold);
  controller->SetIntent(GraspIntent::kOpen);
  EXPECT_LT(controller->Update(state, {}, 0.3).grip_effort, 0.0);
  EXPECT_EQ(graspbed::test_support::AllocationCount(), before) << "Update allocated";
}

// A hand that reports its index: position, current and stops known, the index at `closed_rad`.
hand::HandState IndexAt(double closed_rad, bool at_closed_stop, double current_a) {
  hand::HandState hand;
  hand.time_s = 0.0;
  hand.digit_count = 2;
  hand::DigitState& index = hand.digits[0];
  index.joint_count = 2;
  index.position_known = index.velocity_known = index.current_known = index.stops_known = true;
  index.joint_position = {closed_rad, closed_rad};
  index.motor_current_a = current_a;
  index.stall_current_a = 1.0;
  index.at_closed_stop = at_closed_stop;
  return hand;
}

TEST(PluginLoaderTest, TheControllerReadsTheHandWithoutAllocating) {
  const std::unique_ptr<GraspController> controller = MakeController(Plugin(kThreshold), {});
  controller->Reset();
  controller->SetIntent(GraspIntent::kClose);
  sensor::TactileState state;  // nothing felt
  state.unit_count = 20;
  state.valid_count = 20;
  ASSERT_EQ(controller->diagnostic_channels().size(), 2u);
  EXPECT_STREQ(controller->diagnostic_channels()[1].name, "index_current_a");
  std::array<double, 2> diagnostics{};
  const long before = graspbed::test_support::AllocationCount();
  // Closing freely: the approach effort, and the index's current logged as the hand measured it.
  EXPECT_DOUBLE_EQ(controller->Update(state, IndexAt(0.5, false, 0.02), 0.0).grip_effort, 0.3);
  controller->ReadDiagnostics(diagnostics);
  EXPECT_DOUBLE_EQ(diagnostics[1], 0.02);
  EXPECT_STREQ(controller->telemetry().phase, "closing");
  // At the closed stop without contact: closed on nothing, the motor stops pushing the stop, and
  // stays stopped (even if the index springs back off the stop) until the next intent.
  EXPECT_DOUBLE_EQ(controller->Update(state, IndexAt(0.98, true, 0.31), 0.001).grip_effort, 0.0);
  EXPECT_STREQ(controller->telemetry().phase, "closed_empty");
  EXPECT_DOUBLE_EQ(controller->Update(state, IndexAt(0.9, false, 0.01), 0.002).grip_effort, 0.0);
  // A hand without proprioception: the current is logged unknown (NaN), closing goes on.
  controller->SetIntent(GraspIntent::kClose);
  EXPECT_DOUBLE_EQ(controller->Update(state, hand::HandState{}, 0.003).grip_effort, 0.3);
  controller->ReadDiagnostics(diagnostics);
  EXPECT_TRUE(std::isnan(diagnostics[1]));
  // Stops not known (a device on protocol version 1): the flag is not trusted.
  hand::HandState unknown_stops = IndexAt(0.98, true, 0.31);
  unknown_stops.digits[0].stops_known = false;
  EXPECT_DOUBLE_EQ(controller->Update(state, unknown_stops, 0.004).grip_effort, 0.3);
  EXPECT_EQ(graspbed::test_support::AllocationCount(), before) << "Update allocated";
}

TEST(PluginLoaderTest, AMissingLibraryIsNamed) {
  EXPECT_THAT(ErrorOf([] { MakeController(Plugin(kMissing), {}); }),
              HasSubstr("controller plugin " + kMissing + ": no such file"));
  EXPECT_THAT(ErrorOf([] { ControllerParameters(Plugin("no_such_plugin")); }),
              HasSubstr("controller plugin 'no_such_plugin' not found (looked for no_such_plugin and "
                        "libno_such_plugin.so in"));
  EXPECT_THAT(ErrorOf([] { ControllerParameters("plugin:"); }), HasSubstr("no library named"));
}

TEST(PluginLoaderTest, ALibraryThatIsNoPluginIsRefused) {
  EXPECT_THAT(ErrorOf([] { MakeController(Plugin(kNotAPlugin), {}); }),
              HasSubstr("controller plugin " + kNotAPlugin +
                        ": not a graspbed controller plugin (exports no graspbed_controller_plugin"));
  // A file that is no shared library at all: dlopen's reason.
  const TempDir dir("plugin");
  const std::string text = dir.Write("libtext.so", "not an ELF file\n");
  EXPECT_THAT(ErrorOf([&] { MakeController(Plugin(text), {}); }),
              HasSubstr("controller plugin " + text + ": cannot load: "));
}

TEST(PluginLoaderTest, APluginOfAnotherApiVersionIsRefusedBeforeItIsCalled) {
  EXPECT_THAT(ErrorOf([] { ControllerParameters(Plugin(kWrongVersion)); }),
              HasSubstr(": built against controller API version " +
                        std::to_string(GRASPBED_CONTROLLER_API_VERSION + 1) + ", this graspbed has version " +
                        std::to_string(GRASPBED_CONTROLLER_API_VERSION) + "; rebuild the plugin"));
}

TEST(PluginLoaderTest, APluginBuiltAgainstApiVersion2IsRefusedNamingBothVersions) {
  // Version 3 changed Update (the HandState): a version-2 plugin's vtable is not this graspbed's.
  static_assert(GRASPBED_CONTROLLER_API_VERSION == 3, "update this test's message for the new version");
  EXPECT_THAT(ErrorOf([] { MakeController(Plugin(kApi2), {}); }),
              HasSubstr("controller plugin " + kApi2 +
                        ": built against controller API version 2, this graspbed has version 3; rebuild the "
                        "plugin against this graspbed's headers"));
}

TEST(PluginLoaderTest, AFactoryThatThrowsBecomesBadInput) {
  EXPECT_EQ(ControllerParameters(Plugin(kThrowing)).size(), 1u);
  EXPECT_THAT(
      ErrorOf([] { MakeController(Plugin(kThrowing), {}); }),
      HasSubstr("controller plugin " + kThrowing + " ('throws_when_built'): cannot open weights.bin"));
}

TEST(PluginLoaderTest, BareNamesAreFoundOnTheSearchPath) {
  ASSERT_EQ(::setenv("GRASPBED_PLUGIN_PATH", ("/nonexistent:" + kPluginDir).c_str(), 1), 0);
  EXPECT_EQ(PluginSearchPath().at(1), kPluginDir);
  EXPECT_EQ(LoadPlugin(Plugin("threshold_grip")).path, kThreshold);        // libNAME.so
  EXPECT_EQ(LoadPlugin(Plugin("libthreshold_grip.so")).path, kThreshold);  // the file name itself
  ::unsetenv("GRASPBED_PLUGIN_PATH");
}

TEST(PluginLoaderTest, RelativePathsResolveAgainstTheGivenDirectoryBareNamesStay) {
  EXPECT_EQ(ResolvePluginName("plugin:build/libx.so", "/data/scenarios"),
            "plugin:/data/scenarios/build/libx.so");
  EXPECT_EQ(ResolvePluginName("plugin:../libx.so", "/data/scenarios"), "plugin:/data/libx.so");
  EXPECT_EQ(ResolvePluginName("plugin:/opt/libx.so", "/data"), "plugin:/opt/libx.so");
  EXPECT_EQ(ResolvePluginName("plugin:mine", "/data"), "plugin:mine");
  EXPECT_EQ(ResolvePluginName("grip_slip", "/data"), "grip_slip");
}

// ---- scenario files ----------------------------------------------------------------------------------

constexpr char kScenarioHead[] = "name: p\nduration_s: 0.5\nscript:\n  - {at_s: 0.1, action: close}\n";

TEST(PluginScenarioTest, APluginPathIsRelativeToTheScenarioFile) {
  const TempDir dir("plugin");
  std::filesystem::create_directories(dir.Path("lib"));
  std::filesystem::copy_file(kThreshold, dir.Path("lib/libthreshold_grip.so"));
  const std::string file = dir.Write("s/p.yaml", std::string(kScenarioHead) +
                                                     "controller:\n  plugin: ../lib/libthreshold_grip.so\n"
                                                     "  params: {target_grip_n: 4}\n");
  const testbed::ScenarioConfig config = testbed::LoadScenario(file);
  EXPECT_EQ(config.controller.name, "plugin:" + dir.Path("lib/libthreshold_grip.so"));
  EXPECT_DOUBLE_EQ(config.controller.params.at("target_grip_n"), 4.0);
  EXPECT_DOUBLE_EQ(config.controller.params.at("approach_effort"), 0.3);  // defaults filled in
  // The resolved config (config.yaml of a run) loads again to the same controller.
  const testbed::ScenarioConfig again =
      testbed::LoadScenarioFromString(testbed::EmitScenarioYaml(config), dir.Path("elsewhere/config.yaml"));
  EXPECT_EQ(again.controller.name, config.controller.name);
  EXPECT_EQ(again.controller.params, config.controller.params);
}

TEST(PluginScenarioTest, BadPluginSectionsNameFileLineAndKey) {
  const TempDir dir("plugin");
  struct Case {
    std::string controller;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"controller:\n  plugin: " + kThreshold + "\n  params: {target_grip: 4}\n",
       ":7: controller.params.target_grip = 4: controller 'plugin:" + kThreshold +
           "' has no such parameter; valid parameters: target_grip_n, approach_effort"},
      {"controller:\n  plugin: " + kThreshold + "\n  params: {target_grip_n: 40}\n",
       ":7: controller.params.target_grip_n = 40: must be <= 10"},
      {"controller:\n  plugin: " + kThreshold + "\n  params: {contact_n: 4}\n",
       ":7: controller.params.contact_n = 4: must be below target_grip_n = 3"},
      {"controller:\n  plugin: " + kMissing + "\n",
       ":6: controller.plugin = " + kMissing + ": controller plugin " + kMissing + ": no such file"},
      {"controller:\n  plugin: " + kWrongVersion + "\n", ":6: controller.plugin = " + kWrongVersion +
                                                             ": controller plugin " + kWrongVersion +
                                                             ": built against"},
      {"controller:\n  plugin: " + kApi2 + "\n",
       ":6: controller.plugin = " + kApi2 + ": controller plugin " + kApi2 +
           ": built against controller API version 2, this graspbed has "
           "version 3"},
      {"controller:\n  name: plugin:" + kNotAPlugin + "\n", ":6: controller.name = plugin:" + kNotAPlugin +
                                                                ": controller plugin " + kNotAPlugin +
                                                                ": not a graspbed"},
      {"controller:\n  plugin: " + kThrowing + "\n", ":6: controller.plugin = " + kThrowing +
                                                         ": controller plugin " + kThrowing +
                                                         " ('throws_when_built'): cannot open weights.bin"},
      {"controller:\n  name: grip_slip\n  plugin: " + kThreshold + "\n",
       ":7: controller.plugin = " + kThreshold + ": give either name or plugin, not both"},
  };
  for (const Case& c : cases) {
    const std::string file = dir.Write("bad.yaml", std::string(kScenarioHead) + c.controller);
    const std::string message =
        graspbed::test_support::ErrorOf<std::invalid_argument>([&] { testbed::LoadScenario(file); });
    EXPECT_THAT(message, HasSubstr(file + c.expected)) << c.controller;
  }
}

// ---- the command line ----------------------------------------------------------------------------------

// The plugin's force loop (examples/cpp_controller) adds gain_per_n_s x error x dt to the effort, and
// the default hand pinches stall_pinch_force_n = 20 N per unit of effort: a first-order loop with
// tau = 1 / (0.3 /(N s) x 20 N) = 0.17 s.
constexpr double kPluginLoopTauS = 1.0 / (0.3 * 20.0);
// Held, the grip error decays from the approach's impact (effort 0.3 drives up to 6 N into a 3 N
// target: a 3 N error) to 3 N x e^-5 = 0.02 N five time constants on; the lift's transient and the
// inamp_16bit readout's noise add to it (measured from then on: at most 0.033 N, the mean -0.005 N).
constexpr double kHeldSettleS = 5.0 * kPluginLoopTauS;
constexpr double kHeldGripErrorN = 0.1;
// The true squeeze follows a 1 N step of the target within 10 %: the readout's estimate reads the
// squeeze 2 to 3 % low (measured: 3.07 N to 4.11 N, a rise of 1.04 N).
constexpr double kSqueezeStepTolN = 0.1;

// The numeric columns of a run's signals.csv by name (no cell holds a comma; text cells read as 0).
std::map<std::string, std::vector<double>> ReadSignalColumns(const std::string& path) {
  std::istringstream text(graspbed::test_support::ReadText(path));
  std::string line;
  std::getline(text, line);
  std::vector<std::string> names;
  std::istringstream header(line);
  for (std::string name; std::getline(header, name, ',');) names.push_back(name);
  std::map<std::string, std::vector<double>> columns;
  while (std::getline(text, line)) {
    std::istringstream cells(line);
    std::string cell;
    for (size_t c = 0; c < names.size() && std::getline(cells, cell, ','); ++c) {
      columns[names[c]].push_back(std::strtod(cell.c_str(), nullptr));
    }
  }
  return columns;
}

// A run's hold as its signals.csv shows it, from kHeldSettleS after the metrics first count the
// object held to the end of the run.
struct Hold {
  int rows = 0;
  bool held_to_end = true;       ///< `holding` on every row since it was first
  double max_abs_error_n = 0.0;  ///< the plugin's ctl_grip_error_n
  double mean_estimate_n = 0.0;  ///< est_total_fn_n, the squeeze the plugin regulates
  double mean_squeeze_n = 0.0;   ///< true_squeeze_n
  double min_target_n = std::numeric_limits<double>::infinity();  ///< grip_target_n
  double max_target_n = -std::numeric_limits<double>::infinity();
};

Hold HoldOf(const std::string& csv_path) {
  auto columns = ReadSignalColumns(csv_path);
  const std::vector<double>& time = columns["time_s"];
  const std::vector<double>& holding = columns["holding"];
  const std::vector<double>& error = columns["ctl_grip_error_n"];
  const std::vector<double>& estimate = columns["est_total_fn_n"];
  const std::vector<double>& squeeze = columns["true_squeeze_n"];
  const std::vector<double>& target = columns["grip_target_n"];
  Hold hold;
  for (const auto& [name, values] : columns) {
    if (values.size() != time.size() || time.empty()) {
      ADD_FAILURE() << csv_path << ": no rows, or no column " << name;
      return hold;
    }
  }
  const auto first = std::find(holding.begin(), holding.end(), 1.0);
  if (first == holding.end()) return hold;
  const double settled_s = time[first - holding.begin()] + kHeldSettleS;
  hold.held_to_end = std::all_of(first, holding.end(), [](double value) { return value == 1.0; });
  for (size_t row = 0; row < time.size(); ++row) {
    if (time[row] < settled_s) continue;
    ++hold.rows;
    hold.max_abs_error_n = std::max(hold.max_abs_error_n, std::abs(error[row]));
    hold.mean_estimate_n += estimate[row];
    hold.mean_squeeze_n += squeeze[row];
    hold.min_target_n = std::min(hold.min_target_n, target[row]);
    hold.max_target_n = std::max(hold.max_target_n, target[row]);
  }
  hold.mean_estimate_n /= std::max(hold.rows, 1);
  hold.mean_squeeze_n /= std::max(hold.rows, 1);
  return hold;
}

// Held at the plugin's 3 N target the index's motor makes 0.15 of its stall torque, about 0.17 A of
// the realistic profile's 1 A (measured: 0.18 A on average); before the close, about the 10 mA offset.
constexpr double kHeldIndexCurrentMinA = 0.1;
constexpr size_t kBeforeCloseRow = 100;  // 0.1 s: the default scenario closes at 0.15 s

class PluginCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (CliBinary().empty()) GTEST_FAIL() << "GRASPBED_BINARY must point at the CLI";
  }
  const TempDir dir_{"plugin_cli"};
};

TEST_F(PluginCliTest, EveryRefusedPluginExitsTwoWithItsReason) {
  struct Case {
    std::string library;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {kMissing, "no such file"},
      {kNotAPlugin, "not a graspbed controller plugin"},
      {kWrongVersion, "built against controller API version"},
      {kApi2, "built against controller API version 2, this graspbed has version 3"},
      {kThrowing, "cannot open weights.bin"},
  };
  for (const Case& c : cases) {
    for (const std::string& command : std::vector<std::string>{
             "run scenarios/default.yaml --no-plots --out " + dir_.Path("run"),
             "suite scenarios --out " + dir_.Path("suite"), "hw --port /dev/null --duration 1"}) {
      const CliResult result = RunCli(command + " --controller plugin:" + c.library);
      EXPECT_EQ(result.exit_code, 2) << command << " " << c.library << ": " << result.err;
      EXPECT_THAT(result.err, HasSubstr("graspbed: error: ")) << command;
      EXPECT_THAT(result.err, HasSubstr(c.expected)) << command << ": " << result.err;
    }
  }
  EXPECT_FALSE(std::filesystem::exists(dir_.Path("run"))) << "a refused run wrote outputs";
  EXPECT_FALSE(std::filesystem::exists(dir_.Path("suite")));
}

TEST_F(PluginCliTest, TheDefaultScenarioHoldsWithThePluginByRelativePathAndByName) {
  // A path relative to the working directory (the source tree, where ctest runs).
  const std::string relative = std::filesystem::relative(kThreshold).string();
  const CliResult run = RunCli("run scenarios/default.yaml --no-plots --json --out " + dir_.Path("rel") +
                               " --controller plugin:" + relative);
  ASSERT_EQ(run.exit_code, 0) << run.err << run.out;
  const nlohmann::json summary = nlohmann::json::parse(run.out);
  EXPECT_EQ(summary.at("controller"), "plugin:" + kThreshold);
  EXPECT_TRUE(summary.at("passed").get<bool>());
  EXPECT_FALSE(summary.at("metrics").at("dropped").get<bool>());
  // The plugin's diagnostic channel is a column; held, the grip error is small and the plugin holds
  // its default target (3 N).
  const std::string signals = graspbed::test_support::ReadText(dir_.Path("rel/signals.csv"));
  const std::string header = signals.substr(0, signals.find('\n'));
  EXPECT_THAT(header, ::testing::EndsWith(",ctl_grip_error_n,ctl_index_current_a"));
  const double default_target_n = ControllerParameters(Plugin(kThreshold)).at(0).default_value;
  const Hold hold = HoldOf(dir_.Path("rel/signals.csv"));
  ASSERT_GT(hold.rows, 0) << "never held, or held too late to settle";
  EXPECT_TRUE(hold.held_to_end);
  EXPECT_LE(hold.max_abs_error_n, kHeldGripErrorN);
  EXPECT_EQ(hold.min_target_n, default_target_n);
  EXPECT_EQ(hold.max_target_n, default_target_n);
  EXPECT_NEAR(hold.mean_estimate_n, default_target_n, kHeldGripErrorN);
  // The plugin reads the hand: its diagnostic is the index's motor current the loop logged as the
  // hand state it gave the plugin, row by row, and it rises once the index grips.
  auto columns = ReadSignalColumns(dir_.Path("rel/signals.csv"));
  const std::vector<double>& logged = columns["ctl_index_current_a"];
  const std::vector<double>& measured = columns["finger_current_a"];
  ASSERT_EQ(logged.size(), measured.size());
  for (size_t row = 0; row < logged.size(); ++row) {
    const bool same = logged[row] == measured[row] || (std::isnan(logged[row]) && std::isnan(measured[row]));
    ASSERT_TRUE(same) << "row " << row << ": " << logged[row] << " != " << measured[row];
  }
  EXPECT_LT(measured[kBeforeCloseRow], kHeldIndexCurrentMinA);
  EXPECT_GT(measured.back(), kHeldIndexCurrentMinA);
  // By bare name on GRASPBED_PLUGIN_PATH (the child inherits it), with a parameter through --set.
  ASSERT_EQ(::setenv("GRASPBED_PLUGIN_PATH", kPluginDir.c_str(), 1), 0);
  const CliResult named =
      RunCli("run scenarios/default.yaml --no-plots --json --out " + dir_.Path("named") +
             " --controller plugin:threshold_grip --set controller.params.target_grip_n=4");
  ASSERT_EQ(named.exit_code, 0) << named.err << named.out;
  const nlohmann::json named_summary = nlohmann::json::parse(named.out);
  EXPECT_EQ(named_summary.at("controller"), "plugin:threshold_grip");
  EXPECT_FALSE(named_summary.at("metrics").at("dropped").get<bool>());
  // The parameter took effect: the plugin holds 4 N, and the hand squeezes the box 1 N harder.
  const Hold named_hold = HoldOf(dir_.Path("named/signals.csv"));
  ASSERT_GT(named_hold.rows, 0) << "never held, or held too late to settle";
  EXPECT_TRUE(named_hold.held_to_end);
  EXPECT_LE(named_hold.max_abs_error_n, kHeldGripErrorN);
  EXPECT_EQ(named_hold.min_target_n, 4.0);
  EXPECT_EQ(named_hold.max_target_n, 4.0);
  EXPECT_NEAR(named_hold.mean_estimate_n, 4.0, kHeldGripErrorN);
  EXPECT_NEAR(named_hold.mean_squeeze_n - hold.mean_squeeze_n, 4.0 - default_target_n, kSqueezeStepTolN);
  const CliResult out_of_range =
      RunCli("run scenarios/default.yaml --no-plots --out " + dir_.Path("range") +
             " --controller plugin:threshold_grip --set controller.params.target_grip_n=40");
  ::unsetenv("GRASPBED_PLUGIN_PATH");
  EXPECT_EQ(out_of_range.exit_code, 2);
  EXPECT_THAT(out_of_range.err, HasSubstr("--set controller.params.target_grip_n=40: "));
  EXPECT_THAT(out_of_range.err, HasSubstr("controller.params.target_grip_n = 40: must be <= 10"));
}

TEST_F(PluginCliTest, ThePluginStopsAtTheClosedStopWhenItClosesOnNothing) {
  // The hand lifted clear of the box, then closed: the index runs onto its closed stop (about 2 s at
  // the approach effort), where the plugin stops driving the motor.
  const std::string scenario = dir_.Write("empty.yaml", R"(name: close_on_nothing
duration_s: 3.0
object: {shape: box, size_m: [0.05, 0.05, 0.08], mass_kg: 0.1, friction: 0.8}
controller: {name: grip_slip}
script:
  - {at_s: 0.0, action: lift, height_m: 0.15, duration_s: 0.2}
  - {at_s: 0.3, action: close}
)");
  const CliResult run = RunCli("run " + scenario + " --no-plots --out " + dir_.Path("empty") +
                               " --controller plugin:" + kThreshold);
  ASSERT_EQ(run.exit_code, 0) << run.err << run.out;
  EXPECT_THAT(graspbed::test_support::ReadText(dir_.Path("empty/signals.csv")), HasSubstr(",closed_empty,"));
  auto columns = ReadSignalColumns(dir_.Path("empty/signals.csv"));
  const std::vector<double>& at_stop = columns["finger_at_closed_stop"];
  const std::vector<double>& effort = columns["grip_effort"];
  const auto reached = std::find(at_stop.begin(), at_stop.end(), 1.0);
  ASSERT_NE(reached, at_stop.end()) << "the index never reached its closed stop";
  const size_t first = static_cast<size_t>(reached - at_stop.begin());
  ASSERT_GT(first, 0u);
  EXPECT_DOUBLE_EQ(effort[first - 1], 0.3) << "closing at the approach effort until then";
  for (size_t row = first; row < effort.size(); ++row) ASSERT_EQ(effort[row], 0.0) << "row " << row;
}

TEST_F(PluginCliTest, SuiteSweepAndScoreRunThePlugin) {
  // A short grasp (the default box, no lift) in a directory of its own, for the suite and the sweep.
  const std::string scenario = dir_.Write("scenarios/short.yaml", R"(name: short
duration_s: 0.6
object: {shape: box, size_m: [0.05, 0.05, 0.08], mass_kg: 0.1, friction: 0.8}
controller: {name: grip_slip}
script:
  - {at_s: 0.05, action: close}
expectations: {not_dropped: true}
)");
  const std::string plugin = " --controller plugin:" + kThreshold;
  const CliResult suite =
      RunCli("suite " + dir_.Path("scenarios") + " --no-plots --out " + dir_.Path("suite") + plugin);
  ASSERT_EQ(suite.exit_code, 0) << suite.err << suite.out;
  EXPECT_THAT(suite.out, HasSubstr("plugin:"));
  const nlohmann::json suite_json =
      nlohmann::json::parse(graspbed::test_support::ReadText(dir_.Path("suite/suite.json")));
  ASSERT_EQ(suite_json.at("runs").size(), 1u);
  EXPECT_EQ(suite_json.at("runs")[0].at("controller"), "plugin:" + kThreshold);
  EXPECT_TRUE(suite_json.at("runs")[0].at("passed").get<bool>());

  // The sweep tunes the plugin's own parameter on top of --controller.
  const std::string spec = dir_.Write(
      "sweep.yaml", "scenario: " + scenario + "\nparameters:\n  controller.params.target_grip_n: [2, 4]\n");
  const CliResult sweep = RunCli("sweep " + spec + " --out " + dir_.Path("sweep") + plugin);
  ASSERT_EQ(sweep.exit_code, 0) << sweep.err << sweep.out;
  const std::string rows = graspbed::test_support::ReadText(dir_.Path("sweep/results.jsonl"));
  EXPECT_EQ(std::count(rows.begin(), rows.end(), '\n'), 2) << rows;
  // A parameter only the plugin has: the sweep really ran the plugin (grip_slip would refuse it).
  EXPECT_THAT(rows, HasSubstr("\"controller.params.target_grip_n\":4"));

  const CliResult score =
      RunCli("score --limit 1 --out " + dir_.Path("score") + " --controller open_loop" + plugin);
  ASSERT_EQ(score.exit_code, 0) << score.err << score.out;
  EXPECT_THAT(score.out, HasSubstr("plugin:" + kThreshold.substr(0, 10)));
  const nlohmann::json card =
      nlohmann::json::parse(graspbed::test_support::ReadText(dir_.Path("score/scorecard.json")));
  ASSERT_EQ(card.at("controllers").size(), 2u);
  EXPECT_EQ(card.at("controllers")[1].at("controller"), "plugin:" + kThreshold);
}

}  // namespace
}  // namespace graspbed::controller
