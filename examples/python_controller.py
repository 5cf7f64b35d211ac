#!/usr/bin/env python3
"""A grasp controller written in Python, run in graspbed's simulation.

The same logic as examples/cpp_controller (threshold_grip): close at a fixed effort until the
fingertip feels contact, then integrate the error between the sensed squeeze and a target into the
motor effort; hold with the brake when the tactile data cannot be trusted; open on request. From the
hand's own state it stops driving the motor when the index reached its closed stop without feeling
anything (the hand closed on nothing), and it logs the index's motor current.

    PYTHONPATH=build/python python3 examples/python_controller.py [scenarios/default.yaml]

(an installed graspbed: PYTHONPATH=<prefix>/lib/python3/dist-packages)
"""
import sys

import graspbed


class ThresholdGrip:
    """Force-regulating grip: see the module docstring. Parameters as in the C++ plugin."""

    # Optional: internal signals graspbed logs as signals.csv columns (ctl_grip_error_n,
    # ctl_index_current_a), one number per name from diagnostics() each tick.
    diagnostic_channels = ("grip_error_n", "index_current_a")

    def __init__(self, target_grip_n=3.0, approach_effort=0.3, contact_n=0.2, gain_per_n_s=0.3,
                 open_effort=0.5, min_valid_units=4):
        self.target_grip_n = target_grip_n
        self.approach_effort = approach_effort
        self.contact_n = contact_n
        self.gain_per_n_s = gain_per_n_s
        self.open_effort = open_effort
        self.min_valid_units = min_valid_units
        self.reset()

    def reset(self):
        self.intent = "idle"
        self.effort = 0.0
        self.last_t = None
        self.phase = "idle"
        self.grip_error_n = 0.0  # grip target minus the sensed squeeze while holding [N]
        self.index_current_a = 0.0  # the index's motor current [A]; nan when the hand does not report it
        self.closed_empty = False  # closed onto the stop without contact, since the last intent

    def set_intent(self, intent):
        self.intent = intent  # "idle" | "close" | "open"
        self.closed_empty = False

    def update(self, state, hand, t):
        """state: graspbed.TactileState, hand: graspbed.HandState (proprioception), t: time [s]."""
        dt = 0.0 if self.last_t is None else min(max(t - self.last_t, 0.0), 0.01)
        self.last_t = t
        index = hand.digits[0] if hand.digit_count > 0 else None
        self.index_current_a = index.motor_current_a if index and index.current_known else float("nan")
        if self.intent == "open":
            self.phase, self.effort = "opening", 0.0
            return -self.open_effort
        if self.intent == "idle":
            self.phase, self.effort = "idle", 0.0
            return 0.0
        if state.stale or state.valid_count < self.min_valid_units:
            # Data we cannot trust: keep the grip, never open.
            self.phase = "safe_hold"
            return graspbed.HandCommand(grip_effort=self.effort, brake=True)
        squeeze = state.total_fn_n
        if squeeze < self.contact_n and self.effort <= self.approach_effort:
            # Closed all the way without feeling anything: nothing to hold, stop pushing the stop.
            self.closed_empty = self.closed_empty or bool(index and index.stops_known and index.at_closed_stop)
            self.phase = "closed_empty" if self.closed_empty else "closing"
            self.effort = 0.0 if self.closed_empty else self.approach_effort
        else:
            self.phase = "holding"
            self.grip_error_n = self.target_grip_n - squeeze
            self.effort = min(max(self.effort + self.gain_per_n_s * self.grip_error_n * dt, 0.0), 1.0)
        return self.effort

    def diagnostics(self):
        return (self.grip_error_n, self.index_current_a)

    def telemetry(self):
        return {"phase": self.phase, "grip_target_n": self.target_grip_n, "safe_hold": self.phase == "safe_hold"}


def main():
    scenario = sys.argv[1] if len(sys.argv) > 1 else graspbed.scenario_path("default")
    result = graspbed.run(scenario, controller=ThresholdGrip())
    summary, signals = result["summary"], result["signals"]
    metrics = summary["metrics"]
    print("%s with %s: %s" % (summary["scenario"], summary["controller"], "passed" if summary["passed"] else "FAILED"))
    print("  dropped %s, max slip %.3f mm, peak grip %.2f N, real-time factor %.1f"
          % (metrics["dropped"], metrics["max_slip_mm"], metrics["peak_grip_n"], summary["real_time_factor"]))
    squeeze = signals["true_squeeze_n"]
    print("  %d ticks; true squeeze at the end %.2f N, grip error at the end %.2f N"
          % (len(squeeze), squeeze[-1], signals["ctl_grip_error_n"][-1]))
    return 0 if summary["passed"] else 1


if __name__ == "__main__":
    sys.exit(main())
