#!/usr/bin/python3
"""ctest testbed.slip_dataset: a tiny slip dataset end to end (docs/training-slip-detector.md).

    slip_dataset_test.py GRASPBED SOURCE_DIR

1. `graspbed dataset scenarios/datasets/tiny.yaml` (20 runs: 10 draws x 2 profiles) writes ticks.npz and a
   complete manifest whose class counts add up to the ticks.
2. The labels of one run with gross slips equal what `graspbed run` of the same run (its overrides from
   the manifest) writes in signals.csv and summary.json: the inputs, the truth columns, gross slip
   exactly inside the summary's gross events, and "gross within 20 ms" from those.
3. python/train_slip_model.py trains on it in under a minute and beats the class prior on the test split;
   the same with the labels shuffled (the strawman) does not.
4. The C++ cue (`graspbed slip-model score`) reproduces the Python model's scores on the whole test split
   within 1e-6.
5. A model for another layout, or on another feature set, is refused with the file and what differs.
Needs Debian's python3-numpy and python3-sklearn.
"""

import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

SCORE_TOL = 1e-6
TRAIN_LIMIT_S = 60.0


def run(command, **kwargs):
    result = subprocess.run(command, capture_output=True, text=True, **kwargs)
    return result


def check(condition, message):
    if not condition:
        print("FAIL:", message)
        sys.exit(1)
    print("ok:", message)


def build_dataset(graspbed, source, out):
    result = run([graspbed, "dataset", os.path.join(source, "scenarios/datasets/tiny.yaml"), "--out", out, "-j", "2",
                  "--profiles", "divider_12bit/fea,bridge_24bit/paper"])
    check(result.returncode == 0, f"graspbed dataset exits 0 ({result.stderr.strip()[-300:]})")
    manifest = json.load(open(os.path.join(out, "manifest.json")))
    data = dict(np.load(os.path.join(out, "ticks.npz")))
    check(manifest["completed"] and manifest["format"] == "graspbed-slip-dataset" and manifest["version"] == 1,
          "the manifest says a complete graspbed-slip-dataset version 1")
    n = len(data["time_s"])
    counted = sum(sum(c["contact_state"].values()) for c in manifest["counts"].values())
    check(counted == n == manifest["ticks"], f"class counts add up to the {n} ticks")
    for split, index in (("train", 0), ("validation", 1), ("test", 2)):
        groups = {r["group"] for r in manifest["runs"] if r["split"] == split}
        check(len(groups) >= 1 and int((data["split"] == index).sum()) == manifest["counts"][split]["ticks"],
              f"split {split}: {len(groups)} run group(s), its ticks as counted")
    # The hand state the controller saw: one column per signals.csv hand column, the index's motor
    # current known on every tick of a simulated run and drawing current while something is held.
    hand, columns = data["hand"], manifest["hand_columns"]
    check(hand.shape == (n, len(columns)) and columns[0] == "hand_time_s", f"hand array {hand.shape}, {len(columns)} columns")
    current = hand[:, columns.index("finger_current_a")]
    held = data["holding"] == 1
    check(not np.isnan(current).any() and float(np.median(current[held])) > 0.02,
          "the index motor's current is known on every tick and flows while holding")
    by_group = {}
    for r in manifest["runs"]:
        by_group.setdefault(r["group"], set()).add(r["split"])
    check(all(len(s) == 1 for s in by_group.values()), "every run group (both profiles of a draw) in one split")
    return data, manifest


def read_signals(path):
    with open(path) as stream:
        rows = list(csv.reader(stream))
    header, body = rows[0], rows[1:]
    return {name: np.array([float(r[i]) if r[i] not in ("", "close", "open", "idle") else np.nan for r in body])
            for i, name in enumerate(header) if name not in ("intent", "phase", "slip_cues")}


def check_labels_against_a_run(graspbed, source, data, manifest, scratch):
    runs = [r for r in manifest["runs"] if r["gross_slip_events"] > 0]
    check(len(runs) > 0, "the tiny dataset has runs with gross slips")
    chosen = runs[0]
    spec = manifest["specs"][chosen["spec"]]
    command = [graspbed, "run", spec["scenario"], "--no-plots", "--out", os.path.join(scratch, "rerun")]
    for key, value in chosen["overrides"]:
        command += ["--set", f"{key}={value}"]
    result = run(command)
    check(result.returncode in (0, 1), f"graspbed run of run {chosen['run']} with its overrides ({result.stderr[-200:]})")
    signals = read_signals(os.path.join(scratch, "rerun", "signals.csv"))
    summary = json.load(open(os.path.join(scratch, "rerun", "summary.json")))
    mine = data["run"] == chosen["run"]
    check(int(mine.sum()) == chosen["ticks"] == len(signals["time_s"]), "the run has as many ticks as signals.csv rows")
    check(np.array_equal(data["time_s"][mine], signals["time_s"]), "time_s equals signals.csv's")
    units = manifest["layout"]["units"]
    fn = np.stack([signals[f"fn_est_n_{u}"] for u in range(units)], axis=1).astype(np.float32)
    check(np.array_equal(data["fn_n"][mine], fn), "fn_n is the estimate signals.csv logs (float32)")
    check(np.array_equal(data["slip_speed_mm_s"][mine], signals["sliding_speed_mm_s"].astype(np.float32)),
          "slip_speed_mm_s is signals.csv's sliding_speed_mm_s")
    check(np.array_equal(data["slip_distance_mm"][mine], signals["slip_distance_mm"].astype(np.float32)),
          "slip_distance_mm is signals.csv's")
    check(np.array_equal(data["holding"][mine], signals["holding"].astype(np.uint8)), "holding is signals.csv's")
    t = signals["time_s"]
    gross = np.zeros(len(t), dtype=bool)
    for event in summary["slip_events"]:
        if event["gross"]:
            gross |= (t >= event["onset_s"]) & (t <= event["end_s"])
    check(gross.any() and np.array_equal(data["contact_state"][mine] == 3, gross),
          f"gross slip exactly inside summary.json's gross events ({int(gross.sum())} ticks)")
    stick = (data["contact_state"][mine] == 1)
    check(np.all(signals["true_finger_fn_n"][stick] > 0.05) and np.all(signals["sliding_speed_mm_s"][stick] <= 0.5),
          "stick ticks: the finger touches, nothing slides above creep speed")
    within = np.array([np.any(gross[(t >= ti - 1e-9) & (t <= ti + 0.020 + 1e-9)]) for ti in t])
    check(np.array_equal(data["gross_within_20ms"][mine].astype(bool), within), "gross_within_20ms from those events")


def train(source, dataset, out, extra):
    started = time.time()
    result = run([sys.executable, os.path.join(source, "python/train_slip_model.py"), dataset, "--out", out,
                  "--report", out + ".report.json", "--test-scores", out + ".scores.npz", "--max-iter", "80"] + extra)
    elapsed = time.time() - started
    check(result.returncode == 0, f"training{' ' + ' '.join(extra) if extra else ''} exits 0 ({result.stderr[-300:]})")
    print(result.stdout)
    report = json.load(open(out + ".report.json"))["trees"]
    overall = [row for row in report["test"] if row["sensor"] == "all"][0]
    return overall, elapsed


def main(graspbed, source):
    scratch = tempfile.mkdtemp(prefix="slip_dataset_")
    try:
        return checks(graspbed, source, scratch)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def checks(graspbed, source, scratch):
    dataset = os.path.join(scratch, "ds")
    data, manifest = build_dataset(graspbed, source, dataset)
    check_labels_against_a_run(graspbed, source, data, manifest, scratch)

    model = os.path.join(scratch, "model.json")
    overall, elapsed = train(source, dataset, model, [])
    check(elapsed < TRAIN_LIMIT_S, f"trained in {elapsed:.1f} s (< {TRAIN_LIMIT_S:.0f} s)")
    prior, learned = overall["prior"], overall["learned_pr_auc"]
    check(0.0 < prior < 1.0 and learned is not None, f"the test split has both classes (prior {prior:.3f})")
    check(learned >= prior + 0.3, f"the learned PR-AUC {learned:.3f} beats the prior {prior:.3f} by 0.3 or more")
    shuffled, _ = train(source, dataset, os.path.join(scratch, "shuffled.json"), ["--shuffle-labels"])
    check(shuffled["learned_pr_auc"] < prior + 0.15 and shuffled["learned_pr_auc"] < learned - 0.2,
          f"the strawman on shuffled labels does not (PR-AUC {shuffled['learned_pr_auc']:.3f}, prior {prior:.3f})")

    scores = np.load(model + ".scores.npz")
    features = os.path.join(scratch, "test_features.npy")
    np.save(features, scores["features"])
    result = run([graspbed, "slip-model", "score", model, features, "--out", os.path.join(scratch, "cpp.npy")])
    check(result.returncode == 0, f"graspbed slip-model score exits 0 ({result.stderr.strip()})")
    cpp = np.load(os.path.join(scratch, "cpp.npy"))
    worst = float(np.max(np.abs(cpp - scores["scores"])))
    check(len(cpp) == len(scores["scores"]) > 0 and worst <= SCORE_TOL,
          f"the C++ cue reproduces Python's {len(cpp)} test scores (worst {worst:.2e} <= 1e-6)")

    document = json.load(open(model))
    document["layout"] = {"name": "paper_3x3", "units": 9, "columns": 3}
    other = os.path.join(scratch, "paper_3x3.json")
    json.dump(document, open(other, "w"))
    result = run([graspbed, "slip-model", "check", other])
    check(result.returncode == 2 and f"{other}: layout.units = 9: the model was trained for 9 units (layout "
          "paper_3x3), this sensor has 20 (layout default_20)" in result.stderr,
          f"a model for another layout is refused: {result.stderr.strip()}")
    document = json.load(open(model))
    document["features"]["set"] = "tactile_v0"
    json.dump(document, open(other, "w"))
    result = run([graspbed, "slip-model", "check", other])
    check(result.returncode == 2 and "features.set = tactile_v0" in result.stderr,
          f"a model on another feature set is refused: {result.stderr.strip()}")
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: slip_dataset_test.py GRASPBED SOURCE_DIR")
    sys.exit(main(sys.argv[1], sys.argv[2]))
