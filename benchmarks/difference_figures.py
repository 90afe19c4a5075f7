"""The figures of docs/reproduction.md's diagnoses (issue 37 item 6): where each difference
between a paper's figure and ours comes from, drawn from the runs of benchmarks/reproduction.py
(their ``gt/<seq>/gt/gt.txt`` and ``tracks/<tracker>/<seq>.txt``) and from ``occbench detect``
runs (``det/<seq>.txt``). Every input is given as ``label=path``; ground truth and results are
matched frame by frame as the paper metrics match them (``occbench.metrics.paper.row_matching``,
CLEAR matching at IoU >= 0.5).

    python benchmarks/difference_figures.py coverage GT label=TRACKS ... --out P.png
        per person: the share of its frames matched (what MT / PT / ML count)
    python benchmarks/difference_figures.py boxes GT label=TRACKS ... --out P.png
        boxes reported per frame against people present, over the sequence
    python benchmarks/difference_figures.py sizes label=GT,TRACKS ... --out P.png
        box width / person width and height / height of every matched box (Tables 2-4)
    python benchmarks/difference_figures.py states label=GT,TRACKS ... --out P.png
        where a single-target follower's box is (benchmarks/follower_states.py), as bars
    python benchmarks/difference_figures.py heights GT label=DETS ... --out P.png
        detector recall by person height, precision by box height
    python benchmarks/difference_figures.py all --runs results/reproduction [--img docs/img]
        every figure of docs/reproduction.md's diagnoses, from the runs of
        ``benchmarks/reproduction.py --all --runs RUNS`` (the ``occbench detect`` runs they
        also need are made under RUNS/detect/ when missing: ``DETECT``)
"""

from __future__ import annotations

import argparse
import dataclasses
import subprocess
import sys
from itertools import pairwise
from pathlib import Path

import numpy as np
from follower_states import STATES, states
from occbench.io.mot import read_mot
from occbench.metrics.paper import row_matching
from shared_data import use_shared_data


def _pairs(items: list[str]) -> list[tuple[str, str]]:
    out = []
    for item in items:
        label, sep, path = item.partition("=")
        if not sep:
            raise SystemExit(f"occbench: difference_figures: {item!r} is not label=path")
        out.append((label, path))
    return out


def _matching(gt_path: str, res_path: str):
    """CLEAR matching at IoU >= 0.5; detections (id -1) each get an id of their own, so
    they are matched frame by frame one-to-one, as ``occbench detect`` scores them."""
    res = read_mot(res_path)
    if (res.ids == -1).all():
        res = dataclasses.replace(res, ids=np.arange(len(res), dtype=np.int64))
    return row_matching(read_mot(gt_path, gt=True), res, 0.5)


def coverage(gt_path: str, res_path: str) -> dict[int, float]:
    """person id -> matched frames / frames."""
    m = _matching(gt_path, res_path)
    return {int(p): float((m.match[m.gt.ids == p] >= 0).mean()) for p in np.unique(m.gt.ids)}


def _figure(width: float, height: float, n: int = 1):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt.subplots(1, n, figsize=(width, height), squeeze=False)


def plot_coverage(gt: str, runs: list[tuple[str, str]], lines: list[float], title: str,
                  out: Path) -> None:
    cover = [(label, coverage(gt, path)) for label, path in runs]
    people = sorted(cover[0][1])
    fig, axes = _figure(min(12.0, 1.2 * len(people) + 3), 4.0)
    ax = axes[0, 0]
    step = 0.8 / len(runs)
    for i, (label, c) in enumerate(cover):
        ax.bar(np.arange(len(people)) + i * step - 0.4 + step / 2,
               [c.get(p, 0.0) for p in people], step, label=label)
    for y in lines:
        ax.axhline(y, color="#444444", lw=0.8, ls="--")
    ax.set_xticks(range(len(people)), [f"person {p}" for p in people], fontsize=8, rotation=30)
    ax.set_ylabel("frames matched, IoU >= 0.5")
    ax.set_ylim(0, 1.02)
    ax.legend(fontsize=7, ncol=2, loc="lower left", framealpha=0.9)
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def plot_boxes(gt: str, runs: list[tuple[str, str]], title: str, out: Path) -> None:
    g = read_mot(gt, gt=True)
    frames = np.arange(g.frames.min(), g.frames.max() + 1)
    fig, axes = _figure(9, 3.6)
    ax = axes[0, 0]
    ax.plot(frames, np.bincount(g.frames, minlength=frames[-1] + 1)[frames], color="black",
            lw=2, label="people (ground truth)")
    for label, path in runs:
        r = read_mot(path)
        ax.plot(frames, np.bincount(r.frames, minlength=frames[-1] + 1)[frames][:len(frames)],
                lw=1, label=label)
    ax.set_xlabel("frame")
    ax.set_ylabel("boxes in the frame")
    ax.legend(fontsize=7)
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def ratios(gt_path: str, res_path: str) -> np.ndarray:
    """(N, 3) (xc - xg) / wg, w / wg and h / hg of every matched (gt, result) pair."""
    m = _matching(gt_path, res_path)
    hit = m.match >= 0
    r, g = m.res.boxes[m.match[hit]], m.gt.boxes[hit]
    dx = (r[:, 0] + r[:, 2] / 2 - g[:, 0] - g[:, 2] / 2) / g[:, 2]
    return np.column_stack([dx, r[:, 2:4] / g[:, 2:4]])


def plot_sizes(runs: list[tuple[str, str]], title: str, out: Path) -> None:
    fig, axes = _figure(15, 3.8, 3)
    panels = (("centre offset (xc - xg) / person's width", np.linspace(-0.6, 0.6, 49), 0.0),
              ("matched box width / person's width", np.linspace(0.2, 2.0, 46), 1.0),
              ("matched box height / person's height", np.linspace(0.2, 2.0, 46), 1.0))
    for label, paths in runs:
        gt, res = paths.split(",")
        r = ratios(gt, res)
        for k, (_, bins, ideal) in enumerate(panels):
            err = 100 * np.abs(r[:, k] - ideal).mean()
            axes[0, k].hist(np.clip(r[:, k], bins[0], bins[-1]), bins, histtype="step", lw=1.4,
                            density=True, ls="--" if "real" in label else "-",
                            label=f"{label}: median {np.median(r[:, k]):.2f}, "
                                  f"mean |error| {err:.0f} %")
    for k, (name, _, ideal) in enumerate(panels):
        axes[0, k].axvline(ideal, color="#444444", lw=0.8, ls="--")
        axes[0, k].set_xlabel(name)
        axes[0, k].legend(fontsize=6)
    axes[0, 0].set_ylabel("density of matched boxes")
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def plot_states(runs: list[tuple[str, str]], title: str, out: Path) -> None:
    shares = []
    for label, paths in runs:
        gt, res = paths.split(",")
        g = np.loadtxt(gt, delimiter=",", ndmin=2)
        t = np.loadtxt(res, delimiter=",", ndmin=2)
        table = np.loadtxt(Path(res).with_suffix(".followers.csv"), delimiter=",", skiprows=1,
                           ndmin=2, dtype=np.int64)
        counts, _ = states(g, t, {int(i): int(f) for i, f in table})
        total = sum(counts.values())
        shares.append((label, [counts[s] / total for s in STATES]))
    fig, axes = _figure(8, 0.35 * len(runs) + 1.8)
    ax = axes[0, 0]
    left = np.zeros(len(shares))
    colours = ["#2ca02c", "#98df8a", "#d62728", "#7f7f7f", "#dddddd"]
    for k, state in enumerate(STATES):
        v = np.array([s[1][k] for s in shares])
        ax.barh(range(len(shares)), v, left=left, color=colours[k], label=state)
        left += v
    ax.set_yticks(range(len(shares)), [s[0] for s in shares], fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel("share of person-frames")
    ax.legend(fontsize=7, ncol=5, loc="lower center", bbox_to_anchor=(0.5, 1.0))
    ax.set_title(title, fontsize=9, pad=22)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def plot_heights(gt: str, runs: list[tuple[str, str]], title: str, out: Path) -> None:
    fig, axes = _figure(10, 3.6, 2)
    g = read_mot(gt, gt=True)
    edges = np.quantile(g.boxes[:, 3], np.linspace(0, 1, 7))
    mids = (edges[1:] + edges[:-1]) / 2
    for label, path in runs:
        m = _matching(gt, path)
        hit = m.match >= 0
        rec = [hit[(m.gt.boxes[:, 3] >= a) & (m.gt.boxes[:, 3] <= b)].mean()
               for a, b in pairwise(edges)]
        used = np.zeros(len(m.res), bool)
        used[m.match[hit]] = True
        h = m.res.boxes[:, 3]
        pre = [used[(h >= a) & (h <= b)].mean() if ((h >= a) & (h <= b)).any() else np.nan
               for a, b in pairwise(edges)]
        axes[0, 0].plot(mids, rec, marker="o", label=f"{label} (all: {hit.mean():.2f})")
        axes[0, 1].plot(mids, pre, marker="o", label=f"{label} (all: {used.mean():.2f})")
    axes[0, 0].set_xlabel("person's box height, px (sextiles of the ground truth)")
    axes[0, 0].set_ylabel("recall (IoU >= 0.5)")
    axes[0, 1].set_xlabel("detection's box height, px")
    axes[0, 1].set_ylabel("precision (IoU >= 0.5)")
    for ax in axes[0]:
        ax.set_ylim(0, 1.02)
        ax.legend(fontsize=7)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


_PBM = ("pbm", "pbm_paper")

#: detection runs the figures read beside the tables' runs: name -> occbench detect overrides
DETECT = {
    "foreground_replay": ["dataset=replay", "detector=foreground"],
    "foreground_real": ["dataset=mot", "dataset.root={shared}/PETS09-S2L1-real",
                        "detector=foreground"],
    "foreground_real_whole": ["dataset=mot", "dataset.root={shared}/PETS09-S2L1-real",
                              "detector=foreground", "detector.detector.split_heads=false"],
    "silhouette_real": ["dataset=mot", "dataset.root={shared}/PETS09-S2L1-real",
                        "detector=silhouette"],
}


def detections(runs: Path, name: str, seq: str) -> str:
    """RUNS/detect/<name>/det/<seq>.txt, made by ``occbench detect`` when missing."""
    out = runs / "detect" / name
    det = out / "det" / f"{seq}.txt"
    if not det.is_file():
        args = [a.format(shared=use_shared_data()) for a in DETECT[name]]
        argv = [sys.executable, "-m", "occbench", "detect", *args, "progress=false",
                f"hydra.run.dir={out}"]
        print(" ".join(["occbench", "detect", *args]), flush=True)
        if subprocess.run(argv, capture_output=True, check=False).returncode or not det.is_file():
            raise SystemExit(f"occbench: {' '.join(argv)} failed or wrote no {det}")
    return str(det)


def every_figure(runs: Path, img: Path) -> None:
    """The figures of docs/reproduction.md's diagnoses, from reproduction.py's run folders."""
    cav, pets, real = "CAVIAR-OneLeaveShop1cor", "PETS09-S2L1", "PETS09-S2L1-real"

    def gt(table: str, seq: str) -> str:
        return str(runs / table / "0" / "gt" / seq / "gt" / "gt.txt")

    def tr(table: str, tracker: str, seq: str, i: int = 0) -> str:
        return str(runs / table / str(i) / "tracks" / tracker / f"{seq}.txt")

    def dets(i: int) -> str:
        return str(runs / "reta_detection" / "0" / str(i) / "det" / f"{cav}.txt")

    t2 = [(t, tr("reta_table2", t, cav)) for t in ("reta", "reta_paper")]
    plot_coverage(gt("reta_table2", cav), [
        ("silhouette detections", dets(1)), ("active-basis detections", dets(0)), *t2,
        ("reta_paper, active basis", tr("reta_table2", "reta_paper", cav, 1)),
        ("particle_filter", tr("reta_table2", "particle_filter", cav))], [0.8, 0.2],
        "Reta Table 2, CAVIAR OneLeaveShop1cor 151-295: five people, each 20 points of "
        "MT / PT / ML", img / "diff_few_people.png")
    papers = ("reta", "reta_paper", "pbm", "pbm_paper")
    plot_boxes(gt("reta_table3", pets), [(t, tr("reta_table3", t, pets)) for t in papers],
               "Reta Table 3, PETS09-S2L1 replay (noisy ground truth): boxes per frame",
               img / "diff_replay_boxes.png")
    plot_heights(gt("reta_table2", cav), [(d, dets(i)) for i, d in
                                          enumerate(("active_basis", "silhouette", "hog"))],
                 "Reta 4.2, CAVIAR OneLeaveShop1cor 151-295: recall by person height, "
                 "precision by detection height", img / "diff_detection_heights.png")
    # Tables 2-4 are tabled from Table 1's runs (reproduction.py SAME_RUNS): their tracks
    g1, g2 = gt("pbm_table1", pets), gt("pbm_table1_real", real)
    seg = [(f"{t}, replay", f"{g1},{tr('pbm_table1', t, pets)}") for t in _PBM]
    seg_real = [(f"{t}, real", f"{g2},{tr('pbm_table1_real', t, real)}") for t in _PBM]
    whole = tr("pbm_table1_real", "pbm_paper", real, 1)
    plot_sizes([("blobs, replay", f"{g1},{detections(runs, 'foreground_replay', pets)}"), *seg,
                ("blobs, real", f"{g2},{detections(runs, 'foreground_real', real)}"), *seg_real,
                ("pbm_paper whole blobs, real", f"{g2},{whole}")],
               "PBM Table 2: matched box / person size, PETS replay (rendered people) and real "
               "PETS 1-400", img / "diff_box_sizes.png")
    followers = ("pbm", "pbm_paper", "meanshift", "meanshift_scale", "ccmspf", "particle_filter")
    plot_states([*((f"{t}, replay", f"{g1},{tr('pbm_table1', t, pets)}") for t in followers),
                 *((f"{t}, real", f"{g2},{tr('pbm_table1_real', t, real)}") for t in followers),
                 ("pbm_paper whole blobs, real",
                  f"{g2},{tr('pbm_table1_real', 'pbm_paper', real, 1)}")],
                "PBM Table 1: where each follower's box is, per person-frame",
                img / "diff_follower_states.png")
    plot_coverage(g2, [
        ("blobs split at heads", detections(runs, "foreground_real", real)),
        ("whole blobs", detections(runs, "foreground_real_whole", real)),
        *((t, tr("pbm_table1_real", t, real)) for t in _PBM),
        ("pbm_paper, whole blobs", tr("pbm_table1_real", "pbm_paper", real, 1)),
        *((t, tr("pbm_table1_real", t, real)) for t in ("meanshift", "ccmspf"))], [0.8, 0.4],
        "PBM Table 1 on real PETS 1-400: share of each person's frames matched "
        "(mostly tracked > 0.8, mostly lost < 0.4)", img / "diff_real_pets_coverage.png")
    g3 = gt("reta_table3_real", real)
    plot_coverage(g3, [
        ("silhouette detections", detections(runs, "silhouette_real", real)),
        *((t, tr("reta_table3_real", t, real)) for t in papers),
        ("reta_paper, active basis", tr("reta_table3_real", "reta_paper", real, 1))],
        [0.8, 0.2], "Reta Table 3 on real PETS 1-400: share of each person's frames matched",
        img / "diff_real_pets_multi.png")
    plot_boxes(g3, [(t, tr("reta_table3_real", t, real)) for t in papers],
               "Reta Table 3 on real PETS 1-400 (silhouette detections): boxes per frame",
               img / "diff_real_pets_boxes.png")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("kind", choices=["coverage", "boxes", "sizes", "states", "heights", "all"])
    p.add_argument("inputs", nargs="*", help="GT then label=path (coverage, boxes, heights); "
                                             "label=GT,TRACKS (sizes, states)")
    p.add_argument("--out", type=Path)
    p.add_argument("--runs", type=Path, help="all: benchmarks/reproduction.py's --runs folder")
    p.add_argument("--img", type=Path, default=Path(__file__).resolve().parents[1] / "docs" / "img")
    p.add_argument("--title", default="")
    p.add_argument("--lines", type=float, nargs="*", default=[0.8, 0.2],
                   help="coverage: the thresholds drawn")
    a = p.parse_args(argv)
    if a.kind == "all":
        if a.runs is None:
            p.error("all needs --runs")
        every_figure(a.runs, a.img)
        print(f"wrote the figures into {a.img}")
        return 0
    if a.out is None or not a.inputs:
        p.error(f"{a.kind} needs inputs and --out")
    if a.kind in ("coverage", "boxes", "heights"):
        gt, runs = a.inputs[0], _pairs(a.inputs[1:])
        {"coverage": lambda: plot_coverage(gt, runs, a.lines, a.title, a.out),
         "boxes": lambda: plot_boxes(gt, runs, a.title, a.out),
         "heights": lambda: plot_heights(gt, runs, a.title, a.out)}[a.kind]()
    else:
        {"sizes": plot_sizes, "states": plot_states}[a.kind](_pairs(a.inputs), a.title, a.out)
    print(f"wrote {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
