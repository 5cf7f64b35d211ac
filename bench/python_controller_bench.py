#!/usr/bin/env python3
"""Python controller vs the same logic in C++: per-tick cost and the real-time factor of a scenario.

    PYTHONPATH=build/python python3 bench/python_controller_bench.py build/tests/plugin/plugins/libthreshold_grip.so

Per tick: the controller's Update called from C++ (GIL released, as in a run) on a 20-unit state in
contact, averaged over many ticks; for Python that includes taking the GIL, the state copy, the call
into Python, reading back the command and telemetry. Real-time factor: simulated seconds per wall
second of the whole default scenario (physics, sensor model, readout, controller), best of five.
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples"))

import graspbed  # noqa: E402
from graspbed import _graspbed  # noqa: E402
from python_controller import ThresholdGrip  # noqa: E402


def per_tick_ns(controller, ticks=200000, repeats=5):
    return min(_graspbed._time_controller_update(controller, ticks) for _ in range(repeats))


def real_time_factor(scenario, controller, repeats=5):
    best = 0.0
    for _ in range(repeats):
        controller_arg = controller() if callable(controller) else controller
        summary = graspbed.run(scenario, controller=controller_arg)["summary"]
        if not summary["passed"]:
            raise SystemExit("%s did not pass with %s" % (scenario, summary["controller"]))
        best = max(best, summary["real_time_factor"])
    return best


def main():
    if len(sys.argv) < 2:
        raise SystemExit(__doc__)
    plugin = "plugin:" + os.path.abspath(sys.argv[1])
    scenario = sys.argv[2] if len(sys.argv) > 2 else graspbed.scenario_path("default")
    cpp_ns = per_tick_ns(plugin)
    py_ns = per_tick_ns(ThresholdGrip(), ticks=20000)
    print("controller Update per tick (threshold_grip logic, 20 units):")
    print("  C++ plugin      %9.1f ns" % cpp_ns)
    print("  Python class    %9.1f ns  (%.0fx the C++)" % (py_ns, py_ns / cpp_ns))
    print("real-time factor of %s (best of 5):" % os.path.basename(scenario))
    for label, controller in [("grip_slip (built-in)", "grip_slip"), ("threshold_grip C++ plugin", plugin),
                              ("threshold_grip Python", ThresholdGrip)]:
        print("  %-27s %6.1f" % (label, real_time_factor(scenario, controller)))


if __name__ == "__main__":
    main()
