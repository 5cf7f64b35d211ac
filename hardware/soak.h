#pragma once
/// The soak (docs/hardware.md, "The soak"): a DeviceEmulator injects a fixed schedule of link faults
/// (corrupted, dropped, reordered and truncated frames, garbage, a disconnect and reconnect every
/// period) into a host's session for minutes; afterwards the host's counters are held against what
/// the device injected, exactly, and the host's resident memory must have stayed flat.
/// SoakInjector drives the emulator (`graspbed emulate --soak-*`); CompareSoakCounts and
/// SummariseRss are the checks of `graspbed soak`, plain functions a unit test can reach.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "hardware/device_emulator.h"

namespace graspbed::hardware {

/// The fault schedule. `cycles` cycles of `period_s` each, on the steady clock from the host's first
/// stream start. In each cycle, at fixed fractions of the period (kSoakFaults below): 3 frames
/// corrupted, 5 dropped, 2 frames each swapped with the next, 1 frame truncated by 7 bytes, 1 frame
/// held back by 3, one delimited block of 40 garbage bytes; at 0.80 the device settles
/// (DeviceEmulator::Settle) and vanishes, and returns `downtime_s` later. After the last cycle it
/// settles once more and keeps the stream paused until the host ends the session, so that every
/// frame sent has been read when the counters are compared.
struct SoakSchedule {
  double period_s = 60.0;         ///< one cycle of faults and one disconnect + reconnect [s]
  int cycles = 10;                ///< cycles before the final settle
  double downtime_s = 0.5;        ///< how long the device stays away at each disconnect [s]
  double settle_timeout_s = 5.0;  ///< longest wait for the host to answer a settle's HELLO [s]

  /// @throws common::ConfigError naming the field and value (period_s >= 5 s, so the faults of a
  /// cycle are at least 0.5 s apart; cycles >= 1; 0 < downtime_s <= 0.1 period_s; timeout > 0).
  void Validate() const;
};

/// One kind of fault of a cycle: at `fraction` of the period, `count` times `size` (frames, bytes or
/// frames later, by kind).
struct SoakFault {
  enum class Kind { kCorrupt, kDrop, kReorder, kTruncate, kGarbage };
  Kind kind;
  double fraction;
  int count;
  int size;
};
/// The faults of every cycle, in time order; the disconnect follows at kSoakVanishFraction.
inline constexpr SoakFault kSoakFaults[] = {
    {SoakFault::Kind::kCorrupt, 0.15, 3, 0}, {SoakFault::Kind::kDrop, 0.25, 5, 0},
    {SoakFault::Kind::kReorder, 0.35, 2, 1}, {SoakFault::Kind::kTruncate, 0.45, 1, 7},
    {SoakFault::Kind::kReorder, 0.55, 1, 3}, {SoakFault::Kind::kGarbage, 0.65, 1, 40},
};
inline constexpr double kSoakVanishFraction = 0.80;

/// Where the injector is.
struct SoakProgress {
  int cycles_completed = 0;             ///< cycles whose disconnect and return are done
  bool done = false;                    ///< the final settle was attempted
  bool final_settle_confirmed = false;  ///< ... and the host confirmed it
};

/// Runs a SoakSchedule against `emulator` on a thread of its own.
class SoakInjector {
 public:
  /// The emulator must outlive the injector. @throws common::ConfigError from schedule.Validate().
  SoakInjector(DeviceEmulator& emulator, const SoakSchedule& schedule);
  ~SoakInjector();
  SoakInjector(const SoakInjector&) = delete;
  SoakInjector& operator=(const SoakInjector&) = delete;

  /// Starts the thread; the schedule's clock starts at the emulator's first stream start.
  void Start();
  /// Stops the thread at once (the stream stays as it is). Safe to call twice.
  void Stop();
  SoakProgress progress() const;
  const SoakSchedule& schedule() const { return schedule_; }

 private:
  using Clock = std::chrono::steady_clock;
  void Run();
  /// Sleeps until `when`; false when Stop() came first.
  bool SleepUntil(Clock::time_point when);
  void Inject(const SoakFault& fault);

  DeviceEmulator& emulator_;
  const SoakSchedule schedule_;
  std::thread thread_;
  mutable std::mutex mutex_;  // guards stop_ and progress_
  std::condition_variable wake_;
  bool stop_ = false;
  SoakProgress progress_;
};

/// The device's side of a soak (`graspbed emulate --json`: its counts and "soak" object).
struct SoakDeviceCounts {
  uint64_t frames_sent = 0;
  uint64_t frames_dropped = 0;
  uint64_t frames_corrupted = 0;
  uint64_t frames_reordered = 0;
  uint64_t frames_overflowed = 0;
  uint64_t garbage_packets = 0;
  uint64_t frames_trailing = 0;  ///< EmulatorStats::frames_trailing at the end
  uint64_t connects = 0;
  uint64_t vanishes = 0;
  uint64_t settles_unconfirmed = 0;
  int cycles_planned = 0;
  int cycles_completed = 0;
  bool final_settle_confirmed = false;
};

/// The host's side (`graspbed run --backend serial --json`: its "bench" object).
struct SoakHostCounts {
  uint64_t frames = 0;
  uint64_t corrupt = 0;
  uint64_t dropped = 0;
  uint64_t reordered = 0;
  uint64_t unknown_packets = 0;
  uint64_t reconnects = 0;
  uint64_t sessions = 0;
  bool connected_at_end = false;
};

/// One host counter against what the device's counts say it must be.
struct SoakComparison {
  std::string counter;  ///< the host's counter
  uint64_t host = 0;
  uint64_t expected = 0;
  std::string rule;  ///< how `expected` follows from the device's counts
  bool equal() const { return host == expected; }
};

struct SoakVerdict {
  std::vector<SoakComparison> comparisons;
  /// Why the counts cannot be held against each other (a settle the host did not confirm, the
  /// schedule not run to its end, the device gone at the end); empty when they can.
  std::vector<std::string> not_comparable;
  bool comparable() const { return not_comparable.empty(); }
  /// Comparable, and every counter equal.
  bool exact() const;
};

/// The exact comparison. Every frame the device sent intact and in order is a host frame; every
/// corrupted or truncated frame and every garbage block is one corrupt packet; every sequence
/// number the host did not get in order is dropped: the frames DropFrames skipped, the corrupted
/// ones, the late ones (their sequence numbers were missing when the newer frame came) and those
/// the device's FIFO overflowed with (the host did not read in time: a fault of the machine's pace,
/// not of the schedule, reported apart), less those after the last frame sent intact (no later frame
/// showed the host their gap); every late frame is reordered; every disconnect one
/// reconnect and one more connect; one device session; no unknown packet.
SoakVerdict CompareSoakCounts(const SoakDeviceCounts& device, const SoakHostCounts& host);

/// One resident-memory sample of a process.
struct RssSample {
  double time_s = 0.0;      ///< since the process started [s]
  int64_t resident_kb = 0;  ///< VmRSS [kB]
};

struct RssSummary {
  size_t samples = 0;          ///< in the window
  double baseline_time_s = 0;  ///< time of the window's first sample [s]
  int64_t baseline_kb = 0;     ///< its resident size [kB]
  int64_t last_kb = 0;         ///< the window's last sample [kB]
  int64_t max_kb = 0;          ///< the window's largest [kB]
  int64_t growth_kb = 0;       ///< max_kb - baseline_kb [kB]
};

/// The samples with time in [from_s, until_s]: growth is the largest minus the first of them. No
/// sample in the window: samples = 0, the rest 0.
RssSummary SummariseRss(const std::vector<RssSample>& samples, double from_s, double until_s);

/// VmRSS of process `pid` [kB] from /proc/PID/status; -1 when it cannot be read (the process ended).
int64_t ReadResidentKb(int pid);

}  // namespace graspbed::hardware
