// The Python module graspbed._graspbed (wrapped by python/graspbed/__init__.py): scenario runs,
// suites and sweeps with built-in, plugin or Python controllers; summaries as dicts, signals as numpy
// arrays. Runs release the GIL; a Python controller takes it back for each call.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/data_dir.h"
#include "common/signal_log.h"
#include "controller/controller_api.h"
#include "controller/grasp_controller.h"
#include "controller/learned_slip_controller.h"
#include "controller/learned_slip_cue.h"
#include "controller/plugin_loader.h"
#include "python/python_controller.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"
#include "testbed/scorecard.h"
#include "testbed/suite.h"
#include "testbed/sweep.h"

namespace graspbed::python {
namespace {

namespace py = pybind11;

py::object ToPython(const nlohmann::json& value) {
  return py::module_::import("json").attr("loads")(value.dump());
}

std::vector<testbed::Override> ParseOverrides(const std::vector<std::string>& texts) {
  std::vector<testbed::Override> overrides;
  for (const std::string& text : texts) overrides.push_back(testbed::ParseOverride(text));
  return overrides;
}

/// What a run's `controller` argument asks for.
struct ControllerChoice {
  std::vector<testbed::Override> overrides;  ///< controller.name for a built-in or plugin name
  testbed::ControllerFactory factory;        ///< set for a Python controller
  std::string label;                          ///< "python:ClassName"
};

/// None: the scenario's controller. A str: a built-in or "plugin:..." name. A Python object with
/// update(): that controller (one run at a time). Anything else callable: a factory called once per
/// run (suites and sweeps may run several at once).
ControllerChoice ChooseController(const py::object& controller, bool single_run) {
  ControllerChoice choice;
  if (controller.is_none()) return choice;
  if (py::isinstance<py::str>(controller)) {
    choice.overrides.push_back(
        {"controller.name", controller::ResolvePluginName(controller.cast<std::string>(), ".")});
    return choice;
  }
  const bool instance = py::hasattr(controller, "update") && !py::isinstance<py::type>(controller);
  if (!instance && !PyCallable_Check(controller.ptr())) {
    throw py::type_error(
        "controller: expected None, a controller name, a controller object (with update()) or a "
        "class / factory making one; got " +
        std::string(py::repr(controller)));
  }
  if (instance && !single_run) {
    throw py::type_error(
        "controller: runs of a suite or sweep each need their own controller: pass its class (or "
        "a function that makes one), not an instance");
  }
  const py::object type = instance ? py::reinterpret_borrow<py::object>(controller.get_type()) : controller;
  choice.label = "python:" + std::string(py::str(py::getattr(type, "__name__", py::str("controller"))));
  // The factory runs on the runner's threads: it takes the GIL, and keeps `controller` alive.
  std::shared_ptr<py::object> guarded(new py::object(controller), [](py::object* object) {
    py::gil_scoped_acquire gil;
    delete object;
  });
  const std::string label = choice.label;
  choice.factory = [guarded, instance, label](const testbed::ControllerOptions&) {
    py::gil_scoped_acquire gil;
    py::object made = instance ? *guarded : (*guarded)();
    return std::unique_ptr<controller::GraspController>(new PythonController(made, label));
  };
  return choice;
}

/// Signals of a run, copied out of the log at its end (C++ side, no GIL needed).
struct CollectedSignals {
  std::vector<std::string> numeric_names;
  std::vector<std::vector<double>> numeric;
  std::vector<std::string> text_names;
  std::vector<std::vector<std::string>> text;
  void Collect(const common::SignalLog& log) {
    numeric_names = log.numeric_columns();
    text_names = log.text_columns();
    numeric.assign(numeric_names.size(), std::vector<double>(log.rows()));
    text.assign(text_names.size(), std::vector<std::string>(log.rows()));
    for (size_t row = 0; row < log.rows(); ++row) {
      for (size_t c = 0; c < numeric_names.size(); ++c) numeric[c][row] = log.At(row, c);
      for (size_t c = 0; c < text_names.size(); ++c)
        text[c][row] = log.TextAt(row, c) ? log.TextAt(row, c) : "";
    }
  }
  py::dict ToDict() {
    py::dict columns;
    for (size_t c = 0; c < numeric_names.size(); ++c) {
      columns[py::str(numeric_names[c])] =
          py::array_t<double>(static_cast<py::ssize_t>(numeric[c].size()), numeric[c].data());
    }
    py::module_ numpy = py::module_::import("numpy");
    for (size_t c = 0; c < text_names.size(); ++c)
      columns[py::str(text_names[c])] = numpy.attr("array")(text[c]);
    return columns;
  }
};

py::dict Run(const std::string& scenario_path, const std::vector<std::string>& overrides,
             const py::object& controller, const std::string& out_dir, bool plots, bool prompt_actions,
             const std::string& intent_fifo) {
  ControllerChoice choice = ChooseController(controller, true);
  std::vector<testbed::Override> all = choice.overrides;
  for (const testbed::Override& o : ParseOverrides(overrides)) all.push_back(o);
  testbed::ScenarioConfig config = testbed::LoadScenario(scenario_path, all);
  if (choice.factory) config.controller.name = choice.label;
  testbed::RunOptions options;
  options.out_dir = out_dir;
  options.write_plots = plots;
  options.make_controller = choice.factory;
  options.prompt_actions = prompt_actions;
  options.intent_fifo = intent_fifo;
  CollectedSignals signals;
  options.on_signals = [&signals](const common::SignalLog& log) { signals.Collect(log); };
  testbed::RunResult result;
  {
    py::gil_scoped_release release;
    result = testbed::RunScenario(config, options);
  }
  py::dict out;
  out["summary"] = ToPython(testbed::SummaryJson(result));
  out["signals"] = signals.ToDict();
  return out;
}

py::dict Suite(const std::vector<std::string>& files, const std::vector<std::string>& overrides,
               const py::object& controller, int jobs, const std::string& out_dir, bool plots) {
  ControllerChoice choice = ChooseController(controller, jobs == 1);
  std::vector<testbed::Override> all = choice.overrides;
  for (const testbed::Override& o : ParseOverrides(overrides)) all.push_back(o);
  std::vector<testbed::ScenarioConfig> configs = testbed::LoadScenarios(files, all);
  if (choice.factory) {
    for (testbed::ScenarioConfig& config : configs) config.controller.name = choice.label;
  }
  testbed::SuiteOptions options;
  options.jobs = jobs;
  options.out_dir = out_dir;
  options.write_plots = plots;
  options.make_controller = choice.factory;
  testbed::SuiteResult result;
  {
    py::gil_scoped_release release;
    result = testbed::RunSuite(configs, options);
  }
  return ToPython(testbed::SuiteJson(result));
}

py::dict Sweep(const std::string& spec_path, const py::object& controller, int jobs,
               const std::string& out_dir, const std::string& shard) {
  ControllerChoice choice = ChooseController(controller, jobs == 1);
  testbed::SweepSpec spec = testbed::LoadSweepSpec(spec_path);
  spec.fixed.insert(spec.fixed.begin(), choice.overrides.begin(), choice.overrides.end());
  testbed::SweepOptions options;
  options.shard = testbed::ParseShard(shard);
  options.jobs = jobs;
  options.out_dir = out_dir;
  options.make_controller = choice.factory;
  testbed::SweepOutcome outcome;
  {
    py::gil_scoped_release release;
    outcome = testbed::RunSweep(spec, options);
  }
  py::dict out;
  out["runs"] = outcome.runs;
  out["finished"] = outcome.finished;
  out["passed"] = outcome.passed;
  out["completed"] = outcome.completed;
  out["wall_s"] = outcome.wall_s;
  py::list rows;
  std::ifstream jsonl(out_dir + "/results.jsonl");
  for (std::string line; std::getline(jsonl, line);) {
    if (!line.empty()) rows.append(ToPython(nlohmann::json::parse(line)));
  }
  out["rows"] = rows;
  return out;
}

py::dict Score(const std::vector<py::object>& controllers, const std::string& set_dir, int jobs, int limit,
               const std::string& out_dir) {
  testbed::ScorecardOptions options;
  options.controllers.clear();
  options.jobs = jobs;
  options.limit = limit;
  for (const py::object& controller : controllers) {
    ControllerChoice choice = ChooseController(controller, jobs == 1);
    if (choice.factory) {
      options.controllers.push_back(choice.label);
      options.custom_controllers[choice.label] = choice.factory;
    } else {
      options.controllers.push_back(choice.overrides.at(0).value);
    }
  }
  const testbed::ScorecardSet set = testbed::LoadScorecardSet(
      (set_dir.empty() ? common::DataPath("scenarios/scorecard") : set_dir) + "/set.yaml");
  testbed::Scorecard scorecard;
  {
    py::gil_scoped_release release;
    scorecard = testbed::RunScorecard(set, options);
    if (!out_dir.empty()) testbed::WriteScorecard(scorecard, out_dir);
  }
  py::dict out = ToPython(testbed::ScorecardJson(scorecard));
  out["table"] = testbed::ScorecardTable(scorecard);
  return out;
}

/// Wall time of one controller Update [ns], averaged over `ticks` calls from C++ (the GIL released
/// first, as in a run) on a 20-unit state in steady contact. `controller`: a controller name or a
/// Python controller object. For bench/python_controller_bench.py.
double TimeControllerUpdate(const py::object& controller, int ticks) {
  std::unique_ptr<controller::GraspController> made;
  if (py::isinstance<py::str>(controller)) {
    made = controller::MakeController(controller::ResolvePluginName(controller.cast<std::string>(), "."), {});
  } else {
    made = std::make_unique<PythonController>(
        controller, "python:" + std::string(py::str(controller.get_type().attr("__name__"))));
  }
  sensor::TactileState state;
  state.unit_count = 20;
  state.valid_count = 20;
  state.contact_count = 20;
  for (int u = 0; u < state.unit_count; ++u) state.fn_n[u] = 0.15;
  state.total_fn_n = 3.0;
  made->SetIntent(controller::GraspIntent::kClose);
  double sink = 0.0;
  std::chrono::steady_clock::duration elapsed{};
  {
    py::gil_scoped_release release;
    const auto start = std::chrono::steady_clock::now();
    for (int tick = 0; tick < ticks; ++tick) {
      state.time_s = 1e-3 * tick;
      sink += made->Update(state, {}, state.time_s).grip_effort;
    }
    elapsed = std::chrono::steady_clock::now() - start;
  }
  if (!std::isfinite(sink)) throw std::runtime_error("controller returned a non-finite effort");
  {
    // The controller's Python references go with the GIL held (its destructor takes it anyway).
    made.reset();
  }
  return std::chrono::duration<double, std::nano>(elapsed).count() / ticks;
}

/// graspbed.DigitState: a read-only view of one digit of the tick's hand::HandState (the joint
/// arrays numpy views, write=False, the same objects every tick). Valid during update().
void BindDigitState(py::module_& m) {
  using Digit = DigitStateView;
  py::class_<Digit>(m, "DigitState",
                    "One digit's proprioception (read-only; valid during update()). Check the *_known flags: "
                    "an unknown value means nothing")
      .def_property_readonly(
          "joint_count", [](const Digit& v) { return v.get().joint_count; },
          "joints reported, proximal first")
      .def_property_readonly(
          "linear", [](const Digit& v) { return v.get().linear; },
          "True: slides (jaw fixture) [m], [m/s]; False: hinges [rad], [rad/s]")
      .def_property_readonly("position_known", [](const Digit& v) { return v.get().position_known; })
      .def_property_readonly(
          "joint_position",
          [](Digit& v) {
            v.Refresh();
            return v.joint_position;
          },
          "flexion from the open pose per joint [rad] or [m], + closing (numpy, read-only view)")
      .def_property_readonly("velocity_known", [](const Digit& v) { return v.get().velocity_known; })
      .def_property_readonly(
          "joint_velocity",
          [](Digit& v) {
            v.Refresh();
            return v.joint_velocity;
          },
          "d(joint_position)/dt [rad/s] or [m/s] (numpy, read-only view)")
      .def_property_readonly("current_known", [](const Digit& v) { return v.get().current_known; })
      .def_property_readonly(
          "motor_current_a", [](const Digit& v) { return v.get().motor_current_a; },
          "the drive motor's current [A], + closing")
      .def_property_readonly(
          "stall_current_a", [](const Digit& v) { return v.get().stall_current_a; },
          "the motor's current at stall with full effort [A]; 0 when unknown")
      .def_property_readonly("stops_known", [](const Digit& v) { return v.get().stops_known; })
      .def_property_readonly("at_open_stop", [](const Digit& v) { return v.get().at_open_stop; })
      .def_property_readonly("at_closed_stop", [](const Digit& v) { return v.get().at_closed_stop; })
      .def_property_readonly(
          "encoder_fault", [](const Digit& v) { return v.get().encoder_fault; },
          "the encoder stood still while the motor turned (position then unknown)");
}

/// graspbed.HandState: a read-only view of the tick's hand::HandState, its digits as DigitState.
void BindHandState(py::module_& m) {
  BindDigitState(m);
  py::class_<HandStateView>(m, "HandState",
                            "The hand's proprioception at this tick (read-only; valid during update())")
      .def_property_readonly(
          "time_s", [](const HandStateView& v) { return v.state->time_s; },
          "sample time of the newest reading [s]; < 0 before the first")
      .def_property_readonly(
          "stale", [](const HandStateView& v) { return v.state->stale; },
          "no new reading within the stale timeout")
      .def_property_readonly(
          "digit_count", [](const HandStateView& v) { return v.state->digit_count; },
          "digits reported (0: no proprioception)")
      .def_property_readonly(
          "digits",
          [](HandStateView& v) {
            v.Refresh();
            return v.digits;
          },
          "tuple of DigitState: [0] the index (the jaw's finger), [1] the thumb")
      .def(
          "any_known", [](const HandStateView& v) { return v.state->any_known(); },
          "True when any digit reports any field");
}

}  // namespace

PYBIND11_MODULE(_graspbed, m) {
  m.doc() = "graspbed: simulation-in-the-loop grasp testbed (C++ core; see the graspbed package)";
  m.attr("__version__") = GRASPBED_VERSION;
  m.attr("CONTROLLER_API_VERSION") = GRASPBED_CONTROLLER_API_VERSION;
  py::register_exception<ControllerError>(m, "ControllerError", PyExc_RuntimeError);
  // Bad input (files, overrides, controller names): ValueError, with the file:line:key message.
  py::register_exception<std::invalid_argument>(m, "ConfigError", PyExc_ValueError);

  py::class_<controller::HandCommand>(m, "HandCommand", "One command to the grip motor.")
      .def(py::init([](double grip_effort, bool enable, bool brake) {
             return controller::HandCommand{grip_effort, enable, brake};
           }),
           py::arg("grip_effort") = 0.0, py::arg("enable") = true, py::arg("brake") = false)
      .def_readwrite("grip_effort", &controller::HandCommand::grip_effort,
                     "[-1, 1] of stall torque; + closes")
      .def_readwrite("enable", &controller::HandCommand::enable, "False: motor off (coasts)")
      .def_readwrite("brake", &controller::HandCommand::brake, "True: hold position with the brake")
      .def("__repr__", [](const controller::HandCommand& c) {
        return "HandCommand(grip_effort=" + std::to_string(c.grip_effort) +
               ", enable=" + (c.enable ? "True" : "False") + ", brake=" + (c.brake ? "True" : "False") + ")";
      });

  // Read-only: the arrays are numpy views (write=False) onto the state of the current tick. Valid
  // during update(); copy (numpy.copy) what a controller keeps across ticks.
  py::class_<TactileStateView>(
      m, "TactileState", "Per-unit forces estimated from one sensor frame (read-only; valid during update())")
      .def_property_readonly("sequence", [](const TactileStateView& v) { return v.state->sequence; })
      .def_property_readonly(
          "time_s", [](const TactileStateView& v) { return v.state->time_s; }, "sample time [s]")
      .def_property_readonly("unit_count", [](const TactileStateView& v) { return v.state->unit_count; })
      .def_property_readonly(
          "stale", [](const TactileStateView& v) { return v.state->stale; },
          "no new frame within the stale timeout")
      .def_property_readonly("valid_count", [](const TactileStateView& v) { return v.state->valid_count; })
      .def_property_readonly(
          "total_fn_n", [](const TactileStateView& v) { return v.state->total_fn_n; },
          "sum of Fn over valid units [N]")
      .def_property_readonly("total_shear_axial_n",
                             [](const TactileStateView& v) { return v.state->total_shear_axial_n; })
      .def_property_readonly("total_shear_circumferential_n",
                             [](const TactileStateView& v) { return v.state->total_shear_circumferential_n; })
      .def_property_readonly("contact_count",
                             [](const TactileStateView& v) { return v.state->contact_count; })
      .def_property_readonly("noise_known", [](const TactileStateView& v) { return v.state->noise_known; })
      .def_property_readonly(
          "fn_n",
          [](TactileStateView& v) {
            v.Refresh();
            return v.fn_n;
          },
          "normal force per unit [N], unit frame (numpy, read-only view)")
      .def_property_readonly(
          "ft_n",
          [](TactileStateView& v) {
            v.Refresh();
            return v.ft_n;
          },
          "shear per unit along its beam axis [N] (numpy, read-only view)")
      .def_property_readonly(
          "validity",
          [](TactileStateView& v) {
            v.Refresh();
            return v.validity;
          },
          "per unit: 0 valid, 1 open, 2 short, 3 out of range, 4 implausible, 5 not tared")
      .def_property_readonly("fn_noise_n",
                             [](TactileStateView& v) {
                               v.Refresh();
                               return v.fn_noise_n;
                             })
      .def_property_readonly("ft_noise_n", [](TactileStateView& v) {
        v.Refresh();
        return v.ft_noise_n;
      });

  BindHandState(m);

  // The learned slip cue (controller/learned_slip_cue.h) for Python controllers: the same C++ code,
  // fed the TactileState the controller was given.
  py::class_<controller::LearnedSlipCue>(
      m, "LearnedSlipCue",
      "The learned slip cue (docs/training-slip-detector.md): update(state, time_s) -> (score, flag) once per tick")
      .def(py::init([](const std::string& model, double threshold) {
             const std::string path = model.empty() ? controller::LearnedSlipController::DefaultModelPath() : model;
             return std::make_unique<controller::LearnedSlipCue>(
                 controller::LoadSlipModel(path, {.layout_name = "", .units = 0}), threshold);
           }),
           py::arg("model") = "", py::arg("threshold") = -1.0,
           "model: a model file ('' = $GRASPBED_SLIP_MODEL, else the shipped one); threshold < 0: the model's own")
      .def("reset", &controller::LearnedSlipCue::Reset, "forget the filters' state (a new grasp)")
      .def(
          "update",
          [](controller::LearnedSlipCue& cue, const TactileStateView& state, double time_s) {
            const controller::LearnedSlipOutput output = cue.Update(*state.state, time_s);
            return py::make_tuple(output.score, output.flag);
          },
          py::arg("state"), py::arg("time_s"), "(score [0, 1], flag) for this tick's state")
      .def_property_readonly("threshold", &controller::LearnedSlipCue::threshold)
      .def_property_readonly("label", [](const controller::LearnedSlipCue& cue) { return cue.model().label; })
      .def_property_readonly("layout_name",
                             [](const controller::LearnedSlipCue& cue) { return cue.model().layout_name; });

  m.def("_run", &Run, py::arg("scenario"), py::arg("overrides"), py::arg("controller"), py::arg("out_dir"),
        py::arg("plots"), py::arg("prompt_actions"), py::arg("intent_fifo"));
  m.def("_suite", &Suite, py::arg("files"), py::arg("overrides"), py::arg("controller"), py::arg("jobs"),
        py::arg("out_dir"), py::arg("plots"));
  m.def("_sweep", &Sweep, py::arg("spec"), py::arg("controller"), py::arg("jobs"), py::arg("out_dir"),
        py::arg("shard"));
  m.def("_score", &Score, py::arg("controllers"), py::arg("set_dir"), py::arg("jobs"), py::arg("limit"),
        py::arg("out_dir"));
  m.def("list_scenarios", &testbed::ListScenarioFiles, py::arg("directory"),
        "The scenario files of a directory, sorted.");
  m.def("controller_names", &controller::ControllerNames, "Names of the built-in controllers.");
  m.def(
      "controller_parameters",
      [](const std::string& name) {
        py::list out;
        for (const controller::ControllerParameter& p : controller::ControllerParameters(name)) {
          py::dict entry;
          entry["name"] = p.name;
          entry["default"] = p.default_value;
          entry["min"] = p.min;
          entry["max"] = p.max;
          entry["unit"] = p.unit;
          entry["doc"] = p.doc;
          out.append(entry);
        }
        return out;
      },
      py::arg("name"), "Declared parameters of a built-in or plugin:LIBRARY controller.");
  m.def("_time_controller_update", &TimeControllerUpdate, py::arg("controller"), py::arg("ticks"));
  m.def("data_dir", &common::DataDir, "Directory of the shipped data (layouts, scenarios, models).");
}

}  // namespace graspbed::python
