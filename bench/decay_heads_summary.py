#!/usr/bin/env python3
"""Gathers bench/decay_heads.sh's evaluations into one JSON and prints its table.

Per room and split (held-out, new positions) and metric (T60 %, C50 dB, EDT s):
  - each method's error, mean over seeds (decay heads, published heads, nearest, linear);
  - the paired per-RIR difference decay − other, per seed (mean, per-RIR standard error) and
    over seeds (mean ± standard error over seeds). Negative: the decay heads are better.
  - in --zeros-rooms, also decay heads on the sampled grid − decay heads on a zero grid
    ("grid_zeros", from eval_zeros_sN.json).
Both neraf runs carry their own energy calibration ("griffin_lim_calibrated"); linear is rendered
through the same Griffin-Lim without one (each method's post_processing is copied through).
"""
import argparse
import json
import math
import os
import statistics
import sys

METRICS = ["t60_error_pct", "c50_error_db", "edt_error_s"]
SPLITS = {"held_out": lambda a: a, "new_positions": lambda a: a["novel"]}


def mean_se(values):
    m = statistics.fmean(values)
    se = statistics.stdev(values) / math.sqrt(len(values)) if len(values) > 1 else float("nan")
    return {"mean": m, "se_over_seeds": se, "n_seeds": len(values)}


def load(work, room, name):
    path = os.path.join(work, room, name)
    try:
        with open(path) as f:
            return json.load(f)["audio"]
    except (OSError, KeyError, json.JSONDecodeError) as e:
        sys.exit(f"decay_heads_summary: {path}: {e}; run bench/decay_heads.sh to make it")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--work", required=True)
    p.add_argument("--rooms", nargs="+", required=True)
    p.add_argument("--seeds", nargs="+", required=True)
    p.add_argument("--zeros-rooms", nargs="*", default=[],
                   help="rooms with eval_zeros_sN.json: the decay-head run against its zero grid")
    p.add_argument("--command", required=True)
    p.add_argument("--machine", required=True, help="the CPU's model name")
    p.add_argument("--start", required=True)
    p.add_argument("--load-before", required=True)
    p.add_argument("--seconds", type=int, required=True)
    p.add_argument("--out", required=True)
    a = p.parse_args()

    rooms = {}
    for room in a.rooms:
        evals = {s: load(a.work, room, f"eval_s{s}.json") for s in a.seeds}
        zeros = ({s: load(a.work, room, f"eval_zeros_s{s}.json") for s in a.seeds}
                 if room in a.zeros_rooms else {})
        out = {}
        for split, pick in SPLITS.items():
            per_seed = {s: pick(ev) for s, ev in evals.items()}
            entry = {"methods": {}, "paired": {}}
            for method in ["neraf", "nearest", "linear"]:
                entry["methods"]["decay_heads" if method == "neraf" else method] = {
                    m: mean_se([per_seed[s][method][m] for s in a.seeds]) for m in METRICS}
                entry["methods"]["decay_heads" if method == "neraf" else method][
                    "post_processing"] = per_seed[a.seeds[0]][method]["post_processing"]
            # The one ablation of each seed's evaluation: that seed's run with the published heads.
            published = {s: next(iter(per_seed[s]["ablations"].values())) for s in a.seeds}
            entry["methods"]["published_heads"] = {
                m: mean_se([published[s][m] for s in a.seeds]) for m in METRICS}
            entry["methods"]["published_heads"]["post_processing"] = \
                published[a.seeds[0]]["post_processing"]
            only_ablation = lambda d: next(iter(d["paired_ablations"].values()))
            others = [("published_heads", per_seed, only_ablation),
                      ("nearest", per_seed, lambda d: d["paired"]["nearest"]),
                      ("linear", per_seed, lambda d: d["paired"]["linear"])]
            if zeros:
                others.append(("grid_zeros", {s: pick(z) for s, z in zeros.items()}, only_ablation))
            for other, source, get in others:
                entry["paired"][other] = {}
                for m in METRICS:
                    seeds = {s: get(source[s])[m] for s in a.seeds}
                    entry["paired"][other][m] = {
                        "per_seed": {s: {"mean_difference": v["mean_difference"],
                                         "standard_error": v["standard_error"], "n": v["n"]}
                                     for s, v in seeds.items()},
                        **mean_se([v["mean_difference"] for v in seeds.values()]),
                    }
            out[split] = entry
        rooms[room] = out

    result = {
        "command": a.command,
        "what": "audio-only runs on one frozen vision run per room, identical but for "
                "--decay-heads; paired per RIR, decay heads − other (negative: decay heads better)",
        "date": a.start,
        "machine": {"cpu": a.machine, "cores": os.cpu_count()},
        "load_before": a.load_before,
        "load_after": " ".join(open("/proc/loadavg").read().split()[:3]),
        "seconds": a.seconds,
        "rooms": rooms,
    }
    tmp = a.out + ".tmp"
    with open(tmp, "w") as f:
        json.dump(result, f, indent=1)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, a.out)

    unit = {"t60_error_pct": ("T60 %", 1), "c50_error_db": ("C50 dB", 1), "edt_error_s": ("EDT ms", 1e3)}
    print(f"decay heads − other, mean over {len(a.seeds)} seeds ± SE over seeds (negative: decay better)")
    for room, splits in rooms.items():
        for split, entry in splits.items():
            for m in METRICS:
                name, k = unit[m]
                errs = "  ".join(f"{meth} {entry['methods'][meth][m]['mean'] * k:.3f}"
                                 for meth in ["decay_heads", "published_heads", "nearest", "linear"])
                diffs = "  ".join(
                    f"−{o} {entry['paired'][o][m]['mean'] * k:+.3f} ± {entry['paired'][o][m]['se_over_seeds'] * k:.3f}"
                    for o in entry["paired"])
                print(f"{room:14s} {split:13s} {name:7s} {errs} | {diffs}")
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
