#!/usr/bin/env python3
"""ctest testbed.compare_run_outputs: the before/after check of run outputs
(tests/testbed/compare_run_outputs.py) on real runs. Two runs of two scenarios made twice compare the
same; it refuses what cannot be compared (a folder missing, a side without runs) and names each
difference (a run on one side only, a file on one side only, a changed byte, a changed metric) while
ignoring the wall-clock fields.

  compare_run_outputs_test.py GRASPBED_BINARY SOURCE_DIR
"""
import json
import pathlib
import shutil
import subprocess
import sys
import tempfile

BINARY, SOURCE = sys.argv[1], pathlib.Path(sys.argv[2])
SCRIPT = SOURCE / "tests" / "testbed" / "compare_run_outputs.py"
# Two short runs of different scenarios: enough to have a hold and every output file.
RUNS = {"default": "default.yaml", "wide_box": "wide_box.yaml"}
failures = []


def make_runs(root):
    for name, scenario in RUNS.items():
        subprocess.run([BINARY, "run", str(SOURCE / "scenarios" / scenario), "--out", str(root / name),
                        "--no-plots", "--set", "duration_s=1.0"], check=False, stdout=subprocess.DEVNULL)
        if not (root / name / "summary.json").is_file():
            sys.exit("graspbed run %s wrote no summary.json" % scenario)


def compare(before, after):
    result = subprocess.run([sys.executable, str(SCRIPT), str(before), str(after)], capture_output=True, text=True)
    return result.returncode, result.stdout + result.stderr


def expect(case, before, after, code, *lines):
    """The script's exit code is `code` and its output holds each of `lines`."""
    got, output = compare(before, after)
    missing = [line for line in lines if line not in output]
    verdict = "ok" if got == code and not missing else "FAILED"
    print("%-6s %-44s exit %d (expected %d)%s" % (verdict, case, got, code,
                                                  "; missing: %s" % missing if missing else ""))
    if verdict != "ok":
        failures.append(case)
        print("       " + output.strip().replace("\n", "\n       "))


with tempfile.TemporaryDirectory() as scratch:
    work = pathlib.Path(scratch)
    before, after = work / "before", work / "after"
    make_runs(before)
    make_runs(after)
    expect("the same runs made twice", before, after, 0, "compared 2 runs (8 files): all the same")
    expect("both folders absent", work / "none1", work / "none2", 2, "no such folder")
    (work / "empty").mkdir()
    expect("the before folder empty", work / "empty", after, 2, "no runs in it")
    expect("the after folder empty", before, work / "empty", 2, "no runs in it")

    shutil.copytree(after / "default", after / "extra")
    expect("an extra run after", before, after, 1, "only after: extra")
    shutil.rmtree(after / "extra")

    (after / "wide_box" / "config.yaml").rename(work / "config.yaml")
    expect("a file on one side only", before, after, 1, "only before: wide_box/config.yaml")
    (work / "config.yaml").rename(after / "wide_box" / "config.yaml")

    signals = after / "default" / "signals.csv"
    original = signals.read_bytes()
    signals.write_bytes(original[:-2] + bytes([original[-2] ^ 1]) + original[-1:])
    expect("one byte of signals.csv changed", before, after, 1, "differs: default/signals.csv")
    signals.write_bytes(original)

    summary_path = after / "wide_box" / "summary.json"
    summary_text = summary_path.read_text()
    summary = json.loads(summary_text)
    summary["real_time_factor"] = summary.get("real_time_factor", 1.0) * 3.0 + 1.0
    summary["metrics"]["wall_s"] = summary["metrics"].get("wall_s", 1.0) * 3.0 + 1.0
    summary_path.write_text(json.dumps(summary))
    expect("only the wall-clock fields changed", before, after, 0, "all the same")
    summary["metrics"]["max_slip_mm"] = summary["metrics"].get("max_slip_mm", 0.0) + 0.001
    summary_path.write_text(json.dumps(summary))
    expect("a metric changed", before, after, 1, "differs: wide_box/summary.json")
    summary_path.write_text(summary_text)
    expect("restored", before, after, 0, "all the same")

print("%d cases failed" % len(failures) if failures else "every case as expected")
sys.exit(1 if failures else 0)
