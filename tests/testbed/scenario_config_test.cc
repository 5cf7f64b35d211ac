// Scenario schema: defaults, validation messages (file:line: key = value: reason), --set overrides
// and the resolved config.yaml round trip.
#include "testbed/scenario_config.h"

#include <gmock/gmock.h>
#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace graspbed::testbed {
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

TEST(ScenarioConfigTest, APathTheFileSystemRefusesIsBadInputAtItsKey) {
  // A file name over NAME_MAX (255 bytes): std::filesystem::exists throws for it ("File name too
  // long"), which the loader once let through as a failure (exit 1) instead of bad input (exit 2).
  // Found by fuzz/scenario_fuzz.cc.
  const std::string long_name(300, 'x');
  std::string error = ErrorOf("sensor:\n  layout: " + long_name + "\n");
  EXPECT_NE(error.find("test.yaml:2: sensor.layout"), std::string::npos) << error;
  EXPECT_NE(error.find("no such layout"), std::string::npos) << error;
  error = ErrorOf("sensor:\n  layout: " + long_name + ".yaml\n");
  EXPECT_NE(error.find("no such layout"), std::string::npos) << error;
  error = ErrorOf("sensor:\n  sensitivities: fea\n  fea_config: " + long_name + ".yaml\n");
  EXPECT_NE(error.find("test.yaml:3: sensor.fea_config"), std::string::npos) << error;
  EXPECT_NE(error.find("no such file"), std::string::npos) << error;
  error = ErrorOf("controller:\n  plugin: ./" + long_name + ".so\n");
  EXPECT_NE(error.find("test.yaml:2: controller.plugin"), std::string::npos) << error;
  EXPECT_NE(error.find("File name too long"), std::string::npos) << error;
  error = ErrorOf("duration_s: 1\n", {{"controller.name", "plugin:" + long_name}});
  EXPECT_NE(error.find("--set controller.name=plugin:"), std::string::npos) << error;
  EXPECT_NE(error.find("controller.name"), std::string::npos) << error;
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

// ---- the resolved config.yaml, field by field --------------------------------------------------------
// Comparing two emitted texts cannot see a field the emitter drops (it is dropped both times); these
// compare the loaded structs member by member instead. A member added to any of them needs a line here.

// Equal, NaN included: an automatic pre-shape, wrist position or opposition is NaN on both sides.
bool SameValue(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }
template <typename T>
bool SameValue(const T& a, const T& b) {
  return a == b;
}
template <typename T, size_t N>
bool SameValue(const std::array<T, N>& a, const std::array<T, N>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), [](const T& x, const T& y) { return SameValue(x, y); });
}
template <typename T>
bool SameValue(const std::optional<T>& a, const std::optional<T>& b) {
  return a.has_value() == b.has_value() && (!a.has_value() || SameValue(*a, *b));
}

// Calls field(key, a.member, b.member) for every member of an Action but `line` (where it stands in
// its file, not part of the configuration).
template <typename Fn>
void ForEachActionField(const Action& a, const Action& b, Fn&& field) {
  field("at_s", a.at_s, b.at_s);
  field("kind", a.kind, b.kind);
  field("after", a.after, b.after);
  field("delay_s", a.delay_s, b.delay_s);
  field("timeout_s", a.timeout_s, b.timeout_s);
  field("vector", a.vector, b.vector);
  field("relative", a.relative, b.relative);
  field("height_m", a.height_m, b.height_m);
  field("duration_s", a.duration_s, b.duration_s);
  field("ramp_s", a.ramp_s, b.ramp_s);
  field("profile", a.profile, b.profile);
  field("mass_kg", a.mass_kg, b.mass_kg);
  field("friction", a.friction, b.friction);
  field("frequency_hz", a.frequency_hz, b.frequency_hz);
  field("amplitude_m", a.amplitude_m, b.amplitude_m);
  field("unit", a.unit, b.unit);
  field("r1_bias_ohm", a.r1_bias_ohm, b.r1_bias_ohm);
  field("r2_bias_ohm", a.r2_bias_ohm, b.r2_bias_ohm);
  field("noise_scale", a.noise_scale, b.noise_scale);
  field("noise_ohm", a.noise_ohm, b.noise_ohm);
  field("probability", a.probability, b.probability);
  field("latency_s", a.latency_s, b.latency_s);
}

// Calls field(key, a.member, b.member) for every member of every struct a ScenarioConfig holds but
// its script (ForEachActionField) and source_file (where it was loaded from).
template <typename Fn>
void ForEachConfigField(const ScenarioConfig& a, const ScenarioConfig& b, Fn&& field) {
  field("name", a.name, b.name);
  field("description", a.description, b.description);
  field("seed", a.seed, b.seed);
  field("duration_s", a.duration_s, b.duration_s);
  field("backend", a.backend, b.backend);
  field("log", a.log, b.log);
  const hardware::HardwareConfig& as = a.serial;
  const hardware::HardwareConfig& bs = b.serial;
  field("serial.port", as.port, bs.port);
  field("serial.motor_port", as.motor_port, bs.motor_port);
  field("serial.baud", as.baud, bs.baud);
  field("serial.hello_timeout_s", as.hello_timeout_s, bs.hello_timeout_s);
  field("serial.stale_timeout_s", as.stale_timeout_s, bs.stale_timeout_s);
  field("serial.disconnect_timeout_s", as.disconnect_timeout_s, bs.disconnect_timeout_s);
  field("serial.reconnect_backoff_s", as.reconnect_backoff_s, bs.reconnect_backoff_s);
  field("serial.reconnect_backoff_max_s", as.reconnect_backoff_max_s, bs.reconnect_backoff_max_s);
  field("serial.poll_interval_s", as.poll_interval_s, bs.poll_interval_s);
  field("serial.write_timeout_s", as.write_timeout_s, bs.write_timeout_s);

  const sim::ObjectConfig& ao = a.scene.object;
  const sim::ObjectConfig& bo = b.scene.object;
  field("object.shape", ao.shape, bo.shape);
  field("object.size_m", ao.size_m, bo.size_m);
  field("object.mass_kg", ao.mass_kg, bo.mass_kg);
  field("object.friction", ao.friction, bo.friction);
  field("object.torsional_friction", ao.torsional_friction, bo.torsional_friction);
  field("object.solref_timeconst_s", ao.solref_timeconst_s, bo.solref_timeconst_s);
  field("object.solref_dampratio", ao.solref_dampratio, bo.solref_dampratio);
  field("object.solimp", ao.solimp, bo.solimp);
  field("object.initial_position_m", ao.initial_position_m, bo.initial_position_m);
  field("object.initial_yaw_rad", ao.initial_yaw_rad, bo.initial_yaw_rad);
  field("object.crush_limit_n", ao.crush_limit_n, bo.crush_limit_n);
  const sim::HandConfig& ah = a.scene.hand;
  const sim::HandConfig& bh = b.scene.hand;
  field("hand.model", ah.model, bh.model);
  field("hand.grasp", ah.grasp, bh.grasp);
  field("hand.open_gap_m", ah.open_gap_m, bh.open_gap_m);
  field("hand.preshape_clearance_m", ah.preshape_clearance_m, bh.preshape_clearance_m);
  field("hand.palm_mass_kg", ah.palm_mass_kg, bh.palm_mass_kg);
  field("hand.digit_mass_kg", ah.digit_mass_kg, bh.digit_mass_kg);
  field("hand.friction", ah.friction, bh.friction);
  field("hand.contact_patch_radius_m", ah.contact_patch_radius_m, bh.contact_patch_radius_m);
  field("hand.initial_wrist_position_m", ah.initial_wrist_position_m, bh.initial_wrist_position_m);
  field("hand.wrist_stiffness_n_m", ah.wrist_stiffness_n_m, bh.wrist_stiffness_n_m);
  field("hand.wrist_damping_n_s_m", ah.wrist_damping_n_s_m, bh.wrist_damping_n_s_m);
  field("hand.motor.stall_force_n", ah.motor.stall_force_n, bh.motor.stall_force_n);
  field("hand.motor.no_load_speed_m_s", ah.motor.no_load_speed_m_s, bh.motor.no_load_speed_m_s);
  field("hand.motor.armature_kg", ah.motor.armature_kg, bh.motor.armature_kg);
  field("hand.motor.damping_n_s_m", ah.motor.damping_n_s_m, bh.motor.damping_n_s_m);
  field("hand.finger.proximal_length_m", ah.finger.proximal_length_m, bh.finger.proximal_length_m);
  field("hand.finger.middle_length_m", ah.finger.middle_length_m, bh.finger.middle_length_m);
  field("hand.finger.pip_mcp_ratio", ah.finger.pip_mcp_ratio, bh.finger.pip_mcp_ratio);
  field("hand.finger.dip_flexion_rad", ah.finger.dip_flexion_rad, bh.finger.dip_flexion_rad);
  field("hand.finger.mcp_rest_angle_rad", ah.finger.mcp_rest_angle_rad, bh.finger.mcp_rest_angle_rad);
  field("hand.thumb.proximal_length_m", ah.thumb.proximal_length_m, bh.thumb.proximal_length_m);
  field("hand.thumb.distal_length_m", ah.thumb.distal_length_m, bh.thumb.distal_length_m);
  field("hand.thumb.tip_radius_m", ah.thumb.tip_radius_m, bh.thumb.tip_radius_m);
  field("hand.thumb.ip_flexion_rad", ah.thumb.ip_flexion_rad, bh.thumb.ip_flexion_rad);
  field("hand.thumb.opposition_rad", ah.thumb.opposition_rad, bh.thumb.opposition_rad);
  const sim::DigitMotorConfig& ad = ah.digit_motor;
  const sim::DigitMotorConfig& bd = bh.digit_motor;
  field("hand.digit_motor.stall_pinch_force_n", ad.stall_pinch_force_n, bd.stall_pinch_force_n);
  field("hand.digit_motor.no_load_speed_rad_s", ad.no_load_speed_rad_s, bd.no_load_speed_rad_s);
  field("hand.digit_motor.armature_kg_m2", ad.armature_kg_m2, bd.armature_kg_m2);
  field("hand.digit_motor.damping_n_m_s", ad.damping_n_m_s, bd.damping_n_m_s);
  field("hand.digit_motor.wrap_thumb_share", ad.wrap_thumb_share, bd.wrap_thumb_share);
  const sim::PhysicsConfig& ap = a.scene.physics;
  const sim::PhysicsConfig& bp = b.scene.physics;
  field("physics.timestep_s", ap.timestep_s, bp.timestep_s);
  field("physics.elliptic_cones", ap.elliptic_cones, bp.elliptic_cones);
  field("physics.impratio", ap.impratio, bp.impratio);
  field("physics.noslip_iterations", ap.noslip_iterations, bp.noslip_iterations);
  field("physics.solver_iterations", ap.solver_iterations, bp.solver_iterations);
  field("physics.tolerance", ap.tolerance, bp.tolerance);
  field("physics.condim", ap.condim, bp.condim);
  field("physics.gravity_m_s2", ap.gravity_m_s2, bp.gravity_m_s2);
  field("physics.table", ap.table, bp.table);
  field("physics.contact_pairs", ap.contact_pairs, bp.contact_pairs);

  const SensorOptions& an = a.sensor;
  const SensorOptions& bn = b.sensor;
  field("sensor.layout", an.layout, bn.layout);
  field("sensor.sample_rate_hz", an.sample_rate_hz, bn.sample_rate_hz);
  field("sensor.latency_s", an.latency_s, bn.latency_s);
  field("sensor.drop_probability", an.drop_probability, bn.drop_probability);
  field("sensor.sensitivities", an.sensitivities, bn.sensitivities);
  field("sensor.fea_config", an.fea_config, bn.fea_config);
  field("sensor.profile", an.profile, bn.profile);
  const sensor::StrainModelConfig& am = an.strain_model;
  const sensor::StrainModelConfig& bm = bn.strain_model;
  field("strain_model.r0_ohm", am.nominal.r0_ohm, bm.nominal.r0_ohm);
  field("strain_model.gauge_factor", am.nominal.gauge_factor, bm.nominal.gauge_factor);
  field("strain_model.kn_per_n", am.nominal.kn_per_n, bm.nominal.kn_per_n);
  field("strain_model.kt_per_n", am.nominal.kt_per_n, bm.nominal.kt_per_n);
  field("strain_model.rated_force_n", am.nominal.rated_force_n, bm.nominal.rated_force_n);
  field("strain_model.r0_spread_fraction", am.r0_spread_fraction, bm.r0_spread_fraction);
  field("strain_model.sensitivity_spread_fraction", am.sensitivity_spread_fraction,
        bm.sensitivity_spread_fraction);
  field("strain_model.noise_ohm", am.noise_ohm, bm.noise_ohm);
  field("strain_model.adc_bits", am.adc_bits, bm.adc_bits);
  field("strain_model.adc_full_scale_ohm", am.adc_full_scale_ohm, bm.adc_full_scale_ohm);
  field("strain_model.adc_min_ohm", am.adc_min_ohm, bm.adc_min_ohm);
  field("strain_model.temperature_coefficient_per_k", am.temperature_coefficient_per_k,
        bm.temperature_coefficient_per_k);
  field("strain_model.temperature_offset_k", am.temperature_offset_k, bm.temperature_offset_k);
  field("strain_model.temperature_ramp_k_per_s", am.temperature_ramp_k_per_s, bm.temperature_ramp_k_per_s);
  field("strain_model.saturation_force_n", am.saturation_force_n, bm.saturation_force_n);
  field("strain_model.cross_talk_shear_fraction", am.cross_talk_shear_fraction, bm.cross_talk_shear_fraction);
  field("strain_model.cross_talk_offset_per_mm", am.cross_talk_offset_per_mm, bm.cross_talk_offset_per_mm);
  field("strain_model.dead_units", am.dead_units, bm.dead_units);
  field("strain_model.shorted_units", am.shorted_units, bm.shorted_units);
  const sensor::ReadoutConfig& ar = an.readout;
  const sensor::ReadoutConfig& br = bn.readout;
  field("readout.baseline_frames", ar.baseline_frames, br.baseline_frames);
  field("readout.short_circuit_ohm", ar.short_circuit_ohm, br.short_circuit_ohm);
  field("readout.open_circuit_ohm", ar.open_circuit_ohm, br.open_circuit_ohm);
  field("readout.min_plausible_fraction", ar.min_plausible_fraction, br.min_plausible_fraction);
  field("readout.max_plausible_fraction", ar.max_plausible_fraction, br.max_plausible_fraction);
  field("readout.max_baseline_deviation_fraction", ar.max_baseline_deviation_fraction,
        br.max_baseline_deviation_fraction);
  field("readout.min_mean_dr_rel", ar.min_mean_dr_rel, br.min_mean_dr_rel);
  field("readout.max_abs_dr_rel", ar.max_abs_dr_rel, br.max_abs_dr_rel);
  field("readout.adc_full_scale_ohm", ar.adc_full_scale_ohm, br.adc_full_scale_ohm);
  field("readout.adc_min_ohm", ar.adc_min_ohm, br.adc_min_ohm);
  field("inversion.contact_threshold_n", an.inversion.contact_threshold_n, bn.inversion.contact_threshold_n);
  field("inversion.rated_force_n", an.inversion.rated_force_n, bn.inversion.rated_force_n);
  field("inversion.out_of_range_margin_fraction", an.inversion.out_of_range_margin_fraction,
        bn.inversion.out_of_range_margin_fraction);

  field("controller.name", a.controller.name, b.controller.name);
  field("controller.params", a.controller.params, b.controller.params);
  field("controller.grip_ceiling_n", a.controller.grip_ceiling_n, b.controller.grip_ceiling_n);
  field("controller.rate_hz", a.controller.rate_hz, b.controller.rate_hz);
  field("controller.stale_timeout_s", a.controller.stale_timeout_s, b.controller.stale_timeout_s);

  const Expectations& ae = a.expectations;
  const Expectations& be = b.expectations;
  field("expectations.not_dropped", ae.not_dropped, be.not_dropped);
  field("expectations.max_slip_mm", ae.max_slip_mm, be.max_slip_mm);
  field("expectations.max_peak_grip_n", ae.max_peak_grip_n, be.max_peak_grip_n);
  field("expectations.not_crushed", ae.not_crushed, be.not_crushed);
  field("expectations.slip_detected_within_ms", ae.slip_detected_within_ms, be.slip_detected_within_ms);
  field("expectations.micro_slip_detected_within_ms", ae.micro_slip_detected_within_ms,
        be.micro_slip_detected_within_ms);
  field("expectations.max_grip_efficiency", ae.max_grip_efficiency, be.max_grip_efficiency);
  field("expectations.max_estimation_error_n", ae.max_estimation_error_n, be.max_estimation_error_n);
  field("expectations.stable_within_s", ae.stable_within_s, be.stable_within_s);
  field("expectations.max_false_slip_per_min", ae.max_false_slip_per_min, be.max_false_slip_per_min);
  field("expectations.grasped_on_sensor", ae.grasped_on_sensor, be.grasped_on_sensor);

  const MetricsConfig& at = a.metrics;
  const MetricsConfig& bt = b.metrics;
  field("metrics.sliding_friction_fraction", at.sliding_friction_fraction, bt.sliding_friction_fraction);
  field("metrics.slip_min_load_share", at.slip_min_load_share, bt.slip_min_load_share);
  field("metrics.creep_speed_m_s", at.creep_speed_m_s, bt.creep_speed_m_s);
  field("metrics.slip_speed_m_s", at.slip_speed_m_s, bt.slip_speed_m_s);
  field("metrics.creep_event_m", at.creep_event_m, bt.creep_event_m);
  field("metrics.slip_event_gap_s", at.slip_event_gap_s, bt.slip_event_gap_s);
  field("metrics.early_detection_window_s", at.early_detection_window_s, bt.early_detection_window_s);
  field("metrics.gross_slip_m", at.gross_slip_m, bt.gross_slip_m);
  field("metrics.grasp_force_n", at.grasp_force_n, bt.grasp_force_n);
  field("metrics.seating_s", at.seating_s, bt.seating_s);
  field("metrics.drop_distance_m", at.drop_distance_m, bt.drop_distance_m);
  field("metrics.acquisition_lift_m", at.acquisition_lift_m, bt.acquisition_lift_m);
  field("metrics.acquisition_settle_s", at.acquisition_settle_s, bt.acquisition_settle_s);
  field("metrics.acquisition_settle_m", at.acquisition_settle_m, bt.acquisition_settle_m);
  field("metrics.acquisition_wrist_m", at.acquisition_wrist_m, bt.acquisition_wrist_m);
  field("metrics.acquisition_max_s", at.acquisition_max_s, bt.acquisition_max_s);
  field("metrics.max_unsensed_held_s", at.max_unsensed_held_s, bt.max_unsensed_held_s);
  field("metrics.min_sensed_grip_share", at.min_sensed_grip_share, bt.min_sensed_grip_share);
  field("metrics.stable_window_s", at.stable_window_s, bt.stable_window_s);
  field("metrics.stable_force_band", at.stable_force_band, bt.stable_force_band);
}

// Every member of `a` equals that of `b`, the script action by action; a mismatch names its key.
void ExpectSameConfig(const ScenarioConfig& a, const ScenarioConfig& b) {
  const auto same = [](const std::string& key, const auto& x, const auto& y) {
    EXPECT_TRUE(SameValue(x, y)) << key << ": " << ::testing::PrintToString(x) << " loaded back as "
                                 << ::testing::PrintToString(y);
  };
  ForEachConfigField(a, b, same);
  ASSERT_EQ(a.script.size(), b.script.size());
  for (size_t i = 0; i < a.script.size(); ++i) {
    const std::string prefix = "script[" + std::to_string(i) + "].";
    ForEachActionField(a.script[i], b.script[i], [&](const std::string& key, const auto& x, const auto& y) {
      same(prefix + key, x, y);
    });
  }
}

// Keys of the members `config` leaves at their defaults (actions against a default Action, keyed
// "script[].KEY"), inserted into `keys`.
void InsertDefaultedKeys(const ScenarioConfig& config, std::set<std::string>& keys) {
  ForEachConfigField(config, ScenarioConfig{}, [&](const std::string& key, const auto& x, const auto& y) {
    if (SameValue(x, y)) keys.insert(key);
  });
  std::set<std::string> action_keys;
  ForEachActionField(Action{}, Action{},
                     [&](const std::string& key, const auto&, const auto&) { action_keys.insert(key); });
  for (const Action& action : config.script) {
    ForEachActionField(action, Action{}, [&](const std::string& key, const auto& x, const auto& y) {
      if (!SameValue(x, y)) action_keys.erase(key);
    });
  }
  for (const std::string& key : action_keys) keys.insert("script[]." + key);
}

// Two scenarios that, between them, set every member to a value other than its default (with every
// action, both ways of timing one, every expectation and metric): the simulated backend with the
// prosthetic hand's wrap, a sensor profile overridden key by key and the slip controller; the serial
// backend with the jaw fixture, the FEA's sensitivities and the constant-grip baseline.
const char* const kEveryFieldSim = R"(name: round_trip
description: "every action once, every section set"
seed: 42
duration_s: 6
backend: sim
object: {shape: cylinder, size_m: [0.05, 0, 0.1], mass_kg: 0.15, friction: 0.45, torsional_friction: 0.002,
         solref_timeconst_s: 0.004, solref_dampratio: 1.5, solimp: [0.9, 0.98, 0.001, 0.4, 3],
         initial_position_m: [0.01, -0.02, -1], initial_yaw_rad: 0.2, crush_limit_n: 8}
hand:
  grasp: wrap
  preshape_clearance_m: 0.006
  contact_patch_radius_m: 0.005
  palm_mass_kg: 0.4
  digit_mass_kg: 0.02
  friction: 0.9
  wrist_stiffness_n_m: 15000
  wrist_damping_n_s_m: 300
  motor: {stall_force_n: 25, no_load_speed_m_s: 0.1, armature_kg: 0.04, damping_n_s_m: 1.5}
  finger: {proximal_length_m: 0.045, middle_length_m: 0.025, pip_mcp_ratio: 1.2, dip_flexion_rad: 0.2,
           mcp_rest_angle_rad: 0.25}
  thumb: {proximal_length_m: 0.058, distal_length_m: 0.031, tip_radius_m: 0.009, ip_flexion_rad: 0.3}
  digit_motor: {stall_pinch_force_n: 25, no_load_speed_rad_s: 1.8, armature_kg_m2: 3e-4, damping_n_m_s: 0.003,
                wrap_thumb_share: 0.6}
physics: {timestep_s: 0.0005, elliptic_cones: false, impratio: 100, noslip_iterations: 5, solver_iterations: 50,
          tolerance: 1e-9, condim: 6, gravity_m_s2: 9.7, table: false, contact_pairs: false}
sensor:
  layout: paper_3x3
  sample_rate_hz: 800
  latency_s: 0.002
  drop_probability: 0.01
  profile: inamp_16bit
  strain_model: {r0_ohm: 3500, gauge_factor: 90, kn_per_n: 5e-4, kt_per_n: 4e-4, rated_force_n: 12,
                 r0_spread_fraction: 0.02, sensitivity_spread_fraction: 0.03, noise_ohm: 1.5, adc_bits: 14,
                 adc_full_scale_ohm: 9000, adc_min_ohm: 100, temperature_coefficient_per_k: 0.001,
                 temperature_offset_k: 2, temperature_ramp_k_per_s: 0.1, saturation_force_n: 15,
                 cross_talk_shear_fraction: 0.05, cross_talk_offset_per_mm: 0.02, dead_units: [2],
                 shorted_units: [7]}
  readout: {baseline_frames: 50, short_circuit_ohm: 2, open_circuit_ohm: 2e6, min_plausible_fraction: 0.25,
            max_plausible_fraction: 2.5, max_baseline_deviation_fraction: 0.25, min_mean_dr_rel: -0.2,
            max_abs_dr_rel: 1.2, adc_full_scale_ohm: 8000, adc_min_ohm: 200}
  inversion: {contact_threshold_n: 0.08, rated_force_n: 12, out_of_range_margin_fraction: 0.1}
controller:
  name: grip_slip
  params: {min_grip_n: 1.5, max_grip_n: 12, safety_margin: 1.4}
  grip_ceiling_n: 6
  rate_hz: 500
  stale_timeout_s: 0.03
script:
  - {at_s: 0.1, action: close}
  - {after: grasped, delay_s: 0.05, timeout_s: 1.5, action: lift, height_m: 0.04, duration_s: 0.6,
     profile: linear}
  - {at_s: 1.0, action: move, position_m: [0.01, 0, 0.2], duration_s: 0.3, profile: linear}
  - {at_s: 1.2, action: move, offset_m: [0, 0.01, 0], duration_s: 0.2}
  - {after: stable, timeout_s: 2, action: shake, frequency_hz: 3, amplitude_m: 0.005, duration_s: 0.5,
     axis: [0, 2, 0], ramp_s: 0.1}
  - {at_s: 2.0, action: add_mass, mass_kg: 0.1, ramp_s: 1, profile: linear}
  - {at_s: 2.2, action: pull, force_n: [0, 0, -1], ramp_s: 0.5, duration_s: 0.2, profile: linear}
  - {after: slip_flagged, delay_s: 0.01, timeout_s: 0.5, action: set_friction, friction: 0.3, ramp_s: 0.25,
     profile: linear}
  - {at_s: 2.6, action: dead_unit, unit: 4}
  - {at_s: 2.7, action: short_unit, unit: 5}
  - {at_s: 2.8, action: restore_unit, unit: 5}
  - {at_s: 2.9, action: bias, unit: 6, r1_ohm: 10, r2_ohm: -5}
  - {at_s: 3.0, action: noise_burst, scale: 5, duration_s: 0.2}
  - {at_s: 3.1, action: drop_frames, duration_s: 0.05, probability: 0.5}
  - {at_s: 3.2, action: add_latency, latency_s: 0.003}
  - {at_s: 4.0, action: open}
  - {after: released, delay_s: 0.1, timeout_s: 1, action: idle}
expectations: {not_dropped: true, max_slip_mm: 1, max_peak_grip_n: 7, not_crushed: true,
               slip_detected_within_ms: 30, micro_slip_detected_within_ms: 45, max_grip_efficiency: 2.5,
               max_estimation_error_n: 0.5, stable_within_s: 0.8, max_false_slip_per_min: 2,
               grasped_on_sensor: false}
metrics: {sliding_friction_fraction: 0.9, slip_min_load_share: 0.25, creep_speed_m_s: 0.0004,
          slip_speed_m_s: 0.003, creep_event_m: 0.0002, slip_event_gap_s: 0.04, early_detection_window_s: 0.06,
          gross_slip_m: 0.0007, grasp_force_n: 0.4, seating_s: 0.06, drop_distance_m: 0.025,
          acquisition_lift_m: 0.002, acquisition_settle_s: 0.1, acquisition_settle_m: 0.0003,
          acquisition_wrist_m: 0.002, acquisition_max_s: 0.4, max_unsensed_held_s: 0.2,
          min_sensed_grip_share: 0.3,
          stable_window_s: 0.25, stable_force_band: 0.12}
)";
const char* const kEveryFieldSerial = R"(name: round_trip_serial
description: the serial backend, the jaw fixture and the FEA's sensitivities
seed: 123456789
duration_s: 2
backend: serial
serial: {port: /dev/ttyACM1, motor_port: /dev/ttyACM2, baud: 1000000, hello_timeout_s: 2, stale_timeout_s: 0.04,
         disconnect_timeout_s: 0.4, reconnect_backoff_s: 0.04, reconnect_backoff_max_s: 0.8,
         poll_interval_s: 0.001, write_timeout_s: 0.03}
log: frames.csv
object: {shape: sphere, size_m: [0.045, 0, 0], initial_position_m: [0, 0.01, 0.05]}
hand: {model: jaw, open_gap_m: 0.06, initial_wrist_position_m: [0, 0, 0.12], thumb: {opposition_rad: 0.3}}
sensor: {sensitivities: fea, fea_config: FEA_CONFIG, profile: divider_12bit}
controller: {name: constant_grip, params: {grip_n: 4}}
script:
  - {at_s: 0.1, action: close}
expectations: {not_dropped: false}
)";

TEST(ScenarioConfigTest, ResolvedYamlLoadsBackToTheSameConfigurationFieldByField) {
  std::string serial_text = kEveryFieldSerial;
  const std::string fea_config = std::string(GRASPBED_SOURCE_DIR) + "/sensor/fea/unit_fea.yaml";
  serial_text.replace(serial_text.find("FEA_CONFIG"), std::string("FEA_CONFIG").size(), fea_config);
  std::vector<std::set<std::string>> defaulted;
  for (const std::string& text : {std::string(kEveryFieldSim), serial_text}) {
    const ScenarioConfig config = LoadScenarioFromString(text, "rt.yaml");
    SCOPED_TRACE(config.name);
    const ScenarioConfig again = LoadScenarioFromString(EmitScenarioYaml(config), "config.yaml");
    ExpectSameConfig(config, again);
    // The files set what they say, so the round trip has something to lose.
    InsertDefaultedKeys(config, defaulted.emplace_back());
  }
  std::vector<std::string> defaulted_in_both;
  std::set_intersection(defaulted[0].begin(), defaulted[0].end(), defaulted[1].begin(), defaulted[1].end(),
                        std::back_inserter(defaulted_in_both));
  // Every member is set by one of the two files, but a noise burst's own noise, which no file sets
  // (a burst needs sensor.strain_model.noise_ohm > 0 and scales it).
  EXPECT_THAT(defaulted_in_both, ::testing::ElementsAre("script[].noise_ohm"));
  // A field the emitter dropped would load back as its default: the check sees it.
  const ScenarioConfig config = LoadScenarioFromString(kEveryFieldSim, "rt.yaml");
  ASSERT_EQ(config.script[6].kind, ActionKind::kPull);
  ScenarioConfig dropped = config;
  dropped.script[6].ramp_s = 0.0;
  EXPECT_NONFATAL_FAILURE(ExpectSameConfig(config, dropped), "script[6].ramp_s: 0.5 loaded back as 0");
}

}  // namespace
}  // namespace graspbed::testbed

namespace graspbed::testbed {
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
}  // namespace graspbed::testbed
