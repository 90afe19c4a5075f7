"""Trajectory plots in the manner of PBM Figs. 8-10: one ground-truth person's centroid path
beside the paths of the tracker ids that followed it, one colour per id.

For a chosen GT person, every tracker id matched to that person in at least one frame
(``occbench.metrics.paper.match_rows``: IoU >= threshold, CLEAR matching) is drawn over the
person's lifetime, as a line of box centres labelled ``<tracker>-<id>``. Frames where the
person is hidden (visibility < ``hidden_below`` or an occluded label) are marked on the GT
path. Top row: image x and y (y downwards), time implicit, as in the paper; bottom row: x
against the frame number, where a u-turn or an id change shows. One column per tracker (the
paper overlays all trackers; separate panels keep each id's colour readable).

Command line, on a finished run::

    python -m occbench.replay.trajectories RUN_DIR --sequence stop_behind --person 2
"""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np

from occbench.config.build import compose_config, load_sequences
from occbench.datasets.base import GroundTruth
from occbench.errors import REFUSED, refusal
from occbench.io.mot import MotTable, read_mot
from occbench.metrics.occlusion import row_visibility
from occbench.metrics.paper import considered, match_rows
from occbench.progress import log_to_stderr

log = logging.getLogger(__name__)


def centres(boxes: np.ndarray) -> np.ndarray:
    """(N, 2) centroids of (N, 4) xywh boxes."""
    boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    return boxes[:, :2] + boxes[:, 2:] / 2


def most_occluded_person(gt: GroundTruth | MotTable, hidden_below: float = 0.05) -> int:
    """The GT id with the most hidden frames (ties: the longest trajectory, then the
    smallest id): a natural choice for an occlusion figure."""
    table = gt.table if isinstance(gt, GroundTruth) else gt
    occluded = gt.occluded if isinstance(gt, GroundTruth) else None
    vis = row_visibility(table, occluded)
    hidden = np.nan_to_num(vis, nan=1.0) < hidden_below
    ids = np.unique(table.ids)
    if len(ids) == 0:
        raise ValueError("ground truth has no person")
    n_hidden = np.array([hidden[table.ids == i].sum() for i in ids])
    length = np.array([(table.ids == i).sum() for i in ids])
    order = np.lexsort((ids, -length, -n_hidden))
    return int(ids[order[0]])


def person_paths(gt: MotTable, results: Mapping[str, MotTable], person: int,
                 iou_threshold: float = 0.5) -> dict[str, dict[int, np.ndarray]]:
    """For each tracker: {id: (K, 3) rows (frame, xc, yc)} of every id matched to ``person``
    at least once, over the frames the person is in the ground truth."""
    gt = considered(gt)
    mine = gt.ids == person
    if not mine.any():
        raise ValueError(f"no ground-truth person {person} (ids: {np.unique(gt.ids).tolist()})")
    first, last = gt.frames[mine].min(), gt.frames[mine].max()
    out: dict[str, dict[int, np.ndarray]] = {}
    for name, res in results.items():
        match = match_rows(gt, res, iou_threshold)
        rows = match[mine & (match >= 0)]
        paths = {}
        for rid in dict.fromkeys(res.ids[rows].tolist()):
            sel = (res.ids == rid) & (res.frames >= first) & (res.frames <= last)
            c = centres(res.boxes[sel])
            paths[int(rid)] = np.column_stack([res.frames[sel], c])
        out[name] = paths
    return out


def gaps_broken(frames: np.ndarray, values: np.ndarray) -> np.ndarray:
    """``values`` (N, k) in frame order with a row of NaN wherever ``frames`` (N,) skips a
    frame, so that a plotted line stops at a gap instead of bridging it with a straight
    line (a missed or hidden stretch is not a walk)."""
    frames = np.asarray(frames)
    values = np.asarray(values, dtype=float).reshape(len(frames), -1)
    cut = np.flatnonzero(np.diff(frames) > 1) + 1
    return np.insert(values, cut, np.nan, axis=0)


def plot_person(gt: GroundTruth | MotTable, results: Mapping[str, MotTable], person: int,
                path: str | Path, iou_threshold: float = 0.5, hidden_below: float = 0.05,
                title: str = "") -> Path:
    """Write the figure (PNG) for GT ``person``; returns its path."""
    matplotlib.use("Agg")

    table = gt.table if isinstance(gt, GroundTruth) else gt
    occluded = gt.occluded if isinstance(gt, GroundTruth) else None
    vis = row_visibility(table, occluded)
    mine = table.ids == person
    g_order = np.argsort(table.frames[mine], kind="stable")
    g_xy = centres(table.boxes[mine])[g_order]
    g_hidden = (np.nan_to_num(vis[mine], nan=1.0) < hidden_below)[g_order]
    paths = person_paths(table, results, person, iou_threshold)
    names = list(results) or ["(no tracker)"]
    g_frames = np.sort(table.frames[mine])
    fig, axes = plt.subplots(2, len(names), figsize=(4.6 * len(names), 7.4), squeeze=False,
                             sharex=True, sharey="row", height_ratios=[3, 2])
    cmap = plt.get_cmap("tab10")
    g_line = gaps_broken(g_frames, np.column_stack([g_xy, g_frames]))
    for ax, tax, name in zip(axes[0], axes[1], names):
        for a, y in ((ax, g_line[:, 1]), (tax, g_line[:, 2])):
            a.plot(g_line[:, 0], y, "k--", lw=2.2, label=f"GT {person}", zorder=3)
        for a, y in ((ax, g_xy[:, 1]), (tax, g_frames)):
            if g_hidden.any():
                a.plot(g_xy[g_hidden, 0], y[g_hidden], "o", ms=5, mfc="none", mec="k",
                       label="GT hidden", zorder=3)
        for k, (rid, pth) in enumerate(paths.get(name, {}).items()):
            colour = cmap(k % 10)
            line = gaps_broken(pth[:, 0], pth)  # no line across the frames the id missed
            ax.plot(line[:, 1], line[:, 2], "-", color=colour, lw=1.6, label=f"{name}-{rid}")
            ax.plot(pth[:1, 1], pth[:1, 2], "^", color=colour, ms=6)
            tax.plot(line[:, 1], line[:, 0], "-", color=colour, lw=1.6)
        ax.set_title(f"{name}: {len(paths.get(name, {}))} id(s)")
        tax.set_xlabel("x (pixels)")
        for a in (ax, tax):
            a.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    # limits: every path, with the shorter side at least 30 % of the longer (a nearly
    # straight walk is not stretched into a zig-zag)
    pts = np.vstack([g_xy] + [p[:, 1:] for d in paths.values() for p in d.values() if len(p)])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = np.maximum(hi - lo, 0.3 * (hi - lo).max()) * 1.1 + 2.0
    mid = (lo + hi) / 2
    axes[0][0].set_xlim(mid[0] - span[0] / 2, mid[0] + span[0] / 2)
    axes[0][0].set_ylim(mid[1] + span[1] / 2, mid[1] - span[1] / 2)  # image y points down
    axes[0][0].set_ylabel("y (pixels)")
    axes[1][0].set_ylabel("frame")
    axes[1][0].invert_yaxis()
    fig.suptitle(title or f"Centroid path of GT person {person} and the tracker ids matched "
                 "to it (triangles: where an id starts; a line stops where its frames "
                 "stop); below: x against time", fontsize=9)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m occbench.replay.trajectories",
                                description="PBM Figs. 8-10 style trajectory plot of a run.")
    p.add_argument("run_dir", type=Path, help="run directory of python -m occbench")
    p.add_argument("--sequence", help="sequence name (default: the first with tracks)")
    p.add_argument("--person", type=int, help="GT id (default: the most occluded person)")
    p.add_argument("--out", type=Path, help="PNG path (default RUN_DIR/plots/trajectory_...)")
    p.add_argument("--iou", type=float, default=0.5)
    args = p.parse_args(argv)
    log_to_stderr()

    try:
        tracks = args.run_dir / "tracks"
        if not tracks.is_dir():
            raise FileNotFoundError(f"{tracks} not found (a run directory of python -m occbench)")
        cfg = compose_config([], args.run_dir)
        sequences = {s.info.name: s for s in load_sequences(cfg.dataset)}
        name = args.sequence or next(iter(sequences))
        if name not in sequences:
            raise ValueError(f"no sequence {name!r}; have {sorted(sequences)}")
        seq = sequences[name]
        if seq.gt is None:  # nothing to follow: the tracks are counted by occbench report
            print(f"{name} has no ground truth: no trajectory plot of a person")
            return 0
        results = {d.name: read_mot(d / f"{name}.txt") for d in sorted(tracks.iterdir())
                   if (d / f"{name}.txt").is_file()}
        person = args.person if args.person is not None else most_occluded_person(seq.gt)
        out = args.out or args.run_dir / "plots" / f"trajectory_{name}_{person}.png"
        plot_person(seq.gt, results, person, out, args.iou)
    except (OSError, ValueError) as err:
        print(refusal(err), file=sys.stderr)
        return REFUSED
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
