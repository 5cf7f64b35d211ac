#!/usr/bin/env python3
"""Compares two trees of run outputs, e.g. `graspbed suite scenarios --out BEFORE` before a change to
the run path and `--out AFTER` after it.

A run is a folder holding summary.json. Both trees must hold the same runs (one or more); in each
run, every file of signals.csv, states.csv and config.yaml that either side has must be on both and
equal byte for byte, and summary.json must be equal less its wall-clock fields (real_time_factor,
metrics.wall_s).

  tests/testbed/compare_run_outputs.py BEFORE_DIR AFTER_DIR

Exit 0 when every run is the same, 1 when any file differs or is on one side only (each named),
2 when the input cannot be compared (a folder missing, or either side without runs).
"""
import json
import pathlib
import sys

COMPARED_BYTE_FOR_BYTE = ("signals.csv", "states.csv", "config.yaml")
WALL_CLOCK_FIELDS = (("real_time_factor",), ("metrics", "wall_s"))


def refuse(reason):
    print("compare_run_outputs: " + reason, file=sys.stderr)
    sys.exit(2)


def runs_in(root):
    """The run folders below `root` (one level), by name; exits 2 when there is none."""
    if not root.is_dir():
        refuse("%s: no such folder" % root)
    runs = {entry.name: entry for entry in root.iterdir() if (entry / "summary.json").is_file()}
    if not runs:
        refuse("%s: no runs in it (no folder with a summary.json)" % root)
    return runs


def summary_without_wall_clock(path):
    try:
        summary = json.loads(path.read_text())
    except (OSError, ValueError) as error:
        return "unreadable: %s" % error
    for field_path in WALL_CLOCK_FIELDS:
        holder = summary
        for key in field_path[:-1]:
            holder = holder.get(key, {}) if isinstance(holder, dict) else {}
        if isinstance(holder, dict):
            holder.pop(field_path[-1], None)
    return summary


def differences(name, before, after):
    """One line per difference between two runs of the same name."""
    found = []
    for file in COMPARED_BYTE_FOR_BYTE:
        a, b = before / file, after / file
        if a.exists() != b.exists():
            found.append("only %s: %s/%s" % ("before" if a.exists() else "after", name, file))
        elif a.exists() and a.read_bytes() != b.read_bytes():
            found.append("differs: %s/%s" % (name, file))
    if summary_without_wall_clock(before / "summary.json") != summary_without_wall_clock(after / "summary.json"):
        found.append("differs: %s/summary.json" % name)
    return found


def main(argv):
    if len(argv) != 3:
        refuse("usage: compare_run_outputs.py BEFORE_DIR AFTER_DIR")
    before, after = runs_in(pathlib.Path(argv[1])), runs_in(pathlib.Path(argv[2]))
    lines = ["only before: %s" % name for name in sorted(before.keys() - after.keys())]
    lines += ["only after: %s" % name for name in sorted(after.keys() - before.keys())]
    files = 0
    for name in sorted(before.keys() & after.keys()):
        lines += differences(name, before[name], after[name])
        files += 1 + sum((before[name] / file).exists() for file in COMPARED_BYTE_FOR_BYTE)
    for line in lines:
        print(line)
    common = len(before.keys() & after.keys())
    print("compared %d runs (%d files): %s" % (common, files, "differences above" if lines else "all the same"))
    return 1 if lines else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
