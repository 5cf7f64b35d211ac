#!/usr/bin/python3
"""ctest testbed.slip_signal: python/slip_signal_vs_noise.py on a real scorecard's kept runs.

    slip_signal_test.py GRASPBED SOURCE_DIR

`graspbed score --runs-out` of the reference over the first runs of the shipped set (slip scenarios
among them), then the script: its table names each sensor profile of those runs with finite figures,
has slip ticks where the runs slid, and the figure is written. A directory without reference runs
is refused (exit non-zero, naming it). Needs Debian's python3-matplotlib.
"""

import math
import os
import pathlib
import subprocess
import sys
import tempfile


def check(condition, message):
    if not condition:
        sys.exit("FAIL: " + message)


def main():
    graspbed, source = sys.argv[1], pathlib.Path(sys.argv[2])
    script = source / "python" / "slip_signal_vs_noise.py"
    with tempfile.TemporaryDirectory() as tmp:
        runs = pathlib.Path(tmp) / "runs"
        score = subprocess.run([graspbed, "score", "--controller", "grip_slip", "--limit", "16", "-j", "2",
                                "--out", str(pathlib.Path(tmp) / "score"), "--runs-out", str(runs)],
                               capture_output=True, text=True)
        check(score.returncode in (0, 1), "score failed: " + score.stderr)
        png = pathlib.Path(tmp) / "signal.png"
        result = subprocess.run(["/usr/bin/python3", str(script), str(runs), "--plot", str(png)],
                                capture_output=True, text=True)
        check(result.returncode == 0, "script failed: " + result.stderr)
        rows = [line.split() for line in result.stdout.splitlines()[1:] if line.strip()]
        check(len(rows) >= 1, "no profile in the table:\n" + result.stdout)
        slid = 0
        for name, slip_ticks, slip_median, stick_ticks, noise, noise_p90, ratio in rows:
            check("/" in name, "profile name " + name)
            check(int(stick_ticks) > 100, name + ": too few sticking ticks " + stick_ticks)
            check(math.isfinite(float(noise)) and float(noise) > 0, name + ": noise floor " + noise)
            if int(slip_ticks) > 0:
                slid += 1
                check(math.isfinite(float(slip_median)), name + ": slip median " + slip_median)
        check(slid >= 1, "no profile with slip ticks in runs that include the slip scenarios:\n" + result.stdout)
        check(png.exists() and png.stat().st_size > 10000, "figure not written")
        empty = pathlib.Path(tmp) / "empty"
        empty.mkdir()
        refused = subprocess.run(["/usr/bin/python3", str(script), str(empty)], capture_output=True, text=True)
        check(refused.returncode != 0 and str(empty) in refused.stderr, "an empty directory was not refused")
    print("slip_signal: ok")


if __name__ == "__main__":
    main()
