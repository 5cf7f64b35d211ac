#include "hardware/soak.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>

#include "common/config_error.h"

namespace graspbed::hardware {

void SoakSchedule::Validate() const {
  using common::Require;
  Require(period_s >= 5.0, "soak.period_s", period_s,
          "must be >= 5 s (the faults of a cycle are 0.1 period apart)");
  Require(cycles >= 1, "soak.cycles", cycles, "must be >= 1");
  Require(downtime_s > 0.0 && downtime_s <= 0.1 * period_s, "soak.downtime_s", downtime_s,
          "must be > 0 and <= 0.1 x period_s (the device is back before the next cycle)");
  Require(settle_timeout_s > 0.0, "soak.settle_timeout_s", settle_timeout_s, "must be > 0");
}

SoakInjector::SoakInjector(DeviceEmulator& emulator, const SoakSchedule& schedule)
    : emulator_(emulator), schedule_(schedule) {
  schedule_.Validate();
}

SoakInjector::~SoakInjector() { Stop(); }

void SoakInjector::Start() {
  if (thread_.joinable()) return;
  thread_ = std::thread([this] { Run(); });
}

void SoakInjector::Stop() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

SoakProgress SoakInjector::progress() const {
  std::lock_guard lock(mutex_);
  return progress_;
}

bool SoakInjector::SleepUntil(Clock::time_point when) {
  std::unique_lock lock(mutex_);
  return !wake_.wait_until(lock, when, [this] { return stop_; });
}

void SoakInjector::Inject(const SoakFault& fault) {
  switch (fault.kind) {
    case SoakFault::Kind::kCorrupt:
      emulator_.CorruptFrames(fault.count);
      break;
    case SoakFault::Kind::kDrop:
      emulator_.DropFrames(fault.count);
      break;
    case SoakFault::Kind::kReorder:
      emulator_.ReorderFrames(fault.count, fault.size);
      break;
    case SoakFault::Kind::kTruncate:
      emulator_.TruncateNextFrame(fault.size);
      break;
    case SoakFault::Kind::kGarbage:
      for (int i = 0; i < fault.count; ++i) emulator_.InjectGarbage(fault.size, /*delimited=*/true);
      break;
  }
}

void SoakInjector::Run() {
  // The clock starts when the host first asks for frames.
  while (emulator_.stats().stream_starts == 0) {
    if (!SleepUntil(Clock::now() + std::chrono::milliseconds(10))) return;
  }
  const Clock::time_point start = Clock::now();
  const auto at = [&](int cycle, double fraction) {
    return start + std::chrono::duration_cast<Clock::duration>(
                       std::chrono::duration<double>((cycle + fraction) * schedule_.period_s));
  };
  for (int cycle = 0; cycle < schedule_.cycles; ++cycle) {
    for (const SoakFault& fault : kSoakFaults) {
      if (!SleepUntil(at(cycle, fault.fraction))) return;
      Inject(fault);
    }
    if (!SleepUntil(at(cycle, kSoakVanishFraction))) return;
    // Nothing in flight when the device goes: the frames the host has not read would be lost
    // without either side being able to say how many (emulator stats count what was unconfirmed).
    emulator_.Settle(schedule_.settle_timeout_s);
    emulator_.Vanish();
    const Clock::time_point back = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                      std::chrono::duration<double>(schedule_.downtime_s));
    if (!SleepUntil(back)) return;
    emulator_.Return();
    emulator_.PauseFrames(false);  // the stream goes on once the host has answered the HELLO
    std::lock_guard lock(mutex_);
    ++progress_.cycles_completed;
  }
  if (!SleepUntil(at(schedule_.cycles, 0.0))) return;
  const bool confirmed = emulator_.Settle(schedule_.settle_timeout_s);
  std::lock_guard lock(mutex_);
  progress_.done = true;
  progress_.final_settle_confirmed = confirmed;
}

bool SoakVerdict::exact() const {
  if (!comparable()) return false;
  return std::all_of(comparisons.begin(), comparisons.end(),
                     [](const SoakComparison& c) { return c.equal(); });
}

SoakVerdict CompareSoakCounts(const SoakDeviceCounts& device, const SoakHostCounts& host) {
  SoakVerdict verdict;
  if (device.cycles_completed != device.cycles_planned) {
    verdict.not_comparable.push_back("the schedule ran " + std::to_string(device.cycles_completed) + " of " +
                                     std::to_string(device.cycles_planned) +
                                     " cycles (the host or the emulator ended early)");
  }
  if (!device.final_settle_confirmed) {
    verdict.not_comparable.push_back(
        "the final settle was not confirmed by the host: frames sent at the end may not have been read");
  }
  if (device.settles_unconfirmed > 0) {
    verdict.not_comparable.push_back(
        std::to_string(device.settles_unconfirmed) +
        " settle(s) before a disconnect not confirmed by the host (it did not answer the HELLO within the "
        "timeout, or flushed one when it opened the port): frames in flight then are lost uncounted by the "
        "device");
  }
  if (!host.connected_at_end)
    verdict.not_comparable.push_back("the device was not connected at the host's end");

  auto add = [&](const char* counter, uint64_t host_value, uint64_t expected, const char* rule) {
    verdict.comparisons.push_back({counter, host_value, expected, rule});
  };
  add("frames", host.frames, device.frames_sent - device.frames_corrupted - device.frames_reordered,
      "frames_sent - frames_corrupted - frames_reordered");
  add("corrupt", host.corrupt, device.frames_corrupted + device.garbage_packets,
      "frames_corrupted + garbage_packets");
  add("dropped", host.dropped,
      device.frames_dropped + device.frames_corrupted + device.frames_reordered + device.frames_overflowed -
          device.frames_trailing,
      "frames_dropped + frames_corrupted + frames_reordered + frames_overflowed - frames_trailing");
  add("reordered", host.reordered, device.frames_reordered, "frames_reordered");
  add("reconnects", host.reconnects, device.vanishes, "vanishes");
  add("reconnects", host.reconnects, device.connects > 0 ? device.connects - 1 : 0, "connects - 1");
  add("sessions", host.sessions, 1, "1 (no reboot)");
  add("unknown_packets", host.unknown_packets, 0, "0 (none injected)");
  return verdict;
}

RssSummary SummariseRss(const std::vector<RssSample>& samples, double from_s, double until_s) {
  RssSummary summary;
  for (const RssSample& sample : samples) {
    if (sample.time_s < from_s || sample.time_s > until_s || sample.resident_kb < 0) continue;
    if (summary.samples == 0) {
      summary.baseline_time_s = sample.time_s;
      summary.baseline_kb = sample.resident_kb;
      summary.max_kb = sample.resident_kb;
    }
    ++summary.samples;
    summary.last_kb = sample.resident_kb;
    summary.max_kb = std::max(summary.max_kb, sample.resident_kb);
  }
  summary.growth_kb = summary.max_kb - summary.baseline_kb;
  return summary;
}

int64_t ReadResidentKb(int pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(status, line)) {
    long long kb = 0;
    if (std::sscanf(line.c_str(), "VmRSS: %lld kB", &kb) == 1) return kb;
  }
  return -1;  // gone, or a zombie (no VmRSS line)
}

}  // namespace graspbed::hardware
