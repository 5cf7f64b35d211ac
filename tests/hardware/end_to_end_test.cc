// End to end over a real pseudo-terminal, with the real executable ($GRASPBED_BINARY): `graspbed
// emulate` serves a simulated lift, `graspbed hw` closes the loop with the reference controller, and
// the outcome is held against the same scenario run purely in simulation (`graspbed run`). No timing
// assertion: waits are generous deadlines, and the checks are on outcomes and counters.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <chrono>
#include <cstdio>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "testbed/run_outputs.h"

#include "tests/support/child_process.h"
#include "tests/support/cli_runner.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"

namespace graspbed::hardware {
namespace {

using graspbed::test_support::CliBinary;
using Child = graspbed::test_support::ChildProcess;
using graspbed::test_support::ReadText;
using graspbed::test_support::TempDir;

constexpr char kScenario[] = "tests/hardware/data/e2e_lift.yaml";
constexpr int kUnits = 20;                  // the scenario's layout (default_20)
constexpr double kLiftHeightM = 0.05;       // the scenario's lift
constexpr double kLiftEndS = 1.6;           // lift at 0.8 s over 0.8 s
constexpr double kHostDurationS = 3.0;      // `hw --duration`
constexpr double kEmulatorDurationS = 3.5;  // simulated; the host normally ends the trial first
// Generous deadlines for a machine with both cores busy; none of them is a pass criterion.
constexpr double kStartupDeadlineS = 30.0;
constexpr double kRunDeadlineS = 60.0;
constexpr double kFramePeriodS = 0.001;  // the scenario's 1 kHz sensor
constexpr double kScriptCloseS = 0.15;   // the scenario's close
constexpr double kMaxSlipMm = 2.0;       // the scenario's own expectation
// Outcome tolerances, hardware path vs pure simulation, each from what has to be the same. The
// scenario's sensor is ideal and the wire carries R1/R2 to 1 mOhm, 3e-7 of R0 in dR/R or 5e-6 N of
// Fn per unit (G kn = 0.055 /N): the host senses what the simulated sensor measured. The paths
// differ on purpose only in timing: the host closes after its tare rather than at the script's
// 0.15 s, takes the newest frame rather than every one, and its control period follows frame arrival.
// - Lift: the wrist follows the same script carrying the same object in both paths, so the object's
//   lift differs only by its slip in each grasp, plus the grasp's compliance: a 10 N pinch sinks the
//   box 3.6 um into the mesas (docs/simulation.md), so a different grip moves it < 0.01 mm.
constexpr double kGraspComplianceM = 1e-5;
// - The settled hold: the grip each controller settles on is its own (it follows the slips it has
//   seen, and those depend on frame timing: 7.6 N in one path and 9.8 N in the other are both
//   right), but the share of the squeeze the mesas carry along their normals is where the object
//   sits on the digits, the same in both paths; the grip moves it only through the contacts'
//   penetration (3.6 um per 10 N): measured 0.9771 at 7.6 N and at 10 N, 0.981 at 2 N. Over an
//   exact wire the host's sensed total is that share of the true squeeze, so the shares agree to 0.5 %
//   at those grips. At the 1.5 N hold the preload-fitting controller settles on here, the share moves
//   from tick to tick with the lifted box's sway: 0.9677 .. 0.9742 over the last second of the
//   simulation (`graspbed run tests/hardware/data/e2e_lift.yaml --set sensor.latency_s=0.001`), so
//   two single-tick samples, one per path, differ by up to 0.0065.
constexpr double kShareTol = 0.007;
// - The closing impact: the peak squeeze is reached while the squeeze rises at up to R N/s (read from
//   the simulation's signals); the host's loop reacts up to two frame periods later than the
//   simulation's (one for taking the newest frame when it wakes, one for the pty hand-off), so the
//   peaks differ by at most R x 2 periods.
constexpr double kExtraReactionS = 2 * kFramePeriodS;
// - Grasp time: counted from the close (the script's at 0.15 s; the host's first closing command,
//   which the emulator reports), the closing travel is the same motor over the same gap at the same
//   effort; contact is seen up to the reaction delay above later, and the emulator scores once per
//   frame.
// - The frame log and the loop run the same readout and inversion on the same frames (the loop on
//   the newest ones only), so the loop's peak is one of the log's rows; the log prints fn to 1e-5 N
//   per unit (%.5f), 20 units.
constexpr double kLogRoundingN = kUnits * 0.5e-5;

/// signals.csv of a `graspbed run`: the columns by name.
std::map<std::string, std::vector<double>> ReadSignals(const std::string& path) {
  std::map<std::string, std::vector<double>> columns;
  std::ifstream csv(path);
  std::string line;
  std::getline(csv, line);
  std::vector<std::string> names;
  std::stringstream header(line);
  for (std::string name; std::getline(header, name, ',');) names.push_back(name);
  while (std::getline(csv, line)) {
    std::stringstream row(line);
    size_t c = 0;
    for (std::string cell; std::getline(row, cell, ',') && c < names.size(); ++c) {
      char* end = nullptr;
      const double value = std::strtod(cell.c_str(), &end);
      if (end != cell.c_str()) columns[names[c]].push_back(value);
    }
  }
  return columns;
}
// The host runs 3 s at 1 kHz: a run that kept real time brings about 3000 frames; one with no more
// than this fell behind (a loaded machine stalls the emulator's simulation).
constexpr uint64_t kMinRealTimeFrames = 1000;

class EndToEndTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (binary_.empty()) GTEST_FAIL() << "GRASPBED_BINARY must point at the CLI";
  }

  std::string Path(const std::string& name) const { return dir_.Path(name); }

  /// Runs `graspbed args...` to completion; its parsed stdout JSON (a failure when it is none).
  nlohmann::json RunJson(std::vector<std::string> args, const std::string& tag) {
    args.insert(args.begin(), binary_);
    Child child(args, Path(tag + ".out"), Path(tag + ".err"));
    EXPECT_TRUE(child.started());
    const std::optional<int> code = child.Wait(kRunDeadlineS);
    EXPECT_EQ(code, std::optional<int>(0)) << tag << " stderr: " << child.err();
    return ParseJson(child.out(), tag);
  }

  static nlohmann::json ParseJson(const std::string& text, const std::string& tag) {
    try {
      return nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& error) {
      ADD_FAILURE() << tag << ": stdout is not JSON (" << error.what() << "): " << text;
      return nlohmann::json::object();
    }
  }

  const std::string binary_ = CliBinary();
  const TempDir dir_{"e2e"};
};

// Holding the default box, the index's MCP is flexed about 0.07 rad and its motor draws about
// 0.085 A (sim/proprioception.h, the realistic profile; 0.01 A offset at rest): well above these.
constexpr double kHeldFingerFlexionRad = 0.03;
constexpr double kHeldMotorCurrentA = 0.03;

TEST_F(EndToEndTest, EmulatorAndHwHoldALiftedObjectLikeTheSimulation) {
  // 1. The reference: the same scenario purely in simulation, with the one frame period of latency
  // the hardware path has before its loop sees a frame (the pty hand-off, taking the newest on
  // wake). Since the grip-slip controller fits its preload from the loading ramp, its grasp of this
  // scenario turns on that millisecond: without it the simulation flags a (false) slip at the lift's
  // onset and regrips to 10 N, while over the wire, and in simulation with 1 ms latency, it holds at
  // 1.5 N through the lift.
  const nlohmann::json sim =
      RunJson({"run", kScenario, "--json", "--no-plots", "--set",
               "sensor.latency_s=" + std::to_string(kFramePeriodS), "--out", Path("sim")},
              "run");
  ASSERT_TRUE(sim.contains("metrics")) << sim.dump();
  const nlohmann::json& sim_metrics = sim.at("metrics");
  ASSERT_FALSE(sim_metrics.at("dropped").get<bool>()) << "the reference run itself drops the object";

  // 2. The device: `graspbed emulate` behind a pty symlinked at DIR/dev.
  const std::string link = Path("dev");
  Child emulator({binary_, "emulate", "--link", link, kScenario, "--duration",
                  std::to_string(kEmulatorDurationS), "--json"},
                 Path("emulate.out"), Path("emulate.err"));
  ASSERT_TRUE(emulator.started());
  const auto startup_deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(kStartupDeadlineS);
  struct stat info {};
  while (::lstat(link.c_str(), &info) != 0) {
    ASSERT_FALSE(emulator.Wait(0.0)) << "emulate exited: " << emulator.err();
    ASSERT_LT(std::chrono::steady_clock::now(), startup_deadline)
        << "no link from emulate: " << emulator.err();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }

  // 3. The host: `graspbed hw` with the reference controller, logging every frame.
  const std::string log = Path("frames.csv");
  const nlohmann::json hw = RunJson({"hw", "--port", link, "--controller", "grip_slip", "--duration",
                                     std::to_string(kHostDurationS), "--json", "--log", log, "--latency-report"},
                                    "hw");
  // The host's stream stop ends the emulator's trial; it then prints its outcome.
  const std::optional<int> emulator_code = emulator.Wait(kRunDeadlineS);
  ASSERT_EQ(emulator_code, std::optional<int>(0)) << emulator.err();
  const nlohmann::json device = ParseJson(emulator.out(), "emulate");

  // The host's summary: the keys docs/hardware.md lists, a clean link.
  for (const char* key : {"frames", "corrupt", "dropped", "reconnects", "unknown_packets", "stale_periods",
                          "sessions", "log_rows"}) {
    ASSERT_TRUE(hw.contains(key)) << key << " missing from " << hw.dump();
  }
  const auto frames = hw.at("frames").get<uint64_t>();
  // The loop latency (docs/hardware.md, "Loop latency"): recorded per frame a command answered; its
  // figures are the bench's to judge (bench/loop_latency_bench), here only that they are consistent.
  ASSERT_TRUE(hw.contains("latency")) << hw.dump(2);
  const nlohmann::json& latency = hw.at("latency");
  const auto answered = latency.at("frames_answered").get<uint64_t>();
  EXPECT_GT(answered, 0u);
  EXPECT_LE(answered, frames);
  EXPECT_EQ(latency.at("not_kept").get<uint64_t>(), 0u);
  EXPECT_GT(latency.at("p50_us").get<double>(), 0.0);
  EXPECT_LE(latency.at("p50_us").get<double>(), latency.at("p99_us").get<double>());
  EXPECT_LE(latency.at("p99_us").get<double>(), latency.at("p999_us").get<double>());
  EXPECT_LE(latency.at("p999_us").get<double>(), latency.at("max_us").get<double>());
  EXPECT_LE(latency.at("over_5ms").get<uint64_t>(), latency.at("over_1ms").get<uint64_t>());
  EXPECT_LE(latency.at("over_1ms").get<uint64_t>(), answered);
  EXPECT_EQ(hw.at("corrupt").get<uint64_t>(), 0u);
  EXPECT_EQ(hw.at("reconnects").get<uint64_t>(), 0u);
  EXPECT_EQ(hw.at("unknown_packets").get<uint64_t>(), 0u);
  EXPECT_EQ(hw.at("sessions").get<uint64_t>(), 1u);
  EXPECT_FALSE(hw.at("interrupted").get<bool>());

  // The device's side: the host spoke only after HELLO and stopped the stream. Whether the trial got
  // past the lift is the machine's pace (a device starved of the CPU simulates less than the host's
  // session lasts: 1.3 s of 3 once with both cores loaded); one that did not is judged below as one
  // that did not keep the pace.
  EXPECT_EQ(device.at("commands_before_hello").get<uint64_t>(), 0u);
  EXPECT_EQ(device.at("host_corrupt").get<uint64_t>(), 0u);
  EXPECT_EQ(device.at("ended_by").get<std::string>(), "host_stopped") << device.dump(2);
  const double device_sim_s = device.at("sim_time_s").get<double>();

  // Whether the hardware path kept real time: a machine too busy to feed the host every frame drops
  // frames and makes its state go stale, the controller then holds or regrips on purpose (safe
  // hold), and when commands stop for 100 ms the device's watchdog turns the motor off. Measured with
  // both cores taken by other builds: stale periods, dropped frames (370 of about 3000 once), slip of
  // several mm, a 10 N regrip in 3 of 5 runs, and once 3 watchdog trips and the object dropped. What
  // depends on the pace is checked only in a run that kept it; one that did not is skipped below
  // with its figures (ctest counts it as skipped), not passed.
  const uint64_t dropped = hw.at("dropped").get<uint64_t>();
  const uint64_t stale_periods = hw.at("stale_periods").get<uint64_t>();
  const uint64_t watchdog_trips = device.at("watchdog_trips").get<uint64_t>();
  const bool kept_pace = stale_periods == 0 && dropped == 0 && watchdog_trips == 0 && frames > kMinRealTimeFrames &&
                         device_sim_s > kLiftEndS + 0.2;

  // The outcome: held, lifted with the wrist, a grip like the simulation's (tolerances above).
  const nlohmann::json& hw_metrics = device.at("metrics");
  auto signals = ReadSignals(Path("sim") + "/signals.csv");
  for (const char* column : {"time_s", "object_z_m", "true_squeeze_n", "est_total_fn_n"}) {
    ASSERT_GT(signals[column].size(), 100u) << column << " missing from the simulation's signals.csv";
  }
  EXPECT_TRUE(hw_metrics.at("grasped").get<bool>());
  // Held, unless the device's watchdog stopped the motor: stale periods and dropped frames make the
  // controller hold or regrip on purpose, which keeps the object; only the motor turned off by the
  // watchdog (commands stopped for 100 ms) may let it fall. Measured with both cores taken: the one
  // drop seen came with 3 watchdog trips.
  if (watchdog_trips == 0) {
    EXPECT_FALSE(hw_metrics.at("dropped").get<bool>()) << device.dump(2);
  }
  const double hw_slip_mm = hw_metrics.at("max_slip_mm").get<double>();
  const double sim_slip_mm = sim_metrics.at("max_slip_mm").get<double>();
  EXPECT_LE(sim_slip_mm, kMaxSlipMm);
  const double sim_lift_m = signals["object_z_m"].back() - signals["object_z_m"].front();
  // The reference lifts with the wrist: 50 mm less its slip and the wrist's sag under the object's
  // weight (m g / k = 0.05 mm at the default 20 kN/m; 1 mm leaves room for a softer wrist).
  EXPECT_NEAR(sim_lift_m, kLiftHeightM, 1e-3 * sim_slip_mm + 1e-3) << "the reference itself does not lift";

  // The frame log: the header docs/hardware.md gives, one row per decoded frame, consecutive sequence
  // numbers.
  std::ifstream csv(log);
  ASSERT_TRUE(csv.good()) << log;
  std::string header;
  std::getline(csv, header);
  std::string expected = "seq,device_time_s";
  for (int k = 0; k < kUnits; ++k) {
    const std::string n = std::to_string(k);
    expected += ",r1_" + n + ",r2_" + n + ",fn_" + n + ",ft_" + n + ",valid_" + n;
  }
  // Then the hand state the link held with each frame (HAND, protocol version 2): signals.csv's columns.
  for (const char* name : testbed::internal::HandColumnNames()) expected += std::string(",") + name;
  EXPECT_EQ(header, expected);
  const size_t hand_first = 2u + 5u * kUnits;
  const size_t finger_q1 = hand_first + testbed::internal::kHandDigits + testbed::internal::kDigitQ1 -
                           testbed::internal::kHandTime;
  const size_t finger_current = hand_first + testbed::internal::kHandDigits +
                                testbed::internal::kDigitCurrent - testbed::internal::kHandTime;
  std::string last_finger_q1;
  std::string last_finger_current;
  uint64_t rows = 0;
  uint64_t gaps = 0;
  long previous_seq = -1;
  double peak_row_fn_n = 0.0;
  std::string line;
  while (std::getline(csv, line)) {
    std::vector<std::string> cells;
    std::stringstream split(line);
    for (std::string cell; std::getline(split, cell, ',');) cells.push_back(cell);
    ASSERT_EQ(cells.size(), hand_first + testbed::internal::HandColumnNames().size()) << "row " << rows;
    last_finger_q1 = cells[finger_q1];
    last_finger_current = cells[finger_current];
    const long seq = std::stol(cells[0]);
    if (previous_seq >= 0 && seq != (previous_seq + 1) % 65536) ++gaps;
    previous_seq = seq;
    double row_fn_n = 0.0;
    for (int k = 0; k < kUnits; ++k) {
      const std::string& valid = cells[2 + 5 * k + 4];
      ASSERT_TRUE(valid == "0" || valid == "1") << valid;
      if (valid == "1") row_fn_n += std::stod(cells[2 + 5 * k + 2]);
    }
    peak_row_fn_n = std::max(peak_row_fn_n, row_fn_n);
    ++rows;
  }
  EXPECT_EQ(rows, hw.at("log_rows").get<uint64_t>());
  EXPECT_EQ(rows, frames - hw.at("log_rows_lost").get<uint64_t>());
  EXPECT_LE(gaps, hw.at("dropped").get<uint64_t>() + hw.at("log_rows_lost").get<uint64_t>());
  // The loop's peak is one of these rows (it took a subset of the frames, through the same readout and
  // inversion), so it is not above the log's peak.
  EXPECT_LE(hw.at("peak_total_fn_n").get<double>(), peak_row_fn_n + kLogRoundingN);
  EXPECT_GT(hw.at("peak_total_fn_n").get<double>(), 0.0);
  // Proprioception over the wire: version 2 chosen, the hand's HANDs taken by the loop, and at the end
  // of the hold the index flexed round the box with its motor drawing current (the simulation's
  // realistic profile: about 0.07 rad and 0.085 A; 0.01 A at rest).
  EXPECT_EQ(hw.at("protocol_version").get<int>(), 2) << hw.dump(2);
  EXPECT_GT(hw.at("hand_messages").get<uint64_t>(), kMinRealTimeFrames / 2);
  EXPECT_GT(hw.at("hand_readings").get<uint64_t>(), kMinRealTimeFrames / 2);
  EXPECT_EQ(hw.at("hand_malformed").get<uint64_t>(), 0u);
  ASSERT_NE(last_finger_q1, "nan") << "the index joint is unknown in the frame log's last row";
  ASSERT_NE(last_finger_current, "nan") << "the index motor current is unknown in the frame log's last row";
  EXPECT_GT(std::stod(last_finger_q1), kHeldFingerFlexionRad);
  EXPECT_GT(std::stod(last_finger_current), kHeldMotorCurrentA);

  if (!kept_pace) {
    GTEST_SKIP() << "the hardware path fell behind real time (" << frames << " frames, " << device_sim_s
                 << " s simulated, " << dropped
                 << " dropped, " << stale_periods << " stale periods, " << watchdog_trips
                 << " motor watchdog trips; object " << (hw_metrics.at("dropped").get<bool>() ? "dropped" : "held")
                 << "): its link and grasp are not compared with the simulation's on a machine that did "
                 << "not keep the pace";
  }

  // The lift: the object rode with the wrist as in the simulation.
  EXPECT_LE(hw_slip_mm, kMaxSlipMm);
  // At the same simulated instant: the device's outcome is its state when the host stopped, which on
  // a busy machine comes before the scenario's end (its clock lags the host's), while the object still
  // settles on the wrist after the lift (tens of um).
  const std::vector<double>& sim_time = signals["time_s"];
  const size_t at = static_cast<size_t>(
      std::min<std::ptrdiff_t>(std::lower_bound(sim_time.begin(), sim_time.end(), device_sim_s) - sim_time.begin(),
                               static_cast<std::ptrdiff_t>(sim_time.size()) - 1));
  const double sim_lift_then_m = signals["object_z_m"][at] - signals["object_z_m"].front();
  std::printf("[ measure ] lift at %.3f s: %.4f mm over the wire, %.4f mm simulated (%.4f mm at its end); "
              "acquisition shift %.4f / %.4f mm\n",
              device_sim_s, 1e3 * device.at("object_lift_m").get<double>(), 1e3 * sim_lift_then_m, 1e3 * sim_lift_m,
              hw_metrics.at("acquisition_shift_mm").get<double>(), sim_metrics.at("acquisition_shift_mm").get<double>());
  // Each path's object moves against the wrist by what its metrics count (the shift while the digits
  // seat it, the slip and partial slip after) plus the grasp's compliance: the two lifts differ by at
  // most the sum. (With both cores loaded the seating differs: 0.058 to 0.110 mm over the wire against
  // 0.054 mm simulated, and the lifts 2 to 28 um; the slips alone left that unexplained.)
  const double moved_mm = hw_slip_mm + sim_slip_mm + hw_metrics.at("acquisition_shift_mm").get<double>() +
                          sim_metrics.at("acquisition_shift_mm").get<double>() +
                          hw_metrics.at("partial_slip_mm").get<double>() +
                          sim_metrics.at("partial_slip_mm").get<double>();
  EXPECT_NEAR(device.at("object_lift_m").get<double>(), sim_lift_then_m, 1e-3 * moved_mm + kGraspComplianceM);

  // The settled hold: the share of the squeeze the host sensed, as in the simulation.
  const double sim_final_sensed_n = signals["est_total_fn_n"].back();
  const double sim_final_squeeze_n = signals["true_squeeze_n"].back();
  const double hw_final_sensed_n = hw.at("final_total_fn_n").get<double>();
  const double hw_final_squeeze_n = device.at("final_squeeze_n").get<double>();
  ASSERT_GT(sim_final_squeeze_n, 0.5);
  ASSERT_GT(hw_final_squeeze_n, 0.5);
  EXPECT_NEAR(hw_final_sensed_n / hw_final_squeeze_n, sim_final_sensed_n / sim_final_squeeze_n, kShareTol)
      << "host " << hw_final_sensed_n << " of " << hw_final_squeeze_n << " N, simulation "
      << sim_final_sensed_n << " of " << sim_final_squeeze_n << " N";

  // The closing impact.
  double rise_n_per_s = 0.0;
  const std::vector<double>& time = signals["time_s"];
  const std::vector<double>& squeeze = signals["true_squeeze_n"];
  for (size_t i = 1; i < std::min(time.size(), squeeze.size()); ++i) {
    rise_n_per_s = std::max(rise_n_per_s, (squeeze[i] - squeeze[i - 1]) / (time[i] - time[i - 1]));
  }
  const double sim_peak_n = sim_metrics.at("peak_grip_n").get<double>();
  const double hw_peak_n = hw_metrics.at("peak_grip_n").get<double>();
  EXPECT_NEAR(hw_peak_n, sim_peak_n, rise_n_per_s * kExtraReactionS) << "rise " << rise_n_per_s << " N/s";

  // When the grasp happened: the host's close starts at the end of its tare window.
  ASSERT_TRUE(device.at("host_close_time_s").is_number()) << device.dump(2);
  EXPECT_NEAR(hw_metrics.at("grasp_time_s").get<double>() - device.at("host_close_time_s").get<double>(),
              sim_metrics.at("grasp_time_s").get<double>() - kScriptCloseS, kExtraReactionS + kFramePeriodS);
}

// --realtime-priority where SCHED_FIFO is not allowed (the CAP_SYS_NICE capability dropped with
// util-linux's setpriv): refused before the port is opened, naming what the machine must allow.
TEST_F(EndToEndTest, HwRefusesARealTimePriorityTheMachineDoesNotAllowNamingWhatItNeeds) {
  Child probe({"/usr/bin/setpriv", "--bounding-set", "-sys_nice", "--", "true"}, Path("probe.out"), Path("probe.err"));
  if (!probe.started() || probe.Wait(kRunDeadlineS) != std::optional<int>(0)) {
    GTEST_SKIP() << "setpriv cannot drop CAP_SYS_NICE here: " << probe.err();
  }
  Child hw({"/usr/bin/setpriv", "--bounding-set", "-sys_nice", "--", binary_, "hw", "--port", Path("no-device"),
            "--realtime-priority", "10"},
           Path("rt.out"), Path("rt.err"));
  ASSERT_TRUE(hw.started());
  EXPECT_EQ(hw.Wait(kRunDeadlineS), std::optional<int>(1));
  const std::string err = hw.err();
  EXPECT_NE(err.find("--realtime-priority 10: SCHED_FIFO refused"), std::string::npos) << err;
  EXPECT_NE(err.find("CAP_SYS_NICE"), std::string::npos) << err;
  EXPECT_EQ(err.find("does not exist"), std::string::npos) << "refused before the port was opened: " << err;
}

TEST_F(EndToEndTest, HwRefusesAMissingPortWithAClearMessage) {
  Child hw({binary_, "hw", "--port", Path("no-device"), "--duration", "1"}, Path("hw.out"), Path("hw.err"));
  ASSERT_TRUE(hw.started());
  EXPECT_EQ(hw.Wait(kRunDeadlineS), std::optional<int>(2));
  const std::string err = hw.err();
  EXPECT_NE(err.find(Path("no-device") + " does not exist"), std::string::npos) << err;
  EXPECT_NE(err.find("graspbed emulate --link"), std::string::npos) << err;
}

}  // namespace
}  // namespace graspbed::hardware
