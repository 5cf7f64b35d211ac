#pragma once
/// Rendered stills of a scenario: runs it with the normal scenario runner (the same rig, controller
/// and script as `graspbed run`) and, at each requested instant, renders the scene offscreen to
/// DIR/<scenario>_t<time>s.png (e.g. default_t1.200s.png), the units coloured by the estimated Fn of
/// that control tick. The run stops after the last still and writes no run outputs.

#include <atomic>
#include <string>
#include <vector>

#include "sim/render/renderer.h"
#include "testbed/scenario_config.h"

namespace graspbed::show {

/// What to render and where.
struct StillsOptions {
  /// Simulated instants [s], each in [0, duration_s] of the scenario; rendered at the first control
  /// tick at or after each; sorted, repeats dropped.
  std::vector<double> times_s;
  std::string out_dir;  ///< created if missing
  sim::RenderOptions render;
  sim::CameraSpec camera;
  bool label = true;  ///< scenario, time, controller phase, grip target, estimated Fn in the corner
  /// Set (e.g. by SIGINT) to stop at the next control tick; stills not yet rendered are skipped.
  const std::atomic<bool>* stop = nullptr;
};

/// One picture written.
struct Still {
  double requested_s = 0.0;  ///< instant asked for [s]
  double time_s = 0.0;       ///< simulated time of the control tick rendered [s]
  std::string path;
  double render_ms = 0.0;  ///< wall time to render and read back the picture, without the PNG [ms]
};

/// What a call produced.
struct StillsResult {
  std::vector<Still> stills;   ///< in time order
  std::string gl_description;  ///< the OpenGL context used (OffscreenGlContext::description())
  bool completed = false;      ///< every still written (false: stopped early)
};

/// File name of the still of scenario `scenario_name` at `time_s` [s]: "<name>_t<time, 3 decimals>s.png".
std::string StillFileName(const std::string& scenario_name, double time_s);

/// Runs `config` and writes the stills. Throws std::invalid_argument (bad instants, options or
/// output directory, before simulating; an unknown model camera, at the first still) and
/// std::runtime_error (no OpenGL context, a PNG that cannot be written).
StillsResult RenderStills(const testbed::ScenarioConfig& config, const StillsOptions& options);

}  // namespace graspbed::show
