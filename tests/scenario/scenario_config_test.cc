// Scenario schema: defaults, validation messages (file:line: key = value: reason), --set overrides
// and the resolved config.yaml round trip.
#include "sim/scenario/scenario_config.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

namespace graspbed::scenario {
namespace {

// Loads `text` as scenario "test.yaml" and returns the error message ("" if it loaded).
std::string ErrorOf(const std::string& text, const std::vector<Override>& overrides = {}) {
  try {
    LoadScenarioFromString(text, "test.yaml", overrides);
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "";
}

TEST(ScenarioConfigTest, MinimalFileGetsEveryDefault) {
  const ScenarioConfig config = LoadScenarioFromString("duration_s: 1.5\n", "dir/lift_box.yaml");
  EXPECT_EQ(config.name, "lift_box");
  EXPECT_EQ(config.seed, 1u);
  EXPECT_DOUBLE_EQ(config.duration_s, 1.5);
  EXPECT_EQ(config.controller.name, "open_loop");
  // The controller's declared defaults are filled in, so config.yaml lists them.
  for (const auto& parameter : controller::ControllerParameters("open_loop")) {
    ASSERT_TRUE(config.controller.params.count(parameter.name)) << parameter.name;
    EXPECT_DOUBLE_EQ(config.controller.params.at(parameter.name), parameter.default_value);
  }
  EXPECT_EQ(config.sensor.layout, "default_20");
  EXPECT_DOUBLE_EQ(config.sensor.sample_rate_hz, 1000.0);
  EXPECT_TRUE(config.script.empty());
  EXPECT_TRUE(config.expectations.empty());
}

TEST(ScenarioConfigTest, ShippedDefaultScenarioLoads) {
  const ScenarioConfig config = LoadScenario(std::string(GRASPBED_SOURCE_DIR) + "/scenarios/default.yaml");
  EXPECT_EQ(config.name, "default");
  EXPECT_FALSE(config.script.empty());
  EXPECT_FALSE(config.expectations.empty());
}

TEST(ScenarioConfigTest, EveryShippedScenarioLoadsWithExpectations) {
  int count = 0;
  for (const auto& entry :
       std::filesystem::directory_iterator(std::string(GRASPBED_SOURCE_DIR) + "/scenarios")) {
    if (entry.path().extension() != ".yaml") continue;
    SCOPED_TRACE(entry.path().string());
    const ScenarioConfig config = LoadScenario(entry.path().string());
    EXPECT_EQ(config.name, entry.path().stem().string());
    EXPECT_FALSE(config.expectations.empty());
    EXPECT_FALSE(config.description.empty());
    EXPECT_LE(config.duration_s, 20.0);  // the suite must stay quick (the long static hold is the longest)
    ++count;
  }
  EXPECT_GE(count, 11);
}

TEST(ScenarioConfigTest, ScriptIsSortedByTimeAndActionsKeepTheirParameters) {
  const ScenarioConfig config = LoadScenarioFromString(R"(duration_s: 5
script:
  - {at_s: 2.0, action: add_mass, mass_kg: 0.05, ramp_s: 0.5}
  - {at_s: 0.2, action: close}
  - {at_s: 1.0, action: move, offset_m: [0, 0, 0.03], duration_s: 0.4, profile: linear}
  - {at_s: 3.0, action: shake, frequency_hz: 4, amplitude_m: 0.01, duration_s: 1, axis: [2, 0, 0]}
  - {at_s: 3.5, action: bias, unit: 3, r1_ohm: 20}
)",
                                                       "t.yaml");
  ASSERT_EQ(config.script.size(), 5u);
  EXPECT_EQ(config.script[0].kind, ActionKind::kClose);
  EXPECT_EQ(config.script[1].kind, ActionKind::kMove);
  EXPECT_TRUE(config.script[1].relative);
  EXPECT_DOUBLE_EQ(config.script[1].vector[2], 0.03);
  EXPECT_EQ(config.script[1].profile, Profile::kLinear);
  EXPECT_EQ(config.script[2].kind, ActionKind::kAddMass);
  EXPECT_DOUBLE_EQ(config.script[2].ramp_s, 0.5);
  EXPECT_DOUBLE_EQ(config.script[3].vector[0], 1.0);  // axis normalised
  EXPECT_EQ(config.script[4].unit, 3);
  EXPECT_DOUBLE_EQ(config.script[4].r2_bias_ohm, 0.0);
  EXPECT_EQ(config.script[2].line, 3);
}

TEST(ScenarioConfigTest, UnknownTopLevelKeyNamesLineAndValidKeys) {
  const std::string error = ErrorOf("duration_s: 1\nobjekt:\n  mass_kg: 0.2\n");
  EXPECT_NE(error.find("test.yaml:2: objekt: unknown key; valid keys: "), std::string::npos) << error;
  EXPECT_NE(error.find("object"), std::string::npos) << error;
  EXPECT_NE(error.find("expectations"), std::string::npos) << error;
}

// The signals a run keeps are reserved before it starts; a run whose rows could not fit in the
// bound (2 GB) is refused at load time, naming duration_s. The bound counts every column a row can
// have (kSignalBoundFixedColumns + the diagnostic channels + kSignalBoundColumnsPerUnit per unit).
TEST(ScenarioConfigTest, ARunTooLongForItsSignalsIsRefusedNamingDuration) {
  const double row_bytes =
      8.0 * static_cast<double>(kSignalBoundFixedColumns + controller::kMaxDiagnosticChannels +
                                20 * kSignalBoundColumnsPerUnit);  // default_20
  const double longest_s = 2e9 / (row_bytes * 1000.0);             // 1 kHz ticks, one per 1 ms step
  EXPECT_EQ(ErrorOf("duration_s: " + std::to_string(std::floor(longest_s)) + "\n"), "");
  const std::string error = ErrorOf("duration_s: " + std::to_string(std::ceil(longest_s)) + "\n");
  EXPECT_NE(error.find("duration_s"), std::string::npos) << error;
  EXPECT_NE(error.find("MB of signals (at most 2000 MB)"), std::string::npos) << error;
}

TEST(ScenarioConfigTest, WrongTypeAndOutOfRangeNameKeyAndValue) {
  EXPECT_NE(
      ErrorOf("object:\n  mass_kg: heavy\n").find("test.yaml:2: object.mass_kg = heavy: expected a number"),
      std::string::npos);
  EXPECT_NE(ErrorOf("object:\n  shape: box\n  mass_kg: -0.1\n")
                .find("test.yaml:3: object.mass_kg = -0.1: must be >= 0.001"),
            std::string::npos);
  EXPECT_NE(ErrorOf("duration_s: 0\n").find("test.yaml:1: duration_s = 0: must be > 0"), std::string::npos);
  EXPECT_NE(ErrorOf("seed: 1.5\n").find("test.yaml:1: seed = 1.5: expected a whole number"),
            std::string::npos);
  EXPECT_NE(ErrorOf("sensor:\n  strain_model:\n    noise_ohm: -2\n")
                .find("test.yaml:3: sensor.strain_model.noise_ohm = -2: must be >= 0"),
            std::string::npos);
}

TEST(ScenarioConfigTest, UnknownActionListsValidActions) {
  const std::string error =
      ErrorOf("duration_s: 2\nscript:\n  - {at_s: 0.1, action: close}\n  - {at_s: 0.5, action: jump}\n");
  EXPECT_NE(
      error.find("test.yaml:4: script[1].action = jump: unknown name; valid names: close, open, idle, move, "
                 "lift, shake, add_mass, pull, set_friction, dead_unit"),
      std::string::npos)
      << error;
}

TEST(ScenarioConfigTest, ActionParametersAreCheckedPerAction) {
  // A key that belongs to another action.
  std::string error = ErrorOf("script:\n  - at_s: 0.1\n    action: close\n    height_m: 0.1\n");
  EXPECT_NE(error.find("test.yaml:4: script[0].height_m: unknown key; valid keys: action, at_s"),
            std::string::npos)
      << error;
  // Missing required parameter.
  error = ErrorOf("script:\n  - {at_s: 0.1, action: lift}\n");
  EXPECT_NE(error.find("script[0].height_m = null: missing required key"), std::string::npos) << error;
  // Unit index beyond the layout (default layout has 20 units).
  error = ErrorOf("script:\n  - {at_s: 0.1, action: dead_unit, unit: 20}\n");
  EXPECT_NE(error.find("test.yaml:2: script[0].unit = 20: must be <= 19"), std::string::npos) << error;
  // Action after the end of the run.
  error = ErrorOf("duration_s: 1\nscript:\n  - {at_s: 1.5, action: open}\n");
  EXPECT_NE(error.find("test.yaml:3: script[0].at_s = 1.5: must be <= 1"), std::string::npos) << error;
  // move needs exactly one of position_m / offset_m.
  error = ErrorOf("script:\n  - {at_s: 0.1, action: move, position_m: [0, 0, 0.1], offset_m: [0, 0, 0.1]}\n");
  EXPECT_NE(error.find("test.yaml:2: script[0]: move needs exactly one of position_m"), std::string::npos)
      << error;
  // Vector of the wrong length.
  error = ErrorOf("script:\n  - {at_s: 0.1, action: pull, force_n: [0, 1]}\n");
  EXPECT_NE(error.find("script[0].force_n = [...]: expected 3 numbers, got 2"), std::string::npos) << error;
  // A noise burst needs noise to scale.
  error = ErrorOf("script:\n  - {at_s: 0.1, action: noise_burst, duration_s: 0.1}\n");
  EXPECT_NE(error.find("noise_burst scales sensor.strain_model.noise_ohm"), std::string::npos) << error;
}

TEST(ScenarioConfigTest, ControllerNameAndParametersAreValidated) {
  std::string error = ErrorOf("controller:\n  name: pid\n");
  EXPECT_NE(error.find("test.yaml:2: controller.name = pid: unknown name; valid names: "), std::string::npos)
      << error;
  EXPECT_NE(error.find("open_loop"), std::string::npos) << error;
  error = ErrorOf("controller:\n  name: open_loop\n  params:\n    gain: 3\n");
  EXPECT_NE(
      error.find("test.yaml:4: controller.params.gain = 3: controller 'open_loop' has no such parameter; "
                 "valid parameters: close_effort"),
      std::string::npos)
      << error;
  error = ErrorOf("controller:\n  params:\n    close_effort: 2\n");
  EXPECT_NE(error.find("test.yaml:3: controller.params.close_effort = 2: must be <= 1"), std::string::npos)
      << error;
}

TEST(ScenarioConfigTest, ExpectationsAreValidated) {
  std::string error = ErrorOf("expectations:\n  max_slip: 2\n");
  EXPECT_NE(error.find("test.yaml:2: expectations.max_slip: unknown key; valid keys: "), std::string::npos)
      << error;
  EXPECT_NE(error.find("max_slip_mm"), std::string::npos) << error;
  error = ErrorOf("expectations:\n  not_crushed: true\n");
  EXPECT_NE(error.find("test.yaml:2: expectations.not_crushed = true: needs object.crush_limit_n > 0"),
            std::string::npos)
      << error;
  error = ErrorOf("expectations:\n  not_dropped: maybe\n");
  EXPECT_NE(error.find("expectations.not_dropped = maybe: expected true or false"), std::string::npos)
      << error;
}

TEST(ScenarioConfigTest, UnknownLayoutIsRefused) {
  const std::string error = ErrorOf("sensor:\n  layout: no_such_layout\n");
  EXPECT_NE(error.find("test.yaml:2: sensor.layout = no_such_layout: no such layout"), std::string::npos)
      << error;
}

TEST(ScenarioConfigTest, OverridesUseDottedKeysAndAreValidatedLikeTheFile) {
  const std::string text =
      "duration_s: 2\nobject:\n  mass_kg: 0.1\nscript:\n  - {at_s: 0.2, action: close}\n";
  const ScenarioConfig config = LoadScenarioFromString(text, "t.yaml",
                                                       {{"object.mass_kg", "0.3"},
                                                        {"object.friction", "0.4"},
                                                        {"script[0].at_s", "0.5"},
                                                        {"seed", "7"},
                                                        {"sensor.strain_model.noise_ohm", "2"},
                                                        {"object.size_m", "[0.04, 0.04, 0.06]"}});
  EXPECT_DOUBLE_EQ(config.scene.object.mass_kg, 0.3);
  EXPECT_DOUBLE_EQ(config.scene.object.friction, 0.4);
  EXPECT_DOUBLE_EQ(config.script[0].at_s, 0.5);
  EXPECT_EQ(config.seed, 7u);
  EXPECT_DOUBLE_EQ(config.sensor.strain_model.noise_ohm, 2.0);
  EXPECT_DOUBLE_EQ(config.scene.object.size_m[2], 0.06);

  std::string error = ErrorOf(text, {{"object.mass_kg", "-1"}});
  EXPECT_NE(error.find("--set object.mass_kg=-1: "), std::string::npos) << error;
  EXPECT_NE(error.find("object.mass_kg = -1: must be >= 0.001"), std::string::npos) << error;
  error = ErrorOf(text, {{"object.mas", "1"}});
  EXPECT_NE(error.find("--set object.mas=1: "), std::string::npos) << error;
  EXPECT_NE(error.find("object.mas: unknown key"), std::string::npos) << error;
  error = ErrorOf(text, {{"script[3].at_s", "1"}});
  EXPECT_NE(error.find("index 3 out of range"), std::string::npos) << error;
  EXPECT_THROW(ParseOverride("object.mass_kg"), std::invalid_argument);
  EXPECT_EQ(ParseOverride("a.b=c=d").value, "c=d");
}

TEST(ScenarioConfigTest, OverridesThatBelongTogetherLoadInAnyOrderAndMayCompleteTheFile) {
  const std::string text = "duration_s: 1\nscript:\n  - {at_s: 0.2, action: close}\n";
  // The backend and its port, either order.
  for (const std::vector<Override>& overrides :
       {std::vector<Override>{{"backend", "serial"}, {"serial.port", "/dev/ttyACM0"}},
        std::vector<Override>{{"serial.port", "/dev/ttyACM0"}, {"backend", "serial"}}}) {
    const ScenarioConfig config = LoadScenarioFromString(text, "t.yaml", overrides);
    EXPECT_EQ(config.backend, Backend::kSerial);
    EXPECT_EQ(config.serial.port, "/dev/ttyACM0");
  }
  // A file naming the serial backend without its port, given it as `graspbed run --port` does.
  const std::string serial_file = "backend: serial\n" + text;
  EXPECT_EQ(LoadScenarioFromString(serial_file, "t.yaml", {{"serial.port", "/dev/ttyACM0"}}).serial.port,
            "/dev/ttyACM0");
  // Without it, the file's own error, at its line; an error an override brings in names that one,
  // even when later overrides follow.
  std::string error = ErrorOf(serial_file);
  EXPECT_NE(error.find("test.yaml:1: backend = serial: serial needs a port"), std::string::npos) << error;
  error = ErrorOf(serial_file, {{"seed", "3"}});
  EXPECT_EQ(error.find("--set"), std::string::npos) << error;
  EXPECT_NE(error.find("test.yaml:1: backend = serial"), std::string::npos) << error;
  error = ErrorOf(text, {{"object.mass_kg", "-1"}, {"seed", "3"}});
  EXPECT_NE(error.find("--set object.mass_kg=-1: "), std::string::npos) << error;
  // An override that cannot be applied names itself, once.
  error = ErrorOf(text, {{"seed", "3"}, {"script[9].at_s", "1"}});
  EXPECT_NE(error.find("index 9 out of range"), std::string::npos) << error;
  EXPECT_EQ(error.find("--set"), error.rfind("--set")) << error;
}

TEST(ScenarioConfigTest, ASensorFasterThanTheSimulatedClockIsRefusedNotSilentlyLowered) {
  const std::string text = "duration_s: 1\n";
  // The clock moves at physics steps (1 ms) and control ticks (1 kHz): a 1.5 kHz sensor cannot run.
  std::string error = ErrorOf(text, {{"sensor.sample_rate_hz", "1500"}});
  EXPECT_NE(error.find("sensor.sample_rate_hz = 1500: must be <= the larger of 1 / physics.timestep_s and "
                       "controller.rate_hz = 1000 Hz"),
            std::string::npos)
      << error;
  // A faster control loop ticks between physics steps, and the sensor samples there; so does a
  // shorter step; the serial backend has no physics step.
  EXPECT_EQ(ErrorOf(text, {{"controller.rate_hz", "2000"}}), "");
  EXPECT_EQ(ErrorOf(text, {{"controller.rate_hz", "2000"}, {"sensor.sample_rate_hz", "1500"}}), "");
  EXPECT_EQ(ErrorOf(text, {{"physics.timestep_s", "0.0005"}, {"sensor.sample_rate_hz", "1500"}}), "");
  EXPECT_EQ(
      ErrorOf(text, {{"sensor.sample_rate_hz", "1500"}, {"backend", "serial"}, {"serial.port", "/dev/x"}}),
      "");
}

TEST(ScenarioConfigTest, ChangingTheControllerDropsTheOldControllersParameters) {
  const std::string text = "controller:\n  name: open_loop\n  params:\n    close_effort: 0.7\n";
  const auto names = controller::ControllerNames();
  const ScenarioConfig same = LoadScenarioFromString(text, "t.yaml", {{"controller.name", "open_loop"}});
  EXPECT_DOUBLE_EQ(same.controller.params.at("close_effort"), 0.7);
  for (const std::string& name : names) {
    if (name == "open_loop") continue;
    const ScenarioConfig other = LoadScenarioFromString(text, "t.yaml", {{"controller.name", name}});
    EXPECT_EQ(other.controller.name, name);
  }
}

TEST(ScenarioConfigTest, ResolvedYamlLoadsBackToTheSameConfiguration) {
  const ScenarioConfig config = LoadScenarioFromString(R"(name: round_trip
description: "every action once"
seed: 42
duration_s: 6
object: {shape: cylinder, size_m: [0.04, 0, 0.1], mass_kg: 0.15, friction: 0.45, crush_limit_n: 8}
sensor: {latency_s: 0.002, strain_model: {noise_ohm: 1.5, dead_units: [2]}}
controller: {grip_ceiling_n: 6}
script:
  - {at_s: 0.1, action: close}
  - {at_s: 0.5, action: lift, height_m: 0.04}
  - {at_s: 1.0, action: move, position_m: [0.01, 0, 0.2], duration_s: 0.3}
  - {at_s: 1.5, action: shake, frequency_hz: 3, amplitude_m: 0.005, duration_s: 0.5}
  - {at_s: 2.0, action: add_mass, mass_kg: 0.1, ramp_s: 1}
  - {at_s: 2.2, action: pull, force_n: [0, 0, -1], ramp_s: 0.5, duration_s: 0.2}
  - {at_s: 2.5, action: set_friction, friction: 0.3}
  - {at_s: 2.6, action: dead_unit, unit: 4}
  - {at_s: 2.7, action: short_unit, unit: 5}
  - {at_s: 2.8, action: restore_unit, unit: 5}
  - {at_s: 2.9, action: bias, unit: 6, r1_ohm: 10, r2_ohm: -5}
  - {at_s: 3.0, action: noise_burst, scale: 5, duration_s: 0.2}
  - {at_s: 3.1, action: drop_frames, duration_s: 0.05, probability: 0.5}
  - {at_s: 3.2, action: add_latency, latency_s: 0.003}
  - {at_s: 4.0, action: open}
  - {at_s: 4.5, action: idle}
expectations: {not_dropped: true, max_slip_mm: 1, max_peak_grip_n: 7, not_crushed: true,
               slip_detected_within_ms: 30, max_estimation_error_n: 0.5, stable_within_s: 0.8,
               max_false_slip_per_min: 2}
metrics: {slip_speed_m_s: 0.003}
)",
                                                       "rt.yaml");
  const std::string first = EmitScenarioYaml(config);
  const ScenarioConfig again = LoadScenarioFromString(first, "config.yaml");
  const std::string second = EmitScenarioYaml(again);
  EXPECT_EQ(first, second);
  EXPECT_EQ(again.script.size(), 16u);
  EXPECT_EQ(again.seed, 42u);
  EXPECT_DOUBLE_EQ(again.scene.object.crush_limit_n, 8.0);
  EXPECT_DOUBLE_EQ(*again.expectations.slip_detected_within_ms, 30.0);
  EXPECT_DOUBLE_EQ(again.metrics.slip_speed_m_s, 0.003);
  EXPECT_EQ(again.sensor.strain_model.dead_units, std::vector<int>{2});
  EXPECT_NE(first.find("close_effort"), std::string::npos);  // controller defaults written out
}

}  // namespace
}  // namespace graspbed::scenario

namespace graspbed::scenario {
namespace {

TEST(ScenarioValidationTest, MoreBadInputNamesFileLineKeyAndValue) {
  const struct {
    const char* text;
    const char* message;
  } cases[] = {
      {"duration_s: 1\nobject: [1, 2\n", "test.yaml:3: YAML syntax error"},
      {"- 1\n- 2\n", "test.yaml:1: expected a mapping of keys at the top level"},
      {"script:\n  - {at_s: soon, action: close}\n", "test.yaml:2: script[0].at_s = soon: expected a number"},
      {"script:\n  - {at_s: -0.1, action: close}\n", "test.yaml:2: script[0].at_s = -0.1: must be >= 0"},
      {"script:\n  - {action: close}\n", "test.yaml:2: script[0].at_s = null: missing required key"},
      {"script: close\n", "test.yaml:1: script"},
      {"script:\n  - {at_s: 0.1, action: lift, height_m: 0.1, profile: smooth}\n",
       "test.yaml:2: script[0].profile = smooth: unknown name; valid names: minimum_jerk, linear"},
      {"script:\n  - {at_s: 0.1, action: lift, height_m: 2}\n",
       "test.yaml:2: script[0].height_m = 2: must be <= 1"},
      {"script:\n  - {at_s: 0.1, action: shake, frequency_hz: 4, amplitude_m: 0.01, duration_s: 1, axis: [0, "
       "0, 0]}\n",
       "test.yaml:2: script[0].axis = [...]: must not be the zero vector"},
      {"script:\n  - {at_s: 0.1, action: shake, frequency_hz: 0, amplitude_m: 0.01, duration_s: 1}\n",
       "test.yaml:2: script[0].frequency_hz = 0: must be > 0"},
      {"script:\n  - {at_s: 0.1, action: shake, frequency_hz: 4, amplitude_m: 0.01, duration_s: 1, ramp_s: "
       "0.6}\n",
       "test.yaml:2: script[0].ramp_s = 0.6: must be <= duration_s / 2"},
      {"script:\n  - {at_s: 0.1, action: add_mass, mass_kg: 0}\n",
       "test.yaml:2: script[0].mass_kg = 0: must not be 0"},
      {"script:\n  - {at_s: 0.1, action: add_mass, mass_kg: 0.1, ramp_s: -1}\n",
       "test.yaml:2: script[0].ramp_s = -1: must be >= 0"},
      {"script:\n  - {at_s: 0.1, action: pull, force_n: [0, 0, 2000]}\n",
       "test.yaml:2: script[0].force_n = [...]: each component must be within +-1000 N"},
      {"script:\n  - {at_s: 0.1, action: set_friction, friction: 0}\n",
       "test.yaml:2: script[0].friction = 0: must be > 0"},
      {"script:\n  - {at_s: 0.1, action: bias, unit: 2, r1_ohm: 1e6}\n",
       "test.yaml:2: script[0].r1_ohm = 1e6: must be <= 100000"},
      {"script:\n  - {at_s: 0.1, action: drop_frames, duration_s: 0.1, probability: 1.5}\n",
       "test.yaml:2: script[0].probability = 1.5: must be <= 1"},
      {"script:\n  - {at_s: 0.1, action: add_latency, latency_s: 2}\n",
       "test.yaml:2: script[0].latency_s = 2: must be <= 1"},
      {"script:\n  - {at_s: 0.1, action: dead_unit, unit: 1.5}\n",
       "test.yaml:2: script[0].unit = 1.5: expected a whole number"},
      {"sensor: {layout: paper_3x3}\nscript:\n  - {at_s: 0.1, action: dead_unit, unit: 9}\n",
       "test.yaml:3: script[0].unit = 9: must be <= 8"},
      {"sensor:\n  sample_rate_hz: 0\n", "test.yaml:2: sensor.sample_rate_hz = 0: must be >= 1"},
      // The blamed key is not in the file: no line to point at, the value marked as a default.
      {"sensor:\n  sample_rate_hz: 10\n",
       "test.yaml: controller.stale_timeout_s = 0.02 (default): must be >= one sensor period"},
      {"metrics:\n  creep_speed_m_s: 0.01\n",
       "test.yaml:2: metrics.creep_speed_m_s = 0.01: must be <= slip_speed_m_s (default 0.002)"},
      {"metrics:\n  creep_speed_m_s: 0.01\n  slip_speed_m_s: 0.005\n",
       "test.yaml:3: metrics.slip_speed_m_s = 0.005: must be >= creep_speed_m_s (0.01)"},
      {"expectations:\n  max_slip_mm: -1\n", "test.yaml:2: expectations.max_slip_mm = -1: must be >= 0"},
      {"expectations:\n  max_peak_grip_n: 0\n", "test.yaml:2: expectations.max_peak_grip_n = 0: must be > 0"},
      {"seed: -3\n", "test.yaml:1: seed = -3: must be >= 0"},
      {"duration_s: 4000\n", "test.yaml:1: duration_s = 4000: must be <= 3600"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.text);
    std::string error;
    try {
      LoadScenarioFromString(c.text, "test.yaml");
    } catch (const std::invalid_argument& e) {
      error = e.what();
    }
    EXPECT_NE(error.find(c.message), std::string::npos) << error;
  }
}

TEST(ScenarioConfigTest, ControllerCrossFieldChecksNameTheParameterAndLine) {
  const std::string error =
      ErrorOf("controller:\n  name: grip_slip\n  params:\n    safety_margin: 2\n    min_grip_n: 12\n");
  EXPECT_NE(error.find("test.yaml:5: controller.params.min_grip_n = 12"), std::string::npos) << error;
  EXPECT_NE(error.find("must not exceed max_grip_n"), std::string::npos) << error;
  EXPECT_EQ(ErrorOf("controller:\n  name: grip_slip\n  params: {min_grip_n: 12, max_grip_n: 20}\n"), "");
}

TEST(ScenarioConfigTest, FeaSensitivitiesAndExplicitKnAreRefusedTogether) {
  const std::string error =
      ErrorOf("sensor:\n  sensitivities: fea\n  strain_model:\n    noise_ohm: 1\n    kt_per_n: 2e-4\n");
  EXPECT_NE(error.find("test.yaml:5: sensor.strain_model.kt_per_n = 2e-4: set by the FEA"), std::string::npos)
      << error;
  // The resolved file of an FEA scenario carries the derived values only as a comment, so it loads.
  const ScenarioConfig config = LoadScenarioFromString("sensor: {sensitivities: fea}\n", "t.yaml");
  const ScenarioConfig again = LoadScenarioFromString(EmitScenarioYaml(config), "resolved.yaml");
  EXPECT_DOUBLE_EQ(again.sensor.strain_model.nominal.kt_per_n, config.sensor.strain_model.nominal.kt_per_n);
}

}  // namespace
}  // namespace graspbed::scenario
