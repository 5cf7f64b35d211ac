#pragma once
/// `graspbed view`: a window (GLFW, MuJoCo's renderer) that runs a scenario live with its controller
/// and script, or replays a finished run from its output directory, with the overlays of the videos
/// (units coloured by estimated Fn, Ft arrows, contact forces, the panel).
///
/// Keys: space pause; right arrow one step (live: a control tick; replay: a state row, 5 ms); left
/// arrow one step back (replay); [ and ] half a second back and forward (replay); + and - twice and
/// half the speed; backspace restart; F fingertip camera, G grasp camera; Q or Esc quit. Mouse as
/// in mujoco-simulate: left drag rotates, right drag moves, wheel or middle drag zooms (shift: the
/// horizontal variants); a drag leaves the built-in camera for a free one.
///
/// Needs a display (X11; under xvfb-run on a machine without one).

#include <atomic>
#include <string>

#include "sim/render/renderer.h"
#include "testbed/scenario_config.h"
#include "testbed/show/video.h"

namespace graspbed::show {

/// Window and playback settings.
struct ViewerOptions {
  int width_px = 1280;  ///< initial window size [px]
  int height_px = 800;
  double speed = 1.0;   ///< simulated seconds per wall-clock second at the start, (0, 64]
  bool paused = false;  ///< start paused
  /// Close after this many displayed frames (0: when the window is closed); for scripted and
  /// headless (xvfb-run) checks.
  int exit_after_frames = 0;
  sim::RenderOptions render = [] {
    sim::RenderOptions options;
    options.contact_forces = true;
    options.force_arrow_m_per_n = kVideoForceArrowMPerN;
    options.shadows = false;  // a third of the frame time without them (RenderOptions::shadows)
    return options;
  }();
  sim::CameraSpec camera;                   ///< camera at the start
  const std::atomic<bool>* stop = nullptr;  ///< set (SIGINT) to close the window

  /// Throws std::invalid_argument naming the option and value.
  void Validate() const;
};

/// What a viewer session did.
struct ViewerResult {
  int frames = 0;       ///< frames displayed
  double time_s = 0.0;  ///< simulated (or replayed) time shown last [s]
  int restarts = 0;
  std::string gl_description;  ///< the OpenGL renderer of the window
};

/// Runs `config` live in a window until it is closed. Throws std::runtime_error when no window can
/// be opened (no display) and std::invalid_argument as RunScenario does for a scene the rig refuses.
ViewerResult ViewLive(const testbed::ScenarioConfig& config, const ViewerOptions& options);

/// Replays the run in `run_dir` (config.yaml, signals.csv, states.csv, summary.json from `graspbed
/// run`) without simulating it: the state log gives the scene, the signals the overlays. Throws
/// std::invalid_argument naming the file at fault when one is missing or does not match.
ViewerResult ViewReplay(const std::string& run_dir, const ViewerOptions& options);

}  // namespace graspbed::show
