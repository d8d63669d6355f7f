#!/usr/bin/python3
"""How much of the T60 a method predicts: per-RIR T60s of `neraf eval`'s per-RIR CSVs.

  bench/t60_spread.py OUT_JSON LABEL=RUN/eval/audio_per_rir.csv [LABEL=...]   (.csv or .csv.gz)

For each CSV (one test set) and method: the mean and spread of the predicted T60 beside the
measured one, their correlation over the test RIRs, the slope of the least-squares line of the
predicted on the measured T60 (1: the differences between RIRs kept; below 1: shrunk toward the
mean; above 1: exaggerated), the mean signed T60 error in each fifth of the test RIRs ordered by
their measured T60 (shortest first), and the error of the T60 itself. Beside the
methods, an oracle reference that is no method: every test RIR given the test set's own mean
measured T60. Where every method's error is close to the oracle's, the test set's T60 hardly
varies between RIRs and no method predicts how it varies.

The CSV's t60_pred_s / t60_gt_s are the means over channels, so the "channel-mean" errors here
are not the metric: `t60_error_pct` (the metric, the mean over channels of each channel's error)
is given beside them.
"""
import csv
import datetime
import gzip
import json
import math
import os
import statistics
import sys


def read_rows(path):
    """{method: {rir_id: (pred T60, measured T60, t60_error_pct)}} of one per-RIR CSV."""
    try:
        with (gzip.open(path, "rt") if path.endswith(".gz") else open(path)) as f:
            methods = {}
            for r in csv.DictReader(f):
                methods.setdefault(r["method"], {})[r["rir_id"]] = (
                    None if r["invalid_t60"] != "0" else
                    (float(r["t60_pred_s"]), float(r["t60_gt_s"]), float(r["t60_error_pct"])))
            return methods
    except (OSError, KeyError, ValueError) as e:
        sys.exit(f"bench/t60_spread.py: {path}: not a readable per-RIR CSV of neraf eval ({e}); "
                 "give RUN/eval/audio_per_rir.csv or audio_novel_per_rir.csv")


def summarize(path):
    by_method = read_rows(path)
    if not by_method:
        sys.exit(f"bench/t60_spread.py: {path}: no rows; give a per-RIR CSV of neraf eval")
    # The RIRs every method has a T60 for, so that all methods are compared on the same RIRs.
    common = set.intersection(*(
        {i for i, v in rows.items() if v is not None} for rows in by_method.values()))
    if len(common) < 5:
        sys.exit(f"bench/t60_spread.py: {path}: fewer than 5 RIRs with a T60 from every method")
    ids = sorted(common)
    methods = {name: [rows[i] for i in ids] for name, rows in by_method.items()}
    out = {"csv": path}
    gt_mean = None
    for name, rows in methods.items():
        pred = [p for p, _, _ in rows]
        gt = [g for _, g, _ in rows]
        if gt_mean is None:
            gt_mean = statistics.fmean(gt)
            out["n_rirs"] = len(gt)
            out["n_rirs_left_out_invalid_t60"] = len(set.union(*map(set, by_method.values()))) - len(gt)
            out["measured"] = {"mean_s": gt_mean, "sd_pct_of_mean": 100 * statistics.pstdev(gt) / gt_mean}
            out["oracle_test_mean"] = {
                "channel_mean_error_pct": 100 * statistics.fmean(abs(gt_mean - g) / g for g in gt)}
            out["methods"] = {}
        order = sorted(range(len(gt)), key=lambda k: gt[k])
        fifths = [order[len(order) * q // 5:len(order) * (q + 1) // 5] for q in range(5)]
        out["methods"][name] = {
            "pred_mean_s": statistics.fmean(pred),
            "pred_sd_pct_of_mean": 100 * statistics.pstdev(pred) / gt_mean,
            "correlation": statistics.correlation(pred, gt) if len(set(pred)) > 1 else math.nan,
            "slope": statistics.linear_regression(gt, pred).slope,
            "signed_error_by_measured_fifth_pct": [
                100 * statistics.fmean((pred[k] - gt[k]) / gt[k] for k in f) for f in fifths],
            "channel_mean_error_pct": 100 * statistics.fmean(abs(p - g) / g for p, g in zip(pred, gt)),
            "t60_error_pct": statistics.fmean(e for _, _, e in rows),
        }
    return out


def main():
    if len(sys.argv) < 3 or any("=" not in a for a in sys.argv[2:]):
        sys.exit(__doc__)
    result = {"command": "bench/t60_spread.py " + " ".join(sys.argv[1:]),
              "date": datetime.datetime.utcnow().strftime("%Y-%m-%dT%H:%M:%SZ"), "sets": {}}
    for arg in sys.argv[2:]:
        label, path = arg.split("=", 1)
        result["sets"][label] = summarize(path)
    tmp = sys.argv[1] + ".tmp"
    with open(tmp, "w") as f:
        f.write(json.dumps(result, indent=2) + "\n")
    os.replace(tmp, sys.argv[1])
    for label, s in result["sets"].items():
        m = s["measured"]
        print(f"{label}: {s['n_rirs']} RIRs, measured T60 {m['mean_s']:.4f} s ± {m['sd_pct_of_mean']:.2f} % "
              f"(sd); oracle (test mean) channel-mean error {s['oracle_test_mean']['channel_mean_error_pct']:.3f} %")
        for name, v in s["methods"].items():
            print(f"  {name:22s} pred {v['pred_mean_s']:.4f} s ± {v['pred_sd_pct_of_mean']:.2f} %  "
                  f"corr {v['correlation']:+.3f}  slope {v['slope']:.2f}  channel-mean error {v['channel_mean_error_pct']:.3f} %  "
                  f"metric {v['t60_error_pct']:.3f} %\n    signed error by fifth of measured T60 "
                  + " ".join(f"{x:+.2f}" for x in v["signed_error_by_measured_fifth_pct"]) + " %")


if __name__ == "__main__":
    main()
