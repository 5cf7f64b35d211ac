#!/usr/bin/python3
"""Train a slip detector on a `graspbed dataset` and export it for the C++ learned cue.

    /usr/bin/python3 python/train_slip_model.py out/dataset --out out/slip_model.json --plots out/slip_plots

Reads DIR/ticks.npz and DIR/manifest.json (one or more shards of one dataset), trains on the train
split's held ticks, picks the flag threshold on the validation split and prints, on the test split
and per sensor (profile/sensitivities): the PR-AUC (average precision) of the per-tick label
(default "gross slip within 20 ms") for the learned model and for the reference's hand-tuned cues
(their continuous statistic, and their binary flag, on the ticks of runs that logged them), and the
event-level figures (gross slips flagged within 50 ms, latency, false flags per lift). Writes the
model file (format graspbed-slip-model 1, docs/training-slip-detector.md) with check rows the C++
loader re-evaluates. Needs Debian's python3-numpy and python3-sklearn (python3-matplotlib for
--plots).
"""

import argparse
import json
import os
import sys
import time

import numpy as np

MODEL_FORMAT = "graspbed-slip-model"
MODEL_VERSION = 1
SPLITS = {"train": 0, "validation": 1, "test": 2}
EVENT_WINDOW_S = 0.05  # a flag up to 50 ms before a gross slip's onset detects it (metrics' early window)
CHECK_ROWS = 64


def load_dataset(dirs):
    """The shards' arrays concatenated, and the first manifest (all must be of one dataset)."""
    parts, manifests = [], []
    for directory in dirs:
        with open(os.path.join(directory, "manifest.json")) as stream:
            manifest = json.load(stream)
        if not manifest.get("completed"):
            sys.exit(f"{directory}: the dataset is incomplete (interrupted or still running)")
        manifests.append(manifest)
        with np.load(os.path.join(directory, "ticks.npz")) as archive:
            parts.append({name: archive[name] for name in archive.files})
    first = manifests[0]
    for directory, manifest in zip(dirs, manifests):
        for key in ("feature_set", "layout", "tick_period_s", "sensors", "horizons_ms"):
            if manifest[key] != first[key]:
                sys.exit(f"{directory}: {key} = {manifest[key]} differs from {dirs[0]}'s {first[key]}")
    data = {name: np.concatenate([part[name] for part in parts]) for name in parts[0]}
    return data, first


def event_figures(run, time_s, gross, onset, score, threshold, held):
    """Gross slips flagged within 50 ms (early flags count), latency p50/p95 [ms], false flags per lift.

    An event is a maximal stretch of gross-slip ticks of one run; its onset the first. A false flag is a
    rising edge of score >= threshold on a held tick with no gross slip within 50 ms either side."""
    flag = (score >= threshold) & held
    detected, latencies, false_flags = 0, [], 0
    runs = np.unique(run)
    events = 0
    for r in runs:
        idx = np.flatnonzero(run == r)
        t, g, f = time_s[idx], gross[idx], flag[idx]
        starts = np.flatnonzero(g & ~np.concatenate(([False], g[:-1])))
        for s in starts:
            events += 1
            window = (t >= t[s] - EVENT_WINDOW_S) & (t <= t[s] + EVENT_WINDOW_S) & f
            if window.any():
                detected += 1
                latencies.append(max(0.0, t[np.flatnonzero(window)[0]] - t[s]) * 1e3)
        rises = np.flatnonzero(f & ~np.concatenate(([False], f[:-1])))
        gross_times = t[g]
        for i in rises:
            if gross_times.size == 0 or np.min(np.abs(gross_times - t[i])) > EVENT_WINDOW_S:
                false_flags += 1
    lifts = len(runs)
    return {
        "gross_events": events,
        "detected": detected,
        "detected_pct": 100.0 * detected / events if events else None,
        "latency_p50_ms": float(np.percentile(latencies, 50)) if latencies else None,
        "latency_p95_ms": float(np.percentile(latencies, 95)) if latencies else None,
        "false_flags": false_flags,
        "false_flags_per_lift": false_flags / lifts if lifts else None,
    }


def pr_auc(y, score):
    from sklearn.metrics import average_precision_score
    if y.sum() == 0 or y.sum() == len(y):
        return None
    return float(average_precision_score(y, score))


def train_trees(x, y, xv, yv, args):
    """Gradient-boosted trees; the number of trees chosen on the validation split (by run group)."""
    from sklearn.ensemble import HistGradientBoostingClassifier
    from sklearn.metrics import log_loss
    model = HistGradientBoostingClassifier(
        max_iter=args.max_iter, learning_rate=0.1, max_leaf_nodes=args.max_leaf_nodes, min_samples_leaf=50,
        l2_regularization=1.0, early_stopping=False, random_state=args.seed)
    model.fit(x, y)
    if len(yv) and 0 < yv.sum() < len(yv):
        losses = [log_loss(yv, p[:, 1], labels=[0, 1]) for p in model.staged_predict_proba(xv)]
        best = int(np.argmin(losses)) + 1
        if best < model.n_iter_:
            model.set_params(max_iter=best)
            model.fit(x, y)
    return model


def train_logistic(x, y):
    from sklearn.linear_model import LogisticRegression
    mean, scale = x.mean(axis=0), x.std(axis=0)
    scale[scale <= 0] = 1.0
    model = LogisticRegression(max_iter=500)
    model.fit((x - mean) / scale, y)
    return model, mean, scale


def export_trees(model):
    trees = []
    for (predictor,) in model._predictors:
        nodes = predictor.nodes
        leaf = nodes["is_leaf"].astype(bool)
        trees.append({
            "feature": [int(-1 if l else f) for f, l in zip(nodes["feature_idx"], leaf)],
            "threshold": [float(v) for v in nodes["num_threshold"]],
            "left": [int(v) for v in nodes["left"]],
            "right": [int(v) for v in nodes["right"]],
            "missing_left": [int(v) for v in nodes["missing_go_to_left"]],
            "value": [float(v) for v in nodes["value"]],
        })
    return {"kind": "trees", "baseline": float(np.ravel(model._baseline_prediction)[0]), "trees": trees}


def score_of(kind, model, x):
    if kind == "trees":
        return model.predict_proba(x.astype(np.float64))[:, 1]
    fitted, mean, scale = model
    return fitted.predict_proba((x.astype(np.float64) - mean) / scale)[:, 1]


def choose_threshold(score, y, data, mask, rule, target_pct):
    """The flag threshold, on the validation split's held ticks. rule "f1": the threshold of the best
    per-tick F1 (a flag that is right when up and up when it should be; the default: in closed loop
    every false tick is grip charged to the efficiency). rule "recall": the highest threshold that
    still flags target_pct of the gross slips within 50 ms (one hard event can drive it near 0)."""
    if rule == "f1":
        from sklearn.metrics import precision_recall_curve
        if not 0 < y.sum() < len(y):
            return 0.5
        precision, recall, thresholds = precision_recall_curve(y, score)
        f1 = 2 * precision * recall / np.maximum(precision + recall, 1e-12)
        return float(thresholds[int(np.argmax(f1[:-1]))])
    gross = data["contact_state"][mask] == 3
    if not gross.any():
        return 0.5
    for threshold in np.unique(np.round(np.quantile(score, np.linspace(0.5, 0.9999, 200)), 6))[::-1]:
        figures = event_figures(data["run"][mask], data["time_s"][mask], gross, None, score, threshold,
                                data["holding"][mask].astype(bool))
        if figures["detected_pct"] is not None and figures["detected_pct"] >= target_pct:
            return float(threshold)
    return float(np.quantile(score, 0.5))


def evaluate(kind, model, data, manifest, label, threshold):
    """Per sensor on the test split's held ticks: PR-AUC and event figures of the learned model and of
    the hand-tuned cues, both replayed on every tick (handtuned_replayed_*) and as the reference ran
    them on its own runs (handtuned_score, controller_slip_flag; grip_slip runs only)."""
    test = (data["split"] == SPLITS["test"]) & (data["holding"] == 1)
    y = data[label].astype(bool)
    score = np.zeros(len(y))
    score[test] = score_of(kind, model, data["features"][test])
    gross_all = data["contact_state"] == 3
    rows = []
    for index, sensor in enumerate(manifest["sensors"] + ["all"]):
        mask = test & ((data["sensor"] == index) if sensor != "all" else True)
        if not mask.any():
            continue
        as_run = mask & ~np.isnan(data["handtuned_score"])

        def events(m, s, threshold):
            return event_figures(data["run"][m], data["time_s"][m], gross_all[m], None, s[m], threshold,
                                 np.ones(int(m.sum()), dtype=bool))

        row = {"sensor": sensor, "ticks": int(mask.sum()), "prior": float(y[mask].mean()),
               "learned_pr_auc": pr_auc(y[mask], score[mask]),
               "handtuned_pr_auc": pr_auc(y[mask], data["handtuned_replayed_score"][mask]),
               "handtuned_flag_pr_auc": pr_auc(y[mask], data["handtuned_replayed_flag"][mask]),
               "learned_events": events(mask, score, threshold),
               "handtuned_events": events(mask, data["handtuned_replayed_flag"].astype(float), 0.5),
               "as_run_ticks": int(as_run.sum())}
        if as_run.any():
            row["as_run"] = {"learned_pr_auc": pr_auc(y[as_run], score[as_run]),
                             "handtuned_pr_auc": pr_auc(y[as_run], data["handtuned_score"][as_run]),
                             "handtuned_flag_pr_auc": pr_auc(y[as_run], data["controller_slip_flag"][as_run]),
                             "handtuned_events": events(as_run, data["controller_slip_flag"].astype(float), 0.5)}
        rows.append(row)
    return rows, score


def check_rows(score, data, label, rng):
    """Up to CHECK_ROWS test rows, half of them positives, with the trainer's scores."""
    test = np.flatnonzero((data["split"] == SPLITS["test"]) & (data["holding"] == 1))
    positives = test[data[label][test] == 1]
    negatives = test[data[label][test] == 0]
    pick = np.concatenate([rng.choice(positives, min(len(positives), CHECK_ROWS // 2), replace=False),
                           rng.choice(negatives, min(len(negatives), CHECK_ROWS // 2), replace=False)])
    return pick


def fmt(value, pattern="{:.3f}"):
    return "-" if value is None else pattern.format(value)


def flagged(ev):
    return "-" if ev["detected_pct"] is None else f"{ev['detected_pct']:.1f}% ({ev['detected']}/{ev['gross_events']})"


def print_table(rows, label, threshold):
    print(f"test split, held ticks; label {label}; learned flag at score >= {threshold:.4g}; hand-tuned: the "
          "reference's cues replayed on the same ticks (statistic / flag)")
    print(f"  {'sensor':20s} {'ticks':>7s} {'prior':>6s} | {'PR-AUC':>6s} {'gross<=50ms':>13s} {'p95ms':>6s}"
          f" {'false/lift':>10s} | {'PR-AUC':>6s} {'(flag)':>6s} {'gross<=50ms':>13s} {'p95ms':>6s} {'false/lift':>10s}")
    print(f"  {'':20s} {'':>7s} {'':>6s} | {'learned':^41s} | {'hand-tuned (replayed)':^48s}")
    for row in rows:
        ev, hv = row["learned_events"], row["handtuned_events"]
        print(f"  {row['sensor']:20s} {row['ticks']:7d} {row['prior']:6.3f} | {fmt(row['learned_pr_auc']):>6s}"
              f" {flagged(ev):>13s} {fmt(ev['latency_p95_ms'], '{:.1f}'):>6s} {fmt(ev['false_flags_per_lift'], '{:.2f}'):>10s}"
              f" | {fmt(row['handtuned_pr_auc']):>6s} {fmt(row['handtuned_flag_pr_auc']):>6s} {flagged(hv):>13s}"
              f" {fmt(hv['latency_p95_ms'], '{:.1f}'):>6s} {fmt(hv['false_flags_per_lift'], '{:.2f}'):>10s}")
    print("  as the reference ran them (its own runs of the test split only):")
    for row in rows:
        if "as_run" in row:
            a = row["as_run"]
            print(f"  {row['sensor']:20s} {row['as_run_ticks']:7d} ticks: learned {fmt(a['learned_pr_auc'])}, hand-tuned"
                  f" {fmt(a['handtuned_pr_auc'])} (flag {fmt(a['handtuned_flag_pr_auc'])}), flagged"
                  f" {flagged(a['handtuned_events'])}, false/lift {fmt(a['handtuned_events']['false_flags_per_lift'], '{:.2f}')}")


def write_plots(directory, data, manifest, score, label):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from sklearn.metrics import precision_recall_curve
    os.makedirs(directory, exist_ok=True)
    test = (data["split"] == SPLITS["test"]) & (data["holding"] == 1)
    y = data[label].astype(bool)
    sensors = manifest["sensors"]
    columns = min(3, len(sensors))
    rows_n = (len(sensors) + columns - 1) // columns
    figure, axes = plt.subplots(rows_n, columns, figsize=(4.6 * columns, 4.0 * rows_n), squeeze=False)
    for index, (sensor, axis) in enumerate(zip(sensors, axes.ravel())):
        mask = test & (data["sensor"] == index)
        for name, m, s, style in (("learned", mask, score, "-"),
                                  ("hand-tuned cues (replayed)", mask, data["handtuned_replayed_score"], "--")):
            if m.any() and 0 < y[m].sum() < m.sum():
                precision, recall, _ = precision_recall_curve(y[m], s[m])
                axis.plot(recall, precision, style, label=f"{name} (AP {pr_auc(y[m], s[m]):.2f})")
        if mask.any():
            axis.axhline(y[mask].mean(), color="grey", lw=0.8, label="prior")
        axis.set_title(sensor, fontsize=10)
        axis.set_xlabel("recall")
        axis.set_ylabel("precision")
        axis.set_xlim(0, 1)
        axis.set_ylim(0, 1.02)
        axis.legend(fontsize=7, loc="upper right")
    figure.suptitle(f"test split, held ticks: {label}")
    figure.tight_layout()
    path = os.path.join(directory, "pr_curves.png")
    figure.savefig(path, dpi=90)
    print(f"PR curves -> {path}")


def parse_args(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("datasets", nargs="+", help="dataset directories (shards of one dataset)")
    parser.add_argument("--out", default="slip_model.json", help="model file to write")
    parser.add_argument("--label", default="gross_within_20ms", help="per-tick label to learn")
    parser.add_argument("--model", choices=["trees", "logistic"], default="trees")
    parser.add_argument("--compare", action="store_true", help="also train the other kind and print both PR-AUCs")
    parser.add_argument("--max-iter", type=int, default=150)
    parser.add_argument("--max-leaf-nodes", type=int, default=15)
    parser.add_argument("--max-train-ticks", type=int, default=800000)
    parser.add_argument("--threshold-rule", choices=["f1", "recall"], default="f1",
                        help="flag threshold: best per-tick F1 on the validation split, or --target-recall")
    parser.add_argument("--target-recall", type=float, default=97.0,
                        help="rule recall: %% of the validation split's gross slips the threshold must flag within 50 ms")
    parser.add_argument("--shuffle-labels", action="store_true",
                        help="strawman: train on labels permuted across ticks (must fall to the prior)")
    parser.add_argument("--plots", default="", help="directory for pr_curves.png")
    parser.add_argument("--report", default="", help="write the figures as JSON here")
    parser.add_argument("--test-scores", default="",
                        help="write the test split's held ticks' features and this model's scores (.npz) here")
    parser.add_argument("--seed", type=int, default=1)
    return parser.parse_args(argv)


def main(argv):
    args = parse_args(argv)
    started = time.time()
    data, manifest = load_dataset(args.datasets)
    names = [f["name"] for f in manifest["features"]]
    if args.label not in data:
        sys.exit(f"--label {args.label}: the dataset has no such array")
    rng = np.random.default_rng(args.seed)
    held = data["holding"] == 1
    train = np.flatnonzero((data["split"] == SPLITS["train"]) & held)
    if len(train) > args.max_train_ticks:
        train = np.sort(rng.choice(train, args.max_train_ticks, replace=False))
    validation = (data["split"] == SPLITS["validation"]) & held
    x, y = data["features"][train].astype(np.float64), data[args.label][train].astype(int)
    if args.shuffle_labels:
        y = rng.permutation(y)
    xv, yv = data["features"][validation].astype(np.float64), data[args.label][validation].astype(int)
    print(f"{len(data['time_s'])} ticks, {len(manifest['runs'])} runs; training on {len(train)} held ticks "
          f"({y.mean():.4f} positive), validation {int(validation.sum())}")
    kinds = [args.model] + ([k for k in ("trees", "logistic") if k != args.model] if args.compare else [])
    results = {}
    for kind in kinds:
        model = train_trees(x, y, xv, yv, args) if kind == "trees" else train_logistic(x, y)
        sv = score_of(kind, model, xv) if len(yv) else np.zeros(0)
        threshold = (choose_threshold(sv, yv, data, validation, args.threshold_rule, args.target_recall)
                     if len(yv) else 0.5)
        rows, score = evaluate(kind, model, data, manifest, args.label, threshold)
        print(f"\n{kind}: validation PR-AUC {fmt(pr_auc(yv.astype(bool), sv) if len(yv) else None)}")
        print_table(rows, args.label, threshold)
        results[kind] = (model, threshold, rows, score)
    model, threshold, rows, score = results[args.model]
    export = export_trees(model) if args.model == "trees" else {
        "kind": "logistic", "mean": model[1].tolist(), "scale": model[2].tolist(),
        "weights": model[0].coef_[0].tolist(), "bias": float(model[0].intercept_[0])}
    pick = check_rows(score, data, args.label, rng)
    document = {
        "format": MODEL_FORMAT, "version": MODEL_VERSION,
        "layout": manifest["layout"], "tick_period_s": manifest["tick_period_s"],
        "features": {"set": manifest["feature_set"], "names": names},
        "label": args.label, "threshold": threshold, "model": export,
        "check": {"features": data["features"][pick].astype(np.float64).tolist(), "scores": score[pick].tolist()},
        "training": {"datasets": [os.path.abspath(d) for d in args.datasets], "graspbed_version": manifest["graspbed_version"],
                     "train_ticks": int(len(train)), "shuffled_labels": args.shuffle_labels,
                     "threshold_rule": args.threshold_rule, "target_recall_pct": args.target_recall, "test": rows},
    }
    with open(args.out + ".tmp", "w") as stream:
        json.dump(document, stream, separators=(",", ":"))
    os.replace(args.out + ".tmp", args.out)
    print(f"\nmodel ({args.model}, {os.path.getsize(args.out) / 1024:.0f} kB) -> {args.out}; {time.time() - started:.1f} s")
    if args.test_scores:
        test = (data["split"] == SPLITS["test"]) & held
        np.savez(args.test_scores, features=data["features"][test], scores=score[test])
    if args.plots:
        write_plots(args.plots, data, manifest, score, args.label)
    if args.report:
        with open(args.report, "w") as stream:
            json.dump({kind: {"threshold": r[1], "test": r[2]} for kind, r in results.items()}, stream, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
