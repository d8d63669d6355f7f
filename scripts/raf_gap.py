#!/usr/bin/python3
"""Where the default neraf loses to the baselines in the RAF-layout furnished room (issue 13):
diagnostics of experiment 2's full-model runs, from their per-RIR CSVs and the datasets' poses.

  scripts/raf_gap.py --out build/experiments [--evals EVAL.json ...] --json OUT.json
  (scripts/raf_gap.sh makes the --evals and calls it)

Reads OUT/runs/e2_raf_furnished_full_s{1,2,3}/eval/audio_per_rir.csv (held-out split) and
audio_novel_per_rir.csv (new microphone positions), the poses of OUT/data/raf_furnished and
raf_furnished_novel, and the C50 of training RIRs from `neraf metrics --rir` (the same metric
code). Writes one JSON:
  shared_microphones  how many held-out RIRs have a training RIR (the other source) at the same
                      microphone position, and how many new-position RIRs do
  other_source_pull   at those shared microphones, the least-squares slope (and correlation) of
                      each method's signed C50 error on (the training RIR's C50 - the held-out
                      RIR's own): 1 would be a copy of the other source's RIR, 0 no pull
  by_distance         per split and source-distance bin: RIRs, and each method's mean error
  seed_spread         per split: neraf's per-seed error against the error of the per-RIR mean of
                      its three seeds' predicted T60 / C50, beside the baselines (how much of the
                      error is seed-to-seed scatter, which averaging removes, and how much is
                      shared by every seed)
  evals               (--evals, one `neraf eval --novel-data` JSON per seed, scripts/raf_gap.sh)
                      per part (held_out, novel): RIRs, each method's and ablation's mean error
                      over seeds, and per baseline or ablation and metric the paired difference
                      neraf - it: mean over seeds, its standard error over seeds, each seed's
                      per-RIR standard error, and the seeds where neraf is better by more than
                      two of those
"""
import argparse
import csv
import json
import os
import re
import subprocess
import sys
import time

import numpy as np

from experiments_report import machine

METHODS = ["neraf", "nearest", "linear", "griffin_lim_floor"]
SEEDS = [1, 2, 3]
ERRORS = ["t60_error_pct", "c50_error_db", "edt_error_s"]
BINS = [(0.0, 2.0), (2.0, 3.0), (3.0, 4.0), (4.0, 99.0)]


def vector(path):
    with open(path) as f:
        return np.array([float(x) for x in f.read().replace(",", " ").split()])


def pose(data, rir_id):  # (mic xyz, source xyz): tx_pos.txt is 4 rotation values, then xyz
    d = os.path.join(data, "data", rir_id)
    return vector(os.path.join(d, "rx_pos.txt")), vector(os.path.join(d, "tx_pos.txt"))[4:]


def need(path, fix):
    """Stops with one line naming `path` and the fix when it does not exist."""
    if not os.path.exists(path):
        sys.exit(f"raf_gap: {path}: missing; {fix}")


MAKE_RUNS = "EXPERIMENTS=\"2 5\" E2_ROOMS=raf_furnished scripts/experiments.sh makes it"


def per_rir(out, csv_name):
    """{method: {rir_id: [row of seed 1, 2, 3]}} over the full-model runs."""
    rows = {}
    for s in SEEDS:
        path = os.path.join(out, "runs", f"e2_raf_furnished_full_s{s}", "eval", csv_name)
        need(path, MAKE_RUNS)
        with open(path) as f:
            for r in csv.DictReader(f):
                rows.setdefault(r["method"], {}).setdefault(r["rir_id"], []).append(r)
    return rows


def column(rows, ids, key):  # [RIRs, seeds]
    return np.array([[float(r[key]) for r in rows[i]] for i in ids])


def by_label(runs):
    """{e2_raf_furnished_S24_s1: x} -> {S24: x}: an ablation run's name without room and seed."""
    return {re.sub(r"^e\d_raf_furnished_", "", n).rsplit("_s", 1)[0]: v for n, v in runs.items()}


def summarise_evals(paths):
    audio = []
    for path in paths:
        with open(path) as f:
            audio.append(json.load(f)["audio"])
    parts = {"files": list(paths)}
    for part, pick in [("held_out", lambda a: a), ("novel", lambda a: a["novel"])]:
        seeds = [pick(a) for a in audio]
        errors = [e | by_label(e.get("ablations", {})) for e in seeds]
        paired = [e["paired"] | by_label(e.get("paired_ablations", {})) for e in seeds]
        labels = list(by_label(seeds[0].get("ablations", {})))
        summary = {"rirs": seeds[0]["neraf"]["n_rirs"]}
        for m in METHODS + labels:
            summary[m] = {k: float(np.mean([e[m][k] for e in errors])) for k in ERRORS}
        for other in ["nearest", "linear"] + labels:
            summary["neraf_minus_" + other] = {}
            for k in ERRORS:
                d = np.array([p[other][k]["mean_difference"] for p in paired])
                se = np.array([p[other][k]["standard_error"] for p in paired])
                summary["neraf_minus_" + other][k] = {
                    "mean_difference": float(d.mean()),
                    "se_over_seeds": float(d.std(ddof=1) / np.sqrt(len(d))),
                    "per_rir_se": se.tolist(), "wins": int((d < -2 * se).sum())}
        parts[part] = summary
    return parts


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--out", default="build/experiments", help="scripts/experiments.sh's OUT")
    p.add_argument("--neraf", default="build/neraf")
    p.add_argument("--evals", nargs="*", default=[], help="neraf eval JSONs to summarise")
    p.add_argument("--json", required=True)
    a = p.parse_args()

    data = os.path.join(a.out, "data", "raf_furnished")
    split_file = os.path.join(data, "metadata", "data-split.json")
    novel_data = data + "_novel"
    need(split_file, MAKE_RUNS + " (or give its OUT with --out)")
    need(os.path.join(novel_data, "data"), MAKE_RUNS)
    need(a.neraf, "build it with scripts/build.sh, or give the program with --neraf")
    for path in a.evals:
        need(path, "scripts/raf_gap.sh makes the evaluations")
    with open(split_file) as f:
        split = json.load(f)
    train, test = split["train"][0], split["test"][0]
    novel = sorted(os.listdir(os.path.join(novel_data, "data")))
    train_mic = {i: pose(data, i)[0] for i in train}

    def training_rir_at(mic):
        return next((i for i, m in train_mic.items() if np.allclose(m, mic)), None)

    result = {"command": " ".join(["scripts/raf_gap.py"] + sys.argv[1:]), "runs":
              [f"e2_raf_furnished_full_s{s}" for s in SEEDS], "machine": f"{machine()}, {os.cpu_count()} cores",
              "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}
    splits = {"held_out": (per_rir(a.out, "audio_per_rir.csv"), test, data),
              "novel": (per_rir(a.out, "audio_novel_per_rir.csv"), novel, novel_data)}

    partner = {i: training_rir_at(pose(data, i)[0]) for i in test}
    shared = [i for i in test if partner[i]]
    result["shared_microphones"] = {
        "held_out": len(shared), "held_out_rirs": len(test),
        "novel": sum(training_rir_at(pose(novel_data, i)[0]) is not None for i in novel),
        "novel_rirs": len(novel)}

    def c50_of(rir_id):
        wav = os.path.join(data, "data", rir_id, "rir.wav")
        done = subprocess.run([a.neraf, "metrics", "--rir", wav, "--json"], capture_output=True,
                              text=True)
        if done.returncode != 0:
            sys.exit(f"raf_gap: {a.neraf} metrics --rir {wav} failed (exit {done.returncode}): "
                     f"{done.stderr.strip()}")
        return json.loads(done.stdout)["channels"][0]["c50"]

    rows = splits["held_out"][0]
    own = column(rows["neraf"], shared, "c50_gt_db")[:, 0]
    pull = np.array([c50_of(partner[i]) for i in shared]) - own
    result["other_source_pull"] = {"rirs": len(shared),
                                   "mean_abs_other_minus_own_db": float(np.abs(pull).mean())}
    for m in METHODS:
        err = (column(rows[m], shared, "c50_pred_db") - own[:, None]).mean(1)  # over seeds
        result["other_source_pull"][m] = {"slope": float(pull @ err / (pull @ pull)),
                                          "correlation": float(np.corrcoef(pull, err)[0, 1])}

    result["by_distance"], result["seed_spread"] = {}, {}
    for name, (rows, ids, root) in splits.items():
        dist = np.array([np.linalg.norm(np.subtract(*pose(root, i))) for i in ids])
        bins = []
        for lo, hi in BINS:
            inside = [i for i, d in zip(ids, dist) if lo <= d < hi]
            bins.append({"source_distance_m": [lo, hi], "rirs": len(inside)} | {
                m: {"c50_error_db": float(column(rows[m], inside, "c50_error_db").mean()),
                    "t60_error_pct": float(column(rows[m], inside, "t60_error_pct").mean())}
                for m in METHODS})
        result["by_distance"][name] = bins

        t60_gt = column(rows["neraf"], ids, "t60_gt_s")[:, 0]
        c50_gt = column(rows["neraf"], ids, "c50_gt_db")[:, 0]
        t60_pred = column(rows["neraf"], ids, "t60_pred_s")
        c50_pred = column(rows["neraf"], ids, "c50_pred_db")
        spread = {"neraf_per_seed": {
            "t60_error_pct": float((np.abs(t60_pred / t60_gt[:, None] - 1) * 100).mean()),
            "c50_error_db": float(np.abs(c50_pred - c50_gt[:, None]).mean())},
            "neraf_mean_of_seeds": {
            "t60_error_pct": float((np.abs(t60_pred.mean(1) / t60_gt - 1) * 100).mean()),
            "c50_error_db": float(np.abs(c50_pred.mean(1) - c50_gt).mean())},
            "neraf_seed_sd": {
            "t60_pct": float((t60_pred.std(1, ddof=1) / t60_gt * 100).mean()),
            "c50_db": float(c50_pred.std(1, ddof=1).mean())}}
        for m in ["nearest", "linear"]:
            spread[m] = {k: float(column(rows[m], ids, k)[:, 0].mean())
                         for k in ["t60_error_pct", "c50_error_db"]}
        result["seed_spread"][name] = spread

    if a.evals:
        result["evals"] = summarise_evals(a.evals)

    os.makedirs(os.path.dirname(os.path.abspath(a.json)), exist_ok=True)
    tmp = a.json + ".tmp"
    with open(tmp, "w") as f:
        json.dump(result, f, indent=1)
    os.replace(tmp, a.json)
    print(f"raf_gap: wrote {a.json}")


if __name__ == "__main__":
    main()
