#!/usr/bin/env python3
"""Writes the figures of one still's caption, read from the signals.csv of the run that made it.

Usage: caption_figures.py PICTURE SIGNALS_CSV TIME_S COMMAND
Prints one Markdown table row: the picture, the control tick at or after TIME_S, the controller's
phase, the estimated grip and the true squeeze, how high the object is, and the units loaded (an
estimated Fn of at least 0.2 N) with their Fn. docs/img/regenerate.sh collects the rows in
docs/img/captions.md, which the captions in docs/ point to.
"""
import csv
import sys

LOADED_N = 0.2  # estimated normal force from which a unit counts as loaded [N]


def main() -> int:
    if len(sys.argv) != 5:
        print(__doc__, file=sys.stderr)
        return 2
    picture, signals_path, time_text, command = sys.argv[1:]
    at_s = float(time_text)
    with open(signals_path, newline="") as signals:
        reader = csv.DictReader(signals)
        row = next((r for r in reader if float(r["time_s"]) >= at_s - 1e-9), None)
    if row is None:
        print(f"caption_figures: {signals_path} ends before {at_s} s", file=sys.stderr)
        return 1
    units = sorted(int(key[len("fn_est_n_"):]) for key in row if key.startswith("fn_est_n_"))
    loaded = [f"{u} ({float(row[f'fn_est_n_{u}']):.2f})" for u in units
              if float(row[f"fn_est_n_{u}"]) >= LOADED_N]
    print(f"| [{picture}]({picture}) | {float(row['time_s']):.3f} | {row['phase']} "
          f"| {float(row['est_total_fn_n']):.2f} | {float(row['true_squeeze_n']):.2f} "
          f"| {1e3 * float(row['object_height_m']):.1f} | {', '.join(loaded) or 'none'} | `{command}` |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
