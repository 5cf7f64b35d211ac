#include "testbed/show/stills.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "sim/render/offscreen_gl_context.h"
#include "sim/sim_rig.h"
#include "testbed/runner.h"

namespace graspbed::show {
namespace {

namespace fs = std::filesystem;

// Instants closer than this are one still [s] (well below a control period).
constexpr double kSameInstantS = 1e-9;

std::string Format(const char* format, double value) {
  char text[64];
  std::snprintf(text, sizeof(text), format, value);
  return text;
}

std::string Label(const testbed::ScenarioConfig& config, sim::SimRig& rig) {
  const controller::ControllerTelemetry telemetry = rig.controller().telemetry();
  sim::PanelInfo panel;
  panel.title = config.name + " (" + config.controller.name + ")";
  panel.time_s = rig.time_s();
  panel.telemetry = &telemetry;
  panel.state = &rig.loop().state();
  return sim::PanelText(panel);
}

}  // namespace

std::string StillFileName(const std::string& scenario_name, double time_s) {
  return scenario_name + Format("_t%.3fs.png", time_s);
}

StillsResult RenderStills(const testbed::ScenarioConfig& config, const StillsOptions& options) {
  options.render.Validate();
  if (options.times_s.empty()) throw std::invalid_argument("render: no instant to render (--at)");
  std::vector<double> times = options.times_s;
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end(),
                          [](double a, double b) { return std::abs(a - b) < kSameInstantS; }),
              times.end());
  for (double t : times) {
    if (!(t >= 0.0 && t <= config.duration_s)) {
      throw std::invalid_argument("--at " + Format("%g", t) + ": outside the scenario " + config.name +
                                  " (0 .. " + Format("%g", config.duration_s) + " s, duration_s" +
                                  (config.source_file.empty() ? "" : " in " + config.source_file) + ")");
    }
  }
  std::error_code error;
  fs::create_directories(options.out_dir, error);
  if (options.out_dir.empty() || error || !fs::is_directory(options.out_dir)) {
    throw std::invalid_argument("--out " + options.out_dir + ": cannot create the output directory" +
                                (error ? " (" + error.message() + ")" : ""));
  }

  // The GL context first: no display or driver fails here, before any simulating.
  sim::OffscreenGlContext gl;
  StillsResult result;
  result.gl_description = gl.description();
  std::unique_ptr<sim::Renderer> renderer;

  testbed::RunOptions run;
  run.stop = options.stop;
  run.instants_s = times;
  run.stop_after_instants = true;
  run.at_instant = [&](double instant_s, sim::SimRig& rig) {
    if (!renderer) renderer = std::make_unique<sim::Renderer>(gl, rig.simulation(), options.render);
    const auto start = std::chrono::steady_clock::now();
    const image::RgbImage& picture = renderer->Render(rig.simulation(), &rig.loop().state(), options.camera,
                                                      options.label ? Label(config, rig) : "");
    Still still;
    still.render_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    still.requested_s = instant_s;
    still.time_s = rig.time_s();
    still.path = (fs::path(options.out_dir) / StillFileName(config.name, instant_s)).string();
    image::WritePng(picture, still.path);
    result.stills.push_back(still);
  };
  testbed::RunScenario(config, run);
  result.completed = result.stills.size() == times.size();
  return result;
}

}  // namespace graspbed::show
