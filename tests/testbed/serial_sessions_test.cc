// The sessions behind `graspbed hw` and `graspbed soak` without a device: what PrepareHwSession
// resolves and refuses before any port is opened, PlanSoak's refusal of a schedule it cannot run, and
// the text both commands print (the CLI tests in tests/hardware run them end to end).
#include <cmath>
#include <stdexcept>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "testbed/hw_session.h"
#include "testbed/soak_run.h"

namespace graspbed::testbed {
namespace {

using ::testing::HasSubstr;

constexpr double kTimeTolS = 1e-12;

std::string RefusalOf(const HwSessionOptions& options) {
  try {
    PrepareHwSession(options);
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "(accepted)";
}

TEST(HwSessionTest, OneIntentOnBackendSerialOnceTheTareIsDone) {
  HwSessionOptions options;
  options.port = "/dev/ttyNOTHING";  // never opened here
  options.intent = "open";
  options.tare_frames = 50;
  const HwSession session = PrepareHwSession(options);
  EXPECT_EQ(session.scenario.backend, Backend::kSerial);
  EXPECT_EQ(session.scenario.serial.port, options.port);
  EXPECT_EQ(session.scenario.controller.name, "grip_slip");  // the default without --config
  ASSERT_EQ(session.scenario.script.size(), 1u);
  EXPECT_EQ(session.scenario.script[0].kind, ActionKind::kOpen);
  EXPECT_NEAR(session.scenario.script[0].at_s, 50 / session.scenario.sensor.sample_rate_hz, kTimeTolS);
  EXPECT_TRUE(std::isinf(session.scenario.duration_s)) << "--duration 0 runs until stopped";
  EXPECT_EQ(session.run.latency_frames, 0u);
}

TEST(HwSessionTest, RefusesWhatTheCommandLineGetsWrongNamingTheOption) {
  HwSessionOptions options;
  EXPECT_THAT(RefusalOf(options), HasSubstr("hw: no serial port: give --port PATH"));
  options.port = "/dev/ttyNOTHING";
  options.intent = "grab";
  EXPECT_THAT(RefusalOf(options), HasSubstr("--intent grab: must be close, open or idle"));
  options.intent = "close";
  options.params = {"safety_margin=abc"};
  EXPECT_THAT(RefusalOf(options), HasSubstr("--param safety_margin=abc: expected NAME=NUMBER"));
}

TEST(HwSessionTest, SummaryLineNamesTheDisconnectAndTheLogError) {
  HwSessionResult result;
  result.summary = {{"port", "/dev/ttyACM0"}, {"duration_s", 2.5}, {"frames", 2500},        {"corrupt", 1},
                    {"dropped", 2},           {"reordered", 0},    {"unknown_packets", 0},  {"reconnects", 0},
                    {"stale_periods", 0},     {"sessions", 1},     {"peak_total_fn_n", 4.5}};
  result.connected_at_end = false;
  result.log_error = "disk full";
  EXPECT_TRUE(result.failed());
  EXPECT_EQ(
      HwSummaryText(result),
      "hw /dev/ttyACM0: 2.5 s, 2500 frames, 1 corrupt, 2 dropped, 0 reordered, 0 unknown, 0 reconnects, "
      "0 stale periods, 1 sessions; peak grip 4.50 N (sensed); device DISCONNECTED at the end; log: disk "
      "full\n");
}

TEST(SoakRunTest, RefusesADurationThatIsNotAWholeNumberOfPeriods) {
  SoakOptions options;
  options.scenario = "never-read.yaml";
  options.duration_s = 25.0;
  options.period_s = 10.0;
  try {
    PlanSoak(options);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_THAT(error.what(), HasSubstr("soak: --duration 25 must be a whole number (>= 1) of --period 10"));
  }
}

TEST(SoakRunTest, ReportTextEndsWithTheVerdictAndWhereTheReportIs) {
  SoakPlan plan;
  plan.options.scenario = "hold.yaml";
  plan.options.duration_s = 20.0;
  plan.options.period_s = 10.0;
  plan.options.out_dir = "out/s";
  plan.schedule.cycles = 2;
  SoakResult result;
  result.host_exit = 0;
  result.passed = true;
  result.load_start = result.load_max = result.load_end = 0.5;
  const std::string text = SoakReportText(plan, result);
  EXPECT_THAT(text, HasSubstr("soak hold.yaml: 20 s, 2 cycles of 10 s; load average (1 min) 0.50 at start"));
  EXPECT_THAT(text, HasSubstr("  PASSED (report: out/s/soak.json)\n"));
  EXPECT_THAT(text, ::testing::Not(HasSubstr("the host exited")));
}

}  // namespace
}  // namespace graspbed::testbed
