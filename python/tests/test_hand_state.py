"""The hand's proprioception in a Python controller (graspbed.HandState): update(state, hand, t) sees
the simulated encoders and motor current, as numpy views, tick by tick what the loop logged; an
update(state, t) controller keeps working without it; which form is called is read from update's
signature once."""
import os
import sys

import numpy as np
import pytest

import graspbed

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "examples"))
from python_controller import ThresholdGrip  # noqa: E402

DEFAULT = "scenarios/default.yaml"
# Held on the box, ThresholdGrip's 3 N target takes 0.15 of the stall torque: about 0.17 A of the
# realistic profile's 1 A stall current (gain 1.02, offset 10 mA); closing freely the motor runs near
# its no-load speed and draws about the offset (measured: held 0.18 A on average, closing 0.01 A).
HELD_CURRENT_MIN_A = 0.1
CURRENT_RISE_MIN = 10.0
# The index flexes from its pre-shape onto the 50 mm box (measured: 0.067 rad at MCP).
FLEXION_MIN_RAD = 0.05

# A hand lifted clear of the box before it closes: it closes on nothing, onto its end stops (the
# index reaches its stop about 2 s after the close at ThresholdGrip's approach effort of 0.3).
CLOSE_ON_NOTHING = """name: close_on_nothing
duration_s: 3.0
object: {shape: box, size_m: [0.05, 0.05, 0.08], mass_kg: 0.1, friction: 0.8}
controller: {name: grip_slip}
script:
  - {at_s: 0.0, action: lift, height_m: 0.15, duration_s: 0.2}
  - {at_s: 0.3, action: close}
"""


class HandRecorder(ThresholdGrip):
    """ThresholdGrip (which reads the hand itself) recording what it saw of the hand each tick."""

    def reset(self):
        super().reset()
        self.rows = []
        self.arrays = None

    def update(self, state, hand, t):
        index, thumb = hand.digits
        if self.arrays is None:
            self.arrays = (index.joint_position, index.joint_velocity, thumb.joint_position)
        # The same array objects every tick: views, not copies.
        assert index.joint_position is self.arrays[0] and index.joint_velocity is self.arrays[1]
        nan = float("nan")
        known = index.position_known
        self.rows.append((t, hand.time_s, hand.stale, hand.digit_count,
                          index.joint_position[0] if known else nan, index.joint_position[1] if known else nan,
                          index.joint_velocity[0] if index.velocity_known else nan,
                          index.motor_current_a if index.current_known else nan, index.stall_current_a,
                          index.at_closed_stop, index.encoder_fault,
                          thumb.joint_position[0] if thumb.position_known else nan))
        return super().update(state, hand, t)


def test_a_python_controller_reads_the_hand_in_a_simulated_run():
    controller = HandRecorder()
    result = graspbed.run(DEFAULT, controller=controller)
    assert result["summary"]["passed"], result["summary"]["expectations"]
    signals = result["signals"]
    rows = np.array(controller.rows, dtype=float)
    assert len(rows) == len(signals["time_s"])
    t, hand_time, stale, digits, q1, q2, dq1, current, stall, closed, fault, thumb_q1 = rows.T
    # Tick by tick what the loop logged as the hand state the controller saw.
    np.testing.assert_array_equal(t, signals["time_s"])
    np.testing.assert_array_equal(hand_time, signals["hand_time_s"])
    np.testing.assert_array_equal(stale, signals["hand_stale"])
    for mine, column in [(q1, "finger_q1"), (q2, "finger_q2"), (dq1, "finger_dq1"), (current, "finger_current_a"),
                         (thumb_q1, "thumb_q1")]:
        np.testing.assert_array_equal(mine, signals[column], err_msg=column)
    assert np.all(digits == 2)
    assert np.all(stall == 1.0)  # the realistic profile's stall current
    assert not closed.any() and not fault.any()
    # The hand's sample is the previous tick's (the realistic profile's 1 ms latency).
    np.testing.assert_allclose(t[5:] - hand_time[5:], 1e-3, atol=1e-9)
    # The index flexes onto the box, and the motor's current rises once it grips.
    assert q1[-1] - q1[0] > FLEXION_MIN_RAD and q2[-1] > q2[0]
    phase = signals["phase"]
    held = signals["time_s"] > signals["time_s"][-1] - 0.5
    assert np.all(phase[held] == "holding")
    assert np.mean(current[held]) > HELD_CURRENT_MIN_A
    assert np.mean(current[held]) > CURRENT_RISE_MIN * np.median(current[phase == "closing"])
    # The arrays: read-only views of the digits' joints (the index MCP and PIP, the thumb's flexion).
    index_position, index_velocity, thumb_position = controller.arrays
    assert index_position.shape == (2,) and index_velocity.shape == (2,) and thumb_position.shape == (1,)
    assert not index_position.flags.writeable
    with pytest.raises(ValueError):
        index_position[0] = 1.0


def test_the_example_logs_the_current_and_stops_at_the_closed_stop_on_nothing(tmp_path):
    scenario = tmp_path / "close_on_nothing.yaml"
    scenario.write_text(CLOSE_ON_NOTHING)
    signals = graspbed.run(str(scenario), controller=ThresholdGrip())["signals"]
    np.testing.assert_array_equal(signals["ctl_index_current_a"], signals["finger_current_a"])
    empty = signals["phase"] == "closed_empty"
    assert empty.any(), "never reached the closed stop"
    first = np.argmax(empty)
    assert signals["finger_at_closed_stop"][first] == 1.0 and signals["finger_at_closed_stop"][first - 1] == 0.0
    assert np.all(empty[first:]), "stays stopped until the next intent"
    np.testing.assert_array_equal(signals["grip_effort"][first:], 0.0)
    assert np.all(signals["grip_effort"][signals["phase"] == "closing"] == 0.3)
    assert signals["est_total_fn_n"].max() < 0.2  # nothing touched the fingertip


class ContactHold:
    """The original two-argument form: update(state, t), no hand."""

    def reset(self):
        self.intent, self.calls = "idle", []

    def set_intent(self, intent):
        self.intent = intent

    def update(self, state, t):
        self.calls.append((type(state).__name__, type(t).__name__))
        if self.intent != "close":
            return -0.5 if self.intent == "open" else 0.0
        return 0.4 if state.total_fn_n > 0.2 else 0.3


def test_a_two_argument_controller_still_works(short_grasp):
    controller = ContactHold()
    result = graspbed.run(short_grasp(0.5), controller=controller)
    summary = result["summary"]
    assert summary["completed"] and summary["passed"], summary["expectations"]
    assert summary["metrics"]["grasped"] and not summary["metrics"]["dropped"]
    assert len(controller.calls) == summary["counters"]["control_ticks"]
    assert set(controller.calls) == {("TactileState", "float")}
    np.testing.assert_array_equal(result["signals"]["grip_effort"][-10:], 0.4)


def _update_with(signature):
    """A controller whose update has `signature` (its parameters after self) and records its args."""
    namespace = {}
    exec("def update(self, %s):\n    self.args = args_of(locals())\n    return 0.0\n" % signature,
         {"args_of": lambda local: tuple(type(v).__name__ for k, v in local.items() if k != "self")}, namespace)
    return type("Signature", (), {"reset": lambda self: None, "set_intent": lambda self, intent: None,
                                  "update": namespace["update"]})


@pytest.mark.parametrize("signature, seen", [
    ("state, t", ("TactileState", "float")),
    ("state, t, verbose=False", ("TactileState", "float", "bool")),
    ("state, hand, t", ("TactileState", "HandState", "float")),
    ("state, hand, t, verbose=False", ("TactileState", "HandState", "float", "bool")),
    ("*args", ("tuple",)),
])
def test_the_form_called_is_read_from_the_signature(signature, seen, short_grasp):
    controller = _update_with(signature)()
    graspbed.run(short_grasp(0.05), controller=controller)
    assert controller.args == seen


def test_star_args_get_the_hand(short_grasp):
    class Forwarding(ThresholdGrip):
        def update(self, *args):
            self.count = len(args)
            return super().update(*args)

    controller = Forwarding()
    graspbed.run(short_grasp(0.05), controller=controller)
    assert controller.count == 3


@pytest.mark.parametrize("signature", ["state", "state, hand, t, extra"])
def test_an_update_that_takes_neither_form_is_refused(signature, short_grasp):
    with pytest.raises(graspbed.ConfigError, match=r"Python controller python:Signature.update\(" +
                       signature.replace(" ", r"\s*") + r"\): expected update\(state, t\) or update\(state, hand, t\)"):
        graspbed.run(short_grasp(0.05), controller=_update_with(signature))
