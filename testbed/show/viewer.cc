#include "testbed/show/viewer.h"

#include <GLFW/glfw3.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "sensor/layout.h"
#include "sim/sim_rig.h"
#include "sim/simulation.h"
#include "sim/state_log.h"
#include "testbed/runner.h"
#include "testbed/show/video.h"

namespace graspbed::show {
namespace {

using Clock = std::chrono::steady_clock;

constexpr double kDisplayPeriodS = 1.0 / 60.0;  // window refresh while running [s]
constexpr double kIdlePeriodS = 1.0 / 30.0;     // refresh while paused (the camera still moves) [s]
constexpr double kMaxSpeed = 64.0;
constexpr double kMinSpeed = 1.0 / 64.0;
// Further behind real time than this, the clock is re-anchored instead of sprinting to catch up [s].
constexpr double kMaxLagS = 0.25;
constexpr double kReplayJumpS = 0.5;
constexpr double kScrollZoomPerNotch = 0.05;
constexpr const char* kKeysHelp = "space, arrows, [ ], +/-, backspace, F/G, Q (graspbed view --help)";

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// A GLFW window whose OpenGL context the renderer draws with, and the user's input since the last Poll().
class Window : public sim::GlContext {
 public:
  struct CameraDrag {
    sim::CameraMove move;
    double dx;
    double dy;
  };

  Window(int width_px, int height_px, const std::string& title) {
    glfwSetErrorCallback(
        [](int, const char* description) { std::fprintf(stderr, "GLFW: %s\n", description); });
    if (glfwInit() != GLFW_TRUE) {
      throw std::runtime_error(
          "view: cannot open a window (no display? set DISPLAY, or run under xvfb-run; "
          "videos need none: graspbed run --video)");
    }
    glfwWindowHint(GLFW_SAMPLES, 4);
    window_ = glfwCreateWindow(width_px, height_px, title.c_str(), nullptr, nullptr);
    if (window_ == nullptr) {
      glfwTerminate();
      throw std::runtime_error("view: GLFW cannot create an OpenGL window on this display");
    }
    glfwMakeContextCurrent(window_);
    glfwSwapInterval(0);  // the viewer paces itself on the simulated clock
    glfwSetWindowUserPointer(window_, this);
    glfwSetKeyCallback(window_, [](GLFWwindow* w, int key, int, int action, int) {
      if (action != GLFW_RELEASE) static_cast<Window*>(glfwGetWindowUserPointer(w))->typed_.push_back(key);
    });
    glfwSetCursorPosCallback(window_, [](GLFWwindow* w, double x, double y) {
      static_cast<Window*>(glfwGetWindowUserPointer(w))->OnCursor(x, y);
    });
    glfwSetScrollCallback(window_, [](GLFWwindow* w, double, double y) {
      static_cast<Window*>(glfwGetWindowUserPointer(w))
          ->drags.push_back({sim::CameraMove::kZoom, 0.0, -kScrollZoomPerNotch * y});
    });
    description = std::string("GLFW ") + glfwGetVersionString() + ", OpenGL " +
                  std::to_string(glfwGetWindowAttrib(window_, GLFW_CONTEXT_VERSION_MAJOR)) + "." +
                  std::to_string(glfwGetWindowAttrib(window_, GLFW_CONTEXT_VERSION_MINOR));
  }
  ~Window() override {
    glfwDestroyWindow(window_);
    glfwTerminate();
  }
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  void MakeCurrent() override { glfwMakeContextCurrent(window_); }
  bool Closed() const { return glfwWindowShouldClose(window_) == GLFW_TRUE; }
  void Swap() { glfwSwapBuffers(window_); }
  std::array<int, 2> FramebufferSize() const {
    std::array<int, 2> size{};
    glfwGetFramebufferSize(window_, &size[0], &size[1]);
    return size;
  }

  /// Takes the oldest key typed and not yet taken into the flags below; false when none is left.
  /// One key per frame, in the order typed: keys typed ahead of a slow frame (a loaded machine,
  /// a software renderer) are each acted on, not merged into one flag.
  bool TakeKey() {
    if (typed_.empty()) return false;
    const int key = typed_.front();
    typed_.pop_front();
    ApplyKey(key);
    return true;
  }

  // Input since the last time the viewer took it.
  bool pause_toggle = false, step_forward = false, step_back = false, jump_forward = false, jump_back = false;
  bool restart = false, quit = false, fingertip = false, grasp = false;
  int speed_steps = 0;  ///< +1 twice as fast, -1 half
  std::vector<CameraDrag> drags;
  std::string description;

 private:
  void ApplyKey(int key) {
    switch (key) {
      case GLFW_KEY_SPACE:
        pause_toggle = true;
        break;
      case GLFW_KEY_RIGHT:
        step_forward = true;
        break;
      case GLFW_KEY_LEFT:
        step_back = true;
        break;
      case GLFW_KEY_RIGHT_BRACKET:
        jump_forward = true;
        break;
      case GLFW_KEY_LEFT_BRACKET:
        jump_back = true;
        break;
      case GLFW_KEY_EQUAL:
      case GLFW_KEY_KP_ADD:
        ++speed_steps;
        break;
      case GLFW_KEY_MINUS:
      case GLFW_KEY_KP_SUBTRACT:
        --speed_steps;
        break;
      case GLFW_KEY_BACKSPACE:
        restart = true;
        break;
      case GLFW_KEY_F:
        fingertip = true;
        break;
      case GLFW_KEY_G:
        grasp = true;
        break;
      case GLFW_KEY_Q:
      case GLFW_KEY_ESCAPE:
        quit = true;
        break;
      default:
        break;
    }
  }
  void OnCursor(double x, double y) {
    const double dx = x - last_x_;
    const double dy = y - last_y_;
    last_x_ = x;
    last_y_ = y;
    const bool left = glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
    const bool right = glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS;
    const bool middle = glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS;
    if (!left && !right && !middle) return;
    const bool shift = glfwGetKey(window_, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ||
                       glfwGetKey(window_, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS;
    int width = 0;
    int height = 0;
    glfwGetWindowSize(window_, &width, &height);
    if (height <= 0) return;
    // As mujoco-simulate: right drag moves, left drag rotates, middle zooms; shift the horizontal forms.
    sim::CameraMove move = sim::CameraMove::kZoom;
    if (right) {
      move = shift ? sim::CameraMove::kMoveHorizontal : sim::CameraMove::kMoveVertical;
    } else if (left) {
      move = shift ? sim::CameraMove::kRotateHorizontal : sim::CameraMove::kRotateVertical;
    }
    drags.push_back({move, dx / height, dy / height});
  }

  GLFWwindow* window_ = nullptr;
  std::deque<int> typed_;  ///< GLFW key codes typed, oldest first
  double last_x_ = 0.0;
  double last_y_ = 0.0;
};

/// What both modes share: the window, renderer, camera, speed and pause state.
class ViewerCore {
 public:
  ViewerCore(const ViewerOptions& options, const std::string& title)
      : options_(options),
        window_(options.width_px, options.height_px, title),
        camera_(options.camera),
        speed_(options.speed),
        paused_(options.paused) {}

  Window& window() { return window_; }
  bool paused() const { return paused_; }
  void set_paused(bool paused) { paused_ = paused; }
  double speed() const { return speed_; }
  int frames() const { return frames_; }

  /// Takes the window's events: pause, speed and camera changes are applied here, the rest stays in
  /// window() for the mode to act on. Returns true when the speed or pause changed (re-anchor the clock).
  bool Poll() {
    glfwPollEvents();
    window_.TakeKey();
    bool changed = false;
    if (window_.pause_toggle) {
      paused_ = !paused_;
      window_.pause_toggle = false;
      changed = true;
    }
    if (window_.speed_steps != 0) {
      speed_ = std::clamp(speed_ * std::pow(2.0, window_.speed_steps), kMinSpeed, kMaxSpeed);
      window_.speed_steps = 0;
      changed = true;
    }
    if (window_.fingertip) camera_ = sim::CameraByName("fingertip");
    if (window_.grasp) camera_ = sim::CameraByName("grasp");
    window_.fingertip = window_.grasp = false;
    return changed;
  }

  bool Done() const {
    return window_.quit || window_.Closed() || (options_.stop != nullptr && options_.stop->load()) ||
           (options_.exit_after_frames > 0 && frames_ >= options_.exit_after_frames);
  }

  /// Draws `simulation` as it is now with the panel and shows it.
  void Display(sim::Simulation& simulation, const sensor::TactileState* state, sim::PanelInfo panel) {
    if (!renderer_) renderer_ = std::make_unique<sim::Renderer>(window_, simulation, options_.render);
    for (const Window::CameraDrag& drag : window_.drags) {
      if (camera_.kind != sim::CameraSpec::Kind::kFree) {
        camera_.free = renderer_->LastView();
        camera_.kind = sim::CameraSpec::Kind::kFree;
      }
      renderer_->MoveCamera(drag.move, drag.dx, drag.dy, camera_.free);
    }
    window_.drags.clear();
    char speed[256];
    std::snprintf(speed, sizeof(speed), "speed\t%gx%s\nkeys\t%s", speed_, paused_ ? " (paused)" : "",
                  kKeysHelp);
    panel.extra = speed;
    const std::array<int, 2> size = window_.FramebufferSize();
    renderer_->RenderToWindow(simulation, state, camera_, sim::PanelText(panel), size[0], size[1]);
    window_.Swap();
    ++frames_;
  }

 private:
  ViewerOptions options_;
  Window window_;
  sim::CameraSpec camera_;
  double speed_;
  bool paused_;
  int frames_ = 0;
  std::unique_ptr<sim::Renderer> renderer_;
};

void SleepFor(double seconds) {
  if (seconds > 0.0) std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
}

}  // namespace

void ViewerOptions::Validate() const {
  render.Validate();
  if (width_px < 16 || height_px < 16) {
    throw std::invalid_argument("--size " + std::to_string(width_px) + "x" + std::to_string(height_px) +
                                ": at least 16x16");
  }
  if (!(speed >= kMinSpeed && speed <= kMaxSpeed)) {
    throw std::invalid_argument("--speed " + std::to_string(speed) + ": must be in [1/64, 64]");
  }
  if (exit_after_frames < 0)
    throw std::invalid_argument("--frames " + std::to_string(exit_after_frames) + ": must be >= 0");
}

ViewerResult ViewLive(const testbed::ScenarioConfig& config, const ViewerOptions& options) {
  options.Validate();
  ViewerCore core(options, "graspbed view: " + config.name + " (" + config.controller.name + ")");
  ViewerResult result;
  result.gl_description = core.window().description;
  const std::string title = config.name + " (" + config.controller.name + ")";
  while (!core.Done()) {
    std::atomic<bool> stop_run{false};
    bool held_at_end = false;
    auto last_display = Clock::now() - std::chrono::seconds(1);
    auto anchor_wall = Clock::now();
    double anchor_sim = 0.0;
    testbed::RunOptions run;
    run.stop = &stop_run;
    // Every control tick: the viewer decides when to draw, wait or hold.
    run.frame_period_s = 1.0 / config.controller.rate_hz;
    run.on_frame = [&](const testbed::FrameContext& frame) {
      sim::SimRig& rig = frame.rig;
      result.time_s = frame.time_s;
      const bool last_tick = frame.time_s >= config.duration_s - 1.0 / config.controller.rate_hz;
      const auto display = [&] {
        const controller::ControllerTelemetry telemetry = rig.controller().telemetry();
        core.Display(rig.simulation(), &rig.loop().state(), LivePanel(config, title, frame, telemetry));
        last_display = Clock::now();
      };
      while (true) {
        const bool due =
            SecondsSince(last_display) >= (core.paused() || last_tick ? kIdlePeriodS : kDisplayPeriodS);
        if (!due && !core.paused() && !last_tick) break;
        if (core.Poll()) {
          anchor_wall = Clock::now();
          anchor_sim = frame.time_s;
        }
        Window& window = core.window();
        if (core.Done() || window.restart) {
          stop_run = true;
          return;
        }
        if (core.paused() || last_tick) {
          held_at_end = last_tick;
          if (window.step_forward && !last_tick) {
            window.step_forward = false;
            display();
            anchor_wall = Clock::now();
            anchor_sim = frame.time_s;
            return;
          }
          window.step_forward = window.step_back = window.jump_back = window.jump_forward = false;
          display();
          SleepFor(kIdlePeriodS - SecondsSince(last_display));
          continue;
        }
        display();
        break;
      }
      // Real time times the speed; a viewer that cannot keep up shows it slower instead of sprinting.
      const double ahead_s = (frame.time_s - anchor_sim) / core.speed() - SecondsSince(anchor_wall);
      if (ahead_s > 0.0) {
        SleepFor(ahead_s);
      } else if (ahead_s < -kMaxLagS) {
        anchor_wall = Clock::now();
        anchor_sim = frame.time_s;
      }
    };
    testbed::RunScenario(config, run);
    Window& window = core.window();
    if (window.restart) {
      window.restart = false;
      ++result.restarts;
      continue;
    }
    if (!held_at_end && !core.Done()) {
      std::fprintf(stderr, "graspbed view: the run ended at t = %.3f s (physics fault?); restarting\n",
                   result.time_s);
      ++result.restarts;
    }
  }
  result.frames = core.frames();
  return result;
}

ViewerResult ViewReplay(const std::string& run_dir, const ViewerOptions& options) {
  options.Validate();
  namespace fs = std::filesystem;
  const std::string config_path = (fs::path(run_dir) / "config.yaml").string();
  if (!fs::exists(config_path)) {
    throw std::invalid_argument(run_dir + ": no config.yaml (not an output directory of graspbed run)");
  }
  const testbed::ScenarioConfig config = testbed::LoadScenario(config_path);
  const sensor::Layout layout = sensor::LoadLayout(testbed::ResolveLayoutPath(config));
  sim::Simulation simulation(layout, config.scene);
  const sim::StateLog states =
      sim::LoadStateLog((fs::path(run_dir) / "states.csv").string(), simulation);
  const common::CsvTable signals = common::ReadCsvTable((fs::path(run_dir) / "signals.csv").string());
  if (signals.rows.empty()) throw std::invalid_argument(signals.path + ": no rows");

  // Columns the overlays need.
  const int units = layout.unit_count();
  const size_t c_time = signals.Column("time_s"), c_phase = signals.Column("phase"),
               c_target = signals.Column("grip_target_n"), c_friction = signals.Column("friction_estimate"),
               c_slip = signals.Column("slip_flag"), c_safe = signals.Column("safe_hold"),
               c_stale = signals.Column("stale"), c_valid = signals.Column("valid_units"),
               c_contact = signals.Column("contact_units"), c_total = signals.Column("est_total_fn_n");
  std::vector<size_t> c_fn(units), c_ft(units), c_validity(units);
  for (int u = 0; u < units; ++u) {
    c_fn[u] = signals.Column("fn_est_n_" + std::to_string(u));
    c_ft[u] = signals.Column("ft_est_n_" + std::to_string(u));
    c_validity[u] = signals.Column("validity_" + std::to_string(u));
  }
  // Runs from before the controllers named their cues have no slip_cues column.
  const auto has_column = [&](const std::string& name) {
    return std::find(signals.header.begin(), signals.header.end(), name) != signals.header.end();
  };
  constexpr size_t kNoColumn = static_cast<size_t>(-1);
  const size_t c_cues = has_column("slip_cues") ? signals.Column("slip_cues") : kNoColumn;
  std::vector<double> signal_times(signals.rows.size());
  for (size_t r = 0; r < signals.rows.size(); ++r) signal_times[r] = signals.Number(r, c_time);

  // When each script action fired, from summary.json (absent for an interrupted run: no line then).
  std::vector<std::pair<double, std::string>> fired;
  {
    std::ifstream file(fs::path(run_dir) / "summary.json");
    if (file) {
      try {
        const nlohmann::json summary = nlohmann::json::parse(file);
        for (const nlohmann::json& entry : summary.at("script")) {
          if (!entry.at("fired_s").is_number()) continue;
          char text[96];
          std::snprintf(text, sizeof(text), "%s at %.3f s (line %d)",
                        entry.at("action").get<std::string>().c_str(), entry.at("fired_s").get<double>(),
                        entry.at("line").get<int>());
          fired.emplace_back(entry.at("fired_s").get<double>(), text);
        }
      } catch (const nlohmann::json::exception& error) {
        throw std::invalid_argument((fs::path(run_dir) / "summary.json").string() + ": " + error.what());
      }
    }
  }
  std::sort(fired.begin(), fired.end());

  ViewerCore core(options, "graspbed view (replay): " + config.name + " (" + config.controller.name + ")");
  ViewerResult result;
  result.gl_description = core.window().description;
  const std::string title = "replay: " + config.name + " (" + config.controller.name + ")";
  const double first_s = states.time_s.front();
  const double last_s = states.time_s.back();
  double t = first_s;
  sensor::TactileState state;
  state.unit_count = units;
  controller::ControllerTelemetry telemetry;
  std::string phase;
  std::string slip_cues;
  auto last_frame = Clock::now();
  while (!core.Done()) {
    core.Poll();
    Window& window = core.window();
    const double wall_dt = SecondsSince(last_frame);
    last_frame = Clock::now();
    size_t row = states.RowAt(t);
    if (window.restart) {
      t = first_s;
      ++result.restarts;
    } else if (window.step_forward || window.step_back) {
      row = window.step_forward ? std::min(row + 1, states.rows.size() - 1) : (row > 0 ? row - 1 : 0);
      t = states.time_s[row];
      core.set_paused(true);
    } else if (window.jump_forward || window.jump_back) {
      t = std::clamp(t + (window.jump_forward ? kReplayJumpS : -kReplayJumpS), first_s, last_s);
    } else if (!core.paused()) {
      t = std::min(t + wall_dt * core.speed(), last_s);
      if (t >= last_s) core.set_paused(true);
    }
    window.restart = window.step_forward = window.step_back = window.jump_forward = window.jump_back = false;

    row = states.RowAt(t);
    sim::ShowStateRow(states, row, simulation);

    // The control tick nearest to the state shown.
    const auto after = std::lower_bound(signal_times.begin(), signal_times.end(), states.time_s[row]);
    size_t s = after == signal_times.end() ? signal_times.size() - 1
                                           : static_cast<size_t>(after - signal_times.begin());
    if (s > 0 &&
        std::abs(signal_times[s - 1] - states.time_s[row]) < std::abs(signal_times[s] - states.time_s[row]))
      --s;
    state.time_s = signal_times[s];
    for (int u = 0; u < units; ++u) {
      state.fn_n[u] = signals.Number(s, c_fn[u]);
      state.ft_n[u] = signals.Number(s, c_ft[u]);
      state.validity[u] =
          static_cast<sensor::UnitValidity>(static_cast<int>(signals.Number(s, c_validity[u])));
    }
    state.valid_count = static_cast<int>(signals.Number(s, c_valid));
    state.contact_count = static_cast<int>(signals.Number(s, c_contact));
    state.total_fn_n = signals.Number(s, c_total);
    state.stale = signals.Number(s, c_stale) != 0.0;
    phase = signals.rows[s][c_phase];
    telemetry.phase = phase.c_str();
    slip_cues = c_cues != kNoColumn ? signals.rows[s][c_cues] : "";
    telemetry.slip_cues = slip_cues.c_str();
    telemetry.grip_target_n = signals.Number(s, c_target);
    telemetry.friction_estimate = signals.Number(s, c_friction);
    telemetry.slip_detected = signals.Number(s, c_slip) != 0.0;
    telemetry.safe_hold = signals.Number(s, c_safe) != 0.0;

    sim::PanelInfo panel;
    panel.title = title;
    panel.time_s = states.time_s[row];
    panel.telemetry = &telemetry;
    panel.state = &state;
    panel.last_action = "";
    for (const auto& [fired_s, text] : fired) {
      if (fired_s <= panel.time_s + 1e-9) panel.last_action = text;
    }
    core.Display(simulation, &state, panel);
    result.time_s = panel.time_s;
    SleepFor(kDisplayPeriodS - SecondsSince(last_frame));
  }
  result.frames = core.frames();
  return result;
}

}  // namespace graspbed::show
