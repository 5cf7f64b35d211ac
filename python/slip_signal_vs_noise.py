#!/usr/bin/python3
"""The slip signal beside the noise floor, per sensor profile: can a profile carry slip at all?

Reads the runs a scorecard kept (`graspbed score --runs-out DIR`: DIR/<run>@<controller>/signals.csv
and config.yaml) of the reference controller, whose diagnostics log its vibration cue's statistic
(ctl_vibration_rms_n: RMS of the contact's high-passed shear per unit [N]). For every run it takes
that statistic on the ticks where the object truly slides (ground truth sliding_speed_mm_s above the
slip-event speed, 2 mm/s, while held) and on the ticks where it truly sticks (below 0.05 mm/s, held,
no slip event): the slip signal and the floor the cue must tell it from. The sticking ticks include
the grasp's own transients (seating, the lift's start, a shake), so their upper tail is not the
sensor's noise: the table gives the floor's median (the readout's noise through the statistic) and
its 90th percentile, the slip's median, and the slip median over the floor's 90th percentile. With
--plot it draws both per profile on one log axis (docs/sensor.md shows it).

Usage: /usr/bin/python3 python/slip_signal_vs_noise.py RUNS_DIR [--plot PNG]
"""

import argparse
import csv
import math
import pathlib
import sys

SLIP_SPEED_MM_S = 2.0  # MetricsConfig::slip_speed_m_s
STICK_SPEED_MM_S = 0.05
STATISTIC = "ctl_vibration_rms_n"


def profile_of(config_path):
    """`profile/sensitivities` of a run's config.yaml (its sensor section, read without a YAML library)."""
    profile, sensitivities, in_sensor = "ideal", "paper", False
    for line in config_path.read_text().splitlines():
        if not line.startswith(" ") and line.strip():
            in_sensor = line.startswith("sensor:")
        elif in_sensor and line.startswith("  profile:"):
            profile = line.split(":", 1)[1].strip()
        elif in_sensor and line.startswith("  sensitivities:"):
            sensitivities = line.split(":", 1)[1].strip()
    return f"{profile}/{sensitivities}"


def run_samples(signals_path):
    """(slip values, stick values) of the statistic over one run's held ticks."""
    slip, stick = [], []
    with open(signals_path, newline="") as handle:
        for row in csv.DictReader(handle):
            if STATISTIC not in row or row.get("holding") != "1":
                continue
            value, speed = float(row[STATISTIC]), float(row["sliding_speed_mm_s"])
            if math.isnan(value):
                continue
            if speed >= SLIP_SPEED_MM_S:
                slip.append(value)
            elif speed < STICK_SPEED_MM_S and row.get("slip_event") == "0":
                stick.append(value)
    return slip, stick


def quantile(values, q):
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))] if ordered else float("nan")


def collect(runs_dir):
    """profile -> (slip values, stick values), pooled over the reference's runs."""
    pooled = {}
    for run in sorted(pathlib.Path(runs_dir).iterdir()):
        signals, config = run / "signals.csv", run / "config.yaml"
        if not run.name.endswith("@grip_slip") or not signals.exists() or not config.exists():
            continue
        slip, stick = run_samples(signals)
        entry = pooled.setdefault(profile_of(config), ([], []))
        entry[0].extend(slip)
        entry[1].extend(stick)
    return pooled


def print_table(pooled):
    print(f"{'sensor':<22}{'slip ticks':>11}{'slip median [N]':>17}{'stick ticks':>12}"
          f"{'floor median [N]':>18}{'floor p90 [N]':>15}{'ratio':>8}")
    for name in sorted(pooled):
        slip, stick = pooled[name]
        signal, floor, floor_p90 = quantile(slip, 0.5), quantile(stick, 0.5), quantile(stick, 0.9)
        ratio = signal / floor_p90 if floor_p90 > 0 else float("nan")
        print(f"{name:<22}{len(slip):>11}{signal:>17.4g}{len(stick):>12}{floor:>18.4g}{floor_p90:>15.4g}"
              f"{ratio:>8.2f}")


def plot(pooled, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = sorted(pooled)
    figure, axes = plt.subplots(figsize=(9, 4.5), dpi=110)
    positions = range(len(names))
    stick = [pooled[n][1] or [float("nan")] for n in names]
    slip = [pooled[n][0] or [float("nan")] for n in names]
    noise_box = axes.boxplot(stick, positions=[p - 0.18 for p in positions], widths=0.3,
                             whis=(10, 90), showfliers=False, patch_artist=True)
    slip_box = axes.boxplot(slip, positions=[p + 0.18 for p in positions], widths=0.3,
                            whis=(10, 90), showfliers=False, patch_artist=True)
    for patch in noise_box["boxes"]:
        patch.set_facecolor("#bbbbbb")
    for patch in slip_box["boxes"]:
        patch.set_facecolor("#d95f02")
    axes.set_yscale("log")
    axes.set_xticks(list(positions), names, rotation=20, ha="right")
    axes.set_ylabel("vibration RMS per unit [N]")
    axes.set_title("The reference's vibration statistic (boxes: quartiles, whiskers: 10-90 %)")
    axes.legend([noise_box["boxes"][0], slip_box["boxes"][0]], ["object sticks (noise floor)",
                                                                "object slides >= 2 mm/s"])
    figure.tight_layout()
    figure.savefig(path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs_dir")
    parser.add_argument("--plot", help="write the figure to this PNG")
    args = parser.parse_args()
    pooled = collect(args.runs_dir)
    if not pooled:
        sys.exit(f"{args.runs_dir}: no grip_slip run with signals.csv and config.yaml (graspbed score --runs-out)")
    print_table(pooled)
    if args.plot:
        plot(pooled, args.plot)


if __name__ == "__main__":
    main()
