// End to end over a real pseudo-terminal, with the real executable ($GRASPBED_BINARY): `graspbed
// emulate` serves a simulated lift, `graspbed hw` closes the loop with the reference controller, and
// the outcome is held against the same scenario run purely in simulation (`graspbed run`). No timing
// assertion: waits are generous deadlines, and the checks are on outcomes and counters.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/support/cli_runner.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"

extern char** environ;

namespace graspbed::serial {
namespace {

using graspbed::testing::CliBinary;
using graspbed::testing::ReadText;
using graspbed::testing::TempDir;

constexpr char kScenario[] = "tests/serial/data/e2e_lift.yaml";
constexpr int kUnits = 20;                 // the scenario's layout (default_20)
constexpr double kLiftHeightM = 0.05;      // the scenario's lift
constexpr double kLiftEndS = 1.6;          // lift at 0.8 s over 0.8 s
constexpr double kHostDurationS = 3.0;     // `hw --duration`
constexpr double kEmulatorDurationS = 3.5; // simulated; the host normally ends the trial first
// Generous deadlines for a machine with both cores busy; none of them is a pass criterion.
constexpr double kStartupDeadlineS = 30.0;
constexpr double kRunDeadlineS = 60.0;
// Outcome tolerances, hardware path vs pure simulation. The paths differ on purpose: the host closes
// after its tare (0.1 s) rather than at the script's 0.15 s, takes the newest frame rather than every
// one, and the control period follows frame arrival, so the grip differs by a fraction of a newton.
constexpr double kLiftTolM = 0.005;
constexpr double kPeakGripRelTol = 0.25;
constexpr double kPeakGripAbsTolN = 1.5;
constexpr double kGraspTimeTolS = 0.2;
constexpr double kMaxSlipMm = 2.0;
constexpr double kSensedVsTrueRelTol = 0.3;
// "Few dropped": a loaded machine can stall the host long enough for the emulator's FIFO to overflow.
constexpr double kMaxDroppedFraction = 0.02;

/// A child process with stdout and stderr in files. Ended by its pid only (SIGTERM, then SIGKILL).
class Child {
 public:
  Child(const std::vector<std::string>& args, const std::string& out_path, const std::string& err_path)
      : out_path_(out_path), err_path_(err_path) {
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    std::vector<char*> argv;
    for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
    argv.push_back(nullptr);
    if (posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
  }
  ~Child() {
    if (pid_ <= 0 || exit_code_) return;
    ::kill(pid_, SIGTERM);
    if (!Wait(5.0)) {
      ::kill(pid_, SIGKILL);
      Wait(5.0);
    }
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  bool started() const { return pid_ > 0; }
  /// Waits up to `timeout_s` for the exit; the exit code (128 + signal when killed), or nullopt.
  std::optional<int> Wait(double timeout_s) {
    if (exit_code_ || pid_ <= 0) return exit_code_;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    for (;;) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
        return exit_code_;
      }
      if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  std::string out() const { return ReadText(out_path_); }
  std::string err() const { return ReadText(err_path_); }

 private:
  pid_t pid_ = -1;
  std::optional<int> exit_code_;
  std::string out_path_;
  std::string err_path_;
};

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

TEST_F(EndToEndTest, EmulatorAndHwHoldALiftedObjectLikeTheSimulation) {
  // 1. The reference: the same scenario purely in simulation.
  const nlohmann::json sim =
      RunJson({"run", kScenario, "--json", "--no-plots", "--out", Path("sim")}, "run");
  ASSERT_TRUE(sim.contains("metrics")) << sim.dump();
  const nlohmann::json& sim_metrics = sim.at("metrics");
  ASSERT_FALSE(sim_metrics.at("dropped").get<bool>()) << "the reference run itself drops the object";

  // 2. The device: `graspbed emulate` behind a pty symlinked at DIR/dev.
  const std::string link = Path("dev");
  Child emulator({binary_, "emulate", "--link", link, kScenario, "--duration", std::to_string(kEmulatorDurationS),
                  "--json"},
                 Path("emulate.out"), Path("emulate.err"));
  ASSERT_TRUE(emulator.started());
  const auto startup_deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(kStartupDeadlineS);
  struct stat info {};
  while (::lstat(link.c_str(), &info) != 0) {
    ASSERT_FALSE(emulator.Wait(0.0)) << "emulate exited: " << emulator.err();
    ASSERT_LT(std::chrono::steady_clock::now(), startup_deadline) << "no link from emulate: " << emulator.err();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }

  // 3. The host: `graspbed hw` with the reference controller, logging every frame.
  const std::string log = Path("frames.csv");
  const nlohmann::json hw =
      RunJson({"hw", "--port", link, "--controller", "grip_slip", "--duration", std::to_string(kHostDurationS),
               "--json", "--log", log},
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
  EXPECT_GT(frames, 1000u) << "3 s at 1 kHz should bring about 3000 frames";
  EXPECT_EQ(hw.at("corrupt").get<uint64_t>(), 0u);
  EXPECT_LE(static_cast<double>(hw.at("dropped").get<uint64_t>()), kMaxDroppedFraction * static_cast<double>(frames))
      << hw.dump(2);
  EXPECT_EQ(hw.at("reconnects").get<uint64_t>(), 0u);
  EXPECT_EQ(hw.at("unknown_packets").get<uint64_t>(), 0u);
  EXPECT_EQ(hw.at("sessions").get<uint64_t>(), 1u);
  EXPECT_FALSE(hw.at("interrupted").get<bool>());

  // The device's side: the host spoke only after HELLO, stopped the stream, and the trial got past
  // the lift (a machine too slow to simulate in real time would not).
  EXPECT_EQ(device.at("commands_before_hello").get<uint64_t>(), 0u);
  EXPECT_EQ(device.at("host_corrupt").get<uint64_t>(), 0u);
  EXPECT_EQ(device.at("ended_by").get<std::string>(), "host_stopped") << device.dump(2);
  ASSERT_GT(device.at("sim_time_s").get<double>(), kLiftEndS + 0.2)
      << "the emulator simulated too little before the host stopped (machine far slower than real time)";

  // The outcome: held, lifted with the wrist, a grip close to the simulation's.
  const nlohmann::json& hw_metrics = device.at("metrics");
  EXPECT_TRUE(hw_metrics.at("grasped").get<bool>());
  EXPECT_FALSE(hw_metrics.at("dropped").get<bool>()) << device.dump(2);
  EXPECT_NEAR(device.at("object_lift_m").get<double>(), kLiftHeightM, kLiftTolM);
  EXPECT_LE(hw_metrics.at("max_slip_mm").get<double>(), kMaxSlipMm);
  EXPECT_LE(sim_metrics.at("max_slip_mm").get<double>(), kMaxSlipMm);
  const double sim_peak_n = sim_metrics.at("peak_grip_n").get<double>();
  const double hw_peak_n = hw_metrics.at("peak_grip_n").get<double>();
  EXPECT_NEAR(hw_peak_n, sim_peak_n, std::max(kPeakGripAbsTolN, kPeakGripRelTol * sim_peak_n));
  EXPECT_NEAR(hw_metrics.at("grasp_time_s").get<double>(), sim_metrics.at("grasp_time_s").get<double>(),
              kGraspTimeTolS);
  // What the host sensed through the wire agrees with the squeeze the simulation applied.
  EXPECT_NEAR(hw.at("peak_total_fn_n").get<double>(), hw_peak_n, kSensedVsTrueRelTol * hw_peak_n);

  // The frame log: the header docs/hardware.md gives, one row per decoded frame, consecutive sequence numbers.
  std::ifstream csv(log);
  ASSERT_TRUE(csv.good()) << log;
  std::string header;
  std::getline(csv, header);
  std::string expected = "seq,device_time_s";
  for (int k = 0; k < kUnits; ++k) {
    const std::string n = std::to_string(k);
    expected += ",r1_" + n + ",r2_" + n + ",fn_" + n + ",ft_" + n + ",valid_" + n;
  }
  EXPECT_EQ(header, expected);
  uint64_t rows = 0;
  uint64_t gaps = 0;
  long previous_seq = -1;
  double peak_row_fn_n = 0.0;
  std::string line;
  while (std::getline(csv, line)) {
    std::vector<std::string> cells;
    std::stringstream split(line);
    for (std::string cell; std::getline(split, cell, ',');) cells.push_back(cell);
    ASSERT_EQ(cells.size(), 2u + 5u * kUnits) << "row " << rows;
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
  EXPECT_NEAR(peak_row_fn_n, hw.at("peak_total_fn_n").get<double>(), kSensedVsTrueRelTol * hw_peak_n);
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
}  // namespace graspbed::serial
