#!/usr/bin/python3
"""docs/RESULTS.md from the eval JSONs of scripts/experiments.sh (tables and plots).

  experiments_report.py --out build/experiments --doc docs/RESULTS.md \
      --raw docs/results/experiments --images docs/images/results --seconds N --command CMD
  experiments_report.py --subset-views SRC DST V   (experiment 4's sparse-view datasets)

Over seeds: each seed's eval gives, per metric, the mean per-RIR error of every method and the
mean paired per-RIR difference neraf - other (with its standard error over RIRs). The tables give
the mean over seeds of both, and for a difference the standard error over the seeds' means
(n = seeds), which contains the seed-to-seed variation of training; "wins" counts the seeds
whose difference is below zero by more than two of its own per-RIR standard errors.
Needs matplotlib (Debian: python3-matplotlib).
"""
import argparse
import glob
import json
import math
import os
import re
import shutil
import sys

METRICS = [("t60_error_pct", "T60 error (%)"), ("c50_error_db", "C50 error (dB)"),
           ("edt_error_s", "EDT error (s)")]
BASELINES = ["nearest", "linear"]


def mean(xs):
    return sum(xs) / len(xs) if xs else float("nan")


def se(xs):
    if len(xs) < 2:
        return float("nan")
    m = mean(xs)
    return math.sqrt(sum((x - m) ** 2 for x in xs) / (len(xs) - 1) / len(xs))


def fmt(x, digits=3):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "n/a"
    return f"{x:.{digits}f}"


def pm(xs, digits=3):
    """'m ± se' over seeds."""
    if not xs:
        return "n/a"
    s = se(xs)
    return fmt(mean(xs), digits) + ("" if math.isnan(s) else " ± " + fmt(s, digits))


def digits_for(metric):
    return 4 if metric == "edt_error_s" else 3


class Report:
    def __init__(self, args):
        self.args = args
        self.lines = []
        self.sources = []  # raw JSONs read, copied to --raw
        os.makedirs(args.images, exist_ok=True)
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        plt.rcParams["figure.constrained_layout.use"] = True  # axis labels never overlap
        self.plt = plt

    def load(self, name):
        """The eval JSONs of one experiment cell over seeds: {seed: json}."""
        found = {}
        for path in sorted(glob.glob(os.path.join(self.args.out, "eval", name + "_s*.json"))):
            m = re.search(r"_s(\d+)\.json$", path)
            if not m or not re.fullmatch(re.escape(name) + r"_s\d+\.json", os.path.basename(path)):
                continue
            with open(path) as f:
                found[int(m.group(1))] = json.load(f)
            self.sources.append(path)
        return found

    def w(self, line=""):
        self.lines.append(line)

    def image(self, fig, name, caption):
        path = os.path.join(self.args.images, name)
        fig.savefig(path, dpi=110, bbox_inches="tight")
        self.plt.close(fig)
        rel = os.path.relpath(path, os.path.dirname(self.args.doc))
        self.w(f"![{caption}]({rel})")
        self.w()

    # --- tables ---------------------------------------------------------------------------------
    def method_table(self, evals, part, methods, paired_key="paired"):
        """Rows: methods; columns: metrics (mean over seeds ± SE) and neraf - method."""
        self.w("| method | post-processing | " + " | ".join(label for _, label in METRICS) + " |")
        self.w("|---|---|" + "---|" * len(METRICS))
        for method in methods:
            if not any(method in a for a in part_of(evals, part)):
                continue  # e.g. griffin_lim_floor, which older evals did not score
            cells, post = [], ""
            for metric, _ in METRICS:
                xs = [a[method][metric] for a in part_of(evals, part) if method in a]
                cells.append(pm(xs, digits_for(metric)))
                post = next((a[method].get("post_processing", "") for a in part_of(evals, part)
                             if method in a), post)
            self.w(f"| {method} | {post} | " + " | ".join(cells) + " |")
        self.w()
        self.paired_table(evals, part, paired_key, methods=[m for m in methods if m in BASELINES])

    def paired_table(self, evals, part, key, methods=None):
        rows = {}
        for a in part_of(evals, part):
            for other, per_metric in a.get(key, {}).items():
                if methods is None or other in methods:
                    rows.setdefault(other, []).append(per_metric)
        if not rows:
            return
        self.w("Paired per-RIR difference neraf − other (negative: neraf better), mean over seeds "
               "± SE over seeds; wins: seeds where neraf is better by > 2 per-RIR SE:")
        self.w()
        self.w("| neraf − | " + " | ".join(label for _, label in METRICS) + " |")
        self.w("|---|" + "---|" * len(METRICS))
        for other, per_seed in rows.items():
            cells = []
            for metric, _ in METRICS:
                d = [p[metric]["mean_difference"] for p in per_seed if metric in p]
                wins = sum(1 for p in per_seed if metric in p and
                           p[metric]["mean_difference"] < -2 * p[metric]["standard_error"])
                cells.append(f"{pm(d, digits_for(metric))} (wins {wins}/{len(d)})")
            self.w(f"| {other} | " + " | ".join(cells) + " |")
        self.w()

    def ablation_table(self, evals, part, full_label, baselines=()):
        """Rows: the full model, its ablation runs (eval --ablation-runs) and `baselines`; then
        the paired table of the ablations."""
        labels = list(dict.fromkeys(k for a in part_of(evals, part) for k in a.get("ablations", {})))
        self.w("| run | " + " | ".join(label for _, label in METRICS) + " |")
        self.w("|---|" + "---|" * len(METRICS))
        for name in ["neraf"] + labels + list(baselines):
            cells = []
            for metric, _ in METRICS:
                xs = [(a["ablations"][name] if name in a.get("ablations", {}) else a.get(name, {}))
                      .get(metric) for a in part_of(evals, part)]
                cells.append(pm([x for x in xs if x is not None], digits_for(metric)))
            self.w(f"| {full_label if name == 'neraf' else name} | " + " | ".join(cells) + " |")
        self.w()
        self.paired_table(evals, part, "paired_ablations")

    def bar_chart(self, groups, series, values, errors, xlabel, ylabel, title, name):
        """groups on x, one bar per series in each group; values[s][g], errors[s][g]."""
        fig, ax = self.plt.subplots(figsize=(1.2 + 1.3 * len(groups), 3.2))
        width = 0.8 / max(1, len(series))
        for i, s in enumerate(series):
            xs = [g + (i - (len(series) - 1) / 2) * width for g in range(len(groups))]
            ys = [v if not math.isnan(v) else 0 for v in values[s]]
            es = [e if not math.isnan(e) else 0 for e in errors[s]]
            ax.bar(xs, ys, width, yerr=es, capsize=3, label=s)
        ax.set_xticks(range(len(groups)))
        ax.set_xticklabels(groups)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.set_title(title)
        ax.legend(fontsize=8)
        ax.grid(axis="y", alpha=0.3)
        self.image(fig, name, title)

    # --- experiments ----------------------------------------------------------------------------
    def experiment1(self):
        rooms = [("ss_demo", "SoundSpaces layout, binaural (demo room)"),
                 ("raf_furnished", "RAF layout, mono, directional sources (furnished room)")]
        if not any(self.load("e1_" + r) for r, _ in rooms):
            return
        self.w("## 1. neraf against the baselines")
        self.w()
        self.w("The default `neraf train` (cpu preset, joint: radiance and acoustic fields, 3000 "
               "steps, audio from step 1000), scored by `neraf eval --novel-data` against nearest "
               "and linear interpolation of the training RIRs. `neraf` is scored with its energy "
               "calibration and early/late balance fitted on the training RIRs, "
               "`neraf_uncalibrated` without them, as the baselines are rendered. "
               "`griffin_lim_floor` (where scored) is no method: each test RIR's own measured "
               "magnitudes through the same Griffin-Lim, the error a perfect magnitude prediction "
               "would still have; `nearest` is the only row without it.")
        self.w()
        for room, title in rooms:
            evals = self.load("e1_" + room)
            if not evals:
                continue
            for part, what in (("audio", "held-out split"), ("novel", "new microphone positions")):
                self.w(f"### {title}: {what} ({len(evals)} seeds)")
                self.w()
                rows = ["neraf", "neraf_uncalibrated", "nearest", "linear", "griffin_lim_floor"]
                self.method_table(evals, part, rows)
                if room.startswith("raf"):
                    xs = {m: [a[m].get("stft_error") for a in part_of(evals, part) if m in a]
                          for m in rows}
                    xs = {m: v for m, v in xs.items() if v}
                    self.w("STFT error (RAF's mean |Δ log-STFT|): " + ", ".join(
                        f"{m} {pm([x for x in v if x is not None])}" for m, v in xs.items()))
                    self.w()
            self.plot_methods(evals, room, title)
            features = relabel(self.load("e1_features_" + room))
            if not features:
                continue
            self.w(f"### {title}: the grid read per query (issue 13 §5)")
            self.w()
            self.w("The default runs above (the published global feature) beside the same joint "
                   "training with `--grid-features local` and `both`, scored together by `neraf "
                   "eval --ablation-runs`.")
            self.w()
            for part, what in (("audio", "held-out split"), ("novel", "new microphone positions")):
                self.w(f"#### {what} ({len(features)} seeds)")
                self.w()
                self.ablation_table(features, part, "full (global)")

    def plot_methods(self, evals, room, title):
        methods = ["neraf", "neraf_uncalibrated", "nearest", "linear"]
        self.held_out_and_novel_bars(evals, methods, lambda a, m: a.get(m),
                                     ["neraf", "neraf\nuncal.", "nearest", "linear"],
                                     f"{title}: mean error over seeds (± SE)", f"e1_{room}.png",
                                     f"{title}: errors by method")

    def held_out_and_novel_bars(self, evals, names, row_of, ticks, title, file_name, caption):
        """One panel per metric, a held-out and a new-positions bar per name (mean ± SE over
        seeds); row_of(audio_results, name) gives that name's metrics or None."""
        fig, axes = self.plt.subplots(1, len(METRICS), figsize=(11, 3))
        for ax, (metric, label) in zip(axes, METRICS):
            for i, part in enumerate(["audio", "novel"]):
                ys, es = [], []
                for n in names:
                    xs = [r.get(metric) for r in (row_of(a, n) for a in part_of(evals, part)) if r]
                    xs = [x for x in xs if x is not None]
                    ys.append(mean(xs))
                    es.append(se(xs))
                xs = [j + (i - 0.5) * 0.38 for j in range(len(names))]
                ax.bar(xs, [0 if math.isnan(y) else y for y in ys], 0.38,
                       yerr=[0 if math.isnan(e) else e for e in es], capsize=3,
                       label="held-out" if part == "audio" else "new positions")
            ax.set_xticks(range(len(names)))
            ax.set_xticklabels(ticks, fontsize=7)
            ax.set_ylabel(label)
            ax.grid(axis="y", alpha=0.3)
        axes[0].legend(fontsize=8)
        fig.suptitle(title, fontsize=10)
        self.image(fig, file_name, caption)

    def experiment2(self):
        rooms = [("occluded", "occluded room (partition with a doorway)"),
                 ("raf_furnished", "furnished room (RAF layout)"),
                 ("raf_empty", "empty room (RAF layout)")]
        if not any(self.load("e2_" + r) for r, _ in rooms):
            return
        self.w("## 2. The grid ablation")
        self.w()
        self.w("The acoustic field alone (`--modality audio`, 1500 steps) on one frozen vision run "
               "per room, identical but for the grid: the full model (sampled grid, S = 32, the "
               "published global feature), `--grid none`, `--grid zeros`, `--grid-resolution 24` "
               "and `64`, and the grid read per query (ours, issue 13 §5: `--grid-features local`, "
               "the scene encoder's stem map read at the microphone, at the source and along the "
               "segment between them; `both`, that and the global feature); scored together "
               "by `neraf eval --ablation-runs` (which refuses runs that trained differently). "
               "The paper's coarsest size, S = 16, cannot pass the scene encoder (it halves the "
               "grid four times; BatchNorm would see one voxel), so 24 stands in for it.")
        self.w()
        for room, title in rooms:
            evals = relabel(self.load("e2_" + room))
            if not evals:
                continue
            for part, what in (("audio", "held-out split"), ("novel", "new microphone positions")):
                self.w(f"### {title}: {what} ({len(evals)} seeds)")
                self.w()
                self.ablation_table(evals, part, "full (S = 32, global)", BASELINES)
            self.plot_ablation(evals, room, title)

    def plot_ablation(self, evals, room, title):
        names = ["neraf"]
        for a in part_of(evals, "audio"):
            names += [k for k in a.get("ablations", {}) if k not in names]
        row_of = lambda a, n: a.get("neraf") if n == "neraf" else a.get("ablations", {}).get(n)
        self.held_out_and_novel_bars(evals, names, row_of, [n.replace(" ", "\n") for n in names],
                                     f"grid ablation, {title}: mean error over seeds (± SE)",
                                     f"e2_{room}.png", f"grid ablation, {title}")

    def experiment3(self):
        fractions = ["0.25", "0.5", "0.75", "1"]
        cells = {f: self.load(f"e3_raf_furnished_f{f}") for f in fractions}
        if not any(cells.values()):
            return
        self.w("## 3. Few-shot")
        self.w()
        self.w("The acoustic field alone on the furnished room's frozen vision run, trained on a "
               "seeded 25 / 50 / 75 / 100 % of the training RIRs (`--audio-fraction`); the "
               "baselines interpolate the same subset. Held-out split.")
        self.w()
        self.w("| fraction | method | " + " | ".join(label for _, label in METRICS) + " |")
        self.w("|---|---|" + "---|" * len(METRICS))
        curves = {m: {metric: ([], []) for metric, _ in METRICS} for m in ["neraf", "nearest", "linear"]}
        for f in fractions:
            evals = cells[f]
            for m in ["neraf", "nearest", "linear"]:
                row = []
                for metric, _ in METRICS:
                    xs = [a[m][metric] for a in part_of(evals, "audio") if m in a]
                    row.append(pm(xs, digits_for(metric)))
                    curves[m][metric][0].append(mean(xs))
                    curves[m][metric][1].append(se(xs))
                self.w(f"| {float(f):.0%} | {m} | " + " | ".join(row) + " |")
        self.w()
        fig, axes = self.plt.subplots(1, len(METRICS), figsize=(11, 3))
        xs = [float(f) * 100 for f in fractions]
        for ax, (metric, label) in zip(axes, METRICS):
            for m, c in curves.items():
                ys, es = c[metric]
                ax.errorbar(xs, ys, yerr=[0 if math.isnan(e) else e for e in es], marker="o",
                            capsize=3, label=m)
            ax.set_xlabel("training RIRs used (%)")
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
        axes[0].legend(fontsize=8)
        fig.suptitle("few-shot, furnished room, held-out split: mean over seeds (± SE)", fontsize=10)
        self.image(fig, "e3_few_shot.png", "few-shot curve")
        features = {f: relabel(self.load(f"e3_features_raf_furnished_f{f}")) for f in fractions}
        if not any(features.values()):
            return
        self.w("### The grid read per query at each fraction (issue 13 §5)")
        self.w()
        self.w("The few-shot runs again (the full model: the published global feature) beside the "
               "same runs with `--grid-features local` and `both`, scored together by `neraf eval "
               "--ablation-runs`; 100 % is experiment 2's furnished-room table. Where a few-shot "
               "run's folder had been deleted, the full model was trained again for this table, "
               "so its row can differ from the few-shot table above by the builds between "
               "them. Held-out split.")
        self.w()
        for f in fractions:
            evals = features[f]
            if not evals:
                continue
            self.w(f"#### {float(f):.0%} of the training RIRs ({len(evals)} seeds)")
            self.w()
            self.ablation_table(evals, "audio", "full (global)")

    def experiment4(self):
        views = ["10", "20", "40"]
        cells = {(v, m): self.load(f"e4_views{v}_{m}") for v in views for m in ["vision", "joint"]}
        if not any(cells.values()):
            return
        views = [v for v in views if cells[(v, "vision")] or cells[(v, "joint")]]
        self.w("## 4. Cross-modal learning with sparse images")
        self.w()
        self.w("The demo room with only its first 10 / 20 / 40 training views (the same held-out "
               "views), trained vision-only and jointly for the same number of steps; PSNR and "
               "SSIM on the held-out views (`neraf eval`).")
        self.w()
        self.w("| training views | vision-only PSNR | joint PSNR | joint − vision PSNR | "
               "vision-only SSIM | joint SSIM | joint − vision SSIM |")
        self.w("|---|---|---|---|---|---|---|")
        plot = {m: {"psnr": ([], []), "ssim": ([], [])} for m in ["vision", "joint"]}
        for v in views:
            row = [v]
            for metric in ["psnr", "ssim"]:
                a = {s: e["vision"][metric] for s, e in cells[(v, "vision")].items() if "vision" in e}
                b = {s: e["vision"][metric] for s, e in cells[(v, "joint")].items() if "vision" in e}
                paired = [b[s] - a[s] for s in a if s in b]
                row += [pm(list(a.values())), pm(list(b.values())), pm(paired)]
                for m, d in (("vision", a), ("joint", b)):
                    plot[m][metric][0].append(mean(list(d.values())))
                    plot[m][metric][1].append(se(list(d.values())))
            self.w("| " + " | ".join(row) + " |")
        self.w()
        self.w("The difference is paired by seed (the same seed trains both), ± SE over seeds.")
        self.w()
        for metric, label in (("psnr", "PSNR (dB)"), ("ssim", "SSIM")):
            self.bar_chart(views, ["vision", "joint"],
                           {m: plot[m][metric][0] for m in plot}, {m: plot[m][metric][1] for m in plot},
                           "training views", label,
                           f"held-out views by training-view count: {label}",
                           f"e4_{metric}.png")
        self.sample_views(cells)

    def sample_views(self, cells):
        """The first held-out view of seed 1 with 10 views: vision-only | joint (eval's PNGs)."""
        pngs = []
        for m in ["vision", "joint"]:
            e = cells.get(("10", m), {}).get(1)
            run = e.get("run", "") if e else ""
            found = sorted(glob.glob(os.path.join(run, "eval", "eval_*.png")))
            if not found:
                # The runs are gone (the report regenerated from the raw JSONs alone): keep the
                # picture an earlier report drew from them, if there is one.
                kept = os.path.join(self.args.images, "e4_views.png")
                if e and os.path.exists(kept):
                    self.w(f"![sample held-out view]({os.path.relpath(kept, os.path.dirname(self.args.doc))})")
                    self.w()
                return
            pngs.append((m, found[0]))
        import matplotlib.image as mpimg
        fig, axes = self.plt.subplots(1, 2, figsize=(8, 2.6))
        for ax, (m, path) in zip(axes, pngs):
            ax.imshow(mpimg.imread(path))
            ax.set_title(f"{m}, 10 training views (ground truth | prediction)", fontsize=8)
            ax.axis("off")
        self.image(fig, "e4_views.png", "sample held-out view")

    def experiment5(self):
        evals = relabel(self.load("e5_raf_furnished"))
        if not evals:
            return
        self.w("## 5. The loss study")
        self.w()
        self.w("The acoustic field alone on the furnished room's frozen vision run with the "
               "reference's SC+SL-MSE (the full model), SC+SL-L1 and log-magnitude MSE "
               "(`--audio-loss`), otherwise identical; held-out split.")
        self.w()
        self.w("| criterion | " + " | ".join(label for _, label in METRICS) + " |")
        self.w("|---|" + "---|" * len(METRICS))
        for name in ["neraf"] + sorted({k for a in part_of(evals, "audio") for k in a.get("ablations", {})}):
            cells = []
            for metric, _ in METRICS:
                xs = [(a["ablations"][name] if name != "neraf" else a["neraf"]).get(metric)
                      for a in part_of(evals, "audio") if name == "neraf" or name in a.get("ablations", {})]
                cells.append(pm([x for x in xs if x is not None], digits_for(metric)))
            self.w(f"| {'SC+SL-MSE (full model)' if name == 'neraf' else name} | " + " | ".join(cells) + " |")
        self.w()
        self.paired_table(evals, "audio", "paired_ablations")

    def write(self):
        a = self.args
        raw = os.path.relpath(a.raw, os.path.dirname(a.doc))
        if a.provenance:  # results gathered over several calls: their list, as written down
            made_by = [f"Made by `scripts/experiments.sh` and `scripts/experiments_report.py`; the "
                       f"raw eval JSONs are in `{raw}/` (one per experiment, room and seed; "
                       "`neraf eval --help` describes their fields). Every table is regenerated "
                       "from them; nothing here is typed in by hand.", "",
                       open(a.provenance).read().strip()]
        else:
            made_by = [f"Made by `{a.command}` (scripts/experiments.sh, then "
                       f"scripts/experiments_report.py) in {a.seconds / 60:.0f} min on "
                       f"{os.cpu_count()} cores, {machine()}; the raw eval JSONs are in `{raw}/` "
                       "(one per experiment, room and seed; `neraf eval --help` describes their "
                       "fields). Every table is regenerated from them; nothing here is typed in "
                       "by hand."]
        head = ["# Results: the NeRAF paper's experiments on simulated rooms", ""] + made_by + ["",
                "Errors are the published metrics (docs/METRICS.md): mean per-RIR T60 error (%), "
                "C50 error (dB) and EDT error (s), lower is better. Means over seeds ± standard "
                "error over seeds.", ""]
        os.makedirs(a.raw, exist_ok=True)
        for path in self.sources:
            shutil.copyfile(path, os.path.join(a.raw, os.path.basename(path)))
        tmp = a.doc + ".tmp"
        with open(tmp, "w") as f:
            f.write("\n".join(head + self.lines) + "\n")
        os.replace(tmp, a.doc)
        print(f"experiments_report: wrote {a.doc} ({len(self.sources)} eval JSONs)")


def part_of(evals, part):
    """The audio results of the held-out split ("audio") or of the new positions ("novel")."""
    out = []
    for seed in sorted(evals):
        a = evals[seed].get("audio", {})
        if part == "novel":
            a = a.get("novel")
        if a:
            out.append(a)
    return out


def relabel(evals):
    """Ablation labels without the seed suffix, so seeds line up in paired tables."""
    out = {}
    for seed, e in evals.items():
        e = json.loads(json.dumps(e))
        a = e.get("audio", {})
        for target in (a, a.get("novel") or {}):
            for key in ("ablations", "paired_ablations"):
                if key in target:
                    target[key] = {short(k): v for k, v in target[key].items()}
        out[seed] = e
    return out


def short(label):
    """'e2_occluded_grid_none_s1' -> 'grid none'; 'e5_raf_furnished_loss_mse_s2' -> 'loss mse';
    'e3_raf_furnished_features_local_f0.25_s1' -> 'features local'."""
    m = re.match(r"e\d_[a-z]+(?:_(?:furnished|empty|demo))?_(.*?)(?:_f[0-9.]+)?_s\d+$", label)
    return m.group(1).replace("_", " ") if m else label


def machine():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown CPU"


def subset_views(src, dst, count):
    """A copy of dataset src (links to its files) whose transforms.json lists only the first
    `count` training frames; the eval frames and everything else stay."""
    with open(os.path.join(src, "transforms.json")) as f:
        t = json.load(f)
    os.makedirs(dst, exist_ok=True)
    for entry in os.listdir(src):
        if entry in ("transforms.json", ".neraf_cache"):
            continue
        target = os.path.join(dst, entry)
        if not os.path.lexists(target):
            os.symlink(os.path.abspath(os.path.join(src, entry)), target)
    frames = t["frames"]
    if "train_filenames" in t:  # split lists
        if len(t["train_filenames"]) < count:
            sys.exit(f"--subset-views: {src} has {len(t['train_filenames'])} training views, fewer than {count}")
        t["train_filenames"] = t["train_filenames"][:count]
    else:  # nerfstudio's filename split: "train" in the name first, then "eval"
        is_train = lambda fr: "train" in os.path.basename(fr["file_path"])
        train = sorted((fr for fr in frames if is_train(fr)), key=lambda fr: fr["file_path"])
        if len(train) < count:
            sys.exit(f"--subset-views: {src} has {len(train)} training views, fewer than {count}")
        dropped = {fr["file_path"] for fr in train[count:]}
        t["frames"] = [fr for fr in frames if fr["file_path"] not in dropped]
    tmp = os.path.join(dst, "transforms.json.tmp")
    with open(tmp, "w") as f:
        json.dump(t, f, indent=1)
    os.replace(tmp, os.path.join(dst, "transforms.json"))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--out")
    p.add_argument("--doc")
    p.add_argument("--raw")
    p.add_argument("--images")
    p.add_argument("--seconds", type=float, default=0)
    p.add_argument("--command", default="scripts/experiments.sh")
    p.add_argument("--provenance", help="a Markdown file listing the calls the results come from "
                   "(docs/results/experiments_provenance.md), shown instead of --command")
    p.add_argument("--subset-views", nargs=3, metavar=("SRC", "DST", "V"))
    a = p.parse_args()
    if a.subset_views:
        subset_views(a.subset_views[0], a.subset_views[1], int(a.subset_views[2]))
        return
    if not (a.out and a.doc and a.raw and a.images):
        p.error("--out, --doc, --raw and --images are required")
    if a.provenance and not os.path.isfile(a.provenance):
        p.error(f"--provenance {a.provenance}: no such file (docs/results/experiments_provenance.md "
                "lists the calls of the committed results)")
    r = Report(a)
    for e in (r.experiment1, r.experiment2, r.experiment3, r.experiment4, r.experiment5):
        e()
    r.write()


if __name__ == "__main__":
    main()
