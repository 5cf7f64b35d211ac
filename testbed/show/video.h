#pragma once
/// Videos of scenario runs: `graspbed run --video` (and suite, sweep) renders the run offscreen while
/// it runs -- at the first control tick at or after each frame time, the same renderer, overlays and
/// panel as the viewer -- and pipes the frames to ffmpeg (common/video_writer.h). Rendering reads the
/// simulation and never changes it, so a run gives the same results with and without a video.
///
/// Why while it runs and not afterwards from recorded states: the frame shows the exact TactileState,
/// controller telemetry and contact forces of its tick, with no second simulation and no replay
/// approximations; the cost is the rendering time added to the run (docs/simulation.md, "Videos").

#include <memory>
#include <string>

#include "sim/render/renderer.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"

namespace graspbed::show {

/// Frame rate of videos unless asked otherwise [1/s].
inline constexpr double kDefaultVideoFps = 30.0;
/// Contact-force arrows in videos and the viewer [m/N]: shorter than the stills' 10 mm/N, so a 10 N
/// pinch stays inside a grasp-camera frame.
inline constexpr double kVideoForceArrowMPerN = 0.004;

/// What a video shows and how.
struct VideoOptions {
  double fps =
      kDefaultVideoFps;  ///< frames per second of simulated time (videos play at real time) [1/s], (0, 240]
  sim::RenderOptions render = [] {
    sim::RenderOptions options;
    options.width_px = 640;
    options.height_px = 480;
    options.contact_forces = true;
    options.force_arrow_m_per_n = kVideoForceArrowMPerN;
    options.shadows = false;  // a third of the frame time without them (RenderOptions::shadows)
    return options;
  }();                            ///< size (even), overlays; contact-force arrows on by default
  sim::CameraSpec camera;         ///< grasp camera by default
  int strip_tiles = 6;            ///< frames in the PNG strip beside the video (0: no strip)
  int strip_columns = 3;          ///< tiles per row of the strip
  /// Width of each strip tile [px]; 0: the frames' own width (a 640 px frame's panel text scaled to
  /// half is unreadable).
  int strip_tile_width_px = 0;
  std::string ffmpeg = "ffmpeg";  ///< the encoder program

  /// Throws std::invalid_argument naming the option and value.
  void Validate() const;
};

/// Parses "WxH" (e.g. 640x480) into `options` width and height. Throws std::invalid_argument quoting
/// the text.
void ParseVideoSize(const std::string& text, sim::RenderOptions& options);

/// Number of frames a video of `duration_s` [s] at `fps` has: one at 0 and one per frame period up to
/// and including duration_s.
int VideoFrameCount(double duration_s, double fps);

/// The script action of `config` that fired last before `time_s` [s] given the player's timings,
/// e.g. "lift at 1.000 s"; "" when none has.
std::string LastActionText(const testbed::ScenarioConfig& config, const testbed::ScriptPlayer& player,
                           double time_s);

/// The panel of a frame of a live run (videos, the viewer): `title`, time, the controller's
/// `telemetry` (kept by the caller while the panel is used), the rig's estimate, the last script action.
sim::PanelInfo LivePanel(const testbed::ScenarioConfig& config, const std::string& title,
                         const testbed::FrameContext& frame,
                         const controller::ControllerTelemetry& telemetry);

/// Time spent on a video, filled in as it is made.
struct VideoCost {
  int frames = 0;
  double render_ms = 0.0;  ///< rendering the scene and overlays and reading the pixels back [ms], all frames
  double encode_ms = 0.0;  ///< handing frames to ffmpeg (blocks while it catches up) [ms], all frames
};

/// Sets `run` up to record `config`'s run to `video_path` (and `strip_path`, "" none): opens the GL
/// context and starts ffmpeg now, on this thread (the run must then happen on it), renders each
/// frame from RunOptions::on_frame and finishes the file in RunOptions::on_finished (an interrupted
/// run still gets a video of what ran). Returns the cost so far, updated per frame. Throws
/// std::invalid_argument for bad options, std::runtime_error when there is no OpenGL context or no
/// ffmpeg.
std::shared_ptr<const VideoCost> AttachVideo(const testbed::ScenarioConfig& config,
                                             const VideoOptions& options, const std::string& video_path,
                                             const std::string& strip_path, testbed::RunOptions& run);

}  // namespace graspbed::show
