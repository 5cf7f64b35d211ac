// `graspbed view` as users run it, on a virtual display (xvfb-run): a few frames of the default
// scenario live and of a finished run replayed, each exiting 0 with time advanced; keys typed into the
// window (xdotool) pause, step, restart and quit; a directory that is not a run and a machine without
// a display are refused with a message.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/support/cli_runner.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"

namespace graspbed {
namespace {

using test_support::CliResult;
using test_support::RunCli;
using test_support::RunCliUnder;
using test_support::SourcePath;
using test_support::TempDir;

constexpr int kExitOk = 0;
constexpr int kExitFailed = 1;
constexpr int kExitBadInput = 2;
// xvfb-run: a free display number, a screen deep enough for GLX.
constexpr const char* kVirtualDisplay = "xvfb-run -a -s '-screen 0 640x480x24' ";
constexpr int kFrames = 12;

/// The simulated time the viewer reports at exit ("... frames shown, t = T s ..."); -1 if absent.
double ShownTime(const std::string& out) {
  const size_t at = out.find("t = ");
  return at == std::string::npos ? -1.0 : std::stod(out.substr(at + 4));
}

int ShownFrames(const std::string& out) {
  const size_t at = out.find("graspbed view: ");
  return at == std::string::npos ? -1 : std::stoi(out.substr(at + 15));
}

TEST(ViewCliTest, LiveScenarioShowsFramesAndAdvancesTime) {
  const CliResult result =
      RunCliUnder(kVirtualDisplay, "view " + SourcePath("scenarios/default.yaml") + " --frames " +
                                       std::to_string(kFrames) + " --size 320x240 --speed 4");
  ASSERT_EQ(result.exit_code, kExitOk) << result.out << result.err;
  EXPECT_EQ(ShownFrames(result.out), kFrames) << result.out;
  // Running at 4x real time for 12 frames: well past the start.
  EXPECT_GT(ShownTime(result.out), 0.01) << result.out;
}

// The replay shows what states.csv holds: cut after 0.3 s, it stops at the file's last state, where
// the whole file (and a viewer that simulated config.yaml again) runs on past it.
TEST(ViewCliTest, ReplaysAFinishedRunFromItsStateLogWithoutSimulatingIt) {
  TempDir dir("view_replay");
  const std::string out = dir.Path("run");
  const CliResult run = RunCli("run " + SourcePath("scenarios/default.yaml") + " --no-plots --out " + out);
  ASSERT_EQ(run.exit_code, kExitOk) << run.err;
  const std::string replay = "view " + out + " --frames " + std::to_string(kFrames) + " --size 320x240 --speed 8";
  const CliResult whole = RunCliUnder(kVirtualDisplay, replay);
  ASSERT_EQ(whole.exit_code, kExitOk) << whole.out << whole.err;
  EXPECT_EQ(ShownFrames(whole.out), kFrames) << whole.out;
  constexpr double kCutS = 0.3;
  ASSERT_GT(ShownTime(whole.out), kCutS) << "the premise: 12 frames at 8x replay past the cut";

  const std::string states = out + "/states.csv";
  std::istringstream lines(test_support::ReadText(states));
  std::string line;
  std::getline(lines, line);
  std::string cut = line + "\n";
  double last_s = -1.0;
  while (std::getline(lines, line)) {
    const double time_s = std::stod(line.substr(0, line.find(',')));
    if (time_s > kCutS) break;
    cut += line + "\n";
    last_s = time_s;
  }
  std::ofstream(states) << cut;
  const CliResult shortened = RunCliUnder(kVirtualDisplay, replay);
  ASSERT_EQ(shortened.exit_code, kExitOk) << shortened.out << shortened.err;
  EXPECT_NEAR(ShownTime(shortened.out), last_s, 1e-3) << shortened.out;
}

TEST(ViewCliTest, RefusesADirectoryThatIsNotARunAndSaysWhenThereIsNoDisplay) {
  TempDir dir("view_bad");
  const CliResult not_run = RunCli("view " + dir.Path(""));
  EXPECT_EQ(not_run.exit_code, kExitBadInput) << not_run.err;
  EXPECT_NE(not_run.err.find("no config.yaml (not an output directory of graspbed run)"), std::string::npos)
      << not_run.err;
  const CliResult no_display = RunCliUnder("env -u DISPLAY -u WAYLAND_DISPLAY ",
                                           "view " + SourcePath("scenarios/default.yaml") + " --frames 1");
  EXPECT_EQ(no_display.exit_code, kExitFailed) << no_display.err;
  EXPECT_NE(no_display.err.find("no display?"), std::string::npos) << no_display.err;
}

/// Runs `graspbed view ARGUMENTS` (the script adds `view`) on a virtual display while
/// tests/render/view_keys.sh types `keys` (xdotool key names, `sleep:S` pauses) into its window, as a user's
/// keyboard would.
CliResult ViewWithKeys(const std::string& keys, const std::string& arguments) {
  return RunCliUnder(std::string(kVirtualDisplay) + "sh " + SourcePath("tests/render/view_keys.sh") + " ",
                     "'" + keys + "' " + arguments);
}

int ShownRestarts(const std::string& out) {
  const size_t at = out.find(" restarts");
  if (at == std::string::npos) return -1;
  const size_t start = out.rfind(' ', at - 1);
  return std::stoi(out.substr(start + 1, at - start - 1));
}

TEST(ViewCliTest, KeysPauseStepRestartAndQuitTheLiveRun) {
  const std::string paused = SourcePath("scenarios/default.yaml") + " --paused --size 320x240";
  const double tick_s = 0.001;  // the scenario's 1 kHz control tick: one Right key advances one
  // Started paused, q closes the window on the first tick shown.
  const CliResult quit = ViewWithKeys("q", paused);
  ASSERT_EQ(quit.exit_code, kExitOk) << quit.out << quit.err;
  const double first_s = ShownTime(quit.out);
  EXPECT_NEAR(first_s, tick_s, 1e-9) << quit.out;
  // Right steps one control tick at a time while paused.
  const CliResult steps = ViewWithKeys("Right Right Right q", paused);
  ASSERT_EQ(steps.exit_code, kExitOk) << steps.out << steps.err;
  EXPECT_NEAR(ShownTime(steps.out), first_s + 3 * tick_s, 1e-9) << steps.out;
  EXPECT_EQ(ShownRestarts(steps.out), 0) << steps.out;
  // Backspace restarts the run from the beginning (still paused).
  const CliResult restart = ViewWithKeys("Right Right BackSpace sleep:1 Right q", paused);
  ASSERT_EQ(restart.exit_code, kExitOk) << restart.out << restart.err;
  EXPECT_EQ(ShownRestarts(restart.out), 1) << restart.out;
  EXPECT_NEAR(ShownTime(restart.out), first_s + tick_s, 1e-9) << restart.out;
  // Space resumes: 1.5 s of wall time at 4x runs well past the first ticks.
  const CliResult resumed = ViewWithKeys("space sleep:1.5 q", paused + " --speed 4");
  ASSERT_EQ(resumed.exit_code, kExitOk) << resumed.out << resumed.err;
  EXPECT_GT(ShownTime(resumed.out), 0.1) << resumed.out;
}

}  // namespace
}  // namespace graspbed
