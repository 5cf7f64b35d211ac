#include "testbed/soak_run.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "common/process.h"
#include "common/signal_log.h"
#include "testbed/scenario_config.h"

namespace graspbed::testbed {
namespace {

namespace fs = std::filesystem;

/// The host runs this much longer than the schedule: the final settle and the host's own start-up
/// fit in it with room on a loaded machine [s].
constexpr double kSoakHostTailS = 5.0;
/// The limit on the host's resident growth after the first tenth of the run [kB].
constexpr int64_t kSoakRssGrowthLimitKb = 1024;
/// The window of the RSS check starts after this share of the run (the first minute of ten).
constexpr double kSoakRssWarmupShare = 0.1;
/// Longest wait for the emulator's link: it loads the model before it makes the link [s].
constexpr int kSoakLinkTimeoutS = 120;

/// printf into a std::string (the soak's lines keep the layout they had on stdio).
__attribute__((format(printf, 1, 2))) std::string Format(const char* format, ...) {
  va_list args;
  va_start(args, format);
  va_list copy;
  va_copy(copy, args);
  const int size = std::vsnprintf(nullptr, 0, format, copy);
  va_end(copy);
  std::string text(static_cast<size_t>(std::max(size, 0)), '\0');
  std::vsnprintf(text.data(), text.size() + 1, format, args);
  va_end(args);
  return text;
}

/// A number as `std::ostream <<` writes it (the children's arguments).
std::string Number(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

nlohmann::json ReadJsonFile(const std::string& path, const std::string& what) {
  std::ifstream in(path);
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& error) {
    throw std::runtime_error("soak: " + what + " printed no JSON summary (" + path + "): " + error.what());
  }
}

std::string SoakBinary(const SoakOptions& options) {
  if (!options.binary.empty()) return options.binary;
  try {
    return common::SelfExecutablePath();
  } catch (const std::runtime_error& error) {
    throw std::runtime_error(std::string("soak: ") + error.what());
  }
}

/// Starts `graspbed emulate` with the schedule; returns its pid once it has made the link.
int StartEmulator(const SoakPlan& plan, const std::atomic<bool>& stop) {
  const SoakOptions& options = plan.options;
  const int emulator_pid =
      common::SpawnProcess({plan.binary, "emulate", "--link", plan.link, options.scenario, "--soak-cycles",
                            std::to_string(plan.schedule.cycles), "--soak-period", Number(options.period_s),
                            "--soak-downtime", Number(options.downtime_s), "--json"},
                           -1, options.out_dir + "/emulate.json", options.out_dir + "/emulate.log");
  const auto link_deadline = std::chrono::steady_clock::now() + std::chrono::seconds(kSoakLinkTimeoutS);
  while (!fs::exists(fs::symlink_status(plan.link))) {
    if (common::WaitExit(emulator_pid, 0.0) != -1) {
      throw std::runtime_error("soak: the emulator ended before it made " + plan.link + "; see " +
                               options.out_dir + "/emulate.log");
    }
    if (stop.load() || std::chrono::steady_clock::now() > link_deadline) {
      common::EndChild(emulator_pid);
      throw std::runtime_error("soak: no emulator link at " + plan.link + " after 120 s");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return emulator_pid;
}

/// Runs the host to its end (or until `stop`, then SIGTERM), sampling its resident size from outside
/// (/proc) and the machine's load; fills rss, host_exit, load_max and interrupted.
void RunHost(const SoakPlan& plan, const std::atomic<bool>& stop, std::ostream& progress,
             std::vector<hardware::RssSample>& rss, SoakResult& result) {
  const SoakOptions& options = plan.options;
  const auto host_start = std::chrono::steady_clock::now();
  const int host_pid =
      common::SpawnProcess({plan.binary, "run", options.scenario, "--backend", "serial", "--port", plan.link,
                            "--out", options.out_dir + "/host", "--no-plots", "--no-stdin-intent", "--json",
                            "--set", "duration_s=" + Number(plan.host_duration_s)},
                           -1, options.out_dir + "/host.json", options.out_dir + "/host.log");
  rss.reserve(static_cast<size_t>(plan.host_duration_s / options.rss_interval_s) + 64);
  double next_report_s = options.period_s;
  while (result.host_exit == -1) {
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - host_start).count();
    const int64_t kb = hardware::ReadResidentKb(host_pid);
    if (kb >= 0) rss.push_back({t, kb});
    result.load_max = std::max(result.load_max, common::LoadAverage1Min());
    if (t >= next_report_s && t <= options.duration_s + 1.0) {
      progress << Format("soak: %.0f / %g s, host resident %.1f MB, load average %.2f\n", t,
                         options.duration_s, kb / 1024.0, common::LoadAverage1Min());
      next_report_s += options.period_s;
    }
    if (stop.load() && !result.interrupted) {
      result.interrupted = true;
      ::kill(host_pid, SIGTERM);
    }
    result.host_exit = common::WaitExit(host_pid, options.rss_interval_s);
  }
}

uint64_t Count(const nlohmann::json& object, const char* key) { return object.value(key, uint64_t{0}); }

hardware::SoakDeviceCounts DeviceCounts(const nlohmann::json& emulator, int cycles) {
  hardware::SoakDeviceCounts device;
  device.frames_sent = Count(emulator, "frames_sent");
  device.frames_dropped = Count(emulator, "frames_dropped");
  device.frames_corrupted = Count(emulator, "frames_corrupted");
  device.frames_reordered = Count(emulator, "frames_reordered");
  device.frames_overflowed = Count(emulator, "frames_overflowed");
  device.frames_trailing = Count(emulator, "frames_trailing");
  device.garbage_packets = Count(emulator, "garbage_packets");
  device.connects = Count(emulator, "connects");
  device.vanishes = Count(emulator, "vanishes");
  device.settles_unconfirmed = Count(emulator, "settles_unconfirmed");
  device.cycles_planned = cycles;
  if (emulator.contains("soak")) {
    device.cycles_completed = emulator["soak"].value("cycles_completed", 0);
    device.final_settle_confirmed = emulator["soak"].value("final_settle_confirmed", false);
  }
  return device;
}

hardware::SoakHostCounts HostCounts(const nlohmann::json& bench) {
  hardware::SoakHostCounts host;
  host.frames = Count(bench, "frames");
  host.corrupt = Count(bench, "corrupt");
  host.dropped = Count(bench, "dropped");
  host.reordered = Count(bench, "reordered");
  host.unknown_packets = Count(bench, "unknown_packets");
  host.reconnects = Count(bench, "reconnects");
  host.sessions = Count(bench, "sessions");
  host.connected_at_end = bench.value("connected_at_end", false);
  return host;
}

/// soak.json's "device" and "host": the counts compared and a few more for the reader.
void AddCounts(const SoakResult& result, const nlohmann::json& emulator, const nlohmann::json& bench,
               nlohmann::json& report) {
  const hardware::SoakDeviceCounts& device = result.device;
  const hardware::SoakHostCounts& host = result.host;
  report["device"] = {{"frames_sent", device.frames_sent},
                      {"frames_dropped", device.frames_dropped},
                      {"frames_corrupted", device.frames_corrupted},
                      {"frames_reordered", device.frames_reordered},
                      {"frames_overflowed", device.frames_overflowed},
                      {"frames_trailing", device.frames_trailing},
                      {"garbage_packets", device.garbage_packets},
                      {"connects", device.connects},
                      {"vanishes", device.vanishes},
                      {"settles", Count(emulator, "settles")},
                      {"settles_unconfirmed", device.settles_unconfirmed},
                      {"cycles_completed", device.cycles_completed},
                      {"final_settle_confirmed", device.final_settle_confirmed},
                      {"watchdog_trips", Count(emulator, "watchdog_trips")}};
  report["host"] = {{"frames", host.frames},
                    {"corrupt", host.corrupt},
                    {"dropped", host.dropped},
                    {"reordered", host.reordered},
                    {"unknown_packets", host.unknown_packets},
                    {"reconnects", host.reconnects},
                    {"sessions", host.sessions},
                    {"stale_periods", Count(bench, "stale_periods")},
                    {"actuator_failures", Count(bench, "actuator_failures")},
                    {"connected_at_end", host.connected_at_end}};
}

nlohmann::json SoakReport(const SoakPlan& plan, const SoakResult& result, const nlohmann::json& emulator,
                          const nlohmann::json& bench, const std::vector<hardware::RssSample>& rss) {
  const SoakOptions& options = plan.options;
  const hardware::SoakVerdict& verdict = result.verdict;
  nlohmann::json report = {{"scenario", options.scenario},
                           {"duration_s", options.duration_s},
                           {"period_s", options.period_s},
                           {"cycles", plan.schedule.cycles},
                           {"host_duration_s", plan.host_duration_s},
                           {"host_exit", result.host_exit},
                           {"emulator_exit", result.emulator_exit},
                           {"comparable", verdict.comparable()},
                           {"not_comparable", verdict.not_comparable},
                           {"counters_exact", verdict.exact()},
                           {"passed", result.passed}};
  nlohmann::json comparisons = nlohmann::json::array();
  for (const hardware::SoakComparison& c : verdict.comparisons) {
    comparisons.push_back({{"counter", c.counter},
                           {"host", c.host},
                           {"expected", c.expected},
                           {"rule", c.rule},
                           {"equal", c.equal()}});
  }
  report["comparisons"] = comparisons;
  AddCounts(result, emulator, bench, report);
  const hardware::RssSummary& memory = result.memory;
  nlohmann::json samples = nlohmann::json::array();
  for (const hardware::RssSample& sample : rss) samples.push_back({sample.time_s, sample.resident_kb});
  report["rss"] = {{"window_from_s", kSoakRssWarmupShare * options.duration_s},
                   {"window_until_s", options.duration_s},
                   {"samples_in_window", memory.samples},
                   {"baseline_time_s", memory.baseline_time_s},
                   {"baseline_kb", memory.baseline_kb},
                   {"last_kb", memory.last_kb},
                   {"max_kb", memory.max_kb},
                   {"growth_kb", memory.growth_kb},
                   {"limit_kb", kSoakRssGrowthLimitKb},
                   {"flat", result.memory_flat},
                   {"first_sample_kb", rss.empty() ? int64_t{-1} : rss.front().resident_kb},
                   {"samples", samples}};
  report["load_average_1min"] = {
      {"start", result.load_start}, {"max", result.load_max}, {"end", result.load_end}};
  return report;
}

/// Reads both children's summaries and holds them against each other; the report in soak.json.
void Compare(const SoakPlan& plan, const std::vector<hardware::RssSample>& rss, SoakResult& result) {
  const SoakOptions& options = plan.options;
  const nlohmann::json emulator = ReadJsonFile(options.out_dir + "/emulate.json", "the emulator");
  const nlohmann::json host_summary =
      ReadJsonFile(options.out_dir + "/host.json", "the host (run --backend serial)");
  if (!host_summary.contains("bench"))
    throw std::runtime_error("soak: the host's summary has no bench counters");
  const nlohmann::json& bench = host_summary.at("bench");
  result.device = DeviceCounts(emulator, plan.schedule.cycles);
  result.host = HostCounts(bench);
  result.verdict = hardware::CompareSoakCounts(result.device, result.host);
  result.memory = hardware::SummariseRss(rss, kSoakRssWarmupShare * options.duration_s, options.duration_s);
  result.memory_flat = result.memory.samples >= 2 && result.memory.growth_kb < kSoakRssGrowthLimitKb;
  result.passed = result.verdict.exact() && result.memory_flat && result.host_exit == 0;
  result.report = SoakReport(plan, result, emulator, bench, rss);
  if (!options.keep_signals) fs::remove(options.out_dir + "/host/signals.csv");  // 1-2 GB for 10 min
  common::WriteFileAtomic(options.out_dir + "/soak.json", result.report.dump(2) + "\n");
}

}  // namespace

SoakPlan PlanSoak(const SoakOptions& options) {
  const double cycles_exact = options.duration_s / options.period_s;
  const int cycles = static_cast<int>(std::lround(cycles_exact));
  if (cycles < 1 || std::abs(cycles_exact - cycles) > 1e-9) {
    std::ostringstream message;
    message << "soak: --duration " << options.duration_s << " must be a whole number (>= 1) of --period "
            << options.period_s << " (one disconnect per period)";
    throw std::invalid_argument(message.str());
  }
  SoakPlan plan;
  plan.options = options;
  plan.schedule.cycles = cycles;
  plan.schedule.period_s = options.period_s;
  plan.schedule.downtime_s = options.downtime_s;
  plan.schedule.Validate();
  plan.link = options.link.empty() ? "/tmp/graspbed-soak-" + std::to_string(::getpid()) : options.link;
  plan.host_duration_s = options.duration_s + kSoakHostTailS;
  // Refused here (exit 2) rather than in a child: a bad file, a duration the loader refuses (over
  // 3600 s, or a signal log over its bound). A script the bench cannot play is refused by the host.
  LoadScenario(
      options.scenario,
      {{"serial.port", plan.link}, {"backend", "serial"}, {"duration_s", Number(plan.host_duration_s)}});
  if (fs::exists(fs::symlink_status(plan.link))) {
    throw std::invalid_argument("soak: --link " + plan.link + " exists already (another emulator?)");
  }
  fs::create_directories(options.out_dir);
  plan.binary = SoakBinary(options);
  return plan;
}

SoakResult RunSoak(const SoakPlan& plan, const std::atomic<bool>& stop, std::ostream& progress) {
  const SoakOptions& options = plan.options;
  SoakResult result;
  result.load_start = common::LoadAverage1Min();
  result.load_max = result.load_start;
  const int emulator_pid = StartEmulator(plan, stop);
  progress << Format(
      "soak: %d cycles of %g s (%g s), host `run %s --backend serial --port %s` for %g s; load average "
      "%.2f\n",
      plan.schedule.cycles, options.period_s, options.duration_s, options.scenario.c_str(), plan.link.c_str(),
      plan.host_duration_s, result.load_start);
  std::vector<hardware::RssSample> rss;
  RunHost(plan, stop, progress, rss, result);
  // The emulator ends when the host stops streaming; it prints its summary then. A host that was
  // refused never streamed.
  result.emulator_exit = common::WaitExit(emulator_pid, result.host_exit == 0 ? 30.0 : 2.0);
  if (result.emulator_exit == -1) result.emulator_exit = common::EndChild(emulator_pid);
  result.load_end = common::LoadAverage1Min();
  if (result.interrupted) return result;
  if (result.host_exit == 2) {  // bad input to `run`: its message, as ours
    std::ifstream log(options.out_dir + "/host.log");
    std::string message((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
    while (!message.empty() && message.back() == '\n') message.pop_back();
    throw std::invalid_argument("soak: the host (run --backend serial) refused to start: " + message);
  }
  Compare(plan, rss, result);
  return result;
}

std::string SoakReportText(const SoakPlan& plan, const SoakResult& result) {
  const SoakOptions& options = plan.options;
  const hardware::SoakDeviceCounts& device = result.device;
  const hardware::RssSummary& memory = result.memory;
  std::string text =
      Format("soak %s: %g s, %d cycles of %g s; load average (1 min) %.2f at start, %.2f max, %.2f at end\n",
             options.scenario.c_str(), options.duration_s, plan.schedule.cycles, options.period_s,
             result.load_start, result.load_max, result.load_end);
  text += Format("  %-16s %10s %10s  %s\n", "host counter", "host", "expected", "from the device's counts");
  for (const hardware::SoakComparison& c : result.verdict.comparisons) {
    text += Format("  %-16s %10llu %10llu  %s%s\n", c.counter.c_str(),
                   static_cast<unsigned long long>(c.host), static_cast<unsigned long long>(c.expected),
                   c.rule.c_str(), c.equal() ? "" : "   <-- DIFFERS");
  }
  text += Format(
      "  device: %llu frames sent, %llu corrupted, %llu dropped, %llu reordered, %llu garbage blocks, "
      "%llu disconnects; %llu overflowed (the host did not read in time; in dropped)\n",
      static_cast<unsigned long long>(device.frames_sent),
      static_cast<unsigned long long>(device.frames_corrupted),
      static_cast<unsigned long long>(device.frames_dropped),
      static_cast<unsigned long long>(device.frames_reordered),
      static_cast<unsigned long long>(device.garbage_packets),
      static_cast<unsigned long long>(device.vanishes),
      static_cast<unsigned long long>(device.frames_overflowed));
  text += Format(
      "  host resident: %.1f MB at %.0f s, %.1f MB at the end of the window, %.1f MB max: growth %lld kB "
      "(limit %lld kB, %zu samples)\n",
      memory.baseline_kb / 1024.0, memory.baseline_time_s, memory.last_kb / 1024.0, memory.max_kb / 1024.0,
      static_cast<long long>(memory.growth_kb), static_cast<long long>(kSoakRssGrowthLimitKb),
      memory.samples);
  for (const std::string& reason : result.verdict.not_comparable)
    text += Format("  not comparable: %s\n", reason.c_str());
  if (result.host_exit != 0) {
    text +=
        Format("  the host exited with %d (see %s/host.log)\n", result.host_exit, options.out_dir.c_str());
  }
  text +=
      Format("  %s (report: %s/soak.json)\n", result.passed ? "PASSED" : "FAILED", options.out_dir.c_str());
  return text;
}

}  // namespace graspbed::testbed
