#include "testbed/sweep.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <random>
#include <set>
#include <sstream>
#include <thread>

#include "common/yaml_map.h"
#include "testbed/schedule.h"
#include "testbed/sweep_columns.h"

namespace graspbed::testbed {
namespace {

namespace fs = std::filesystem;
using common::ConfigError;
using common::NumberRule;
using common::YamlMap;

constexpr int kMaxRuns = 1000000;
// Columns every row has, in CSV order; parameter columns go between "scenario" and "passed".
const std::vector<std::string> kMetricColumns(kSweepMetricColumns.begin(), kSweepMetricColumns.end());

std::string ReadText(const std::string& path) {
  std::ifstream stream(path);
  if (!stream) throw ConfigError(path + ": cannot open file");
  std::stringstream text;
  text << stream.rdbuf();
  return text.str();
}

// FNV-1a, 64 bit: a stable fingerprint across machines and builds (std::hash is not).
uint64_t Fnv1a(const std::string& text, uint64_t hash = 1469598103934665603ull) {
  for (unsigned char c : text) {
    hash ^= c;
    hash *= 1099511628211ull;
  }
  return hash;
}

std::string NodeText(const YAML::Node& node) {
  if (node.IsScalar()) return node.Scalar();
  YAML::Emitter out;
  out << YAML::Flow << node;
  return out.c_str();
}

std::string FormatSample(double value, bool integer) {
  if (integer) return std::to_string(static_cast<long long>(std::llround(value)));
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.6g", value);
  return buffer;
}

// JSON value of a parameter text: a number when it reads as one, else the text.
nlohmann::json ParameterJson(const std::string& text) {
  double number = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), number);
  if (error == std::errc() && end == text.data() + text.size()) return number;
  return text;
}

std::string CsvCell(const nlohmann::json& value) {
  if (value.is_null()) return "";
  if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
  if (value.is_number_integer()) return std::to_string(value.get<long long>());
  if (value.is_number()) {
    char buffer[64];
    std::snprintf(buffer, sizeof(buffer), "%.9g", value.get<double>());
    return buffer;
  }
  std::string text = value.is_string() ? value.get<std::string>() : value.dump();
  if (text.find_first_of(",\"\n") != std::string::npos) {
    std::string quoted = "\"";
    for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
    return quoted + "\"";
  }
  return text;
}

std::vector<std::string> Columns(const std::vector<std::string>& parameter_keys) {
  std::vector<std::string> columns(kSweepRowColumns.begin(), kSweepRowColumns.end());
  columns.insert(columns.end(), parameter_keys.begin(), parameter_keys.end());
  columns.insert(columns.end(), kMetricColumns.begin(), kMetricColumns.end());
  return columns;
}

std::string Csv(const std::vector<std::string>& columns, const std::vector<nlohmann::json>& rows) {
  std::string text;
  for (size_t c = 0; c < columns.size(); ++c) text += (c ? "," : "") + CsvCell(columns[c]);
  text += "\n";
  for (const nlohmann::json& row : rows) {
    for (size_t c = 0; c < columns.size(); ++c) {
      text += c ? "," : "";
      if (row.contains(columns[c])) text += CsvCell(row.at(columns[c]));
    }
    text += "\n";
  }
  return text;
}

std::string Jsonl(const std::vector<nlohmann::json>& rows) {
  std::string text;
  for (const nlohmann::json& row : rows) text += row.dump() + "\n";
  return text;
}

std::vector<std::string> ParameterKeys(const SweepSpec& spec) {
  std::vector<std::string> keys;
  for (const SweepParameter& parameter : spec.parameters) keys.push_back(parameter.key);
  return keys;
}

void WriteOutputs(const std::string& dir, const std::vector<std::string>& columns,
                  std::vector<nlohmann::json> rows, nlohmann::json manifest) {
  std::sort(rows.begin(), rows.end(),
            [](const nlohmann::json& a, const nlohmann::json& b) { return a.at("run") < b.at("run"); });
  common::WriteFileAtomic(dir + "/results.jsonl", Jsonl(rows));
  common::WriteFileAtomic(dir + "/results.csv", Csv(columns, rows));
  manifest["columns"] = columns;
  // The manifest goes last: its "completed" vouches for the files before it.
  common::WriteFileAtomic(dir + "/manifest.json", manifest.dump(2) + "\n");
}

}  // namespace

SweepSpec LoadSweepSpec(const std::string& path) {
  const std::string text = ReadText(path);
  const YamlMap map = YamlMap::LoadString(text, path);
  SweepSpec spec;
  spec.source_file = path;
  std::string scenario = map.RequireString("scenario");
  fs::path scenario_path(scenario);
  if (scenario_path.is_relative()) scenario_path = fs::path(path).parent_path() / scenario_path;
  if (!fs::exists(scenario_path))
    map.Fail("scenario", "no such scenario file (paths are relative to the spec)");
  spec.scenario_path = scenario_path.lexically_normal().string();
  spec.random = map.GetString("mode", "grid", {"grid", "random"}) == "random";
  if (!spec.random && map.Has("samples")) {
    map.Fail("samples", "draws runs in random mode only: set `mode: random` to sample, or remove it for a grid");
  }
  spec.samples = spec.random ? map.RequireInt("samples", 1, kMaxRuns) : 0;
  const double seed = map.GetNumber("seed", 1.0, NumberRule::Between(0.0, 9007199254740992.0));
  if (seed != std::floor(seed)) map.Fail("seed", "expected a whole number");
  spec.seed = static_cast<uint64_t>(seed);
  if (auto fixed = map.GetMap("set")) {
    for (const std::string& key : fixed->Keys()) spec.fixed.push_back({key, NodeText(fixed->Raw(key))});
  }
  const YamlMap parameters = map.RequireMap("parameters");
  for (const std::string& key : parameters.Keys()) {
    SweepParameter parameter;
    parameter.key = key;
    const YAML::Node node = parameters.Raw(key);
    if (node.IsSequence()) {
      if (node.size() == 0) parameters.Fail(key, "needs at least one value");
      for (const auto& value : node) parameter.values.push_back(NodeText(value));
    } else if (node.IsMap()) {
      const YamlMap range(node, path, "parameters." + key);
      parameter.min = range.RequireNumber("min");
      parameter.max = range.RequireNumber("max");
      parameter.log_scale = range.GetBool("log", false);
      parameter.integer = range.GetBool("integer", false);
      range.RejectUnknownKeys();
      if (parameter.max < parameter.min) range.Fail("max", "must be >= min");
      if (parameter.log_scale && parameter.min <= 0.0) range.Fail("min", "must be > 0 with log: true");
      if (!spec.random)
        parameters.Fail(key, "a range {min, max} needs mode: random; a grid takes a list of values");
    } else {
      parameters.Fail(key, "expected a list of values or a range {min: .., max: ..}");
    }
    spec.parameters.push_back(parameter);
  }
  if (spec.parameters.empty()) map.Fail("parameters", "needs at least one swept key");
  map.RejectUnknownKeys();
  if (!spec.random) {
    double runs = 1.0;
    for (const SweepParameter& parameter : spec.parameters)
      runs *= static_cast<double>(parameter.values.size());
    if (runs > kMaxRuns) map.Fail("parameters", "the grid has more than 1000000 runs");
  }
  char fingerprint[17];
  std::snprintf(fingerprint, sizeof(fingerprint), "%016llx",
                static_cast<unsigned long long>(Fnv1a(ReadText(spec.scenario_path), Fnv1a(text))));
  spec.fingerprint = fingerprint;
  return spec;
}

std::vector<SweepRun> ExpandSweep(const SweepSpec& spec) {
  std::vector<SweepRun> runs;
  if (spec.random) {
    for (int i = 0; i < spec.samples; ++i) {
      std::seed_seq seeds{static_cast<uint32_t>(spec.seed), static_cast<uint32_t>(spec.seed >> 32),
                          static_cast<uint32_t>(i)};
      std::mt19937_64 rng(seeds);
      SweepRun run{i, spec.fixed};
      for (const SweepParameter& parameter : spec.parameters) {
        std::string value;
        if (!parameter.values.empty()) {
          value =
              parameter.values[std::uniform_int_distribution<size_t>(0, parameter.values.size() - 1)(rng)];
        } else {
          const double u = std::uniform_real_distribution<double>(0.0, 1.0)(rng);
          const double sample = parameter.log_scale
                                    ? std::exp(std::log(parameter.min) +
                                               u * (std::log(parameter.max) - std::log(parameter.min)))
                                    : parameter.min + u * (parameter.max - parameter.min);
          value = FormatSample(sample, parameter.integer);
        }
        run.overrides.push_back({parameter.key, value});
      }
      runs.push_back(run);
    }
    return runs;
  }
  size_t total = 1;
  for (const SweepParameter& parameter : spec.parameters) total *= parameter.values.size();
  for (size_t i = 0; i < total; ++i) {
    SweepRun run{static_cast<int>(i), spec.fixed};
    size_t rest = i;
    std::vector<Override> chosen(spec.parameters.size());
    for (size_t p = spec.parameters.size(); p-- > 0;) {
      const SweepParameter& parameter = spec.parameters[p];
      chosen[p] = {parameter.key, parameter.values[rest % parameter.values.size()]};
      rest /= parameter.values.size();
    }
    run.overrides.insert(run.overrides.end(), chosen.begin(), chosen.end());
    runs.push_back(run);
  }
  return runs;
}

Shard ParseShard(const std::string& text) {
  const size_t slash = text.find('/');
  Shard shard;
  const auto parse = [&](const std::string& part, int* value) {
    const auto [end, error] = std::from_chars(part.data(), part.data() + part.size(), *value);
    return error == std::errc() && end == part.data() + part.size() && !part.empty();
  };
  if (slash == std::string::npos || !parse(text.substr(0, slash), &shard.index) ||
      !parse(text.substr(slash + 1), &shard.count) || shard.count < 1 || shard.index < 1 ||
      shard.index > shard.count) {
    throw std::invalid_argument("--shard " + text + ": expected K/N with 1 <= K <= N, e.g. 2/8");
  }
  return shard;
}

std::vector<SweepRun> ShardRuns(const std::vector<SweepRun>& runs, const Shard& shard) {
  std::vector<SweepRun> mine;
  for (const SweepRun& run : runs) {
    if (run.index % shard.count == shard.index - 1) mine.push_back(run);
  }
  return mine;
}

nlohmann::json SweepRow(const SweepSpec& spec, const SweepRun& run, const RunResult& result) {
  nlohmann::json row;
  row["run"] = run.index;
  row["scenario"] = result.config.name;
  const size_t first = run.overrides.size() - spec.parameters.size();
  for (size_t p = 0; p < spec.parameters.size(); ++p) {
    row[spec.parameters[p].key] = ParameterJson(run.overrides[first + p].value);
  }
  const nlohmann::json summary = SummaryJson(result);
  row["passed"] = result.passed;
  row["completed"] = result.completed;
  for (const char* key :
       {"dropped", "max_slip_mm", "peak_grip_n", "crushed", "slip_detect_latency_ms", "false_slip_per_min",
        "fn_rmse_n", "ft_rmse_n", "time_to_stable_s", "sim_s", "wall_s"}) {
    row[key] = summary.at("metrics").at(key);
  }
  std::string failed;
  for (const ExpectationOutcome& o : result.outcomes) {
    if (!o.passed) failed += (failed.empty() ? "" : " ") + o.name;
  }
  row["failed_expectations"] = failed;
  return row;
}

SweepOutcome RunSweep(const SweepSpec& spec, const SweepOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const std::vector<SweepRun> all = ExpandSweep(spec);
  const std::vector<SweepRun> runs = ShardRuns(all, options.shard);
  // Every run's configuration is checked before the first one starts.
  std::vector<ScenarioConfig> configs;
  for (const SweepRun& run : runs) {
    try {
      configs.push_back(LoadScenario(spec.scenario_path, run.overrides));
    } catch (const ConfigError& error) {
      throw error.WithContext(spec.source_file + ": run " + std::to_string(run.index));
    }
  }

  fs::create_directories(options.out_dir);
  const std::string partial = options.out_dir + "/results.jsonl.partial";
  for (const char* name : {"results.jsonl", "results.csv", "manifest.json"})
    fs::remove(fs::path(options.out_dir) / name);
  std::ofstream partial_stream(partial, std::ios::trunc);
  if (!partial_stream) throw std::runtime_error(partial + ": cannot write");

  SweepOutcome outcome;
  outcome.runs = static_cast<int>(runs.size());
  std::vector<nlohmann::json> rows;
  std::mutex mutex;
  // Longest expected run first (a sweep over duration_s or the time step has runs of any length).
  const std::vector<size_t> order = LongestFirst(configs);
  std::atomic<size_t> next{0};
  const auto worker = [&] {
    while (true) {
      if (options.stop != nullptr && options.stop->load()) return;
      const size_t position = next.fetch_add(1);
      if (position >= order.size()) return;
      const size_t i = order[position];
      RunOptions run_options;
      run_options.stop = options.stop;
      run_options.make_controller = options.make_controller;
      RunResult result;
      std::string error;
      try {
        if (options.prepare_run)
          options.prepare_run(configs[i], "run_" + std::to_string(runs[i].index), run_options);
        result = RunScenario(configs[i], run_options);
      } catch (const std::exception& e) {
        result.config = configs[i];
        error = e.what();
      }
      if (!result.completed && error.empty()) return;  // interrupted: the row would not be a result
      nlohmann::json row = SweepRow(spec, runs[i], result);
      if (!error.empty()) row[kSweepErrorKey] = error;
      std::lock_guard<std::mutex> lock(mutex);
      partial_stream << row.dump() << '\n' << std::flush;
      rows.push_back(row);
      ++outcome.finished;
      if (result.passed) ++outcome.passed;
      if (options.on_finished) options.on_finished(outcome.finished, outcome.runs);
    }
  };
  std::vector<std::thread> threads;
  const int thread_count = std::max(1, std::min<int>(options.jobs, static_cast<int>(runs.size())));
  for (int i = 0; i < thread_count; ++i) threads.emplace_back(worker);
  for (std::thread& thread : threads) thread.join();
  partial_stream.close();

  outcome.completed = outcome.finished == outcome.runs;
  outcome.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::vector<int> indices;
  for (const SweepRun& run : runs) indices.push_back(run.index);
  nlohmann::json manifest = {
      {"spec", spec.source_file},
      {"scenario", spec.scenario_path},
      {"fingerprint", spec.fingerprint},
      {"total_runs", all.size()},
      {"shard", std::to_string(options.shard.index) + "/" + std::to_string(options.shard.count)},
      {"shard_index", options.shard.index},
      {"shard_count", options.shard.count},
      {"runs", indices},
      {"completed", outcome.completed},
      {"finished_runs", outcome.finished},
      {"wall_s", outcome.wall_s}};
  if (outcome.completed) {
    WriteOutputs(options.out_dir, Columns(ParameterKeys(spec)), rows, manifest);
    fs::remove(partial);
  } else {
    // Only the .partial rows and an incomplete manifest: nothing that merge would accept.
    common::WriteFileAtomic(options.out_dir + "/manifest.json", manifest.dump(2) + "\n");
  }
  return outcome;
}

int MergeSweeps(const std::vector<std::string>& shard_dirs, const std::string& out_dir) {
  if (shard_dirs.empty()) throw std::invalid_argument("merge: no shard directories given");
  struct ShardData {
    std::string dir;
    nlohmann::json manifest;
  };
  std::vector<ShardData> shards;
  for (const std::string& dir : shard_dirs) {
    const std::string manifest_path = dir + "/manifest.json";
    nlohmann::json manifest;
    try {
      manifest = nlohmann::json::parse(ReadText(manifest_path));
    } catch (const nlohmann::json::exception& error) {
      throw std::invalid_argument(manifest_path + ": not a sweep manifest: " + error.what());
    } catch (const ConfigError&) {
      throw std::invalid_argument(dir + ": no manifest.json; not a sweep output directory");
    }
    if (!manifest.value("completed", false)) {
      throw std::invalid_argument(dir + ": shard " + manifest.value("shard", std::string("?")) +
                                  " is incomplete (interrupted or still running); run it again");
    }
    shards.push_back({dir, manifest});
  }
  const nlohmann::json& first = shards.front().manifest;
  const int count = first.at("shard_count").get<int>();
  std::map<int, std::string> seen;
  for (const ShardData& shard : shards) {
    if (shard.manifest.at("fingerprint") != first.at("fingerprint") ||
        shard.manifest.at("total_runs") != first.at("total_runs")) {
      throw std::invalid_argument(shard.dir + " and " + shards.front().dir +
                                  " come from different sweeps (spec or scenario differ)");
    }
    if (shard.manifest.at("shard_count").get<int>() != count) {
      throw std::invalid_argument(shard.dir + ": shard " + shard.manifest.at("shard").get<std::string>() +
                                  " of " + std::to_string(shard.manifest.at("shard_count").get<int>()) +
                                  " shards, but " + shards.front().dir + " is one of " +
                                  std::to_string(count));
    }
    const int index = shard.manifest.at("shard_index").get<int>();
    if (seen.count(index)) {
      throw std::invalid_argument("shard " + std::to_string(index) + "/" + std::to_string(count) +
                                  " given twice: " + seen[index] + " and " + shard.dir);
    }
    seen[index] = shard.dir;
  }
  std::string missing;
  for (int k = 1; k <= count; ++k) {
    if (!seen.count(k))
      missing += (missing.empty() ? "" : ", ") + std::to_string(k) + "/" + std::to_string(count);
  }
  if (!missing.empty())
    throw std::invalid_argument("missing shard(s) " + missing + "; merge needs all of them");

  std::vector<nlohmann::json> rows;
  std::set<int> indices;
  for (const ShardData& shard : shards) {
    std::istringstream lines(ReadText(shard.dir + "/results.jsonl"));
    std::string line;
    int line_number = 0;
    while (std::getline(lines, line)) {
      ++line_number;
      if (line.empty()) continue;
      nlohmann::json row;
      try {
        row = nlohmann::json::parse(line);
      } catch (const nlohmann::json::exception&) {
        throw std::invalid_argument(shard.dir + "/results.jsonl:" + std::to_string(line_number) +
                                    ": not JSON");
      }
      const int run = row.at("run").get<int>();
      if (!indices.insert(run).second) {
        throw std::invalid_argument(shard.dir + "/results.jsonl:" + std::to_string(line_number) + ": run " +
                                    std::to_string(run) + " appears in more than one shard");
      }
      rows.push_back(row);
    }
  }
  const int total = first.at("total_runs").get<int>();
  if (static_cast<int>(indices.size()) != total) {
    throw std::invalid_argument("the shards hold " + std::to_string(indices.size()) + " of " +
                                std::to_string(total) + " runs; some rows are missing");
  }
  fs::create_directories(out_dir);
  nlohmann::json manifest = first;
  manifest["shard"] = "1/1";
  manifest["shard_index"] = 1;
  manifest["shard_count"] = 1;
  std::vector<int> all(total);
  for (int i = 0; i < total; ++i) all[i] = i;
  manifest["runs"] = all;
  manifest["finished_runs"] = total;
  manifest["merged_from"] = shard_dirs;
  const std::vector<std::string> columns = first.at("columns").get<std::vector<std::string>>();
  WriteOutputs(out_dir, columns, rows, manifest);
  return total;
}

}  // namespace graspbed::testbed
