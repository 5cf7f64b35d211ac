// `graspbed view` as users run it, on a virtual display (xvfb-run): a few frames of the default
// scenario live and of a finished run replayed, each exiting 0 with time advanced; a directory that is
// not a run and a machine without a display are refused with a message.
#include <gtest/gtest.h>

#include <cstdio>
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

TEST(ViewCliTest, ReplaysAFinishedRunWithoutSimulatingIt) {
  TempDir dir("view_replay");
  const std::string out = dir.Path("run");
  const CliResult run = RunCli("run " + SourcePath("scenarios/default.yaml") + " --no-plots --out " + out);
  ASSERT_EQ(run.exit_code, kExitOk) << run.err;
  const CliResult result = RunCliUnder(
      kVirtualDisplay, "view " + out + " --frames " + std::to_string(kFrames) + " --size 320x240 --speed 8");
  ASSERT_EQ(result.exit_code, kExitOk) << result.out << result.err;
  EXPECT_EQ(ShownFrames(result.out), kFrames) << result.out;
  EXPECT_GT(ShownTime(result.out), 0.01) << result.out;
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

}  // namespace
}  // namespace graspbed
