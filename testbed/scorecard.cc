#include "testbed/scorecard.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <sstream>
#include <utility>

#include <yaml-cpp/yaml.h>

#include "common/plot.h"
#include "common/yaml_map.h"
#include "testbed/run_outputs.h"
#include "testbed/suite.h"

namespace graspbed::testbed {

namespace fs = std::filesystem;

namespace {

/// ScorecardRow::error of a run that did not finish (stopped, or never started).
constexpr char kInterrupted[] = "interrupted";

using internal::OptionalJson;
using internal::OptionalText;

[[noreturn]] void Fail(const std::string& file, const YAML::Node& node, const std::string& key,
                       const std::string& value, const std::string& reason) {
  const int line = node.IsDefined() ? node.Mark().line + 1 : 0;
  throw common::ConfigError(file + ":" + std::to_string(line) + ": " + key + " = " + value + ": " + reason);
}

std::string NodeText(const YAML::Node& node) {
  YAML::Emitter emitter;
  emitter.SetSeqFormat(YAML::Flow);
  emitter.SetMapFormat(YAML::Flow);
  emitter << node;
  return emitter.c_str();
}

double NumberOf(const std::string& file, const YAML::Node& node, const std::string& key) {
  try {
    const double value = node.as<double>();
    if (std::isfinite(value)) return value;
  } catch (const YAML::Exception&) {
  }
  Fail(file, node, key, NodeText(node), "expected a number");
}

/// A map of dotted keys to values as --set overrides, in file order; a map or list value as flow YAML.
std::vector<Override> OverridesOf(const YAML::Node& group) {
  std::vector<Override> overrides;
  for (const auto& pair : group) {
    const YAML::Node value = pair.second;
    overrides.push_back({pair.first.as<std::string>(), value.IsScalar() ? value.as<std::string>() : NodeText(value)});
  }
  return overrides;
}

std::vector<ScorecardVary> ParseVary(const std::string& file, const YAML::Node& list,
                                     const std::string& where) {
  std::vector<ScorecardVary> vary;
  if (!list.IsDefined() || list.IsNull()) return vary;
  if (!list.IsSequence())
    Fail(file, list, where, NodeText(list), "expected a list of {key, min, max} or {choose: [...]}");
  for (size_t i = 0; i < list.size(); ++i) {
    const YAML::Node item = list[i];
    const std::string at = where + "[" + std::to_string(i) + "]";
    if (!item.IsMap()) Fail(file, item, at, NodeText(item), "expected {key, min, max} or {choose: [...]}");
    ScorecardVary entry;
    if (item["choose"]) {
      const YAML::Node choices = item["choose"];
      if (!choices.IsSequence() || choices.size() == 0) {
        Fail(file, choices, at + ".choose", NodeText(choices), "expected a non-empty list of override maps");
      }
      for (size_t c = 0; c < choices.size(); ++c) {
        const YAML::Node group = choices[c];
        if (!group.IsMap() || group.size() == 0) {
          Fail(file, group, at + ".choose[" + std::to_string(c) + "]", NodeText(group),
               "expected a map of dotted keys to values, e.g. {object.shape: box}");
        }
        entry.choices.push_back(OverridesOf(group));
      }
    } else {
      if (!item["key"] || !item["min"] || !item["max"]) {
        Fail(file, item, at, NodeText(item), "a range needs key, min and max");
      }
      entry.key = item["key"].as<std::string>();
      entry.min = NumberOf(file, item["min"], at + ".min");
      entry.max = NumberOf(file, item["max"], at + ".max");
      if (entry.max < entry.min)
        Fail(file, item["max"], at + ".max", NodeText(item["max"]), "must be >= min");
    }
    vary.push_back(std::move(entry));
  }
  return vary;
}

std::string FormatNumber(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.4g", value);
  return text;
}

void Sample(const ScorecardVary& vary, std::mt19937_64& rng, std::vector<Override>& out) {
  if (vary.key.empty()) {
    const size_t pick = std::uniform_int_distribution<size_t>(0, vary.choices.size() - 1)(rng);
    for (const Override& each : vary.choices[pick]) out.push_back(each);
    return;
  }
  const double u = std::uniform_real_distribution<double>(0.0, 1.0)(rng);
  out.push_back({vary.key, FormatNumber(vary.min + u * (vary.max - vary.min))});
}

}  // namespace

ScorecardSet LoadScorecardSet(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw common::ConfigError(path + ": cannot read the scorecard set");
  } catch (const YAML::Exception& error) {
    throw common::ConfigError(path + ":" + std::to_string(error.mark.line + 1) + ": " + error.msg);
  }
  if (!root.IsMap()) throw common::ConfigError(path + ": expected a map with name, version, seed, bases");
  ScorecardSet set;
  set.source_file = path;
  if (!root["name"] || !root["name"].IsScalar()) Fail(path, root, "name", "", "the set needs a name");
  set.name = root["name"].as<std::string>();
  if (!root["version"]) Fail(path, root, "version", "", "the set needs a version (a whole number >= 1)");
  const double version = NumberOf(path, root["version"], "version");
  if (version < 1 || version != std::floor(version)) {
    Fail(path, root["version"], "version", NodeText(root["version"]), "expected a whole number >= 1");
  }
  set.version = static_cast<int>(version);
  if (root["seed"]) {
    const double seed = NumberOf(path, root["seed"], "seed");
    if (seed < 0 || seed != std::floor(seed))
      Fail(path, root["seed"], "seed", NodeText(root["seed"]), "expected a whole number >= 0");
    set.seed = static_cast<uint64_t>(seed);
  }
  set.common = ParseVary(path, root["vary"], "vary");
  const YAML::Node bases = root["bases"];
  if (!bases.IsSequence() || bases.size() == 0) {
    Fail(path, bases.IsDefined() ? bases : root, "bases", bases.IsDefined() ? NodeText(bases) : "",
         "expected a non-empty list of {scenario, variations}");
  }
  const fs::path directory = fs::path(path).parent_path();
  for (size_t i = 0; i < bases.size(); ++i) {
    const YAML::Node item = bases[i];
    const std::string at = "bases[" + std::to_string(i) + "]";
    if (!item.IsMap() || !item["scenario"])
      Fail(path, item, at, NodeText(item), "expected {scenario: FILE, variations: N}");
    ScorecardBase base;
    base.scenario_path = (directory / item["scenario"].as<std::string>()).lexically_normal().string();
    if (!fs::is_regular_file(base.scenario_path)) {
      Fail(path, item["scenario"], at + ".scenario", item["scenario"].as<std::string>(),
           "no such file (" + base.scenario_path + ")");
    }
    if (item["variations"]) {
      const double count = NumberOf(path, item["variations"], at + ".variations");
      if (count < 0 || count > 1000 || count != std::floor(count)) {
        Fail(path, item["variations"], at + ".variations", NodeText(item["variations"]),
             "expected a whole number in [0, 1000]");
      }
      base.variations = static_cast<int>(count);
    }
    base.name = fs::path(base.scenario_path).stem().string();
    if (item["name"]) {
      const YAML::Node name = item["name"];
      if (!name.IsScalar() || name.Scalar().empty() || name.Scalar().find_first_of("/ ") != std::string::npos)
        Fail(path, name, at + ".name", NodeText(name), "expected a run name (no spaces or slashes)");
      base.name = name.Scalar();
    }
    for (const ScorecardBase& earlier : set.bases) {
      if (earlier.name == base.name) {
        Fail(path, item["name"] ? item["name"] : item["scenario"], at + ".name", base.name,
             "another base has this name; give each base of the same scenario its own `name`");
      }
    }
    if (item["set"]) {
      const YAML::Node group = item["set"];
      if (!group.IsMap() || group.size() == 0) {
        Fail(path, group, at + ".set", NodeText(group),
             "expected a map of keys to values, e.g. {object: {name: apple}}");
      }
      base.set = OverridesOf(group);
    }
    base.vary = ParseVary(path, item["vary"], at + ".vary");
    set.bases.push_back(std::move(base));
  }
  return set;
}

std::vector<ScorecardRun> ExpandScorecardSet(const ScorecardSet& set) {
  std::vector<ScorecardRun> runs;
  for (size_t b = 0; b < set.bases.size(); ++b) {
    const ScorecardBase& base = set.bases[b];
    for (int k = 0; k <= base.variations; ++k) {
      ScorecardRun run;
      run.name = base.name + ".v" + std::to_string(k);
      run.scenario_path = base.scenario_path;
      run.overrides = base.set;
      if (k > 0) {
        std::seed_seq seeds{static_cast<uint32_t>(set.seed), static_cast<uint32_t>(set.seed >> 32),
                            static_cast<uint32_t>(b), static_cast<uint32_t>(k)};
        std::mt19937_64 rng(seeds);
        for (const ScorecardVary& vary : set.common) Sample(vary, rng, run.overrides);
        for (const ScorecardVary& vary : base.vary) Sample(vary, rng, run.overrides);
        // A seed per variation too, so sensor noise and any random script differ between variations.
        run.overrides.push_back(
            {"seed", std::to_string(std::uniform_int_distribution<uint32_t>(1, 1u << 30)(rng))});
      }
      runs.push_back(std::move(run));
    }
  }
  return runs;
}

std::optional<double> Percentile(std::vector<double> values, double p) {
  if (values.empty()) return std::nullopt;
  std::sort(values.begin(), values.end());
  const double rank = std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(values.size() - 1);
  const size_t lower = static_cast<size_t>(std::floor(rank));
  const size_t upper = std::min(lower + 1, values.size() - 1);
  return values[lower] + (rank - static_cast<double>(lower)) * (values[upper] - values[lower]);
}

ControllerScore ScoreRuns(const std::string& controller, const std::vector<const RunResult*>& finished,
                          int errors) {
  ControllerScore score;
  score.controller = controller;
  score.errors = errors;
  std::vector<double> latencies_ms;
  std::vector<double> gross_latencies_ms;
  std::vector<double> efficiencies;
  std::vector<double> peak_ratios;
  std::vector<double> sensed_shares;
  double fn_square_sum = 0.0;
  int64_t fn_samples = 0;
  for (const RunResult* result : finished) {
    const Metrics& metrics = result->metrics;
    ++score.runs;
    if (result->passed) ++score.passed;
    score.slip_events += metrics.slip_events;
    score.slip_detected += metrics.slip_events - metrics.missed_slip_events;
    score.missed_unsensed += metrics.missed_unsensed_slip_events;
    score.missed_thumb_only += metrics.missed_thumb_only_slip_events;
    score.gross_slip_events += metrics.gross.events;
    score.gross_slip_detected += metrics.gross.detected;
    score.micro_slip_events += metrics.micro.events;
    score.micro_slip_detected += metrics.micro.detected;
    for (const SlipEvent& event : metrics.events) {
      if (!event.detected) continue;
      latencies_ms.push_back(event.latency_s * 1000.0);
      if (event.gross) gross_latencies_ms.push_back(event.latency_s * 1000.0);
    }
    score.false_flags += metrics.false_slip_flags;
    for (const auto& [cues, count] : metrics.false_slip_flags_by_cue) score.false_flags_by_cue[cues] += count;
    score.incipient_flags += metrics.incipient_slip_flags;
    score.held_min += metrics.held_s / 60.0;
    if (metrics.held_s > 0.0) ++score.lifts;
    score.false_flag_min += metrics.false_slip_flag_s / 60.0;
    if (metrics.dropped) ++score.drops;
    if (metrics.crushed) ++score.crushes;
    if (metrics.grip_efficiency) efficiencies.push_back(*metrics.grip_efficiency);
    if (metrics.peak_grip_ratio) peak_ratios.push_back(*metrics.peak_grip_ratio);
    if (metrics.oracle && !metrics.oracle->grip_n) ++score.no_oracle;
    for (const ExpectationOutcome& outcome : result->outcomes)
      if (outcome.name == "grasped_on_sensor" && !outcome.passed) ++score.off_sensor;
    if (metrics.sensed_grip_share) sensed_shares.push_back(*metrics.sensed_grip_share);
    if (metrics.fn_rmse_n && metrics.estimation_samples > 0) {
      fn_square_sum +=
          *metrics.fn_rmse_n * *metrics.fn_rmse_n * static_cast<double>(metrics.estimation_samples);
      fn_samples += metrics.estimation_samples;
    }
    if (metrics.physics_fault) ++score.physics_faults;
  }
  if (score.slip_events > 0) score.detected_pct = 100.0 * score.slip_detected / score.slip_events;
  if (score.gross_slip_events > 0)
    score.gross_detected_pct = 100.0 * score.gross_slip_detected / score.gross_slip_events;
  if (score.micro_slip_events > 0)
    score.micro_detected_pct = 100.0 * score.micro_slip_detected / score.micro_slip_events;
  score.gross_latency_p50_ms = Percentile(gross_latencies_ms, 50.0);
  score.gross_latency_p95_ms = Percentile(gross_latencies_ms, 95.0);
  score.latency_p50_ms = Percentile(latencies_ms, 50.0);
  score.latency_p95_ms = Percentile(latencies_ms, 95.0);
  if (score.held_min > 0.0) {
    score.false_per_min = score.false_flags / score.held_min;
    score.incipient_per_min = score.incipient_flags / score.held_min;
    score.false_flag_pct = 100.0 * score.false_flag_min / score.held_min;
  }
  if (score.lifts > 0) score.false_per_lift = static_cast<double>(score.false_flags) / score.lifts;
  score.grip_efficiency_median = Percentile(efficiencies, 50.0);
  score.grip_efficiency_p95 = Percentile(efficiencies, 95.0);
  score.peak_grip_ratio_median = Percentile(peak_ratios, 50.0);
  score.peak_grip_ratio_p95 = Percentile(peak_ratios, 95.0);
  score.sensed_share_median = Percentile(sensed_shares, 50.0);
  score.sensed_share_min = Percentile(sensed_shares, 0.0);
  if (fn_samples > 0) score.fn_rmse_n = std::sqrt(fn_square_sum / static_cast<double>(fn_samples));
  return score;
}

Scorecard RunScorecard(const ScorecardSet& set, const ScorecardOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (options.controllers.empty()) throw common::ConfigError("score: no controller to score");
  std::vector<ScorecardRun> runs = ExpandScorecardSet(set);
  if (options.limit > 0 && static_cast<size_t>(options.limit) < runs.size()) runs.resize(options.limit);

  Scorecard scorecard;
  scorecard.set_name = set.name;
  scorecard.set_version = set.version;
  scorecard.set_seed = set.seed;
  scorecard.set_file = set.source_file;
  scorecard.runs_per_controller = static_cast<int>(runs.size());
  scorecard.jobs = std::max(1, options.jobs);

  // Load everything first: a bad override or an unknown controller refuses the whole scorecard.
  std::vector<ScenarioConfig> configs;
  for (const std::string& controller : options.controllers) {
    for (const ScorecardRun& run : runs) {
      const bool custom = options.custom_controllers.contains(controller);
      std::vector<Override> overrides = run.overrides;
      overrides.insert(overrides.end(), options.overrides.begin(), options.overrides.end());
      if (!custom) overrides.push_back({"controller.name", controller});
      ScenarioConfig config = LoadScenario(run.scenario_path, overrides);
      if (custom) config.controller.name = controller;
      config.name = run.name + "@" + controller;
      configs.push_back(std::move(config));
      scorecard.rows.push_back({controller, run.name, run.overrides, "", {}});
    }
  }

  // The suite's worker pool (longest expected run first, Ctrl-C aware); nothing written per run
  // unless runs_dir asks for it.
  SuiteOptions suite_options;
  suite_options.jobs = scorecard.jobs;
  suite_options.out_dir = options.runs_dir;
  suite_options.write_plots = false;
  suite_options.stop = options.stop;
  if (!options.custom_controllers.empty()) {
    suite_options.make_controller = [&options](const ControllerOptions& controller) {
      const auto custom = options.custom_controllers.find(controller.name);
      return custom != options.custom_controllers.end()
                 ? custom->second(controller)
                 : controller::MakeController(controller.name, controller.params);
    };
  }
  if (options.on_finished) {
    suite_options.on_finished = [&](int finished, int total, const SuiteRun&) {
      options.on_finished(finished, total);
    };
  }
  SuiteResult suite = RunSuite(configs, suite_options);
  scorecard.completed = suite.completed;
  for (size_t i = 0; i < suite.runs.size(); ++i) {
    ScorecardRow& row = scorecard.rows[i];
    SuiteRun& run = suite.runs[i];
    row.result = std::move(run.result);
    if (!run.error.empty()) {
      row.error = run.error;
    } else if (!run.started || !row.result.completed) {
      row.error = kInterrupted;
    }
  }
  for (const std::string& controller : options.controllers) {
    std::vector<const RunResult*> done;
    int errors = 0;
    for (const ScorecardRow& row : scorecard.rows) {
      if (row.controller != controller) continue;
      if (row.error.empty() && row.result.completed) {
        done.push_back(&row.result);
      } else {
        ++errors;
      }
    }
    scorecard.scores.push_back(ScoreRuns(controller, done, errors));
  }
  scorecard.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return scorecard;
}

namespace {

/// One figure of the table/CSV: label, CSV column, and its text for a score.
struct Figure {
  const char* label;
  const char* column;
  std::function<std::string(const ControllerScore&)> text;
  std::function<nlohmann::json(const ControllerScore&)> json;
};

std::string Int(int value) { return std::to_string(value); }

const std::vector<Figure>& Figures() {
  static const std::vector<Figure> figures = {
      {"runs (errors)", "runs",
       [](const ControllerScore& s) { return Int(s.runs) + (s.errors ? " (" + Int(s.errors) + ")" : ""); },
       [](const ControllerScore& s) { return nlohmann::json(s.runs); }},
      {"errors", "errors", [](const ControllerScore& s) { return Int(s.errors); },
       [](const ControllerScore& s) { return nlohmann::json(s.errors); }},
      {"passed", "passed", [](const ControllerScore& s) { return Int(s.passed) + "/" + Int(s.runs); },
       [](const ControllerScore& s) { return nlohmann::json(s.passed); }},
      {"gross slips flagged", "gross_slip_detected_pct",
       [](const ControllerScore& s) {
         return OptionalText(s.gross_detected_pct, "%.1f %%") + " (" + Int(s.gross_slip_detected) + "/" +
                Int(s.gross_slip_events) + ")";
       },
       [](const ControllerScore& s) { return OptionalJson(s.gross_detected_pct); }},
      {"gross slip events", "gross_slip_events", [](const ControllerScore& s) { return Int(s.gross_slip_events); },
       [](const ControllerScore& s) { return nlohmann::json(s.gross_slip_events); }},
      {"gross slips flagged (count)", "gross_slip_detected",
       [](const ControllerScore& s) { return Int(s.gross_slip_detected); },
       [](const ControllerScore& s) { return nlohmann::json(s.gross_slip_detected); }},
      {"gross latency p50", "gross_latency_p50_ms",
       [](const ControllerScore& s) { return OptionalText(s.gross_latency_p50_ms, "%.1f ms"); },
       [](const ControllerScore& s) { return OptionalJson(s.gross_latency_p50_ms); }},
      {"gross latency p95", "gross_latency_p95_ms",
       [](const ControllerScore& s) { return OptionalText(s.gross_latency_p95_ms, "%.1f ms"); },
       [](const ControllerScore& s) { return OptionalJson(s.gross_latency_p95_ms); }},
      {"micro-slips flagged", "micro_slip_detected_pct",
       [](const ControllerScore& s) {
         return OptionalText(s.micro_detected_pct, "%.1f %%") + " (" + Int(s.micro_slip_detected) + "/" +
                Int(s.micro_slip_events) + ")";
       },
       [](const ControllerScore& s) { return OptionalJson(s.micro_detected_pct); }},
      {"micro-slip events", "micro_slip_events", [](const ControllerScore& s) { return Int(s.micro_slip_events); },
       [](const ControllerScore& s) { return nlohmann::json(s.micro_slip_events); }},
      {"micro-slips flagged (count)", "micro_slip_detected",
       [](const ControllerScore& s) { return Int(s.micro_slip_detected); },
       [](const ControllerScore& s) { return nlohmann::json(s.micro_slip_detected); }},
      {"all slip events flagged", "slip_detected_pct",
       [](const ControllerScore& s) {
         return OptionalText(s.detected_pct, "%.1f %%") + " (" + Int(s.slip_detected) + "/" +
                Int(s.slip_events) + ")";
       },
       [](const ControllerScore& s) { return OptionalJson(s.detected_pct); }},
      {"slip events", "slip_events", [](const ControllerScore& s) { return Int(s.slip_events); },
       [](const ControllerScore& s) { return nlohmann::json(s.slip_events); }},
      {"slip events flagged", "slip_detected", [](const ControllerScore& s) { return Int(s.slip_detected); },
       [](const ControllerScore& s) { return nlohmann::json(s.slip_detected); }},
      {"missed, no unit loaded", "missed_unsensed",
       [](const ControllerScore& s) {
         return Int(s.missed_unsensed) + " of " + Int(s.slip_events - s.slip_detected);
       },
       [](const ControllerScore& s) { return nlohmann::json(s.missed_unsensed); }},
      {"missed, only thumb slid", "missed_thumb_only",
       [](const ControllerScore& s) {
         return Int(s.missed_thumb_only) + " of " + Int(s.slip_events - s.slip_detected);
       },
       [](const ControllerScore& s) { return nlohmann::json(s.missed_thumb_only); }},
      {"all latency p50", "latency_p50_ms",
       [](const ControllerScore& s) { return OptionalText(s.latency_p50_ms, "%.1f ms"); },
       [](const ControllerScore& s) { return OptionalJson(s.latency_p50_ms); }},
      {"all latency p95", "latency_p95_ms",
       [](const ControllerScore& s) { return OptionalText(s.latency_p95_ms, "%.1f ms"); },
       [](const ControllerScore& s) { return OptionalJson(s.latency_p95_ms); }},
      {"false flags / min held", "false_flags_per_min",
       [](const ControllerScore& s) {
         return OptionalText(s.false_per_min, "%.2f") + " (" + Int(s.false_flags) + ")";
       },
       [](const ControllerScore& s) { return OptionalJson(s.false_per_min); }},
      {"false flags / lift", "false_flags_per_lift",
       [](const ControllerScore& s) {
         return OptionalText(s.false_per_lift, "%.2f") + " (" + Int(s.false_flags) + "/" + Int(s.lifts) + ")";
       },
       [](const ControllerScore& s) { return OptionalJson(s.false_per_lift); }},
      {"lifts", "lifts", [](const ControllerScore& s) { return Int(s.lifts); },
       [](const ControllerScore& s) { return nlohmann::json(s.lifts); }},
      {"false flags", "false_flags", [](const ControllerScore& s) { return Int(s.false_flags); },
       [](const ControllerScore& s) { return nlohmann::json(s.false_flags); }},
      {"incipient flags / min", "incipient_flags_per_min",
       [](const ControllerScore& s) {
         return OptionalText(s.incipient_per_min, "%.2f") + " (" + Int(s.incipient_flags) + ")";
       },
       [](const ControllerScore& s) { return OptionalJson(s.incipient_per_min); }},
      {"incipient-slip flags", "incipient_flags",
       [](const ControllerScore& s) { return Int(s.incipient_flags); },
       [](const ControllerScore& s) { return nlohmann::json(s.incipient_flags); }},
      {"false flag up, % of held", "false_flag_pct",
       [](const ControllerScore& s) { return OptionalText(s.false_flag_pct, "%.1f %%"); },
       [](const ControllerScore& s) { return OptionalJson(s.false_flag_pct); }},
      {"time held", "held_min", [](const ControllerScore& s) { return OptionalText(s.held_min, "%.2f min"); },
       [](const ControllerScore& s) { return nlohmann::json(s.held_min); }},
      {"drops", "drops", [](const ControllerScore& s) { return Int(s.drops); },
       [](const ControllerScore& s) { return nlohmann::json(s.drops); }},
      {"crushes", "crushes", [](const ControllerScore& s) { return Int(s.crushes); },
       [](const ControllerScore& s) { return nlohmann::json(s.crushes); }},
      {"grip efficiency median", "grip_efficiency_median",
       [](const ControllerScore& s) { return OptionalText(s.grip_efficiency_median, "%.2f"); },
       [](const ControllerScore& s) { return OptionalJson(s.grip_efficiency_median); }},
      {"grip efficiency p95", "grip_efficiency_p95",
       [](const ControllerScore& s) { return OptionalText(s.grip_efficiency_p95, "%.2f"); },
       [](const ControllerScore& s) { return OptionalJson(s.grip_efficiency_p95); }},
      {"peak grip / oracle median", "peak_grip_ratio_median",
       [](const ControllerScore& s) { return OptionalText(s.peak_grip_ratio_median, "%.2f"); },
       [](const ControllerScore& s) { return OptionalJson(s.peak_grip_ratio_median); }},
      {"peak grip / oracle p95", "peak_grip_ratio_p95",
       [](const ControllerScore& s) { return OptionalText(s.peak_grip_ratio_p95, "%.2f"); },
       [](const ControllerScore& s) { return OptionalJson(s.peak_grip_ratio_p95); }},
      {"runs without oracle grip", "no_oracle", [](const ControllerScore& s) { return Int(s.no_oracle); },
       [](const ControllerScore& s) { return nlohmann::json(s.no_oracle); }},
      {"runs held off the sensor", "off_sensor", [](const ControllerScore& s) { return Int(s.off_sensor); },
       [](const ControllerScore& s) { return nlohmann::json(s.off_sensor); }},
      {"sensed share median / min", "sensed_share_median",
       [](const ControllerScore& s) {
         return OptionalText(s.sensed_share_median, "%.2f") + " / " + OptionalText(s.sensed_share_min, "%.2f");
       },
       [](const ControllerScore& s) { return OptionalJson(s.sensed_share_median); }},
      {"Fn estimation RMSE", "fn_rmse_n",
       [](const ControllerScore& s) { return OptionalText(s.fn_rmse_n, "%.3f N"); },
       [](const ControllerScore& s) { return OptionalJson(s.fn_rmse_n); }},
      {"physics faults", "physics_faults", [](const ControllerScore& s) { return Int(s.physics_faults); },
       [](const ControllerScore& s) { return nlohmann::json(s.physics_faults); }},
  };
  return figures;
}

// Figures shown in the printed table (the CSV has every column).
bool InTable(const Figure& figure) {
  const std::string column = figure.column;
  return column != "errors" && column != "slip_events" && column != "slip_detected" &&
         column != "false_flags" && column != "lifts" && column != "incipient_flags" &&
         column != "gross_slip_events" && column != "gross_slip_detected" && column != "micro_slip_events" &&
         column != "micro_slip_detected";
}

}  // namespace

std::string ScorecardTable(const Scorecard& scorecard) {
  std::ostringstream out;
  out << "scorecard " << scorecard.set_name << " v" << scorecard.set_version << " seed " << scorecard.set_seed
      << " (" << scorecard.set_file << "): " << scorecard.runs_per_controller << " runs per controller, "
      << scorecard.jobs << (scorecard.jobs == 1 ? " job, " : " jobs, ") << FormatNumber(scorecard.wall_s) << " s"
      << (scorecard.completed ? "" : ", INCOMPLETE") << "\n";
  constexpr int kLabelWidth = 26;
  constexpr int kColumnWidth = 24;
  char cell[128];
  std::snprintf(cell, sizeof(cell), "  %-*s", kLabelWidth, "");
  out << cell;
  for (const ControllerScore& score : scorecard.scores) {
    std::snprintf(cell, sizeof(cell), "%-*s", kColumnWidth, score.controller.c_str());
    out << cell;
  }
  out << "\n";
  for (const Figure& figure : Figures()) {
    if (!InTable(figure)) continue;
    std::snprintf(cell, sizeof(cell), "  %-*s", kLabelWidth, figure.label);
    out << cell;
    for (const ControllerScore& score : scorecard.scores) {
      std::snprintf(cell, sizeof(cell), "%-*s", kColumnWidth, figure.text(score).c_str());
      out << cell;
    }
    out << "\n";
  }
  // Where each controller's false flags came from, by its own cue labels, most first.
  for (const ControllerScore& score : scorecard.scores) {
    if (score.false_flags_by_cue.empty()) continue;
    std::vector<std::pair<std::string, int>> by_cue(score.false_flags_by_cue.begin(),
                                                    score.false_flags_by_cue.end());
    std::stable_sort(by_cue.begin(), by_cue.end(),
                     [](const auto& a, const auto& b) { return a.second > b.second; });
    out << "  false flags by cue, " << score.controller << ":";
    for (size_t i = 0; i < by_cue.size(); ++i)
      out << (i ? ", " : " ") << by_cue[i].first << " " << by_cue[i].second;
    out << "\n";
  }
  // Which runs have no oracle grip or were held off the sensor, and why: a count alone says nothing
  // a user can act on. An oracle belongs to the run, not the controller: listed once.
  std::vector<std::string> listed;
  for (const ScorecardRow& row : scorecard.rows) {
    const Metrics& m = row.result.metrics;
    if (row.error.empty() && m.oracle && !m.oracle->grip_n &&
        std::find(listed.begin(), listed.end(), row.run) == listed.end()) {
      listed.push_back(row.run);
      out << "  no oracle grip: " << row.run << ": " << m.oracle->reason << "\n";
    }
  }
  for (const ScorecardRow& row : scorecard.rows) {
    for (const ExpectationOutcome& o : row.result.outcomes) {
      if (o.name == "grasped_on_sensor" && !o.passed)
        out << "  held off the sensor: " << row.run << "@" << row.controller << ": " << o.note << "\n";
    }
  }
  return out.str();
}

std::string ScorecardFailedRuns(const Scorecard& scorecard) {
  std::ostringstream out;
  int listed = 0;
  int interrupted = 0;
  const auto header = [&] {
    if (listed++ == 0) out << "  failed runs (run@controller: first failed expectation: got, limit):\n";
  };
  for (const ScorecardRow& row : scorecard.rows) {
    if (row.error == kInterrupted) {
      ++interrupted;
    } else if (!row.error.empty()) {
      header();
      out << "    " << row.run << "@" << row.controller << ": error: " << row.error << "\n";
    } else if (!row.result.passed) {
      // The first outcome the run recorded as failed, as summary.json and the report give it.
      const auto failed = std::find_if(row.result.outcomes.begin(), row.result.outcomes.end(),
                                       [](const ExpectationOutcome& o) { return !o.passed; });
      header();
      out << "    " << row.run << "@" << row.controller << ": ";
      if (failed == row.result.outcomes.end()) {
        out << "no expectation recorded as failed\n";
        continue;
      }
      out << failed->name << ": got " << failed->value_text << ", limit " << failed->limit;
      if (!failed->note.empty()) out << " (" << failed->note << ")";
      out << "\n";
    }
  }
  if (listed == 0) out << "  failed runs: none\n";
  if (interrupted > 0)
    out << "  not finished (interrupted): " << interrupted << (interrupted == 1 ? " run\n" : " runs\n");
  return out.str();
}

namespace {

/// The runs of each group (`group_of` a row's group name), groups sorted by name, scored per
/// controller in the scorecard's order.
struct GroupScore {
  std::string group;
  std::vector<ControllerScore> scores;
};

template <typename GroupOf>
std::vector<GroupScore> ScoreGroups(const Scorecard& scorecard, GroupOf group_of) {
  std::vector<std::string> groups;
  for (const ScorecardRow& row : scorecard.rows) {
    if (!row.error.empty() || !row.result.completed) continue;
    const std::string group = group_of(row);
    if (std::find(groups.begin(), groups.end(), group) == groups.end()) groups.push_back(group);
  }
  std::sort(groups.begin(), groups.end());
  std::vector<GroupScore> scored;
  for (const std::string& group : groups) {
    GroupScore entry{group, {}};
    for (const ControllerScore& total : scorecard.scores) {
      std::vector<const RunResult*> finished;
      for (const ScorecardRow& row : scorecard.rows) {
        if (row.controller == total.controller && row.error.empty() && row.result.completed &&
            group_of(row) == group) {
          finished.push_back(&row.result);
        }
      }
      entry.scores.push_back(ScoreRuns(total.controller, finished, 0));
    }
    scored.push_back(std::move(entry));
  }
  return scored;
}

/// A run's sensor: the profile and sensitivity source of its resolved config.
std::string SensorOf(const ScorecardRow& row) {
  return row.result.config.sensor.profile + "/" + row.result.config.sensor.sensitivities;
}

// The headline figures per group of runs: one line per (group, controller).
std::string GroupTable(const char* group_label, const std::vector<GroupScore>& groups) {
  std::ostringstream out;
  char line[256];
  std::snprintf(line, sizeof(line), "  %-22s %-13s %4s %14s %11s %16s %17s %8s %5s %10s\n", group_label,
                "controller", "runs", "gross flagged", "latency p95", "false flags/min", "false flags/lift",
                "flag up", "drops", "efficiency");
  out << line;
  for (const GroupScore& group : groups) {
    for (const ControllerScore& score : group.scores) {
      const std::string detected = OptionalText(score.gross_detected_pct, "%.0f %%") + " (" +
                                   Int(score.gross_slip_detected) + "/" + Int(score.gross_slip_events) + ")";
      const std::string per_lift = OptionalText(score.false_per_lift, "%.2f") + " (" + Int(score.lifts) +
                                   (score.lifts == 1 ? " lift)" : " lifts)");
      std::snprintf(line, sizeof(line), "  %-22s %-13s %4d %14s %11s %16s %17s %8s %5d %10s\n",
                    group.group.c_str(), score.controller.c_str(), score.runs, detected.c_str(),
                    OptionalText(score.gross_latency_p95_ms, "%.1f ms").c_str(),
                    (OptionalText(score.false_per_min, "%.1f") + " (" + Int(score.false_flags) + ")").c_str(),
                    per_lift.c_str(), OptionalText(score.false_flag_pct, "%.1f %%").c_str(), score.drops,
                    OptionalText(score.grip_efficiency_median, "%.2f").c_str());
      out << line;
    }
  }
  return out.str();
}

}  // namespace

std::string ScorecardBySensorTable(const Scorecard& scorecard) {
  return GroupTable("sensor", ScoreGroups(scorecard, SensorOf));
}

std::string ScorecardByScenarioTable(const Scorecard& scorecard) {
  // A run is named <base>.v<k>: its base scenario is the name up to the last ".v".
  return GroupTable("scenario", ScoreGroups(scorecard, [](const ScorecardRow& row) {
                      const size_t dot = row.run.rfind(".v");
                      return dot == std::string::npos ? row.run : row.run.substr(0, dot);
                    }));
}

std::string ScorecardCsv(const Scorecard& scorecard) {
  std::ostringstream out;
  out << "set,version,controller";
  for (const Figure& figure : Figures()) out << "," << figure.column;
  out << "\n";
  for (const ControllerScore& score : scorecard.scores) {
    out << scorecard.set_name << "," << scorecard.set_version << "," << score.controller;
    for (const Figure& figure : Figures()) {
      const nlohmann::json value = figure.json(score);
      out << ",";
      if (value.is_null()) continue;
      if (value.is_number_float()) {
        char text[32];
        std::snprintf(text, sizeof(text), "%.6g", value.get<double>());
        out << text;
      } else {
        out << value.dump();
      }
    }
    out << "\n";
  }
  return out.str();
}

nlohmann::json ScorecardJson(const Scorecard& scorecard) {
  nlohmann::json json;
  json["set"] = {{"name", scorecard.set_name},
                 {"version", scorecard.set_version},
                 {"seed", scorecard.set_seed},
                 {"file", scorecard.set_file},
                 {"runs_per_controller", scorecard.runs_per_controller}};
  json["completed"] = scorecard.completed;
  json["wall_s"] = scorecard.wall_s;
  json["jobs"] = scorecard.jobs;
  json["controllers"] = nlohmann::json::array();
  const std::vector<GroupScore> by_sensor = ScoreGroups(scorecard, SensorOf);
  for (size_t c = 0; c < scorecard.scores.size(); ++c) {
    const ControllerScore& score = scorecard.scores[c];
    nlohmann::json entry = {{"controller", score.controller}};
    for (const Figure& figure : Figures()) entry[figure.column] = figure.json(score);
    entry["false_flags_by_cue"] = score.false_flags_by_cue;
    // The same figures per sensor (profile/sensitivities): the targets hold per profile.
    nlohmann::json sensors = nlohmann::json::object();
    for (const GroupScore& group : by_sensor) {
      nlohmann::json figures = nlohmann::json::object();
      for (const Figure& figure : Figures()) figures[figure.column] = figure.json(group.scores[c]);
      sensors[group.group] = figures;
    }
    entry["by_sensor"] = sensors;
    json["controllers"].push_back(entry);
  }
  json["runs"] = nlohmann::json::array();
  for (const ScorecardRow& row : scorecard.rows) {
    nlohmann::json entry = {{"controller", row.controller}, {"run", row.run}};
    nlohmann::json overrides = nlohmann::json::object();
    for (const Override& each : row.overrides) overrides[each.key] = each.value;
    entry["overrides"] = overrides;
    if (!row.error.empty()) {
      entry["error"] = row.error;
    } else {
      entry["summary"] = SummaryJson(row.result);
    }
    json["runs"].push_back(entry);
  }
  return json;
}

plot::Figure ScorecardFigure(const Scorecard& scorecard) {
  // A figure a controller does not have (no event to detect, no time held) is a note, not a bar at 0:
  // a latency of 0 ms would read as perfect where the table says "-".
  struct Panel {
    const char* title;
    const char* y_label;
    const char* value_format;
    std::function<std::optional<double>(const ControllerScore&)> value;
    std::function<std::string(const ControllerScore&)> missing_note;
  };
  const auto no_events = [](const ControllerScore&) { return std::string("no events"); };
  const std::vector<Panel> panels = {
      {"gross slips flagged", "flagged [%]", "%.0f %%",
       [](const ControllerScore& s) { return s.gross_detected_pct; }, no_events},
      {"gross slip latency p95", "latency [ms]", "%.1f ms",
       [](const ControllerScore& s) { return s.gross_latency_p95_ms; },
       [](const ControllerScore& s) {
         return std::string(s.gross_slip_events > 0 ? "none flagged" : "no events");
       }},
      {"false flags per minute held", "false flags [1/min]", "%.2f/min",
       [](const ControllerScore& s) { return s.false_per_min; },
       [](const ControllerScore&) { return std::string("never held"); }},
      {"false flags per lift", "false flags [1/lift]", "%.2f/lift",
       [](const ControllerScore& s) { return s.false_per_lift; },
       [](const ControllerScore&) { return std::string("never held"); }},
      {"grip efficiency (mean / oracle), median", "ratio [-]", "%.2f",
       [](const ControllerScore& s) { return s.grip_efficiency_median; },
       [](const ControllerScore&) { return std::string("no oracle grip"); }},
      {"drops + crushes", "runs [-]", "%.0f",
       [](const ControllerScore& s) { return std::optional<double>(s.drops + s.crushes); }, no_events},
      {"runs passed", "passed [%]", "%.0f %%",
       [](const ControllerScore& s) {
         return s.runs > 0 ? std::optional<double>(100.0 * s.passed / s.runs) : std::nullopt;
       },
       [](const ControllerScore&) { return std::string("no runs"); }},
  };
  plot::Figure figure;
  figure.title = "scorecard " + scorecard.set_name + " v" + std::to_string(scorecard.set_version) + ", " +
                 std::to_string(scorecard.runs_per_controller) + " runs per controller";
  figure.columns = 4;  // the slip figures in the first row, grip and outcomes in the second
  figure.panel_width_px = 420;
  figure.panel_height_px = 320;
  for (const Panel& panel : panels) {
    plot::Chart chart;
    chart.title = panel.title;
    chart.x_label = "controller";
    chart.y_label = panel.y_label;
    chart.bar_value_format = panel.value_format;
    for (const ControllerScore& score : scorecard.scores) {
      chart.bars.push_back({score.controller, panel.value(score), panel.missing_note(score)});
    }
    figure.panels.push_back(std::move(chart));
  }
  return figure;
}

void WriteScorecardPlot(const Scorecard& scorecard, const std::string& path) {
  plot::WritePng(ScorecardFigure(scorecard), path);
}

void WriteScorecard(const Scorecard& scorecard, const std::string& out_dir) {
  std::error_code error;
  fs::create_directories(out_dir, error);
  if (error) throw std::runtime_error(out_dir + ": cannot create the output directory: " + error.message());
  common::WriteFileAtomic(out_dir + "/scorecard.csv", ScorecardCsv(scorecard));
  common::WriteFileAtomic(out_dir + "/scorecard.json", ScorecardJson(scorecard).dump(2) + "\n");
  WriteScorecardPlot(scorecard, out_dir + "/scorecard.png");
}

}  // namespace graspbed::testbed
