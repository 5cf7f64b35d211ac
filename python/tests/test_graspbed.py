"""The graspbed Python module against the real simulation (ctest runs this with the build tree's
package on PYTHONPATH, in the source tree)."""
import json
import os
import subprocess
import sys
import time

import numpy as np
import pytest

import graspbed

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "examples"))
from python_controller import ThresholdGrip  # noqa: E402

DEFAULT = "scenarios/default.yaml"
UNITS = 20  # the default layout


def test_a_python_controller_holds_the_default_object():
    result = graspbed.run(DEFAULT, controller=ThresholdGrip())
    assert set(result) == {"summary", "signals"}
    summary = result["summary"]
    assert summary["controller"] == "python:ThresholdGrip"
    assert summary["completed"] and summary["passed"], summary["expectations"]
    assert summary["metrics"]["grasped"] and not summary["metrics"]["dropped"]
    # The controller's telemetry reached the signals (its phases and target).
    phases = set(result["signals"]["phase"])
    assert {"closing", "holding"} <= phases
    np.testing.assert_array_equal(np.unique(result["signals"]["grip_target_n"][-10:]), [3.0])
    # Its diagnostic channel too: the grip error it integrates, settled near zero by the end.
    grip_error = result["signals"]["ctl_grip_error_n"]
    assert np.abs(grip_error).max() > 0.5
    assert abs(grip_error[-1]) < 0.3


def test_signals_are_numpy_columns_of_one_length(short_grasp):
    result = graspbed.run(short_grasp(0.5))
    signals = result["signals"]
    ticks = result["summary"]["counters"]["control_ticks"]
    for name in ["time_s", "true_squeeze_n", "object_z_m", "grip_effort"] + \
            ["fn_est_n_%d" % u for u in range(UNITS)]:
        assert name in signals, name
        assert isinstance(signals[name], np.ndarray) and signals[name].dtype == np.float64
        assert signals[name].shape == (ticks,), name
    assert np.all(np.diff(signals["time_s"]) > 0)
    assert signals["time_s"][-1] == pytest.approx(0.5, abs=2e-3)
    assert signals["intent"].shape == (ticks,)


def test_the_same_logic_in_python_and_in_the_cpp_plugin_grips_alike():
    plugin = os.environ.get("GRASPBED_TEST_PLUGIN")
    if not plugin:
        pytest.skip("GRASPBED_TEST_PLUGIN not set")
    py = graspbed.run(DEFAULT, controller=ThresholdGrip())["signals"]
    cpp = graspbed.run(DEFAULT, controller="plugin:" + plugin)["signals"]
    # Same arithmetic on the same state, tick by tick: the same efforts to rounding; the same hand
    # state read into the same diagnostic.
    np.testing.assert_allclose(py["grip_effort"], cpp["grip_effort"], atol=1e-9)
    np.testing.assert_array_equal(py["ctl_index_current_a"], cpp["ctl_index_current_a"])


def test_numpy_scalars_and_dicts_are_commands_too(short_grasp):
    class NumpyEffort(ThresholdGrip):
        def update(self, state, hand, t):
            effort = super().update(state, hand, t)
            if isinstance(effort, graspbed.HandCommand):
                return {"grip_effort": effort.grip_effort, "brake": effort.brake}
            return np.float32(effort)

    summary = graspbed.run(short_grasp(0.5), controller=NumpyEffort())["summary"]
    assert summary["metrics"]["grasped"] and not summary["metrics"]["dropped"]


def test_telemetry_reaches_the_signals(short_grasp):
    class Flags(ThresholdGrip):
        def telemetry(self):
            flagged = self.phase == "holding"
            return {"phase": self.phase, "slip_detected": flagged, "slip_cues": "mine" if flagged else ""}

    signals = graspbed.run(short_grasp(0.4), controller=Flags())["signals"]
    holding = signals["phase"] == "holding"
    assert holding.any()
    np.testing.assert_array_equal(signals["slip_cues"][holding], "mine")
    np.testing.assert_array_equal(signals["slip_flag"][holding], 1.0)
    np.testing.assert_array_equal(signals["slip_flag"][~holding], 0.0)


def test_diagnostic_channels_reach_the_signals(short_grasp):
    class Traced(ThresholdGrip):
        diagnostic_channels = ("sensed_fn_n", "units_in_contact")

        def update(self, state, hand, t):
            self.last = (state.total_fn_n, state.contact_count)
            return super().update(state, hand, t)

        def diagnostics(self):
            return self.last

    signals = graspbed.run(short_grasp(0.4), controller=Traced())["signals"]
    # What the controller saw, tick by tick, is what the loop logged from the same state.
    np.testing.assert_array_equal(signals["ctl_sensed_fn_n"], signals["est_total_fn_n"])
    assert signals["ctl_units_in_contact"].max() >= 1.0

    class Undeclared(ThresholdGrip):
        diagnostic_channels = None  # read as not declared (the example declares one)

    assert not any(name.startswith("ctl_") for name in graspbed.run(
        short_grasp(0.2), controller=Undeclared())["signals"])


@pytest.mark.parametrize("channels, values, message", [
    (("a_n",), lambda: (1.0, 2.0), r"diagnostics\(\): returned \(1.0, 2.0\): expected 1 numbers"),
    (("a_n",), lambda: ("x",), r"diagnostics\(\): a_n = 'x': not a number"),
    (("A n",), lambda: (1.0,), r"diagnostic channel 'A n': a name is lower-case letters"),
])
def test_bad_diagnostics_are_refused_naming_the_controller(channels, values, message, short_grasp):
    class Bad(ThresholdGrip):
        diagnostic_channels = channels

        def diagnostics(self):
            return values()

    with pytest.raises((graspbed.ControllerError, ValueError), match=message):
        graspbed.run(short_grasp(0.3), controller=Bad())


def test_the_state_is_read_only_and_its_arrays_are_views_of_the_units(short_grasp):
    seen = {}

    class Probe(ThresholdGrip):
        def update(self, state, hand, t):
            if state.contact_count > 0 and "fn" not in seen:
                fn = state.fn_n
                seen["fn"] = np.copy(fn)
                seen["shape"] = fn.shape
                seen["writeable"] = fn.flags.writeable
                seen["total"] = state.total_fn_n
                seen["same_object"] = state.fn_n is fn  # no new array per access
                with pytest.raises(ValueError):
                    fn[0] = 1.0
                with pytest.raises(AttributeError):
                    state.total_fn_n = 0.0
            return super().update(state, hand, t)

    graspbed.run(short_grasp(0.4), controller=Probe())
    assert seen["shape"] == (UNITS,)
    assert not seen["writeable"]
    assert seen["same_object"]
    valid_sum = seen["fn"].sum()
    assert seen["total"] == pytest.approx(valid_sum, rel=1e-6, abs=1e-9)


@pytest.mark.parametrize("bad, message", [
    ("close", r"update\(\): returned 'close' \(str\): expected a graspbed.HandCommand"),
    (float("nan"), r"grip_effort = nan: must be in \[-1, 1\]"),
    (2.0, r"grip_effort = 2.000000: must be in \[-1, 1\]"),
    ({"effort": 0.5}, r"returned a dict with key 'effort'"),
])
def test_a_bad_controller_return_ends_the_run_with_controller_error(bad, message, short_grasp):
    class Bad(ThresholdGrip):
        def update(self, state, hand, t):
            return bad

    with pytest.raises(graspbed.ControllerError, match=message):
        graspbed.run(short_grasp(0.2), controller=Bad())


def test_an_exception_in_update_names_the_controller_and_the_error(short_grasp):
    class Raises(ThresholdGrip):
        def update(self, state, hand, t):
            if t > 0.1:
                raise KeyError("lost my gains")
            return super().update(state, hand, t)

    with pytest.raises(graspbed.ControllerError, match=r"Python controller python:Raises.update\(\): KeyError"):
        graspbed.run(short_grasp(0.3), controller=Raises())


def test_a_controller_without_update_is_bad_input():
    class NoUpdate:
        def reset(self):
            pass

        def set_intent(self, intent):
            pass

    with pytest.raises(TypeError):
        graspbed.run(DEFAULT, controller=NoUpdate())  # not a controller object, not a factory of one
    with pytest.raises(graspbed.ConfigError, match="has no method update"):
        graspbed.run(DEFAULT, controller=NoUpdate)  # a class making one without update()


def test_bad_input_is_a_config_error_with_file_line_and_key():
    with pytest.raises(graspbed.ConfigError, match=r"scenarios/default.yaml: object.mass_kg = -1: must be >= 0.001"):
        graspbed.run(DEFAULT, overrides={"object.mass_kg": -1})
    with pytest.raises(ValueError, match="controller.name = nope: unknown name; valid names: constant_grip, grip_slip, learned_slip, open_loop"):
        graspbed.run(DEFAULT, controller="nope")


def test_a_suite_with_a_python_controller_class_on_two_threads():
    files = [DEFAULT, "scenarios/static_hold.yaml"]
    result = graspbed.suite(files, controller=ThresholdGrip, jobs=2)
    assert len(result["runs"]) == 2
    for run in result["runs"]:
        assert run["controller"] == "python:ThresholdGrip", run
    with pytest.raises(TypeError, match="pass its class"):
        graspbed.suite(files, controller=ThresholdGrip(), jobs=2)


def test_a_sweep_returns_one_row_per_run(tmp_path, short_grasp):
    spec = tmp_path / "sweep.yaml"
    spec.write_text("scenario: %s\nparameters:\n  object.mass_kg: [0.05, 0.1]\n" % short_grasp(0.3))
    result = graspbed.sweep(str(spec), controller=ThresholdGrip, jobs=1)
    assert result["runs"] == 2 and result["finished"] == 2 and result["completed"]
    assert [row["object.mass_kg"] for row in result["rows"]] == [0.05, 0.1]


def test_the_scorecard_scores_a_python_controller_beside_a_built_in():
    card = graspbed.score(["open_loop", ThresholdGrip], limit=1)
    assert [c["controller"] for c in card["controllers"]] == ["open_loop", "python:ThresholdGrip"]
    assert len(card["runs"]) == 2
    assert "python:ThresholdGrip" in card["table"]


def test_controller_parameters_and_version():
    names = [p["name"] for p in graspbed.controller_parameters("open_loop")]
    assert names == ["close_effort", "open_effort"]
    assert graspbed.CONTROLLER_API_VERSION >= 1
    assert os.path.isfile(graspbed.scenario_path("default"))


def test_a_python_controller_runs_on_the_hand_over_the_serial_link(tmp_path):
    """The same Python class on the serial backend, against `graspbed emulate` on a pseudo-terminal:
    the hardware path of `graspbed run --backend serial`, unchanged."""
    binary = os.environ.get("GRASPBED_BIN")
    if not binary:
        pytest.skip("GRASPBED_BIN not set")
    link = tmp_path / "hand"
    emulator = subprocess.Popen([binary, "emulate", "--link", str(link), DEFAULT, "--duration", "3.6", "--json"],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 30.0
        while not os.path.lexists(link):
            assert emulator.poll() is None, emulator.stderr.read()
            assert time.monotonic() < deadline, "no link from graspbed emulate"
            time.sleep(0.02)
        result = graspbed.run(DEFAULT, controller=ThresholdGrip, out_dir=str(tmp_path / "serial"),
                              overrides={"backend": "serial", "serial.port": str(link)}, prompt_actions=True)
        out, err = emulator.communicate(timeout=60.0)
    finally:
        if emulator.poll() is None:
            emulator.kill()
    summary = result["summary"]
    assert summary["backend"] == "serial" and summary["completed"], summary
    assert summary["controller"] == "python:ThresholdGrip"
    assert summary["bench"]["corrupt"] == 0
    assert [p["action"] for p in summary["bench"]["prompts"]] == ["lift"]  # announced, not refused
    signals = result["signals"]
    assert "true_squeeze_n" not in signals  # no ground truth over the wire
    assert {"closing", "holding"} <= set(signals["phase"])
    hand = json.loads(out)
    # Stale periods and dropped frames are the host falling behind for a moment: the controller
    # still commands the motor, so the grasp is judged. Only a tripped watchdog (the device stopped
    # the motor after 100 ms without a command) takes the hand from the controller: then the grasp
    # is not judged, and ctest shows the entry skipped (ctest_pytest.py) with the figures.
    bench = summary["bench"]
    behind = {"stale periods": bench["stale_periods"], "dropped frames": bench["dropped"],
              "watchdog trips": hand["watchdog_trips"]}
    print("serial link: %s" % ", ".join("%d %s" % (n, what) for what, n in behind.items()))
    if hand["watchdog_trips"]:
        pytest.skip("the device's watchdog stopped the motor (%s): the grasp is not judged" %
                    ", ".join("%d %s" % (n, what) for what, n in behind.items()))
    # It held the box at its 3 N target, as it does in simulation: the sensed grip over the last
    # 0.3 s, and the hand's own account of the object (the emulator's ground truth).
    held = signals["est_total_fn_n"][signals["time_s"] > signals["time_s"][-1] - 0.3]
    assert np.mean(held) == pytest.approx(3.0, rel=0.1)
    assert hand["metrics"]["grasped"] and not hand["metrics"]["dropped"], hand
