// The soak's pure parts: the late-frame rule of docs/protocol.md ("Late frames"), the exact
// comparison of the host's counters with the device's (CompareSoakCounts) and the resident-memory
// summary (SummariseRss). The soak itself runs in soak_test.cc.
#include <gtest/gtest.h>

#include <unistd.h>

#include <string>
#include <vector>

#include "common/config_error.h"
#include "hardware/serial_link.h"
#include "hardware/soak.h"

namespace graspbed::hardware {
namespace {

constexpr int64_t kPeriodUs = 1000;  // 1 kHz

TEST(FrameOrder, NextGapLateAndRestart) {
  EXPECT_EQ(ClassifyFrameOrder(1, kPeriodUs, kPeriodUs), FrameOrder::kNext);
  EXPECT_EQ(ClassifyFrameOrder(6, 6 * kPeriodUs, kPeriodUs), FrameOrder::kGap);
  // One behind (a swapped pair) and the window's end: late, not a gap of 65535.
  EXPECT_EQ(ClassifyFrameOrder(-1, -kPeriodUs, kPeriodUs), FrameOrder::kLate);
  EXPECT_EQ(ClassifyFrameOrder(-kLateFrameWindow, -kLateFrameWindow * kPeriodUs, kPeriodUs),
            FrameOrder::kLate);
  // Beyond the window, in sequence or in time, or not back in time: the device restarted.
  EXPECT_EQ(ClassifyFrameOrder(-kLateFrameWindow - 1, -(kLateFrameWindow + 1) * kPeriodUs, kPeriodUs),
            FrameOrder::kRestart);
  EXPECT_EQ(ClassifyFrameOrder(-3, -5'000'000, kPeriodUs), FrameOrder::kRestart);  // time went back 5 s
  EXPECT_EQ(ClassifyFrameOrder(-3, 2 * kPeriodUs, kPeriodUs), FrameOrder::kRestart);
  EXPECT_EQ(ClassifyFrameOrder(0, 0, kPeriodUs), FrameOrder::kRestart);  // a duplicate
  EXPECT_EQ(ClassifyFrameOrder(4, -kPeriodUs, kPeriodUs), FrameOrder::kRestart);
}

// One soak cycle's worth of faults as the device counts them, and the host that counted them right.
SoakDeviceCounts OneCycleDevice() {
  SoakDeviceCounts device;
  device.frames_sent = 10'000;
  device.frames_dropped = 5;
  device.frames_corrupted = 4;  // 3 corrupted + 1 truncated
  device.frames_reordered = 3;
  device.frames_overflowed = 7;
  device.garbage_packets = 1;
  device.connects = 2;
  device.vanishes = 1;
  device.cycles_planned = 1;
  device.cycles_completed = 1;
  device.final_settle_confirmed = true;
  return device;
}

SoakHostCounts ExactHost() {
  SoakHostCounts host;
  host.frames = 10'000 - 4 - 3;
  host.corrupt = 4 + 1;
  host.dropped = 5 + 4 + 3 + 7;
  host.reordered = 3;
  host.reconnects = 1;
  host.sessions = 1;
  host.connected_at_end = true;
  return host;
}

TEST(SoakCheck, ExactCountsPass) {
  const SoakVerdict verdict = CompareSoakCounts(OneCycleDevice(), ExactHost());
  EXPECT_TRUE(verdict.comparable());
  EXPECT_TRUE(verdict.exact());
  for (const SoakComparison& c : verdict.comparisons) EXPECT_TRUE(c.equal()) << c.counter << " " << c.rule;
}

TEST(SoakCheck, ALateFrameTakenForNewDataOrAHugeGapFails) {
  SoakHostCounts host = ExactHost();
  host.reordered = 2;  // one late frame was used as new data
  host.frames += 1;
  SoakVerdict verdict = CompareSoakCounts(OneCycleDevice(), host);
  EXPECT_FALSE(verdict.exact());
  int differing = 0;
  for (const SoakComparison& c : verdict.comparisons) differing += c.equal() ? 0 : 1;
  EXPECT_EQ(differing, 2);  // frames and reordered

  host = ExactHost();
  host.dropped += 65535;  // a swapped pair read as a wrap-around gap
  EXPECT_FALSE(CompareSoakCounts(OneCycleDevice(), host).exact());
}

TEST(SoakCheck, FramesAfterTheLastIntactOneAreNoGapTheHostCouldSee) {
  SoakDeviceCounts device = OneCycleDevice();
  device.frames_overflowed += 2;  // the host fell behind just before the final settle
  device.frames_trailing = 2;
  EXPECT_TRUE(CompareSoakCounts(device, ExactHost()).exact());
}

TEST(SoakCheck, AnUnconfirmedSettleOrAnUnfinishedScheduleIsNotComparable) {
  SoakDeviceCounts device = OneCycleDevice();
  device.settles_unconfirmed = 1;
  SoakVerdict verdict = CompareSoakCounts(device, ExactHost());
  EXPECT_FALSE(verdict.comparable());
  EXPECT_FALSE(verdict.exact());
  ASSERT_EQ(verdict.not_comparable.size(), 1u);
  EXPECT_NE(verdict.not_comparable[0].find("not confirmed"), std::string::npos) << verdict.not_comparable[0];

  device = OneCycleDevice();
  device.cycles_completed = 0;
  device.final_settle_confirmed = false;
  verdict = CompareSoakCounts(device, ExactHost());
  ASSERT_EQ(verdict.not_comparable.size(), 2u);
  EXPECT_NE(verdict.not_comparable[0].find("ran 0 of 1 cycles"), std::string::npos)
      << verdict.not_comparable[0];
}

TEST(SoakCheck, RssGrowthIsTheWindowsLargestOverItsFirst) {
  const std::vector<RssSample> samples = {{0.5, 1000}, {1.0, 9000}, {2.0, 9100},
                                          {3.0, 9900}, {4.0, 9200}, {9.0, 20000}};
  const RssSummary summary = SummariseRss(samples, 1.0, 4.0);
  EXPECT_EQ(summary.samples, 4u);
  EXPECT_EQ(summary.baseline_time_s, 1.0);
  EXPECT_EQ(summary.baseline_kb, 9000);
  EXPECT_EQ(summary.max_kb, 9900);
  EXPECT_EQ(summary.last_kb, 9200);
  EXPECT_EQ(summary.growth_kb, 900);
  EXPECT_EQ(SummariseRss(samples, 10.0, 20.0).samples, 0u);
}

TEST(SoakCheck, ReadsThisProcesssResidentSize) {
  EXPECT_GT(ReadResidentKb(getpid()), 0);
  EXPECT_EQ(ReadResidentKb(-5), -1);
}

TEST(SoakCheck, ScheduleRefusesAPeriodTooShortForItsFaults) {
  SoakSchedule schedule;
  schedule.period_s = 2.0;
  try {
    schedule.Validate();
    FAIL() << "a 2 s period was accepted";
  } catch (const common::ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("soak.period_s"), std::string::npos) << error.what();
  }
  schedule.period_s = 10.0;
  schedule.downtime_s = 2.0;
  EXPECT_THROW(schedule.Validate(), common::ConfigError);
}

}  // namespace
}  // namespace graspbed::hardware
