#include "testbed/suite.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include "common/yaml_map.h"
#include "testbed/run_outputs.h"
#include "testbed/schedule.h"

namespace graspbed::testbed {

namespace fs = std::filesystem;

std::vector<std::string> ListScenarioFiles(const std::string& dir) {
  if (!fs::is_directory(dir)) throw common::ConfigError(dir + ": not a directory of scenario files");
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.is_regular_file() && entry.path().extension() == ".yaml")
      files.push_back(entry.path().string());
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) throw common::ConfigError(dir + ": no *.yaml scenario files");
  return files;
}

std::vector<ScenarioConfig> LoadScenarios(const std::vector<std::string>& files,
                                          const std::vector<Override>& overrides) {
  std::vector<ScenarioConfig> configs;
  std::set<std::string> names;
  for (const std::string& file : files) {
    configs.push_back(LoadScenario(file, overrides));
    if (!names.insert(configs.back().name).second) {
      throw common::ConfigError(file + ": name = " + configs.back().name +
                                ": another scenario of the suite has the same name (names must be unique)");
    }
  }
  return configs;
}

SuiteResult RunSuite(const std::vector<ScenarioConfig>& configs, const SuiteOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  SuiteResult suite;
  suite.jobs = std::max(1, options.jobs);
  suite.runs.resize(configs.size());
  // Longest expected run first, so that it does not start last and run alone.
  const std::vector<size_t> order = LongestFirst(configs);
  std::atomic<size_t> next{0};
  std::mutex mutex;
  int finished = 0;

  const auto worker = [&] {
    while (true) {
      if (options.stop != nullptr && options.stop->load()) return;
      const size_t position = next.fetch_add(1);
      if (position >= order.size()) return;
      const size_t index = order[position];
      SuiteRun run;
      run.started = true;
      run.result.config = configs[index];
      try {
        RunOptions run_options;
        run_options.out_dir = options.out_dir.empty() ? "" : options.out_dir + "/" + configs[index].name;
        run_options.write_plots = options.write_plots;
        run_options.stop = options.stop;
        run_options.make_controller = options.make_controller;
        run_options.oracle = options.oracle;
        if (options.prepare_run) options.prepare_run(configs[index], configs[index].name, run_options);
        run.result = RunScenario(configs[index], run_options);
      } catch (const std::exception& error) {
        run.error = error.what();
      }
      std::lock_guard<std::mutex> lock(mutex);
      suite.runs[index] = std::move(run);
      ++finished;
      if (options.on_finished)
        options.on_finished(finished, static_cast<int>(configs.size()), suite.runs[index]);
    }
  };
  std::vector<std::thread> threads;
  const int thread_count = std::min<int>(suite.jobs, static_cast<int>(configs.size()));
  for (int i = 0; i < thread_count; ++i) threads.emplace_back(worker);
  for (std::thread& thread : threads) thread.join();

  suite.completed = true;
  for (size_t i = 0; i < suite.runs.size(); ++i) {
    SuiteRun& run = suite.runs[i];
    if (!run.started) run.result.config = configs[i];
    const bool ok = run.started && run.error.empty() && run.result.completed;
    // A run that threw did finish (as an error); one never started or stopped early did not.
    if (!run.started || (run.error.empty() && !run.result.completed)) suite.completed = false;
    if (ok && run.result.passed) {
      ++suite.passed;
    } else {
      ++suite.failed;
    }
  }
  suite.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!options.out_dir.empty()) {
    fs::create_directories(options.out_dir);
    common::WriteFileAtomic(options.out_dir + "/suite.json", SuiteJson(suite).dump(2) + "\n");
  }
  return suite;
}

nlohmann::json SuiteJson(const SuiteResult& result) {
  nlohmann::json runs = nlohmann::json::array();
  for (const SuiteRun& run : result.runs) {
    nlohmann::json entry;
    if (!run.started) {
      entry = {{"scenario", run.result.config.name},
               {"completed", false},
               {"passed", false},
               {"error", "not run (interrupted)"}};
    } else if (!run.error.empty()) {
      entry = {{"scenario", run.result.config.name},
               {"completed", false},
               {"passed", false},
               {"error", run.error}};
    } else {
      entry = SummaryJson(run.result);
    }
    runs.push_back(entry);
  }
  return {{"completed", result.completed},   {"passed", result.completed && result.failed == 0},
          {"scenarios", result.runs.size()}, {"passed_count", result.passed},
          {"failed_count", result.failed},   {"jobs", result.jobs},
          {"wall_s", result.wall_s},         {"runs", runs}};
}

std::string SuiteTable(const SuiteResult& result) {
  std::ostringstream out;
  char line[512];
  std::snprintf(line, sizeof(line), "%-22s %-13s %-6s %7s %6s %7s %7s %8s %8s %6s %6s %7s  %s\n", "scenario",
                "controller", "result", "slip_mm", "acq_mm", "gross", "micro", "peak_N", "oracle_N", "effic", "sensed",
                "wall_s", "failed expectations");
  out << line;
  for (const SuiteRun& run : result.runs) {
    const RunResult& r = run.result;
    std::string verdict = !run.started         ? "SKIP"
                          : !run.error.empty() ? "ERROR"
                          : !r.completed       ? "STOP"
                          : r.passed           ? "pass"
                                               : "FAIL";
    std::string failures;
    if (!run.error.empty()) failures = run.error;
    for (const ExpectationOutcome& o : r.outcomes) {
      if (!o.passed) failures += (failures.empty() ? "" : ", ") + o.name + " (" + o.value_text + ")";
    }
    const Metrics& m = r.metrics;
    const auto counts = [](const SlipClassCounts& c) {
      return std::to_string(c.detected) + "/" + std::to_string(c.events);
    };
    const std::string oracle_text = m.oracle ? internal::OptionalText(m.oracle->grip_n, "%.2f") : "-";
    if (m.oracle && !m.oracle->grip_n && failures.empty()) failures = "(no oracle grip: " + m.oracle->reason + ")";
    std::snprintf(line, sizeof(line), "%-22s %-13s %-6s %7.2f %6.2f %7s %7s %8.2f %8s %6s %6s %7.2f  %s\n",
                  r.config.name.c_str(), r.config.controller.name.c_str(), verdict.c_str(), m.max_slip_mm,
                  m.acquisition_shift_mm, counts(m.gross).c_str(), counts(m.micro).c_str(), m.peak_grip_n,
                  oracle_text.c_str(), internal::OptionalText(m.grip_efficiency, "%.2f").c_str(),
                  internal::OptionalText(m.sensed_grip_share, "%.2f").c_str(), m.wall_s, failures.c_str());
    out << line;
  }
  out << "  (acq_mm: the object's shift while the digits closed, before the grasp was established; gross, micro: "
         "slip events flagged / all; oracle_N: the lightest constant grip that holds; effic: mean grip held / "
         "oracle; sensed: share of the finger's squeeze on the units)\n";
  std::snprintf(line, sizeof(line), "%d passed, %d failed, %zu scenario%s in %.2f s with %d job%s%s\n",
                result.passed, result.failed, result.runs.size(), result.runs.size() == 1 ? "" : "s", result.wall_s,
                result.jobs, result.jobs == 1 ? "" : "s", result.completed ? "" : " (INTERRUPTED)");
  out << line;
  return out.str();
}

}  // namespace graspbed::testbed
