// `graspbed run | suite | sweep | merge`: scripted scenarios, regression suites and parameter sweeps.
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/command_registry.h"
#include "app/stop_signal.h"
#include "controller/plugin_loader.h"
#include "testbed/report.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"
#include "testbed/show/video.h"
#include "testbed/suite.h"
#include "testbed/sweep.h"

namespace graspbed::app {
namespace {

namespace fs = std::filesystem;

/// Exit code after Ctrl-C (128 + SIGINT, the shell convention).
constexpr int kExitInterrupted = 130;

bool StderrIsTerminal() { return ::isatty(STDERR_FILENO) == 1; }

/// --video and its settings, shared by run, suite and sweep.
struct VideoCommandOptions {
  bool enabled = false;
  double fps = show::kDefaultVideoFps;
  std::string size = "640x480";
  std::string camera;
  bool shadows = false;

  void Add(CLI::App* command, const std::string& where) {
    command->add_flag("--video", enabled,
                      "render the run offscreen to " + where +
                          " (MP4 by ffmpeg, H.264) and a PNG strip of 6 frames beside it");
    command->add_option("--video-fps", fps, "video frames per simulated second")->capture_default_str();
    command->add_option("--video-size", size, "video WIDTHxHEIGHT [px], even")->capture_default_str();
    command->add_option("--video-camera", camera, "grasp (default), fingertip, or a camera of the model");
    command->add_flag("--video-shadows", shadows,
                      "draw shadows (about 3x the rendering time on a software renderer)");
  }

  /// Checked before any run starts (exit 2 on a bad value).
  show::VideoOptions Resolve() const {
    show::VideoOptions video;
    video.fps = fps;
    show::ParseVideoSize(size, video.render);
    video.camera = sim::CameraByName(camera);
    video.render.shadows = shadows;
    video.Validate();
    return video;
  }

  /// For suites and sweeps: each run gets its video in `dir`/<run name>/ ("" = the run's own out_dir).
  testbed::PrepareRun Preparer(const std::string& dir) const {
    if (!enabled) return {};
    const show::VideoOptions video = Resolve();
    return [video, dir](const testbed::ScenarioConfig& config, const std::string& name,
                        testbed::RunOptions& run) {
      const std::string out = dir.empty() ? run.out_dir : dir + "/" + name;
      fs::create_directories(out);
      show::AttachVideo(config, video, out + "/video.mp4", out + "/video_strip.png", run);
    };
  }
};

/// Throws CLI::RuntimeError(code) for a non-zero exit, which main() returns silently.
void ExitWith(int code) {
  if (code != kExitOk) throw CLI::RuntimeError(code);
}

// ---- run -------------------------------------------------------------------------------------------

struct RunCommandOptions {
  std::string scenario;
  std::string out_dir;
  std::string controller;
  int64_t seed = -1;
  std::vector<std::string> sets;
  bool json = false;
  bool no_plots = false;
  bool oracle = false;
  VideoCommandOptions video;
  // Backend (docs/hardware.md, "One runner, three backends").
  std::string backend;
  std::string port;
  std::string log;
  bool prompt_actions = false;
  std::string intent_fifo;
  bool no_stdin_intent = false;
};

/// The scenario with the command line's overrides applied.
testbed::ScenarioConfig LoadRunScenario(const RunCommandOptions& options) {
  std::vector<testbed::Override> overrides;
  // The port and the log before the backend that needs them (each override is checked as applied).
  if (!options.port.empty()) overrides.push_back({"serial.port", options.port});
  if (!options.log.empty()) overrides.push_back({"log", options.log});
  if (!options.backend.empty()) overrides.push_back({"backend", options.backend});
  if (!options.controller.empty()) {
    overrides.push_back({"controller.name", controller::ResolvePluginName(options.controller, "."),
                         "--controller " + options.controller});
  }
  if (options.seed >= 0) overrides.push_back({"seed", std::to_string(options.seed)});
  for (const std::string& text : options.sets) overrides.push_back(testbed::ParseOverride(text));
  return testbed::LoadScenario(options.scenario, overrides);
}

/// The run's options from the command line; `terminal`: draw the progress line.
testbed::RunOptions MakeRunOptions(const RunCommandOptions& options, const testbed::ScenarioConfig& config,
                                   bool terminal) {
  testbed::RunOptions run;
  run.out_dir = options.out_dir.empty() ? "out/" + config.name : options.out_dir;
  run.write_plots = !options.no_plots;
  run.stop = &StopRequested();
  if (options.oracle) run.oracle = testbed::OracleMode::kAlways;
  run.prompt_actions = options.prompt_actions;
  run.intent_stdin = config.backend == testbed::Backend::kSerial && !options.no_stdin_intent;
  run.intent_fifo = options.intent_fifo;
  if (terminal) {
    run.progress = [name = config.name](double sim_s, double duration_s) {
      std::fprintf(stderr, "\r  %s: %.2f / %.2f s simulated ", name.c_str(), sim_s, duration_s);
      std::fflush(stderr);
    };
  }
  return run;
}

/// With --video, attaches the recorder to `run` (null without); refused for a backend without a
/// simulation.
std::shared_ptr<const show::VideoCost> AttachRunVideo(const RunCommandOptions& options,
                                                      const testbed::ScenarioConfig& config,
                                                      testbed::RunOptions& run) {
  if (options.video.enabled && config.backend != testbed::Backend::kSim) {
    throw std::invalid_argument(std::string("--video: renders the simulation, and backend ") +
                                testbed::BackendName(config.backend) + " has none");
  }
  if (!options.video.enabled) return nullptr;
  const show::VideoOptions video = options.video.Resolve();
  std::error_code error;
  fs::create_directories(run.out_dir, error);  // the encoder writes there from the first frame
  return show::AttachVideo(config, video, run.out_dir + "/video.mp4", run.out_dir + "/video_strip.png", run);
}

/// The summary (table or JSON) and the list of outputs on stdout.
void PrintRunSummary(const RunCommandOptions& options, const testbed::ScenarioConfig& config,
                     const testbed::RunResult& result, const std::string& out_dir) {
  if (options.json) {
    std::cout << testbed::SummaryJson(result).dump(2) << '\n';
    return;
  }
  std::cout << testbed::SummaryTable(result);
  const bool sim = config.backend == testbed::Backend::kSim;
  std::cout << "  outputs: " << out_dir << "/ (signals.csv, summary.json, config.yaml"
            << (options.no_plots ? ""
                : sim            ? ", forces.png, estimate_vs_truth.png, grip.png, slip.png, height.png, "
                                   "taxels_fn.png, taxels_ft.png"
                                 : ", forces.png, grip.png, taxels_fn.png, taxels_ft.png")
            << (sim ? ", states.csv" : "") << (options.video.enabled ? ", video.mp4, video_strip.png" : "")
            << ")\n";
}

/// An interrupted run (exit 130) or a physics fault on stderr; the exit code.
void EndRun(const testbed::RunResult& result, const std::string& out_dir) {
  if (!result.completed) {
    std::cerr << "graspbed: interrupted at t = " << result.metrics.sim_s << " s; partial results in "
              << out_dir << " (marked INCOMPLETE)\n";
    ExitWith(kExitInterrupted);
  }
  if (result.metrics.physics_fault) {
    std::cerr << "graspbed: physics fault at t = " << result.metrics.physics_fault_time_s
              << " s ended the run (" << result.metrics.physics_fault_cause << "); results up to it in "
              << out_dir << "\n";
  }
  ExitWith(result.passed ? kExitOk : kExitFailed);
}

void RunCommand(const RunCommandOptions& options) {
  const testbed::ScenarioConfig config = LoadRunScenario(options);
  // The progress line would run into the bench's prompts and intent echoes.
  const bool terminal = StderrIsTerminal() && config.backend == testbed::Backend::kSim;
  testbed::RunOptions run = MakeRunOptions(options, config, terminal);
  const std::shared_ptr<const show::VideoCost> video_cost = AttachRunVideo(options, config, run);
  StopSignalGuard guard;
  const testbed::RunResult result = testbed::RunScenario(config, run);
  if (terminal) std::fprintf(stderr, "\r\033[K");
  if (video_cost && video_cost->frames > 0) {
    std::fprintf(
        stderr,
        "graspbed run: video %s/video.mp4, %d frames, rendering %.1f ms/frame, encoding %.1f ms/frame\n",
        run.out_dir.c_str(), video_cost->frames, video_cost->render_ms / video_cost->frames,
        video_cost->encode_ms / video_cost->frames);
  }
  PrintRunSummary(options, config, result, run.out_dir);
  EndRun(result, run.out_dir);
}

void AddRunCommand(CLI::App& root) {
  auto options = std::make_shared<RunCommandOptions>();
  CLI::App* command = root.add_subcommand(
      "run",
      "Run one scenario: writes signals.csv, summary.json, config.yaml and PNG plots; exit 0 when every "
      "expectation holds, 1 when one fails, 2 on bad input, 130 when interrupted");
  command->add_option("scenario", options->scenario, "scenario YAML file (see docs/scenarios.md)")
      ->required();
  command->add_option("--out", options->out_dir, "output directory (default out/<scenario name>)");
  command->add_option("--controller", options->controller,
                      "controller to test instead of the file's (its parameters in the file are dropped): a "
                      "built-in name or plugin:LIBRARY (a path, or a name on $GRASPBED_PLUGIN_PATH)");
  command->add_option("--seed", options->seed, "seed instead of the file's")->check(CLI::NonNegativeNumber);
  command->add_option("--set", options->sets, "override a key, e.g. --set object.mass_kg=0.3 (repeatable)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  command->add_flag("--json", options->json, "print the summary JSON on stdout instead of the table");
  command->add_flag("--no-plots", options->no_plots, "skip the PNG plots");
  command->add_flag("--oracle", options->oracle,
                    "also find the scenario's oracle grip (the lightest constant grip that holds it, "
                    "`graspbed oracle`) and score the grip against it: grip_efficiency, peak_grip_ratio "
                    "(done anyway when the scenario states max_grip_efficiency)");
  options->video.Add(command, "OUT/video.mp4");
  command
      ->add_option(
          "--backend", options->backend,
          "sim (default), serial (the hand or `graspbed emulate` on --port) or replay (the recording "
          "at --log)")
      ->check(CLI::IsMember({"sim", "serial", "replay"}));
  command->add_option("--port", options->port, "backend serial: serial device (serial.port)");
  command->add_option(
      "--log", options->log,
      "backend serial: also write every decoded frame to this CSV; backend replay: the recording "
      "(a run's signals.csv or a frame log)");
  command->add_flag(
      "--prompt-actions", options->prompt_actions,
      "backend serial: print script actions that need the simulator (lift, pull, add_mass, ...) as "
      "prompts at their times instead of refusing them");
  command->add_option(
      "--intent-fifo", options->intent_fifo,
      "backend serial: read intent lines (close/open/idle/quit) from this FIFO, e.g. from an EMG "
      "pipeline (created when missing)");
  command->add_flag(
      "--no-stdin-intent", options->no_stdin_intent,
      "backend serial: do not read intent from stdin (keys c/o/i/q on a terminal, lines otherwise)");
  command->callback([options] { RunCommand(*options); });
}

// ---- suite -----------------------------------------------------------------------------------------

struct SuiteCommandOptions {
  std::string dir;
  int jobs = 1;
  std::string out_dir = "out/suite";
  std::string controller;
  std::vector<std::string> sets;
  bool json = false;
  bool no_plots = false;
  bool report = false;
  VideoCommandOptions video;
};

void SuiteCommand(const SuiteCommandOptions& options) {
  std::vector<testbed::Override> overrides;
  if (!options.controller.empty()) {
    overrides.push_back({"controller.name", controller::ResolvePluginName(options.controller, "."),
                         "--controller " + options.controller});
  }
  for (const std::string& text : options.sets) overrides.push_back(testbed::ParseOverride(text));
  const std::vector<testbed::ScenarioConfig> configs =
      testbed::LoadScenarios(testbed::ListScenarioFiles(options.dir), overrides);

  testbed::SuiteOptions suite;
  suite.jobs = options.jobs;
  suite.out_dir = options.out_dir;
  suite.write_plots = !options.no_plots;
  suite.stop = &StopRequested();
  suite.prepare_run = options.video.Preparer("");
  const bool terminal = StderrIsTerminal();
  suite.on_finished = [terminal](int done, int total, const testbed::SuiteRun& run) {
    if (!terminal) return;
    std::fprintf(stderr, "\r\033[K  [%d/%d] %s: %s", done, total, run.result.config.name.c_str(),
                 !run.error.empty()  ? "error"
                 : run.result.passed ? "pass"
                                     : "FAIL");
    std::fflush(stderr);
  };
  StopSignalGuard guard;
  const testbed::SuiteResult result = testbed::RunSuite(configs, suite);
  if (terminal) std::fprintf(stderr, "\r\033[K");
  if (options.json) {
    std::cout << testbed::SuiteJson(result).dump(2) << '\n';
  } else {
    std::cout << testbed::SuiteTable(result);
    std::cout << "  outputs: " << options.out_dir << "/ (suite.json, one directory per scenario)\n";
  }
  if (options.report) {  // on stderr beside --json, whose stdout is the JSON alone
    (options.json ? std::cerr : std::cout)
        << "  " << testbed::DescribeReport(testbed::WriteReport(options.out_dir)) << '\n';
  }
  if (!result.completed) ExitWith(kExitInterrupted);
  ExitWith(result.failed == 0 ? kExitOk : kExitFailed);
}

void AddSuiteCommand(CLI::App& root) {
  auto options = std::make_shared<SuiteCommandOptions>();
  CLI::App* command = root.add_subcommand(
      "suite",
      "Run every scenario (*.yaml) of a directory in parallel: pass/fail table, DIR_OUT/suite.json and "
      "one output directory per scenario; exit 1 if any fails");
  command->add_option("dir", options->dir, "directory of scenario files, e.g. scenarios")->required();
  command->add_option("-j,--jobs", options->jobs, "parallel runs")->check(CLI::Range(1, 256));
  command->add_option("--out", options->out_dir, "output directory (default out/suite)");
  command->add_option("--controller", options->controller, "run every scenario with this controller");
  command->add_option("--set", options->sets, "override a key in every scenario (repeatable)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  command->add_flag("--json", options->json, "print the combined JSON instead of the table");
  command->add_flag("--no-plots", options->no_plots, "skip the PNG plots");
  command->add_flag("--report", options->report, "also write OUT/report.html (graspbed report)");
  options->video.Add(command, "each scenario's OUT/<name>/video.mp4");
  command->callback([options] { SuiteCommand(*options); });
}

// ---- sweep and merge ---------------------------------------------------------------------------------

struct SweepCommandOptions {
  std::string spec;
  std::string shard = "1/1";
  std::string out_dir = "out/sweep";
  int jobs = 1;
  std::string controller;
  VideoCommandOptions video;
};

void SweepCommand(const SweepCommandOptions& options) {
  testbed::SweepSpec spec = testbed::LoadSweepSpec(options.spec);
  if (!options.controller.empty()) {
    // Before the spec's own `set:` (which may tune this controller); shards must agree on it to merge.
    const std::string name = controller::ResolvePluginName(options.controller, ".");
    spec.fixed.insert(spec.fixed.begin(), {"controller.name", name});
    spec.fingerprint += " controller=" + name;
  }
  testbed::SweepOptions sweep;
  sweep.shard = testbed::ParseShard(options.shard);
  sweep.jobs = options.jobs;
  sweep.out_dir = options.out_dir;
  sweep.stop = &StopRequested();
  sweep.prepare_run = options.video.Preparer(options.out_dir + "/videos");
  const bool terminal = StderrIsTerminal();
  sweep.on_finished = [terminal](int done, int total) {
    if (!terminal) return;
    std::fprintf(stderr, "\r\033[K  sweep: %d/%d runs", done, total);
    std::fflush(stderr);
  };
  StopSignalGuard guard;
  const testbed::SweepOutcome outcome = testbed::RunSweep(spec, sweep);
  if (terminal) std::fprintf(stderr, "\r\033[K");
  std::printf(
      "sweep %s shard %s: %d of %d runs finished, %d passed, %.2f s -> %s/results.csv, results.jsonl\n",
      spec.source_file.c_str(), options.shard.c_str(), outcome.finished, outcome.runs, outcome.passed,
      outcome.wall_s, options.out_dir.c_str());
  if (!outcome.completed) {
    std::fprintf(stderr,
                 "graspbed: interrupted; finished rows are in %s/results.jsonl.partial (not merged)\n",
                 options.out_dir.c_str());
    ExitWith(kExitInterrupted);
  }
}

void AddSweepCommand(CLI::App& root) {
  auto options = std::make_shared<SweepCommandOptions>();
  CLI::App* command = root.add_subcommand(
      "sweep",
      "Run a grid or seeded random sample over scenario parameters: one row per run in "
      "DIR/results.csv and results.jsonl; --shard K/N runs every N-th run for cluster arrays");
  command->add_option("spec", options->spec, "sweep spec YAML (see docs/scenarios.md, Sweeps)")->required();
  command->add_option("--shard", options->shard,
                      "run shard K of N (1-based: runs with index % N == K - 1), e.g. with sbatch "
                      "--array=0-7: --shard $((SLURM_ARRAY_TASK_ID+1))/8");
  command->add_option("--out", options->out_dir, "output directory (default out/sweep)");
  command->add_option("-j,--jobs", options->jobs, "parallel runs")->check(CLI::Range(1, 256));
  command->add_option(
      "--controller", options->controller,
      "controller for every run instead of the scenario's: a built-in name or plugin:LIBRARY");
  options->video.Add(command, "OUT/videos/run_<index>/video.mp4");
  command->callback([options] { SweepCommand(*options); });

  auto dirs = std::make_shared<std::vector<std::string>>();
  auto out = std::make_shared<std::string>("out/sweep-merged");
  CLI::App* merge = root.add_subcommand(
      "merge",
      "Combine the output directories of all shards of one sweep into one results.csv/jsonl; refuses "
      "missing, repeated, incomplete or foreign shards");
  merge->add_option("shards", *dirs, "shard output directories")->required();
  merge->add_option("--out", *out, "merged output directory (default out/sweep-merged)");
  merge->callback([dirs, out] {
    const int rows = testbed::MergeSweeps(*dirs, *out);
    std::printf("merged %zu shards: %d rows -> %s/results.csv, results.jsonl\n", dirs->size(), rows,
                out->c_str());
  });
}

void AddCommands(CLI::App& root) {
  AddRunCommand(root);
  AddSuiteCommand(root);
  AddSweepCommand(root);
}

const bool kRegisteredRun = RegisterCommands(&AddCommands);

}  // namespace
}  // namespace graspbed::app
