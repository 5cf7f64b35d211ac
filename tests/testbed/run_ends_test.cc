// Every run ends. A physics fault (a NaN injected into the state mid-run; an unstable but valid
// scene) ends the run at once with the fault named, its time, and the outputs so far written; in a
// suite that run fails and the others go on. The simulated clock never stalls or runs backwards at a
// fault, so no loop waiting on it can spin. A scene whose bodies start inside each other and values
// no real scene has are bad input (exit 2, the keys named), not results.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sensor/layout.h"
#include "sim/scene_check.h"
#include "sim/sim_rig.h"
#include "sim/simulation.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"
#include "tests/support/cli_runner.h"
#include "tests/support/error_of.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"
#include "tests/testbed/scenario_test_util.h"

namespace graspbed::testbed {
namespace {

namespace fs = std::filesystem;
using graspbed::test_support::CliBinary;
using graspbed::test_support::CliResult;
using graspbed::test_support::ErrorOf;
using graspbed::test_support::ReadText;
using graspbed::test_support::RunCli;
using graspbed::test_support::SourcePath;
using graspbed::test_support::TempDir;
using test_support::HeldBoxScenario;
using test_support::Signals;

constexpr int kExitOk = 0;
constexpr int kExitFailed = 1;
constexpr int kExitBadInput = 2;
const double kStepS = sim::PhysicsConfig{}.timestep_s;  // the default physics step [s]
constexpr double kTimeTolS = 1e-9;                      // sums of timesteps
constexpr double kInjectAtS = 0.3;                      // mid-run: the object is held and being lifted
// A run that ends at its fault takes a fraction of a second; without the fix it spun forever. The
// bound only has to tell the two apart on a loaded 2-core machine.
constexpr double kPromptWallS = 20.0;

// HeldBoxScenario with a coarse step and a wrist servo far too stiff for its light palm: valid
// values, unstable physics (MuJoCo warns within 0.2 s: the exploding scene fills the constraint
// buffer at 0.06 s on the table plane; on the former box table "Nan, Inf or huge value in QACC").
std::string UnstableScenario() {
  return R"(duration_s: 1.0
object: {shape: box, size_m: [0.05, 0.05, 0.08], mass_kg: 0.1, friction: 0.7, solref_timeconst_s: 0.02}
hand: {open_gap_m: 0.055, palm_mass_kg: 0.01, wrist_stiffness_n_m: 1.0e+6}
physics: {timestep_s: 0.01}
sensor: {sample_rate_hz: 100}
controller: {name: open_loop, rate_hz: 100}
script:
  - {at_s: 0.04, action: close}
)";
}

nlohmann::json ReadJson(const std::string& path) {
  const std::string text = ReadText(path);
  if (text.empty()) {
    ADD_FAILURE() << "cannot read " << path;
    return nlohmann::json::object();
  }
  return nlohmann::json::parse(text);
}

// ---- the clock at a fault ----------------------------------------------------------------------------

TEST(RunEndsTest, AfterAFaultTheClockAdvancesEveryStepAndThePhysicsStaysFrozen) {
  sim::Simulation simulation(sensor::LoadLayout(SourcePath("sensor/layouts/default_20.yaml")),
                             sim::SceneConfig{});
  simulation.StepUntil(0.05);
  ASSERT_FALSE(simulation.fault().occurred);
  const double fault_time_s = simulation.time_s();
  simulation.mutable_data()->qvel[0] = std::numeric_limits<double>::quiet_NaN();
  simulation.Step();
  ASSERT_TRUE(simulation.fault().occurred);
  EXPECT_NE(std::string(simulation.fault().cause_text()).find("QVEL"), std::string::npos)
      << simulation.fault().cause_text();
  EXPECT_NEAR(simulation.fault().time_s, fault_time_s, kTimeTolS);
  // MuJoCo reset the clock to 0 in that step; the simulation undid it: one step later, not earlier.
  EXPECT_NEAR(simulation.time_s(), fault_time_s + kStepS, kTimeTolS);
  const std::array<double, 3> frozen = simulation.truth().object_position_m;
  for (int i = 1; i <= 10; ++i) {
    simulation.Step();
    EXPECT_NEAR(simulation.time_s(), fault_time_s + (i + 1) * kStepS, kTimeTolS);
  }
  EXPECT_EQ(simulation.truth().object_position_m, frozen);
  // Stepping towards a far time ends at once instead of stepping a dead simulation.
  const double before_s = simulation.time_s();
  simulation.StepUntil(1e3);
  EXPECT_EQ(simulation.time_s(), before_s);
  EXPECT_NEAR(simulation.fault().time_s, fault_time_s, kTimeTolS);
}

// ---- a run with a NaN injected mid-run ----------------------------------------------------------------

TEST(RunEndsTest, ANanInjectedMidRunEndsTheRunAtOnceWithTheFaultNamedAndTheOutputsWritten) {
  const TempDir dir("run_ends");
  const ScenarioConfig config =
      LoadScenario(dir.Write("held.yaml", HeldBoxScenario(2.0, "", "expectations: {not_dropped: true}\n")));
  RunOptions options;
  options.out_dir = dir.Path("out");
  options.write_plots = false;
  int injections = 0;
  // From kInjectAtS on, every step would get a NaN: the run must end at the first one.
  options.before_step = [&injections](sim::SimRig& rig) {
    if (rig.time_s() < kInjectAtS - kTimeTolS) return;
    rig.simulation().mutable_data()->qvel[0] = std::numeric_limits<double>::quiet_NaN();
    ++injections;
  };
  const auto wall_start = std::chrono::steady_clock::now();
  const RunResult result = RunScenario(config, options);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();

  EXPECT_LT(wall_s, kPromptWallS);
  EXPECT_EQ(injections, 1) << "the run went on after the fault";
  EXPECT_TRUE(result.completed);
  EXPECT_FALSE(result.passed);
  const Metrics& m = result.metrics;
  ASSERT_TRUE(m.physics_fault);
  EXPECT_NE(m.physics_fault_cause.find("Nan, Inf or huge value in QVEL"), std::string::npos)
      << m.physics_fault_cause;
  EXPECT_NEAR(m.physics_fault_time_s, kInjectAtS, kStepS + kTimeTolS);
  EXPECT_LE(m.sim_s, m.physics_fault_time_s + kStepS + kTimeTolS);
  EXPECT_TRUE(m.grasped) << "the fault came mid-run, with the object held";
  const ExpectationOutcome& physics = result.outcomes.back();
  EXPECT_EQ(physics.name, "no_physics_fault");
  EXPECT_FALSE(physics.passed);
  EXPECT_EQ(physics.value_text, m.physics_fault_cause);
  EXPECT_NE(SummaryTable(result).find("PHYSICS FAULT at t = 0.3"), std::string::npos) << SummaryTable(result);

  // The outputs up to the fault, final (not INCOMPLETE): the signals end before it.
  EXPECT_FALSE(fs::exists(options.out_dir + "/INCOMPLETE"));
  const Signals signals(options.out_dir + "/signals.csv");
  ASSERT_GT(signals.rows(), 100u);
  EXPECT_LE(signals.At("time_s", signals.rows() - 1), m.physics_fault_time_s + kTimeTolS);
  EXPECT_GE(signals.At("time_s", signals.rows() - 1), m.physics_fault_time_s - 2 * kStepS);
  const nlohmann::json summary = ReadJson(options.out_dir + "/summary.json");
  EXPECT_EQ(summary.at("completed"), true);
  EXPECT_EQ(summary.at("passed"), false);
  EXPECT_EQ(summary.at("physics_fault").at("occurred"), true);
  EXPECT_EQ(summary.at("physics_fault").at("cause"), m.physics_fault_cause);
  EXPECT_NEAR(summary.at("physics_fault").at("time_s").get<double>(), kInjectAtS, kStepS + kTimeTolS);
  EXPECT_TRUE(fs::exists(options.out_dir + "/config.yaml"));
}

// ---- through the CLI: run and suite -----------------------------------------------------------------------

class RunEndsCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (CliBinary().empty()) GTEST_FAIL() << "GRASPBED_BINARY must point at the CLI";
  }
  TempDir dir_{"run_ends_cli"};
};

TEST_F(RunEndsCliTest, AnUnstableRunExitsOneAtItsFaultAndASuiteRunsTheOthers) {
  const std::string unstable = dir_.Write("suite/unstable.yaml", UnstableScenario());
  dir_.Write("suite/held.yaml", HeldBoxScenario(0.5, "", "expectations: {not_dropped: true}\n"));

  const std::string out = dir_.Path("run_out");
  const CliResult run = RunCli("run " + unstable + " --no-plots --out " + out);
  EXPECT_EQ(run.exit_code, kExitFailed) << run.out << run.err;
  EXPECT_NE(run.out.find("PHYSICS FAULT at t = "), std::string::npos) << run.out;
  EXPECT_NE(run.err.find("physics fault at t = "), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("MuJoCo warning: "), std::string::npos) << "the cause is named: " << run.err;
  const nlohmann::json summary = ReadJson(out + "/summary.json");
  EXPECT_EQ(summary.at("physics_fault").at("occurred"), true);
  EXPECT_LT(summary.at("metrics").at("sim_s").get<double>(), 1.0) << "ended at the fault, not at duration_s";
  EXPECT_TRUE(fs::exists(out + "/signals.csv"));
  EXPECT_FALSE(fs::exists(out + "/INCOMPLETE"));

  const std::string suite_out = dir_.Path("suite_out");
  const CliResult suite = RunCli("suite " + dir_.Path("suite") + " -j 2 --no-plots --out " + suite_out);
  EXPECT_EQ(suite.exit_code, kExitFailed) << suite.out << suite.err;
  const nlohmann::json suite_json = ReadJson(suite_out + "/suite.json");
  EXPECT_EQ(suite_json.at("completed"), true);
  EXPECT_EQ(suite_json.at("passed_count"), 1);
  EXPECT_EQ(suite_json.at("failed_count"), 1);
  for (const nlohmann::json& entry : suite_json.at("runs")) {
    SCOPED_TRACE(entry.dump());
    if (entry.at("scenario") == "unstable") {
      EXPECT_EQ(entry.at("passed"), false);
      EXPECT_EQ(entry.at("physics_fault").at("occurred"), true);
    } else {
      EXPECT_EQ(entry.at("passed"), true);
    }
  }
  EXPECT_TRUE(fs::exists(suite_out + "/held/summary.json"));
}

// ---- bodies that start inside each other
// -------------------------------------------------------------------

TEST_F(RunEndsCliTest, ScenesWhoseBodiesStartInsideEachOtherAreRefusedNamingTheKeys) {
  const std::string shipped = SourcePath("scenarios/default.yaml");
  const struct {
    std::string set;
    std::vector<std::string> message;
  } cases[] = {
      // The default wrist is at [0, 0, 0.1546]; 20 mm along the pinch puts the finger into the box.
      {"hand.initial_wrist_position_m=[0.02,0,0.1546]",
       {"the object and the hand overlap by ", "object.size_m = [0.05, 0.05, 0.08]",
        "hand.open_gap_m = auto = 0.065 m", "hand.initial_wrist_position_m = [0.02, 0, 0.1546]"}},
      // A 3 mm high box: the pad's centre cannot come down to it with the fingertip above the table.
      {"object.size_m=[0.05,0.05,0.003]",
       {"object.size_m = [0.05, 0.05, 0.003]: the box: this hand cannot pinch it: its top is 3.0 mm above "
        "the table"}},
      {"object.initial_position_m=[0,0,0.01]",
       {"the object and the table overlap by ", "object.initial_position_m = [0, 0, 0.01]"}},
  };
  int index = 0;
  for (const auto& c : cases) {
    SCOPED_TRACE(c.set);
    const std::string out = dir_.Path("out" + std::to_string(index++));
    const CliResult result = RunCli("run " + shipped + " --no-plots --out " + out + " --set " + c.set);
    EXPECT_EQ(result.exit_code, kExitBadInput) << result.out << result.err;
    EXPECT_NE(result.err.find(shipped + ": scene: "), std::string::npos) << result.err;
    for (const std::string& part : c.message)
      EXPECT_NE(result.err.find(part), std::string::npos) << result.err;
    EXPECT_EQ(result.out, "");
    EXPECT_FALSE(fs::exists(out)) << "a refused scene must not create the output directory";
  }
}

TEST(RunEndsTest, TheOverlapCheckPassesAHandPreShapedJustAroundTheObject) {
  const sensor::Layout layout = sensor::LoadLayout(SourcePath("sensor/layouts/default_20.yaml"));
  for (const sim::HandModel model : {sim::HandModel::kProsthetic, sim::HandModel::kJaw}) {
    sim::SceneConfig scene;
    scene.hand.model = model;
    scene.object.size_m = {0.05, 0.05, 0.08};
    scene.hand.open_gap_m = 0.0505;  // 0.25 mm clearance each side
    SCOPED_TRACE(sim::ToString(model));
    sim::Simulation fits(layout, scene);
    EXPECT_EQ(ErrorOf<std::invalid_argument>([&] { sim::CheckInitialPenetration(fits); }), "(no error)");
  }
}

// The frame ring is sized for the script's largest latency: half a second added mid-run (the ring
// used to hold 0.1 s) delays the frames instead of ending the run with an error.
TEST(RunEndsTest, LatencyAddedMidRunBeyondTheDefaultRingRunsToTheEnd) {
  const TempDir dir("run_ends_latency");
  const test_support::ScenarioRun run = test_support::RunScenarioText(
      dir, "late", HeldBoxScenario(0.8, "  - {at_s: 0.2, action: add_latency, latency_s: 0.5}\n"));
  EXPECT_TRUE(run.result.completed);
  EXPECT_FALSE(run.result.metrics.physics_fault);
  EXPECT_NEAR(run.result.metrics.sim_s, 0.8, kStepS);
  EXPECT_GT(run.result.stale_ticks, 0u) << "0.5 s without a fresh frame must leave the state stale";
}

// ---- values no real scene has
// ---------------------------------------------------------------------------------

TEST(RunEndsTest, ValuesNoRealSceneHasAreRefusedWithFileLineAndKey) {
  const struct {
    std::string yaml;
    std::string message;
  } cases[] = {
      {"object: {mass_kg: 1.0e+308}", "x.yaml:2: object.mass_kg = 1.0e+308: must be <= 10"},
      {"object: {size_m: [0.05, 1.0e+3, 0.08]}", "x.yaml:2: object.size_m[1] = 1.0e+3: must be <= 0.3"},
      {"hand: {motor: {stall_force_n: 1.0e+9}}",
       "x.yaml:2: hand.motor.stall_force_n = 1.0e+9: must be <= 500"},
      {"hand: {wrist_stiffness_n_m: 1.0e+300}",
       "x.yaml:2: hand.wrist_stiffness_n_m = 1.0e+300: must be <= 1e+06"},
      {"physics: {gravity_m_s2: 1.0e+10}", "x.yaml:2: physics.gravity_m_s2 = 1.0e+10: must be <= 100"},
      {"physics: {solver_iterations: 100000}",
       "x.yaml:2: physics.solver_iterations = 100000: must be <= 1000"},
      {"controller: {stale_timeout_s: 1.0e+300}",
       "x.yaml:2: controller.stale_timeout_s = 1.0e+300: must be <= 1"},
      {"controller: {rate_hz: 1.0e+5}", "x.yaml:2: controller.rate_hz = 1.0e+5: must be <= 10000"},
      {"sensor: {sample_rate_hz: 1.0e+5}", "x.yaml:2: sensor.sample_rate_hz = 1.0e+5: must be <= 10000"},
      {"metrics: {stable_window_s: 1.0e+300}",
       "x.yaml:2: metrics.stable_window_s = 1.0e+300: must be <= 3600"},
      {"script:\n  - {at_s: 0.1, action: move, offset_m: [0, 0, 1.0e+300]}",
       "x.yaml:3: script[0].offset_m[2] = 1.0e+300: must be <= 1"},
      {"script:\n  - {at_s: 0.1, action: pull, force_n: [0, 0, 1], ramp_s: 1.0e+300}",
       "x.yaml:3: script[0].ramp_s = 1.0e+300: must be <= 3600"},
      {"script:\n  - {at_s: 0.1, action: add_mass, mass_kg: 50}",
       "x.yaml:3: script[0].mass_kg = 50: must be <= 10"},
      {"script:\n  - {at_s: 0.1, action: add_latency, latency_s: 0.7}\n  - {at_s: 0.2, action: add_latency, "
       "latency_s: 0.7}",
       "x.yaml:4: add_latency at_s = 0.2: sensor.latency_s plus the add_latency actions up to here = 1.4 s: "
       "must be <= 1 s"},
      {"duration_s: 3000\ncontroller: {rate_hz: 2000}\nphysics: {timestep_s: 0.0002}",
       "x.yaml:1: duration_s = 3000: with controller.rate_hz = 2000 the run keeps "},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.yaml);
    // Line 1 is duration_s unless the case sets it.
    const std::string text = (c.yaml.rfind("duration_s", 0) == 0 ? "" : "duration_s: 1.0\n") + c.yaml + "\n";
    const std::string error =
        ErrorOf<std::invalid_argument>([&] { LoadScenarioFromString(text, "x.yaml", {}); });
    EXPECT_NE(error.find(c.message), std::string::npos) << error;
  }
}

}  // namespace
}  // namespace graspbed::testbed
