#pragma once
/// `graspbed soak` (docs/hardware.md, "The soak"): `graspbed emulate` with the soak's fault schedule
/// and `graspbed run --backend serial` on the same scenario, as two child processes of the graspbed
/// executable; afterwards the host's counters are held against what the device injected, exactly
/// (hardware::CompareSoakCounts), and the host's resident memory, sampled from outside while it ran,
/// must have stayed flat (hardware::SummariseRss). PlanSoak checks the options and the scenario
/// before anything starts; RunSoak runs both children, writes OUT/soak.json and returns the verdict.

#include <atomic>
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hardware/soak.h"

namespace graspbed::testbed {

/// What `graspbed soak` takes on its command line (messages name these options).
struct SoakOptions {
  std::string scenario;              ///< scenario YAML for both sides (close/open/idle script)
  double duration_s = 600.0;         ///< length of the fault schedule [s], a whole number of periods
  double period_s = 60.0;            ///< one cycle of faults and one disconnect [s]
  double downtime_s = 0.5;           ///< how long the device stays away each time [s]
  std::string link;                  ///< emulator link path; empty: /tmp/graspbed-soak-PID
  std::string out_dir = "out/soak";  ///< soak.json, both children's summaries and logs
  double rss_interval_s = 1.0;       ///< host RSS sampling interval [s]
  bool keep_signals = false;         ///< keep the host's signals.csv (a row per tick: ~2 GB for 10 min)
  /// The graspbed executable the children run; empty: this process's own (/proc/self/exe).
  std::string binary;
};

/// A soak checked and ready to start.
struct SoakPlan {
  SoakOptions options;
  hardware::SoakSchedule schedule;  ///< cycles = duration_s / period_s
  std::string link;                 ///< the emulator's link (options.link or the default)
  double host_duration_s = 0.0;     ///< the host runs the schedule and a tail for the final settle [s]
  std::string binary;               ///< the graspbed executable for both children
};

/// Checks the schedule (a whole number of periods, SoakSchedule::Validate), the scenario as the host
/// will load it and that the link is free; creates options.out_dir.
/// @throws std::invalid_argument (common::ConfigError) naming the option or file, line and key.
SoakPlan PlanSoak(const SoakOptions& options);

/// The outcome of a soak.
struct SoakResult {
  /// `stop` came: the host was ended and nothing was compared or written; the rest is unset.
  bool interrupted = false;
  int host_exit = -1;      ///< the host's exit code (128 + signal when killed)
  int emulator_exit = -1;  ///< the emulator's (after SIGTERM/SIGKILL when it did not end itself)
  double load_start = -1.0, load_max = -1.0, load_end = -1.0;  ///< 1-min load average (-1 unknown)
  hardware::SoakDeviceCounts device;                           ///< from the emulator's summary
  hardware::SoakHostCounts host;                               ///< from the host's "bench"
  hardware::SoakVerdict verdict;
  hardware::RssSummary memory;  ///< the host's resident size after the first tenth of the run
  bool memory_flat = false;     ///< two samples at least, and growth under the limit (1 MB)
  bool passed = false;          ///< counters exact, memory flat, host exit 0
  nlohmann::json report;        ///< what OUT/soak.json holds
};

/// Runs the soak of `plan`: the emulator, then the host once the link exists; samples the host's
/// resident size every rss_interval_s until it exits; compares. Progress lines go to `progress`. A
/// set `stop` ends the host (SIGTERM) and returns an interrupted result. Blocks for about
/// duration_s + 5 s.
/// @throws std::invalid_argument when the host refused its input (exit 2; its message quoted);
/// std::runtime_error when a child could not start, made no link or printed no summary.
SoakResult RunSoak(const SoakPlan& plan, const std::atomic<bool>& stop, std::ostream& progress);

/// The table `soak` prints without --json: the host's counters against the expected, the device's
/// counts, the host's memory and the verdict.
std::string SoakReportText(const SoakPlan& plan, const SoakResult& result);

}  // namespace graspbed::testbed
