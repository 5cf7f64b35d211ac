// `graspbed render`: stills of a scenario at chosen instants, rendered offscreen (no display needed).
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "app/command_registry.h"
#include "app/stop_signal.h"
#include "testbed/scenario_config.h"
#include "testbed/show/stills.h"

namespace graspbed::app {
namespace {

/// Exit code after Ctrl-C (128 + SIGINT, the shell convention).
constexpr int kExitInterrupted = 130;

struct RenderCommandOptions {
  std::string scenario;
  std::vector<double> times_s;
  std::string out_dir;
  int width_px = 800;
  int height_px = 600;
  std::string camera;
  std::string view;
  bool contact_forces = false;
  double force_scale_mm_per_n = sim::RenderOptions{}.force_arrow_m_per_n * 1e3;
  double object_alpha = sim::RenderOptions{}.object_alpha;
  bool no_label = false;
  std::vector<std::string> sets;
};

void RenderCommand(const RenderCommandOptions& options) {
  std::vector<testbed::Override> overrides;
  for (const std::string& text : options.sets) overrides.push_back(testbed::ParseOverride(text));
  const testbed::ScenarioConfig config = testbed::LoadScenario(options.scenario, overrides);

  show::StillsOptions stills;
  stills.times_s = options.times_s;
  stills.out_dir = options.out_dir;
  stills.render.width_px = options.width_px;
  stills.render.height_px = options.height_px;
  stills.render.contact_forces = options.contact_forces;
  stills.render.force_arrow_m_per_n = options.force_scale_mm_per_n * 1e-3;
  stills.render.object_alpha = options.object_alpha;
  if (!options.view.empty()) {
    stills.camera.kind = sim::CameraSpec::Kind::kFree;
    stills.camera.free = sim::ParseFreeView(options.view);
  } else {
    stills.camera = sim::CameraByName(options.camera);
  }
  stills.label = !options.no_label;
  stills.stop = &StopRequested();
  StopSignalGuard guard;
  const show::StillsResult result = show::RenderStills(config, stills);
  for (const show::Still& still : result.stills) {
    std::printf("%s  (t = %.3f s, rendered in %.0f ms)\n", still.path.c_str(), still.time_s, still.render_ms);
  }
  std::fprintf(stderr, "graspbed render: %s\n", result.gl_description.c_str());
  if (!result.completed) {
    std::cerr << "graspbed: interrupted; " << result.stills.size() << " of the stills written\n";
    throw CLI::RuntimeError(kExitInterrupted);
  }
}

void AddRenderCommand(CLI::App& root) {
  auto options = std::make_shared<RenderCommandOptions>();
  CLI::App* command = root.add_subcommand(
      "render",
      "Render stills of a scenario offscreen (no display or GPU needed: EGL, Mesa llvmpipe): runs it with "
      "its "
      "controller and script up to each --at instant and writes OUT/<scenario>_t<time>s.png. Units are "
      "coloured by "
      "their estimated Fn: grey unloaded to red at the rated 10 N (square-root scale: 2.5 N is half way), "
      "magenta saturated, black unusable (open, short, "
      "implausible, not yet tared). The object is drawn see-through so the units it covers show. "
      "Exit 0 written, 1 rendering failed, 2 bad input, 130 interrupted");
  command->footer(
      "Cameras: 'grasp' (default) frames hand and object from 45 deg beside the units' outward normal, from "
      "above; 'fingertip' is a close-up of the units; any other NAME is a <camera> of the model. --view "
      "places "
      "MuJoCo's orbit camera: azimuth 0 looks along +x, 90 along +y; elevation < 0 looks down; world frame, "
      "z up, "
      "table top at z = 0.\n"
      "Example: graspbed render scenarios/default.yaml --at 0.1 --at 1.2 --out docs/img");
  command->add_option("scenario", options->scenario, "scenario YAML file (see docs/scenarios.md)")
      ->required();
  command->add_option("--at", options->times_s, "simulated time to render [s] (repeatable)")
      ->required()
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
      ->check(CLI::NonNegativeNumber);
  command->add_option("--out", options->out_dir, "output directory (created if missing)")->required();
  command->add_option("--width", options->width_px, "picture width [px], 16..4096")->capture_default_str();
  command->add_option("--height", options->height_px, "picture height [px], 16..4096")->capture_default_str();
  CLI::Option* camera = command->add_option("--camera", options->camera,
                                            "grasp (default), fingertip, or a camera of the model");
  command
      ->add_option(
          "--view", options->view,
          "free camera: azimuth,elevation,distance,lookat_x,lookat_y,lookat_z (deg, deg, m, m, m, m)")
      ->excludes(camera);
  command->add_flag("--contact-forces", options->contact_forces, "draw an arrow at every contact");
  command->add_option("--force-scale", options->force_scale_mm_per_n, "contact-force arrow length [mm/N]")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command
      ->add_option("--object-alpha", options->object_alpha,
                   "opacity of the object, 0..1 (1 opaque; 0 leaves it out)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  command->add_flag("--no-label", options->no_label, "no text (scenario, time, controller phase, forces)");
  command
      ->add_option("--set", options->sets,
                   "override a scenario key, e.g. --set object.mass_kg=0.3 (repeatable)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  command->callback([options] { RenderCommand(*options); });
}

const bool kRegistered = RegisterCommands(&AddRenderCommand);

}  // namespace
}  // namespace graspbed::app
