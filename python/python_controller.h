#pragma once
/// PythonController: a GraspController whose decisions a Python object makes. The C++ control loop
/// calls it every tick; it takes the GIL, shows the tick's TactileState and HandState to Python as
/// read-only views (numpy arrays onto one TactileState and one HandState it owns, each refreshed by
/// one struct copy per tick, no new array objects per tick) and turns what update() returns into a
/// HandCommand.
///
/// The Python object: reset(), set_intent(intent: "idle" | "close" | "open"), update(state, t) or
/// update(state, hand, t) -> command (a graspbed.HandCommand, a number taken as grip_effort, or a
/// dict with grip_effort, enable, brake); `hand` is the tick's HandState as a read-only view like
/// the TactileState's (UpdateTakesHand says which form is called); optionally telemetry() -> dict (phase,
/// grip_target_n, friction_estimate, slip_detected, slip_cues, slip_events, safe_hold),
/// set_grip_ceiling(newtons), and diagnostic_channels (a sequence of names) with diagnostics() -> as many
/// numbers, logged as signals.csv columns ctl_<name> every tick. Anything it raises, or a return that is no
/// command (wrong type, effort not finite or outside [-1, 1]), ends the run with ControllerError naming the
/// controller and the method.

#include <pybind11/pybind11.h>

#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "controller/grasp_controller.h"
#include "hand/hand_state.h"

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

/// What Python sees of one digit of a HandState: its scalars read through `state`, its joint
/// arrays as read-only numpy views of `state`'s, made once per joint count.
struct DigitStateView {
  std::shared_ptr<hand::HandState> state;  ///< shared with the HandStateView that made this view
  int digit = 0;                           ///< index into state->digits (0 index or jaw finger, 1 thumb)
  int viewed_joints = -1;                  ///< joint count the arrays below were made for
  pybind11::object joint_position, joint_velocity;
  const hand::DigitState& get() const { return state->digits[digit]; }
  /// Makes the arrays again if the digit's joint count changed (first use, another backend).
  void Refresh();
};

/// What Python sees of a HandState: the state (owned; copied in every tick) and a tuple of its
/// digits' views, made once per digit count.
struct HandStateView {
  std::shared_ptr<hand::HandState> state = std::make_shared<hand::HandState>();
  int viewed_digits = -1;   ///< digit count `digits` was made for
  pybind11::object digits;  ///< tuple of DigitStateView, one per reported digit
  /// Makes `digits` again if the digit count changed.
  void Refresh();
};

/// Whether the Python `update` (a bound method or any callable) is called as update(state, hand, t)
/// (true) or as the original update(state, t) (false), from its signature: three positional
/// parameters without a default, or a `*args`, take the hand; one or two without a default (and at
/// least two in all) do not; a callable without a signature (a builtin) is called the old way.
/// @throws std::invalid_argument naming `label` when it can take neither form (fewer than two
/// positional parameters, more than three without a default).
bool UpdateTakesHand(const pybind11::handle& update, const std::string& label);

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
  bool update_takes_hand_ = false;                       ///< update(state, hand, t), else update(state, t)
  pybind11::object hand_view_object_;                    ///< the HandStateView handed to update()
  HandStateView* hand_view_ = nullptr;                   ///< owned by hand_view_object_
  controller::ControllerTelemetry telemetry_;
  /// A telemetry string as a pointer that stays valid (kept in strings_); `last` caches the object.
  const char* Intern(const pybind11::handle& value, pybind11::object* last, const char* current);

  std::set<std::string> strings_;    ///< telemetry strings seen, so telemetry_.phase/slip_cues stay valid
  pybind11::object last_phase_;      ///< the phase object of the last telemetry() (skips the lookup)
  pybind11::object last_slip_cues_;  ///< the same for slip_cues
};

}  // namespace graspbed::python
