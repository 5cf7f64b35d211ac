#include "testbed/oracle.h"

#include <dlfcn.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <map>
#include <mutex>
#include <sstream>

#include "testbed/run_outputs.h"
#include "testbed/runner.h"

namespace graspbed::testbed {
namespace {

std::string Hex(uint64_t value) {
  char buffer[17];
  std::snprintf(buffer, sizeof(buffer), "%016llx", static_cast<unsigned long long>(value));
  return buffer;
}

std::string Number(double value, const char* format = "%.3g") {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

/// One constant_grip run at `setpoint_n` and whether it held.
OracleStep RunStep(const ScenarioConfig& config, double setpoint_n, const std::atomic<bool>* stop) {
  RunOptions options;
  options.oracle = OracleMode::kNever;
  options.stop = stop;
  return JudgeOracleStep(setpoint_n, RunScenario(OracleStepConfig(config, setpoint_n), options));
}

/// Lightest setpoint the search halves down to when nothing above the first guess holds [N].
constexpr double kLowestSetpointN = 0.1;

/// Bisection between a setpoint that does not hold and one that does.
OracleSearch Search(const ScenarioConfig& config, const OracleOptions& options) {
  OracleSearch search;
  search.stall_pinch_n = StallPinchForceN(config);
  const auto stopped = [&] { return options.stop != nullptr && options.stop->load(); };
  const auto run = [&](double setpoint_n) {
    search.steps.push_back(RunStep(config, setpoint_n, options.stop));
    return search.steps.back();
  };
  // Bracket: from the first guess, double until a grip holds (up to the stall pinch).
  double low_n = 0.0;
  double high_n = std::min(options.first_guess_n, search.stall_pinch_n);
  std::optional<OracleStep> best;
  for (;;) {
    const OracleStep step = run(high_n);
    if (stopped()) break;
    if (step.held) {
      best = step;
      break;
    }
    low_n = high_n;
    if (high_n >= search.stall_pinch_n) break;
    high_n = std::min(2.0 * high_n, search.stall_pinch_n);
  }
  const std::string stall_outcome = search.steps.back().outcome;
  // Nothing from the first guess up held. An object a firmer squeeze pushes out of the pinch (a
  // soft one the pads sink into) may still be held lighter: halve down from the first guess, and
  // once one holds keep halving to the lightest that still does, so the bisection below brackets it.
  if (!best && !stopped()) {
    low_n = 0.0;
    for (double setpoint_n = 0.5 * options.first_guess_n; setpoint_n >= kLowestSetpointN && !stopped();
         setpoint_n *= 0.5) {
      const OracleStep step = run(setpoint_n);
      if (step.held) {
        best = step;
        high_n = setpoint_n;
      } else if (best) {
        low_n = setpoint_n;
        break;
      }
    }
  }
  if (!best) {
    search.completed = !stopped();
    search.grip.reason = !search.completed ? "interrupted"
                                           : "not held at the motor's stall pinch of " +
                                                 Number(search.stall_pinch_n) + " N (" + stall_outcome +
                                                 ") nor at any grip halved down to " +
                                                 Number(kLowestSetpointN) + " N";
    return search;
  }
  while (!stopped() &&
         high_n - low_n > std::max(options.absolute_resolution_n, options.relative_resolution * high_n)) {
    const double middle_n = 0.5 * (low_n + high_n);
    const OracleStep step = run(middle_n);
    if (step.held) {
      high_n = middle_n;
      best = step;
    } else {
      low_n = middle_n;
    }
  }
  search.completed = !stopped();
  search.grip.grip_n = best->mean_grip_n;
  search.setpoint_n = best->setpoint_n;
  return search;
}

std::atomic<bool> disk_cache_off{false};

/// The file holding this code (the executable, or the Python module) with its size and modification
/// time: a rebuild changes it, so searches cached by another build are not read.
const std::string& BuildIdentity() {
  static const std::string identity = [] {
    Dl_info info{};
    std::string code = "/proc/self/exe";  // the executable, when dladdr does not name a file that exists
    struct stat status {};
    if (dladdr(reinterpret_cast<const void*>(&BuildIdentity), &info) != 0 && info.dli_fname != nullptr &&
        ::stat(info.dli_fname, &status) == 0) {
      code = info.dli_fname;
    } else if (::stat(code.c_str(), &status) != 0) {
      return std::string("unknown build");
    }
    return code + " " + std::to_string(status.st_size) + " " + std::to_string(status.st_mtim.tv_sec) + "." +
           std::to_string(status.st_mtim.tv_nsec);
  }();
  return identity;
}

nlohmann::json SearchJson(const OracleSearch& search);
OracleSearch SearchFromJson(const nlohmann::json& json);

/// A search stored under `hash` in the disk cache; nullopt when absent or unreadable (then it is
/// searched again and rewritten).
std::optional<OracleSearch> ReadDiskCache(const std::string& dir, const std::string& hash) {
  std::ifstream file(dir + "/" + hash + ".json");
  if (!file) return std::nullopt;
  const nlohmann::json json = nlohmann::json::parse(file, nullptr, /*allow_exceptions=*/false);
  if (json.is_discarded()) return std::nullopt;
  try {
    return SearchFromJson(json);
  } catch (const nlohmann::json::exception&) {
    return std::nullopt;
  }
}

/// Stores `search` (common::WriteFileAtomic: a reader never sees half a file). A cache that cannot be
/// written is no error: the search stands.
void WriteDiskCache(const std::string& dir, const OracleSearch& search) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  try {
    common::WriteFileAtomic(dir + "/" + search.config_hash + ".json", SearchJson(search).dump() + "\n");
  } catch (const std::runtime_error&) {
  }
}

struct Cache {
  std::mutex mutex;
  std::map<uint64_t, std::shared_future<OracleSearch>> searches;
  OracleCacheCounters counters;
};

Cache& TheCache() {
  static Cache cache;
  return cache;
}

}  // namespace

namespace {

/// Why a holding run held the object beside the units, or "": the mesas carried less of the finger's
/// squeeze over the held time than grasped_on_sensor's floor, so no controller of this sensor could
/// feel that grip. Only the share: the time a slow close seats the object on the fingertip's cap
/// before the pad (narrow_box: 0.47 s at every grip) is the constant grip's close, not its grip.
std::string HeldBesideTheUnits(const RunResult& result) {
  const std::optional<double>& share = result.metrics.sensed_grip_share;
  const double floor = result.config.metrics.min_sensed_grip_share;
  if (!result.config.expectations.grasped_on_sensor.value_or(true) || !share || *share >= floor) return "";
  return "held beside the units: they carried " + Number(*share) + " of the finger's squeeze (floor " +
         Number(floor) + ")";
}

}  // namespace

OracleStep JudgeOracleStep(double setpoint_n, const RunResult& result) {
  const Metrics& m = result.metrics;
  OracleStep step;
  step.setpoint_n = setpoint_n;
  step.mean_grip_n = m.mean_held_grip_n;
  step.peak_grip_n = m.peak_grip_n;
  step.max_slip_mm = m.max_slip_mm;
  if (m.physics_fault) {
    step.outcome = "physics fault: " + m.physics_fault_cause;
  } else if (!m.grasped) {
    step.outcome = "never grasped";
  } else if (m.ungrasped_closes > 0) {
    step.outcome = "not grasped after " + std::to_string(m.ungrasped_closes) + " close command(s)";
  } else if (m.dropped) {
    step.outcome = "dropped at " + Number(m.drop_time_s) + " s";
  } else if (m.gross.events > 0) {
    step.outcome = "gross slip";
    for (const SlipEvent& event : m.events) {
      if (!event.gross) continue;
      step.outcome = "gross slip of " + Number(event.distance_m * 1e3) + " mm at " + Number(event.onset_s) + " s";
      break;
    }
  } else if (const std::string beside = HeldBesideTheUnits(result); !beside.empty()) {
    step.outcome = beside;
  } else if (!result.completed) {
    step.outcome = "stopped";
  } else {
    step.held = true;
    step.outcome = "held";
  }
  return step;
}

bool IsDisturbance(ActionKind kind) {
  return kind == ActionKind::kAddMass || kind == ActionKind::kPull || kind == ActionKind::kSetFriction ||
         kind == ActionKind::kShake;
}

bool IsSensorAction(ActionKind kind) {
  switch (kind) {
    case ActionKind::kDeadUnit:
    case ActionKind::kShortUnit:
    case ActionKind::kRestoreUnit:
    case ActionKind::kBias:
    case ActionKind::kNoiseBurst:
    case ActionKind::kDropFrames:
    case ActionKind::kAddLatency:
      return true;
    default:
      return false;
  }
}

double StallPinchForceN(const ScenarioConfig& config) {
  return config.scene.hand.model == sim::HandModel::kJaw ? config.scene.hand.motor.stall_force_n
                                                        : config.scene.hand.digit_motor.stall_pinch_force_n;
}

ScenarioConfig OracleStepConfig(const ScenarioConfig& config, double setpoint_n) {
  ScenarioConfig oracle = config;
  oracle.backend = Backend::kSim;
  oracle.log.clear();
  // The instrument's own controller section: the oracle must not depend on the controller under test
  // (its rate, its stale timeout, its ceiling).
  oracle.controller = ControllerOptions{};
  oracle.controller.name = "constant_grip";
  oracle.controller.params = {{"grip_n", setpoint_n}};
  SensorOptions sensor;  // the ideal readout, the paper's sensitivities
  sensor.layout = config.sensor.layout;
  sensor.sample_rate_hz = config.sensor.sample_rate_hz;
  oracle.sensor = sensor;
  oracle.script.clear();
  for (const Action& action : config.script) {
    if (!IsSensorAction(action.kind)) oracle.script.push_back(action);
  }
  oracle.expectations = Expectations{};
  return oracle;
}

std::optional<ScenarioConfig> UntilFirstDisturbance(const ScenarioConfig& config) {
  const auto first = std::find_if(config.script.begin(), config.script.end(),
                                  [](const Action& action) { return IsDisturbance(action.kind); });
  if (first == config.script.end()) return std::nullopt;
  ScenarioConfig until = config;
  const auto index = first - config.script.begin();
  if (first->after == ScriptEvent::kNone) until.duration_s = std::min(config.duration_s, first->at_s);
  until.script.erase(until.script.begin() + index, until.script.end());
  return until;
}

OracleSearch FindOracleGrip(const ScenarioConfig& config, const OracleOptions& options) {
  if (!(options.first_guess_n > 0.0) || !(options.relative_resolution > 0.0 || options.absolute_resolution_n > 0.0)) {
    throw std::invalid_argument("oracle: first_guess_n must be > 0 and one resolution > 0");
  }
  // The hash covers everything the search runs (the step config at a placeholder setpoint) and how.
  // Not the run's name or description: one scenario under several controllers ("default.v1@open_loop")
  // is one search.
  ScenarioConfig keyed = OracleStepConfig(config, 1.0);
  keyed.name = "oracle";
  keyed.description.clear();
  const std::string key_text = EmitScenarioYaml(keyed) + "\n# oracle search 4 graspbed " + GRASPBED_VERSION +
                               " " + BuildIdentity() + " " +
                               Number(options.relative_resolution, "%.17g") + " " +
                               Number(options.absolute_resolution_n, "%.17g") + " " +
                               Number(options.first_guess_n, "%.17g");
  const uint64_t key = std::hash<std::string>{}(key_text);
  Cache& cache = TheCache();
  std::promise<OracleSearch> promise;
  std::shared_future<OracleSearch> future;
  bool compute = false;
  {
    const std::lock_guard<std::mutex> lock(cache.mutex);
    ++cache.counters.searches;
    const auto found = cache.searches.find(key);
    if (found != cache.searches.end()) {
      ++cache.counters.cache_hits;
      future = found->second;
    } else {
      future = promise.get_future().share();
      cache.searches.emplace(key, future);
      compute = true;
    }
  }
  if (!compute) return future.get();  // computed, or being computed by another thread
  try {
    const std::string disk = OracleDiskCacheDir();
    if (!disk.empty()) {
      if (std::optional<OracleSearch> stored = ReadDiskCache(disk, Hex(key))) {
        stored->config_hash = Hex(key);
        promise.set_value(*stored);
        return future.get();
      }
    }
    OracleSearch search = Search(config, options);
    search.config_hash = Hex(key);
    if (!disk.empty() && search.completed) WriteDiskCache(disk, search);
    if (!search.completed) {  // an interrupted search is not kept
      const std::lock_guard<std::mutex> lock(cache.mutex);
      cache.searches.erase(key);
    }
    promise.set_value(search);
  } catch (...) {
    {
      const std::lock_guard<std::mutex> lock(cache.mutex);
      cache.searches.erase(key);
    }
    promise.set_exception(std::current_exception());
  }
  return future.get();
}

OracleReport RunOracleReport(const ScenarioConfig& config, const OracleOptions& options) {
  OracleReport report;
  report.full = FindOracleGrip(config, options);
  for (size_t i = 0; i < config.script.size(); ++i) {
    if (!IsDisturbance(config.script[i].kind)) continue;
    report.first_disturbance = ActionName(config.script[i].kind);
    report.first_disturbance_index = static_cast<int>(i);
    break;
  }
  if (const std::optional<ScenarioConfig> until = UntilFirstDisturbance(config)) {
    report.until_disturbance = FindOracleGrip(*until, options);
  }
  return report;
}

namespace {

OracleSearch SearchFromJson(const nlohmann::json& json) {
  OracleSearch search;
  if (!json.at("grip_n").is_null()) search.grip.grip_n = json.at("grip_n").get<double>();
  if (!json.at("setpoint_n").is_null()) search.setpoint_n = json.at("setpoint_n").get<double>();
  if (!json.at("reason").is_null()) search.grip.reason = json.at("reason").get<std::string>();
  search.stall_pinch_n = json.at("stall_pinch_n").get<double>();
  search.completed = json.at("completed").get<bool>();
  for (const nlohmann::json& entry : json.at("steps")) {
    OracleStep step;
    step.setpoint_n = entry.at("setpoint_n").get<double>();
    step.held = entry.at("held").get<bool>();
    step.mean_grip_n = entry.at("mean_grip_n").get<double>();
    step.peak_grip_n = entry.at("peak_grip_n").get<double>();
    step.max_slip_mm = entry.at("max_slip_mm").get<double>();
    step.outcome = entry.at("outcome").get<std::string>();
    search.steps.push_back(step);
  }
  return search;
}

nlohmann::json SearchJson(const OracleSearch& search) {
  nlohmann::json steps = nlohmann::json::array();
  for (const OracleStep& step : search.steps) {
    steps.push_back({{"setpoint_n", step.setpoint_n},
                     {"held", step.held},
                     {"mean_grip_n", step.mean_grip_n},
                     {"peak_grip_n", step.peak_grip_n},
                     {"max_slip_mm", step.max_slip_mm},
                     {"outcome", step.outcome}});
  }
  return {{"grip_n", internal::OptionalJson(search.grip.grip_n)},
          {"setpoint_n", internal::OptionalJson(search.setpoint_n)},
          {"reason", search.grip.reason.empty() ? nlohmann::json(nullptr) : nlohmann::json(search.grip.reason)},
          {"stall_pinch_n", search.stall_pinch_n},
          {"completed", search.completed},
          {"config_hash", search.config_hash},
          {"steps", steps}};
}

}  // namespace

nlohmann::json OracleReportJson(const ScenarioConfig& config, const OracleReport& report) {
  nlohmann::json json = {{"scenario", config.name},
                         {"source_file", config.source_file},
                         {"oracle_grip_n", internal::OptionalJson(report.full.grip.grip_n)},
                         {"oracle_grip_until_disturbance_n", nullptr},
                         {"first_disturbance", nullptr},
                         {"disturbance_ratio", nullptr},
                         {"full", SearchJson(report.full)}};
  if (report.until_disturbance) {
    json["oracle_grip_until_disturbance_n"] = internal::OptionalJson(report.until_disturbance->grip.grip_n);
    json["first_disturbance"] = {{"action", report.first_disturbance},
                                 {"script_index", report.first_disturbance_index}};
    json["until_disturbance"] = SearchJson(*report.until_disturbance);
    if (report.full.grip.grip_n && report.until_disturbance->grip.grip_n)
      json["disturbance_ratio"] = *report.full.grip.grip_n / *report.until_disturbance->grip.grip_n;
  }
  return json;
}

std::string OracleReportTable(const ScenarioConfig& config, const OracleReport& report) {
  std::ostringstream out;
  const auto describe = [&](const char* label, const OracleSearch& search) {
    out << label;
    if (search.grip.grip_n) {
      out << Number(*search.grip.grip_n, "%.3f") << " N (constant_grip at " << Number(*search.setpoint_n, "%.3f")
          << " N)";
    } else {
      out << "none: " << search.grip.reason;
    }
    out << ", " << search.steps.size() << " runs\n";
    for (const OracleStep& step : search.steps) {
      out << "    grip_n " << Number(step.setpoint_n, "%7.3f") << " N: mean squeeze "
          << Number(step.mean_grip_n, "%6.3f") << " N, slip " << Number(step.max_slip_mm, "%.2f") << " mm, "
          << step.outcome << "\n";
    }
  };
  out << "oracle of " << config.name << " (constant_grip on the ideal sensor; no drop, no gross slip, on the pad)\n";
  describe("  oracle grip:                 ", report.full);
  if (report.until_disturbance) {
    describe(("  until the first disturbance (" + report.first_disturbance + "): ").c_str(),
             *report.until_disturbance);
    if (report.full.grip.grip_n && report.until_disturbance->grip.grip_n) {
      out << "  the disturbance raises the oracle grip " << Number(*report.full.grip.grip_n /
                                                                    *report.until_disturbance->grip.grip_n,
                                                                    "%.2f")
          << "x\n";
    }
  } else {
    out << "  no disturbance action in the script\n";
  }
  return out.str();
}

std::string OracleDiskCacheDir() {
  if (disk_cache_off) return "";
  if (const char* dir = std::getenv("GRASPBED_ORACLE_CACHE_DIR")) {
    const std::string text = dir;
    return text == "off" ? "" : text;
  }
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  if (xdg != nullptr && *xdg != '\0') return std::string(xdg) + "/graspbed/oracle";
  const char* home = std::getenv("HOME");
  if (home != nullptr && *home != '\0') return std::string(home) + "/.cache/graspbed/oracle";
  return "";
}

void SetOracleDiskCacheOff() { disk_cache_off = true; }

OracleCacheCounters OracleCacheCountersNow() {
  Cache& cache = TheCache();
  const std::lock_guard<std::mutex> lock(cache.mutex);
  return cache.counters;
}

}  // namespace graspbed::testbed
