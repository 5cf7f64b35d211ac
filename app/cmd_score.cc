// `graspbed score`: controllers side by side over the shipped benchmark set (a scorecard).
#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/command_registry.h"
#include "app/stop_signal.h"
#include "common/data_dir.h"
#include "controller/plugin_loader.h"
#include "testbed/report.h"
#include "testbed/scorecard.h"

namespace graspbed::app {
namespace {

/// Exit code after Ctrl-C (128 + SIGINT, the shell convention).
constexpr int kExitInterrupted = 130;

struct ScoreCommandOptions {
  std::vector<std::string> controllers;
  std::string set_dir;  ///< empty: the shipped set, scenarios/scorecard under the data directory
  int jobs = 1;
  int limit = 0;
  std::optional<uint64_t> seed;  ///< replaces the set's sampling seed: a held-out draw of the same set
  int variations_scale = 1;      ///< every base's variation count times this
  std::string out_dir = "out/scorecard";
  std::string runs_dir;  ///< empty: no per-run outputs
  std::vector<std::string> sets;
  bool report = false;  ///< also OUT/report.html (graspbed report)
};

void ScoreCommand(const ScoreCommandOptions& options) {
  const std::string set_dir =
      options.set_dir.empty() ? common::DataPath("scenarios/scorecard") : options.set_dir;
  testbed::ScorecardSet set = testbed::LoadScorecardSet(set_dir + "/set.yaml");
  // A set tuned against is flattered by its own draws: the same bases and ranges drawn with another
  // seed, and more of them, show how a controller generalises (the figures are then not the set's).
  if (options.seed) set.seed = *options.seed;
  for (testbed::ScorecardBase& base : set.bases) base.variations *= options.variations_scale;
  testbed::ScorecardOptions score;
  if (!options.controllers.empty()) {
    score.controllers.clear();
    for (const std::string& name : options.controllers) {
      score.controllers.push_back(controller::ResolvePluginName(name, "."));
    }
  }
  score.jobs = options.jobs;
  score.limit = options.limit;
  score.runs_dir = options.runs_dir;
  for (const std::string& text : options.sets) score.overrides.push_back(testbed::ParseOverride(text));
  score.stop = &StopRequested();
  const bool terminal = ::isatty(STDERR_FILENO) == 1;
  score.on_finished = [terminal](int done, int total) {
    if (!terminal) return;
    std::fprintf(stderr, "\r\033[K  score: %d/%d runs", done, total);
    std::fflush(stderr);
  };
  StopSignalGuard guard;
  const testbed::Scorecard scorecard = testbed::RunScorecard(set, score);
  if (terminal) std::fprintf(stderr, "\r\033[K");
  testbed::WriteScorecard(scorecard, options.out_dir);
  std::cout << testbed::ScorecardTable(scorecard);
  std::cout << testbed::ScorecardFailedRuns(scorecard);
  std::cout << "  by sensor (profile/sensitivities):\n" << testbed::ScorecardBySensorTable(scorecard);
  std::cout << "  by scenario (base and its variations):\n" << testbed::ScorecardByScenarioTable(scorecard);
  std::cout << "  outputs: " << options.out_dir << "/ (scorecard.csv, scorecard.json, scorecard.png)\n";
  if (options.report) {
    const testbed::ReportOptions report{.runs_dir = options.runs_dir, .out_path = ""};
    std::cout << "  " << testbed::DescribeReport(testbed::WriteReport(options.out_dir, report)) << '\n';
  }
  if (!scorecard.completed) throw CLI::RuntimeError(kExitInterrupted);
}

void AddScoreCommand(CLI::App& root) {
  auto options = std::make_shared<ScoreCommandOptions>();
  CLI::App* command = root.add_subcommand(
      "score",
      "Score controllers side by side over the versioned benchmark set (scenarios/scorecard/set.yaml: "
      "base scenarios plus seeded variations): gross slips flagged and their latency (micro-slips and all "
      "events beside them; the misses with no unit loaded or where only the thumb slid), false flags (per "
      "minute held and per lift; also by the controller's own cue label), drops, crushes, grip efficiency "
      "and peak grip against each run's oracle grip (`graspbed oracle`), Fn RMSE, passes, overall and per "
      "sensor profile, and each failed run with its first failed expectation; writes DIR/scorecard.csv, "
      "scorecard.json and scorecard.png");
  command
      ->add_option("--controller", options->controllers,
                   "controller to score: a built-in name or plugin:LIBRARY (repeatable; default grip_slip "
                   "and open_loop)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  command->add_option(
      "--set-dir", options->set_dir,
      "directory holding set.yaml (default: the shipped set, share/graspbed/scenarios/scorecard)");
  command->add_option("-j,--jobs", options->jobs, "parallel runs")->check(CLI::Range(1, 256));
  command
      ->add_option("--limit", options->limit, "only the first N runs of the set per controller (smoke tests)")
      ->check(CLI::NonNegativeNumber);
  command
      ->add_option("--seed", options->seed,
                   "draw the variations with this seed instead of the set's (a held-out draw of the same "
                   "bases and ranges; the figures are then not the set's)")
      ->check(CLI::Validator(
          [](const std::string& text) {
            return !text.empty() && text.find_first_not_of("0123456789") == std::string::npos
                       ? std::string()
                       : "expected a whole number >= 0, got " + text;
          },
          "UINT"));
  command
      ->add_option("--variations-scale", options->variations_scale,
                   "run this many times each base's variations (with --seed: a larger held-out draw)")
      ->check(CLI::Range(1, 100));
  command->add_option("--out", options->out_dir, "output directory (default out/scorecard)");
  command->add_option("--runs-out", options->runs_dir,
                      "also keep every run's outputs (signals.csv, summary.json, config.yaml; no plots) "
                      "in DIR/<run>@<controller>/, to trace the figures back to their runs");
  command
      ->add_option("--set", options->sets,
                   "override a key in every run, after the set's own (repeatable; the figures are then "
                   "not the set's)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  command->add_flag("--report", options->report,
                    "also write OUT/report.html, the HTML page of `graspbed report` (rows link --runs-out)");
  command->callback([options] { ScoreCommand(*options); });
}

const bool kRegisteredScore = RegisterCommands(&AddScoreCommand);

}  // namespace
}  // namespace graspbed::app
