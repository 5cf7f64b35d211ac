#pragma once
/// PythonController: a GraspController whose decisions a Python object makes. The C++ control loop
/// calls it every tick; it takes the GIL, shows the tick's TactileState to Python as a read-only
/// view (numpy arrays onto one TactileState it owns, refreshed by one struct copy per tick, no new
/// array objects per tick) and turns what update() returns into a HandCommand.
///
/// The Python object: reset(), set_intent(intent: "idle" | "close" | "open"), update(state, t) ->
/// command (a graspbed.HandCommand, a number taken as grip_effort, or a dict with grip_effort,
/// enable, brake); optionally telemetry() -> dict (phase, grip_target_n, friction_estimate,
/// slip_detected, slip_cues, slip_events, safe_hold), set_grip_ceiling(newtons), and
/// diagnostic_channels (a sequence of names) with diagnostics() -> as many numbers, logged as
/// signals.csv columns ctl_<name> every tick. Anything it raises, or a
/// return that is no command (wrong type, effort not finite or outside [-1, 1]), ends the run with
/// ControllerError naming the controller and the method.

#include <pybind11/pybind11.h>

#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "controller/grasp_controller.h"

namespace graspbed::python {

/// A Python controller misbehaved (raised, or returned something that is no command).
class ControllerError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What Python sees of a TactileState: the state (owned; copied in every tick) and numpy views of
/// its per-unit arrays, made once per unit count.
struct TactileStateView {
  std::shared_ptr<sensor::TactileState> state = std::make_shared<sensor::TactileState>();
  int viewed_units = -1;  ///< unit count the arrays below were made for
  pybind11::object fn_n, ft_n, validity, fn_noise_n, ft_noise_n;
  /// Makes the arrays again if the unit count changed (first use, or another layout).
  void Refresh();
};

class PythonController final : public controller::GraspController {
 public:
  /// `controller` must have reset, set_intent and update (std::invalid_argument otherwise); its
  /// reset() is called once here. Call with the GIL held.
  PythonController(pybind11::object controller, std::string label);
  /// Takes the GIL to drop the Python references (runs may end on worker threads).
  ~PythonController() override;

  void Reset() override;
  void SetIntent(controller::GraspIntent intent) override;
  controller::HandCommand Update(const sensor::TactileState& state, const hand::HandState& hand,
                                 double time_s) override;
  void SetGripCeiling(double ceiling_n) override;
  controller::ControllerTelemetry telemetry() const override { return telemetry_; }
  std::string name() const override { return label_; }
  std::span<const controller::DiagnosticChannel> diagnostic_channels() const override { return channels_; }
  void ReadDiagnostics(std::span<double> values) const override;

 private:
  /// Raises ControllerError for a Python error in `method` (call with the GIL held).
  [[noreturn]] void Fail(const char* method, const std::string& message) const;
  controller::HandCommand ToCommand(const pybind11::handle& result) const;
  void ReadTelemetry(const pybind11::handle& result);
  void ReadDiagnosticValues(const pybind11::handle& result);

  std::string label_;
  pybind11::object controller_;
  pybind11::object update_;                 ///< bound method, looked up once
  pybind11::object telemetry_method_;       ///< bound method or None
  pybind11::object diagnostics_method_;     ///< bound method, or None without diagnostic_channels
  std::vector<std::string> channel_names_;  ///< diagnostic_channels, as declared
  std::vector<controller::DiagnosticChannel> channels_;  ///< pointing into channel_names_
  std::vector<double> diagnostic_values_;                ///< the last diagnostics(), one per channel
  pybind11::object view_object_;                         ///< the TactileStateView handed to update()
  TactileStateView* view_ = nullptr;                     ///< owned by view_object_
  controller::ControllerTelemetry telemetry_;
  /// A telemetry string as a pointer that stays valid (kept in strings_); `last` caches the object.
  const char* Intern(const pybind11::handle& value, pybind11::object* last, const char* current);

  std::set<std::string> strings_;    ///< telemetry strings seen, so telemetry_.phase/slip_cues stay valid
  pybind11::object last_phase_;      ///< the phase object of the last telemetry() (skips the lookup)
  pybind11::object last_slip_cues_;  ///< the same for slip_cues
};

}  // namespace graspbed::python
