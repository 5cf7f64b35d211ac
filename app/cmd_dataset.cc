// `graspbed dataset` (labelled ticks for learning slip detection, testbed/dataset.h) and
// `graspbed slip-model` (check a model file, score feature rows with it: controller/learned_slip_cue.h).
#include <unistd.h>

#include <cstdio>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "app/command_registry.h"
#include "app/stop_signal.h"
#include "common/npz.h"
#include "common/signal_log.h"
#include "controller/learned_slip_cue.h"
#include "testbed/dataset.h"

namespace graspbed::app {
namespace {

constexpr int kExitInterrupted = 130;

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    if (!item.empty()) items.push_back(item);
  }
  return items;
}

struct DatasetCommandOptions {
  std::vector<std::string> specs;
  std::string out_dir = "out/dataset";
  std::string shard = "1/1";
  std::string profiles;
  std::string horizons = "10,20,50,100";
  int jobs = 1;
  uint64_t split_seed = 1;
};

void DatasetCommand(const DatasetCommandOptions& options) {
  std::vector<testbed::SweepSpec> specs;
  for (const std::string& path : options.specs) specs.push_back(testbed::LoadSweepSpec(path));
  testbed::DatasetOptions dataset;
  dataset.profiles = SplitList(options.profiles);
  dataset.horizons_ms.clear();
  for (const std::string& text : SplitList(options.horizons)) {
    const int horizon = std::stoi(text);
    if (horizon < 1 || horizon > 10000) throw std::invalid_argument("--horizons " + text + ": expected 1..10000 ms");
    dataset.horizons_ms.push_back(horizon);
  }
  dataset.shard = testbed::ParseShard(options.shard);
  dataset.jobs = options.jobs;
  dataset.split_seed = options.split_seed;
  dataset.out_dir = options.out_dir;
  dataset.stop = &StopRequested();
  const bool terminal = ::isatty(STDERR_FILENO) == 1;
  dataset.on_finished = [terminal](int done, int total) {
    if (!terminal) return;
    std::fprintf(stderr, "\r\033[K  dataset: %d/%d runs", done, total);
    std::fflush(stderr);
  };
  StopSignalGuard guard;
  const testbed::DatasetOutcome outcome = testbed::BuildDataset(specs, dataset);
  if (terminal) std::fprintf(stderr, "\r\033[K");
  std::printf("dataset shard %s: %d of %d runs finished (%d errors), %lld ticks, %.2f s -> %s/ticks.npz, manifest.json\n",
              options.shard.c_str(), outcome.finished, outcome.runs, outcome.errors,
              static_cast<long long>(outcome.ticks), outcome.wall_s, options.out_dir.c_str());
  if (!outcome.completed) {
    std::fprintf(stderr, "graspbed: interrupted; %s/manifest.json says \"completed\": false and no ticks.npz was written\n",
                 options.out_dir.c_str());
    throw CLI::RuntimeError(kExitInterrupted);
  }
}

void AddDatasetCommand(CLI::App& root) {
  auto options = std::make_shared<DatasetCommandOptions>();
  CLI::App* command = root.add_subcommand(
      "dataset",
      "Run the runs of sweep specs under every sensor profile and write per control tick what the "
      "controller saw (TactileState, features, command) with labels from the ground truth (contact state, "
      "slip speed and distance, gross slip within h ms) to DIR/ticks.npz and manifest.json, split into "
      "train/validation/test by run group (docs/training-slip-detector.md)");
  command->add_option("specs", options->specs, "sweep spec YAML file(s) (docs/scenarios.md, Sweeps)")->required();
  command->add_option("--out", options->out_dir, "output directory (default out/dataset)");
  command->add_option("--shard", options->shard, "build shard K of N (runs with index % N == K - 1)");
  command->add_option("--profiles", options->profiles,
                      "comma-separated sensors every run is run under: PROFILE or PROFILE/SENSITIVITIES "
                      "(default: divider_12bit, inamp_16bit, bridge_24bit, each with paper and fea)");
  command->add_option("--horizons", options->horizons, "horizons of the gross-slip labels [ms] (default 10,20,50,100)");
  command->add_option("--split-seed", options->split_seed, "seeds the order of the run groups before the split");
  command->add_option("-j,--jobs", options->jobs, "parallel runs")->check(CLI::Range(1, 256));
  command->callback([options] { DatasetCommand(*options); });
}

struct SlipModelOptions {
  std::string model;
  std::string features;
  std::string out;
  std::string layout = "default_20";
  int units = 20;
};

/// Scores every row of a features .npy with the model and writes the scores as a .npy (float64).
void SlipModelScore(const SlipModelOptions& options) {
  const controller::SlipModel model =
      controller::LoadSlipModel(options.model, {.layout_name = options.layout, .units = options.units});
  const common::NpyMatrix features = common::ReadNpyMatrix(options.features);
  if (features.columns != controller::kSlipFeatureCount) {
    throw std::invalid_argument(options.features + ": " + std::to_string(features.columns) + " columns, the model takes " +
                                std::to_string(controller::kSlipFeatureCount) + " features");
  }
  std::vector<double> scores(features.rows);
  for (size_t r = 0; r < features.rows; ++r) {
    scores[r] = controller::EvaluateSlipModel(
        model, std::span<const double>(features.data.data() + r * features.columns, features.columns));
  }
  const std::string out = options.out.empty() ? "scores.npy" : options.out;
  common::WriteFileAtomic(out, common::NpyBytes(common::MakeNpyArray("scores", scores, {scores.size()})));
  std::printf("%s: %zu rows scored -> %s\n", options.model.c_str(), features.rows, out.c_str());
}

void AddSlipModelCommand(CLI::App& root) {
  CLI::App* command = root.add_subcommand(
      "slip-model", "Check a learned slip model file against a layout, or score feature rows with it");
  command->require_subcommand(1);
  auto options = std::make_shared<SlipModelOptions>();
  CLI::App* check = command->add_subcommand(
      "check", "Load MODEL as the learned cue would for LAYOUT (refusing another layout or feature set) and "
               "print what it is; exit 2 when refused");
  CLI::App* score = command->add_subcommand(
      "score", "Score every row of a features .npy (float32/64, rows x features) -> a .npy of scores");
  for (CLI::App* sub : {check, score}) {
    sub->add_option("model", options->model, "model file (JSON)")->required();
    sub->add_option("--layout", options->layout, "layout name the sensor has (default default_20)");
    sub->add_option("--units", options->units, "units the sensor has (default 20)");
  }
  score->add_option("features", options->features, "features .npy")->required();
  score->add_option("--out", options->out, "scores .npy (default scores.npy)");
  check->callback([options] {
    const controller::SlipModel model =
        controller::LoadSlipModel(options->model, {.layout_name = options->layout, .units = options->units});
    std::printf("%s: %s model for layout %s (%d units), features %s (%zu), label %s, threshold %.4g, %zu trees\n",
                options->model.c_str(), model.kind == controller::SlipModel::Kind::kTrees ? "trees" : "logistic",
                model.layout_name.c_str(), model.layout.units, model.feature_set.c_str(), controller::kSlipFeatureCount,
                model.label.c_str(), model.threshold, model.tree_roots.size());
  });
  score->callback([options] { SlipModelScore(*options); });
}

const bool kRegisteredDataset = RegisterCommands(&AddDatasetCommand);
const bool kRegisteredSlipModel = RegisterCommands(&AddSlipModelCommand);

}  // namespace
}  // namespace graspbed::app
