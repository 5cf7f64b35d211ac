#include "testbed/show/video.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>

#include "common/video_writer.h"
#include "sim/render/offscreen_gl_context.h"
#include "sim/sim_rig.h"

namespace graspbed::show {
namespace {

constexpr double kMaxFps = 240.0;
// Frame times that land on a control tick count as reached (same slack as the runner's clock) [s].
constexpr double kClockSlackS = 1e-9;

double MsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

/// Everything one video needs; shared by the run's two callbacks.
struct Recorder {
  Recorder(const testbed::ScenarioConfig& config_in, const VideoOptions& options_in,
           const std::string& video, const std::string& strip)
      : config(config_in),
        options(options_in),
        video_path(video),
        strip_path(strip),
        writer({video, options_in.render.width_px, options_in.render.height_px, options_in.fps,
                options_in.ffmpeg}),
        title(config_in.name + " (" + config_in.controller.name + ")"),
        cost(std::make_shared<VideoCost>()) {}

  void Frame(const testbed::FrameContext& frame) {
    const auto start = std::chrono::steady_clock::now();
    sim::SimRig& rig = frame.rig;
    if (!renderer) renderer = std::make_unique<sim::Renderer>(gl, rig.simulation(), options.render);
    const controller::ControllerTelemetry telemetry = rig.controller().telemetry();
    const image::RgbImage& picture =
        renderer->Render(rig.simulation(), &rig.loop().state(), options.camera,
                         sim::PanelText(LivePanel(config, title, frame, telemetry)));
    cost->render_ms += MsSince(start);
    const auto encode_start = std::chrono::steady_clock::now();
    writer.Write(picture);
    cost->encode_ms += MsSince(encode_start);
    cost->frames = writer.frames();
  }

  void Finish() {
    const auto start = std::chrono::steady_clock::now();
    renderer.reset();
    writer.Finish();
    if (!strip_path.empty() && options.strip_tiles > 0 && writer.frames() > 0) {
      image::WriteVideoStrip(video_path, writer.frames(), options.strip_tiles, options.strip_columns,
                             options.strip_tile_width_px, strip_path, options.ffmpeg);
    }
    cost->encode_ms += MsSince(start);
  }
  testbed::ScenarioConfig config;
  VideoOptions options;
  std::string video_path;
  std::string strip_path;
  // The GL context before the renderer that uses it and the encoder (no display or no ffmpeg fails
  // before any simulating).
  sim::OffscreenGlContext gl;
  image::VideoWriter writer;
  std::unique_ptr<sim::Renderer> renderer;
  std::string title;
  std::shared_ptr<VideoCost> cost;
};

}  // namespace

void VideoOptions::Validate() const {
  render.Validate();
  if (render.width_px % 2 != 0 || render.height_px % 2 != 0) {
    throw std::invalid_argument("--video-size " + std::to_string(render.width_px) + "x" +
                                std::to_string(render.height_px) + ": width and height must be even (H.264)");
  }
  if (!(fps > 0.0 && fps <= kMaxFps)) {
    char text[64];
    std::snprintf(text, sizeof(text), "--video-fps %g: must be in (0, %g]", fps, kMaxFps);
    throw std::invalid_argument(text);
  }
  if (strip_tiles < 0 ||
      (strip_tiles > 0 && ((strip_tile_width_px != 0 && strip_tile_width_px < 16) || strip_columns < 1))) {
    throw std::invalid_argument("video strip: " + std::to_string(strip_tiles) + " tiles " +
                                std::to_string(strip_tile_width_px) + " px wide in rows of " +
                                std::to_string(strip_columns) +
                                ": need >= 0 tiles of >= 16 px (or 0: the frames' width), >= 1 per row");
  }
}

void ParseVideoSize(const std::string& text, sim::RenderOptions& options) {
  int width = 0;
  int height = 0;
  char rest = 0;
  if (std::sscanf(text.c_str(), "%dx%d%c", &width, &height, &rest) != 2) {
    throw std::invalid_argument("--video-size " + text + ": expected WIDTHxHEIGHT in pixels, e.g. 640x480");
  }
  options.width_px = width;
  options.height_px = height;
}

int VideoFrameCount(double duration_s, double fps) {
  return static_cast<int>(std::floor(duration_s * fps + kClockSlackS * fps)) + 1;
}

std::string LastActionText(const testbed::ScenarioConfig& config, const testbed::ScriptPlayer& player,
                           double time_s) {
  const std::vector<testbed::ActionTiming>& timings = player.timings();
  int last = -1;
  for (size_t i = 0; i < timings.size() && i < config.script.size(); ++i) {
    const double fired = timings[i].fired_s;
    if (fired >= 0.0 && fired <= time_s + kClockSlackS && (last < 0 || fired >= timings[last].fired_s)) {
      last = static_cast<int>(i);
    }
  }
  if (last < 0) return "";
  char text[96];
  std::snprintf(text, sizeof(text), "%s at %.3f s (line %d)", testbed::ActionName(config.script[last].kind),
                timings[last].fired_s, config.script[last].line);
  return text;
}

sim::PanelInfo LivePanel(const testbed::ScenarioConfig& config, const std::string& title,
                         const testbed::FrameContext& frame,
                         const controller::ControllerTelemetry& telemetry) {
  sim::PanelInfo panel;
  panel.title = title;
  panel.time_s = frame.time_s;
  panel.telemetry = &telemetry;
  panel.state = &frame.rig.loop().state();
  panel.last_action = LastActionText(config, frame.player, frame.time_s);
  return panel;
}

std::shared_ptr<const VideoCost> AttachVideo(const testbed::ScenarioConfig& config,
                                             const VideoOptions& options, const std::string& video_path,
                                             const std::string& strip_path, testbed::RunOptions& run) {
  options.Validate();
  auto recorder = std::make_shared<Recorder>(config, options, video_path, strip_path);
  run.frame_period_s = 1.0 / options.fps;
  run.on_frame = [recorder](const testbed::FrameContext& frame) { recorder->Frame(frame); };
  run.on_finished = [recorder](const testbed::RunResult&) { recorder->Finish(); };
  return recorder->cost;
}

}  // namespace graspbed::show
