// `graspbed view`: a scenario live in a window, or a finished run replayed (needs a display).
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "app/command_registry.h"
#include "app/stop_signal.h"
#include "testbed/scenario_config.h"
#include "testbed/show/video.h"
#include "testbed/show/viewer.h"

namespace graspbed::app {
namespace {

namespace fs = std::filesystem;

struct ViewCommandOptions {
  std::string target;
  std::string size = "1280x800";
  double speed = 1.0;
  bool paused = false;
  int frames = 0;
  std::string camera;
  bool shadows = false;
  std::vector<std::string> sets;
};

void ViewCommand(const ViewCommandOptions& options) {
  show::ViewerOptions viewer;
  sim::RenderOptions size;
  show::ParseVideoSize(options.size, size);
  viewer.width_px = size.width_px;
  viewer.height_px = size.height_px;
  viewer.speed = options.speed;
  viewer.paused = options.paused;
  viewer.exit_after_frames = options.frames;
  viewer.camera = sim::CameraByName(options.camera);
  viewer.render.shadows = options.shadows;
  viewer.stop = &StopRequested();
  viewer.Validate();
  StopSignalGuard guard;
  show::ViewerResult result;
  if (fs::is_directory(options.target)) {
    if (!options.sets.empty())
      throw std::invalid_argument("--set: a replay shows the run as it was; no overrides");
    result = show::ViewReplay(options.target, viewer);
  } else {
    std::vector<testbed::Override> overrides;
    for (const std::string& text : options.sets) overrides.push_back(testbed::ParseOverride(text));
    result = show::ViewLive(testbed::LoadScenario(options.target, overrides), viewer);
  }
  std::printf("graspbed view: %d frames shown, t = %.3f s, %d restarts (%s)\n", result.frames, result.time_s,
              result.restarts, result.gl_description.c_str());
}

void AddViewCommand(CLI::App& root) {
  auto options = std::make_shared<ViewCommandOptions>();
  CLI::App* command = root.add_subcommand(
      "view",
      "Watch a scenario live in a window, run by its controller and script (real time by default), or replay "
      "a "
      "finished run from its output directory (config.yaml, signals.csv, states.csv) without simulating it. "
      "Units coloured by estimated Fn, Ft arrows along their beams, contact forces, a panel with the "
      "controller's "
      "state. Needs a display (xvfb-run works); videos need none (graspbed run --video). Exit 0 closed, 1 no "
      "window, 2 bad input");
  command->footer(
      "Keys: space pause; right arrow one step (live: a control tick; replay: 5 ms), left arrow back "
      "(replay); "
      "[ ] half a second back/forward (replay); + - speed x2 / x0.5; backspace restart; F fingertip camera, "
      "G grasp "
      "camera; Q or Esc quit. Mouse as mujoco-simulate: left drag rotate, right drag move, wheel zoom, shift "
      "for "
      "the horizontal forms.\n"
      "Examples: graspbed view scenarios/default.yaml\n"
      "          graspbed run scenarios/slip_recovery.yaml --out out/s && graspbed view out/s");
  command->add_option("target", options->target, "scenario YAML file, or a run's output directory to replay")
      ->required();
  command->add_option("--size", options->size, "window WIDTHxHEIGHT [px]")->capture_default_str();
  command->add_option("--speed", options->speed, "simulated seconds per second at the start (1 = real time)")
      ->capture_default_str();
  command->add_flag("--paused", options->paused, "start paused");
  command
      ->add_option("--frames", options->frames, "close after this many frames (0: when the window is closed)")
      ->check(CLI::NonNegativeNumber);
  command->add_option("--camera", options->camera, "grasp (default), fingertip, or a camera of the model");
  command->add_flag("--shadows", options->shadows, "draw shadows (slow on a software renderer)");
  command->add_option("--set", options->sets, "override a scenario key (live only; repeatable)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  command->callback([options] { ViewCommand(*options); });
}

const bool kRegistered = RegisterCommands(&AddViewCommand);

}  // namespace
}  // namespace graspbed::app
