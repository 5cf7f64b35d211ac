"""graspbed from Python: run scenarios, suites and sweeps of the grasp testbed, with the built-in
controllers, C++ plugins ("plugin:libmine.so") or a controller written in Python.

    import graspbed
    result = graspbed.run("scenarios/default.yaml", controller=MyController())
    result["summary"]["passed"], result["signals"]["true_squeeze_n"]   # dict, numpy array

A Python controller is any object with

    reset()                        back to the initial state
    set_intent(intent)             "idle" | "close" | "open"; takes effect at the next update
    update(state, t) -> command    state: graspbed.TactileState (read-only, numpy views, valid during the
                                   call), t: time [s]; command: graspbed.HandCommand, a number (grip
                                   effort in [-1, 1], + closes) or a dict(grip_effort=, enable=, brake=)
    update(state, hand, t)         the same with the hand's proprioception, hand: graspbed.HandState
                                   (hand.digits[0] the index, [1] the thumb: joint_position and
                                   joint_velocity numpy views, motor_current_a, stop flags, each group
                                   with its *_known flag). Which form is called is read once from
                                   update's signature: three positional parameters without a default
                                   (or *args) get the hand, two do not
    telemetry() -> dict            optional: phase, grip_target_n, friction_estimate, slip_detected,
                                   slip_cues, slip_events, safe_hold (logged and scored like a C++
                                   controller's)
    set_grip_ceiling(newtons)      optional

The C++ loop calls update() every control tick (1 kHz by default). An exception in it, or a return
that is no command, ends the run with graspbed.ControllerError. docs/controllers.md has the contract.
"""
import json
import os
import tempfile

from ._graspbed import (CONTROLLER_API_VERSION, ConfigError, ControllerError, DigitState, HandCommand, HandState,
                        LearnedSlipCue,
                        TactileState, __version__, controller_names, controller_parameters, data_dir,
                        list_scenarios)

__all__ = ["run", "suite", "sweep", "score", "HandCommand", "TactileState", "HandState", "DigitState",
           "ControllerError", "ConfigError",
           "controller_names", "controller_parameters", "data_dir", "list_scenarios", "scenario_path",
           "CONTROLLER_API_VERSION", "__version__"]


def _yaml_value(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float, str)):
        return str(value)
    return json.dumps(value)  # lists and maps: JSON is YAML flow style


def _overrides(overrides, seed=None):
    """{key: value} or ["key=value", ...] -> ["key=value", ...] (the --set syntax)."""
    texts = []
    if overrides is None:
        pass
    elif isinstance(overrides, dict):
        texts = ["%s=%s" % (key, _yaml_value(value)) for key, value in overrides.items()]
    else:
        texts = [str(text) for text in overrides]
    if seed is not None:
        texts.append("seed=%d" % seed)
    return texts


def scenario_path(name):
    """Path of a shipped scenario by name ("default") in graspbed's data directory."""
    return os.path.join(data_dir(), "scenarios", name if name.endswith(".yaml") else name + ".yaml")


def run(scenario, controller=None, overrides=None, seed=None, out_dir=None, plots=False,
        prompt_actions=False, intent_fifo=None):
    """Runs one scenario file.

    controller: None (the file's), a name ("grip_slip", "plugin:path/libmine.so"), a Python controller
    object, or a class / function making one. overrides: {"object.mass_kg": 0.3} or ["key=value"], as
    `graspbed run --set`. out_dir: also write signals.csv, summary.json, config.yaml (and PNGs with
    plots=True) there. Returns {"summary": dict (summary.json), "signals": {column: numpy array}}.
    Raises graspbed.ConfigError (a ValueError) on bad input, graspbed.ControllerError when a Python
    controller fails.

    On the hand: overrides {"backend": "serial", "serial.port": "/dev/ttyACM0"} (or a `graspbed
    emulate` link) run the same loop over the serial link, as `graspbed run --backend serial`;
    prompt_actions=True announces the script's simulator-only actions (lift, pull, ...) on stderr
    for a person at the bench instead of refusing them, intent_fifo="PATH" takes live close / open /
    idle / quit lines from a FIFO (docs/hardware.md).
    """
    return _graspbed_run(str(scenario), _overrides(overrides, seed), controller, out_dir or "", plots,
                         prompt_actions, intent_fifo or "")


def suite(scenarios, controller=None, overrides=None, jobs=1, out_dir=None, plots=False):
    """Runs several scenarios (a directory or a list of files) on `jobs` threads.

    A Python controller must be given as its class (or a function making one) when jobs > 1: each run
    gets its own. Returns suite.json as a dict (one entry per run with its summary)."""
    if isinstance(scenarios, (str, os.PathLike)) and os.path.isdir(scenarios):
        files = list_scenarios(str(scenarios))
    elif isinstance(scenarios, (str, os.PathLike)):
        files = [str(scenarios)]
    else:
        files = [str(path) for path in scenarios]
    return _graspbed_suite(files, _overrides(overrides), controller, jobs, out_dir or "", plots)


def sweep(spec, controller=None, jobs=1, out_dir=None, shard="1/1"):
    """Runs a sweep spec (docs/scenarios.md, Sweeps). Writes results.csv / results.jsonl to out_dir (a
    temporary directory, removed afterwards, when None) and returns {"runs", "finished", "passed",
    "completed", "wall_s", "rows": [one dict per run]}."""
    if out_dir is not None:
        return _graspbed_sweep(str(spec), controller, jobs, str(out_dir), shard)
    with tempfile.TemporaryDirectory(prefix="graspbed-sweep-") as directory:
        return _graspbed_sweep(str(spec), controller, jobs, os.path.join(directory, "sweep"), shard)


def score(controllers=("grip_slip", "open_loop"), jobs=1, limit=0, set_dir=None, out_dir=None):
    """The scorecard (`graspbed score`): each controller over the versioned benchmark set.

    controllers: names ("grip_slip", "plugin:...") and Python controller classes (or factories; each
    run gets its own), side by side. limit > 0: only the first runs of the set. Returns scorecard.json
    as a dict plus "table", the printed comparison; out_dir also writes scorecard.csv/json/png."""
    return _graspbed_score(list(controllers), str(set_dir or ""), jobs, limit, str(out_dir or ""))


from ._graspbed import _run as _graspbed_run, _score as _graspbed_score  # noqa: E402
from ._graspbed import _suite as _graspbed_suite, _sweep as _graspbed_sweep  # noqa: E402
