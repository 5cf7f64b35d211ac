#include "python/python_controller.h"

#include <pybind11/numpy.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace graspbed::python {
namespace py = pybind11;

namespace {

/// A read-only 1-D numpy array of `count` elements at `data`, keeping `owner` alive.
template <typename T, typename Owner>
py::object ReadOnlyView(const T* data, int count, const std::shared_ptr<Owner>& owner) {
  // The capsule owns a reference to the state, so an array kept after the run stays valid.
  py::capsule base(new std::shared_ptr<Owner>(owner),
                   [](void* p) { delete static_cast<std::shared_ptr<Owner>*>(p); });
  py::array_t<T> array({static_cast<py::ssize_t>(count)}, {static_cast<py::ssize_t>(sizeof(T))}, data, base);
  array.attr("setflags")(py::arg("write") = false);
  return array;
}

}  // namespace

void TactileStateView::Refresh() {
  const int units = state->unit_count;
  if (units == viewed_units) return;
  const sensor::TactileState& s = *state;
  fn_n = ReadOnlyView(s.fn_n.data(), units, state);
  ft_n = ReadOnlyView(s.ft_n.data(), units, state);
  validity = ReadOnlyView(reinterpret_cast<const uint8_t*>(s.validity.data()), units, state);
  fn_noise_n = ReadOnlyView(s.fn_noise_n.data(), units, state);
  ft_noise_n = ReadOnlyView(s.ft_noise_n.data(), units, state);
  viewed_units = units;
}

void DigitStateView::Refresh() {
  const int joints = get().joint_count;
  if (joints == viewed_joints) return;
  joint_position = ReadOnlyView(get().joint_position.data(), joints, state);
  joint_velocity = ReadOnlyView(get().joint_velocity.data(), joints, state);
  viewed_joints = joints;
}

void HandStateView::Refresh() {
  const int count = state->digit_count;
  if (count == viewed_digits) return;
  py::tuple made(count);
  for (int d = 0; d < count; ++d) {
    DigitStateView digit;
    digit.state = state;
    digit.digit = d;
    made[d] = py::cast(std::move(digit));
  }
  digits = std::move(made);
  viewed_digits = count;
}

bool UpdateTakesHand(const py::handle& update, const std::string& label) {
  py::object signature;
  try {
    signature = py::module_::import("inspect").attr("signature")(update);
  } catch (py::error_already_set&) {
    return false;  // no signature to read (a builtin): the original form
  }
  const py::object parameter = py::module_::import("inspect").attr("Parameter");
  int positional = 0;
  int required = 0;
  bool var_positional = false;
  for (const py::handle p : signature.attr("parameters").attr("values")()) {
    const py::object kind = p.attr("kind");
    if (kind.equal(parameter.attr("VAR_POSITIONAL"))) var_positional = true;
    if (!kind.equal(parameter.attr("POSITIONAL_ONLY")) &&
        !kind.equal(parameter.attr("POSITIONAL_OR_KEYWORD"))) {
      continue;
    }
    ++positional;
    if (p.attr("default").is(parameter.attr("empty"))) ++required;
  }
  if (required <= 3 && (var_positional || required == 3)) return true;
  if (required <= 2 && positional >= 2) return false;
  throw std::invalid_argument("Python controller " + label + ".update" + std::string(py::str(signature)) +
                              ": expected update(state, t) or update(state, hand, t)");
}

PythonController::PythonController(py::object controller, std::string label)
    : label_(std::move(label)), controller_(std::move(controller)) {
  for (const char* method : {"reset", "set_intent", "update"}) {
    if (!py::hasattr(controller_, method)) {
      throw std::invalid_argument("Python controller " + label_ + " has no method " + method +
                                  "() (a controller has reset, set_intent and update)");
    }
  }
  update_ = controller_.attr("update");
  telemetry_method_ = py::getattr(controller_, "telemetry", py::none());
  const py::object declared = py::getattr(controller_, "diagnostic_channels", py::none());
  if (!declared.is_none()) {
    if (!py::isinstance<py::sequence>(declared) || py::isinstance<py::str>(declared)) {
      throw std::invalid_argument("Python controller " + label_ + ".diagnostic_channels = " +
                                  std::string(py::repr(declared)) + ": expected a sequence of names");
    }
    for (const py::handle name : declared) channel_names_.push_back(py::str(name).cast<std::string>());
    for (const std::string& name : channel_names_) channels_.push_back({name.c_str(), "declared in Python"});
    diagnostic_values_.assign(channels_.size(), 0.0);
    diagnostics_method_ = py::getattr(controller_, "diagnostics", py::none());
    if (diagnostics_method_.is_none() && !channels_.empty()) {
      throw std::invalid_argument("Python controller " + label_ +
                                  " declares diagnostic_channels but has no method diagnostics()");
    }
  }
  update_takes_hand_ = UpdateTakesHand(update_, label_);
  view_object_ = py::cast(TactileStateView{});
  view_ = &view_object_.cast<TactileStateView&>();
  hand_view_object_ = py::cast(HandStateView{});
  hand_view_ = &hand_view_object_.cast<HandStateView&>();
  Reset();
}

PythonController::~PythonController() {
  py::gil_scoped_acquire gil;
  update_ = py::object();
  telemetry_method_ = py::object();
  diagnostics_method_ = py::object();
  view_object_ = py::object();
  hand_view_object_ = py::object();
  last_phase_ = py::object();
  last_slip_cues_ = py::object();
  controller_ = py::object();
}

void PythonController::Fail(const char* method, const std::string& message) const {
  throw ControllerError("Python controller " + label_ + "." + method + ": " + message);
}

void PythonController::Reset() {
  py::gil_scoped_acquire gil;
  try {
    controller_.attr("reset")();
  } catch (py::error_already_set& error) {
    Fail("reset()", error.what());
  }
  telemetry_ = controller::ControllerTelemetry{};
  last_phase_ = py::object();
  last_slip_cues_ = py::object();
}

void PythonController::SetIntent(controller::GraspIntent intent) {
  py::gil_scoped_acquire gil;
  try {
    controller_.attr("set_intent")(controller::ToString(intent));
  } catch (py::error_already_set& error) {
    Fail("set_intent()", error.what());
  }
}

void PythonController::SetGripCeiling(double ceiling_n) {
  py::gil_scoped_acquire gil;
  if (!py::hasattr(controller_, "set_grip_ceiling")) return;
  try {
    controller_.attr("set_grip_ceiling")(ceiling_n);
  } catch (py::error_already_set& error) {
    Fail("set_grip_ceiling()", error.what());
  }
}

controller::HandCommand PythonController::ToCommand(const py::handle& result) const {
  controller::HandCommand command;
  if (py::isinstance<controller::HandCommand>(result)) {
    command = result.cast<controller::HandCommand>();
  } else if (PyNumber_Check(result.ptr()) && !PyBool_Check(result.ptr()) && !PyDict_Check(result.ptr())) {
    // float, int, numpy scalars: anything with __float__.
    const double effort = PyFloat_AsDouble(result.ptr());
    if (effort == -1.0 && PyErr_Occurred()) throw py::error_already_set();
    command.grip_effort = effort;
  } else if (PyDict_Check(result.ptr())) {
    const py::dict fields = py::reinterpret_borrow<py::dict>(result);
    for (const auto& [key, value] : fields) {
      const std::string name = py::str(key);
      try {
        if (name == "grip_effort") {
          command.grip_effort = value.cast<double>();
        } else if (name == "enable") {
          command.enable = value.cast<bool>();
        } else if (name == "brake") {
          command.brake = value.cast<bool>();
        } else {
          Fail("update()", "returned a dict with key '" + name + "' (valid: grip_effort, enable, brake)");
        }
      } catch (const py::cast_error&) {
        Fail("update()", "returned " + name + " = " + std::string(py::repr(value)) + ": wrong type");
      }
    }
  } else {
    Fail("update()", "returned " + std::string(py::repr(result)) + " (" +
                         std::string(py::str(result.get_type().attr("__name__"))) +
                         "): expected a graspbed.HandCommand, a number (grip effort) or a dict");
  }
  if (!std::isfinite(command.grip_effort) || command.grip_effort < -1.0 || command.grip_effort > 1.0) {
    Fail("update()",
         "returned grip_effort = " + std::to_string(command.grip_effort) + ": must be in [-1, 1]");
  }
  return command;
}

const char* PythonController::Intern(const py::handle& value, py::object* last, const char* current) {
  // The same str object as last tick (the usual case: a literal) needs no lookup.
  if (value.is(*last)) return current;
  *last = py::reinterpret_borrow<py::object>(value);
  return strings_.insert(py::str(value).cast<std::string>()).first->c_str();
}

void PythonController::ReadTelemetry(const py::handle& result) {
  if (!PyDict_Check(result.ptr())) {
    Fail("telemetry()", "returned " + std::string(py::repr(result)) + ": expected a dict");
  }
  const py::dict fields = py::reinterpret_borrow<py::dict>(result);
  try {
    for (const auto& [key, value] : fields) {
      const std::string name = py::str(key);
      if (name == "phase") {
        telemetry_.phase = Intern(value, &last_phase_, telemetry_.phase);
      } else if (name == "slip_cues") {
        telemetry_.slip_cues = Intern(value, &last_slip_cues_, telemetry_.slip_cues);
      } else if (name == "grip_target_n") {
        telemetry_.grip_target_n = value.cast<double>();
      } else if (name == "friction_estimate") {
        telemetry_.friction_estimate = value.cast<double>();
      } else if (name == "slip_detected") {
        telemetry_.slip_detected = value.cast<bool>();
      } else if (name == "slip_events") {
        telemetry_.slip_events = value.cast<int>();
      } else if (name == "safe_hold") {
        telemetry_.safe_hold = value.cast<bool>();
      } else {
        Fail("telemetry()",
             "unknown key '" + name +
                 "' (valid: phase, grip_target_n, friction_estimate, slip_detected, slip_cues, slip_events, "
                 "safe_hold)");
      }
    }
  } catch (const py::cast_error& error) {
    Fail("telemetry()", std::string("a value of the wrong type: ") + error.what());
  }
}

void PythonController::ReadDiagnosticValues(const py::handle& result) {
  if (!py::isinstance<py::sequence>(result) || py::isinstance<py::str>(result) ||
      py::len(result) != diagnostic_values_.size()) {
    Fail("diagnostics()", "returned " + std::string(py::repr(result)) + ": expected " +
                              std::to_string(diagnostic_values_.size()) +
                              " numbers, one per diagnostic_channels entry");
  }
  size_t i = 0;
  for (const py::handle value : result) {
    try {
      diagnostic_values_[i] = value.cast<double>();
    } catch (const py::cast_error&) {
      Fail("diagnostics()", channel_names_[i] + " = " + std::string(py::repr(value)) + ": not a number");
    }
    ++i;
  }
}

void PythonController::ReadDiagnostics(std::span<double> values) const {
  std::copy_n(diagnostic_values_.begin(), std::min(values.size(), diagnostic_values_.size()), values.begin());
}

controller::HandCommand PythonController::Update(const sensor::TactileState& state,
                                                 const hand::HandState& hand, double time_s) {
  py::gil_scoped_acquire gil;
  *view_->state = state;
  controller::HandCommand command;
  try {
    if (update_takes_hand_) {
      *hand_view_->state = hand;
      command = ToCommand(update_(view_object_, hand_view_object_, time_s));
    } else {
      command = ToCommand(update_(view_object_, time_s));
    }
  } catch (py::error_already_set& error) {
    Fail("update()", error.what());
  }
  if (!telemetry_method_.is_none()) {
    try {
      ReadTelemetry(telemetry_method_());
    } catch (py::error_already_set& error) {
      Fail("telemetry()", error.what());
    }
  }
  if (!channels_.empty()) {
    try {
      ReadDiagnosticValues(diagnostics_method_());
    } catch (py::error_already_set& error) {
      Fail("diagnostics()", error.what());
    }
  }
  return command;
}

}  // namespace graspbed::python
