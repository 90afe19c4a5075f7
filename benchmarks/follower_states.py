"""Where a single-target follower's box is, frame by frame (issue 37 item 6: why PBM's
comparators are mostly lost or switch less than the paper's): for every person of a
single-target run (``protocol.name=single_target``, the ``tracks/<tracker>/<seq>.txt`` and
``.followers.csv`` it writes) and every frame of the person's ground truth, the follower's box
(its hand-started track or a restart) is

* on: IoU >= 0.5 with its person (what PBM Table 1 counts as tracked);
* inside, IoU < 0.5: its centre inside the person's box (misplaced or mis-sized);
* on another: its centre inside another person's box only;
* off: anywhere else (background);
* none: the follower reports no box (between a loss and a restart).

Prints the shares per tracks file, pooled over persons, and the median box / person width
and height ratios while the centre is on the person. Plain MOT files.

    python benchmarks/follower_states.py GT.txt RUN/tracks/ccmspf/PETS09-S2L1.txt [...]
"""

from __future__ import annotations

import sys
from collections import Counter
from pathlib import Path

import numpy as np

from box_size_errors import iou

STATES = ("on", "inside, IoU < 0.5", "on another", "off", "none")


def inside(points: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """(N, M) whether point n lies in xywh box m."""
    x, y = points[:, None, 0], points[:, None, 1]
    return ((x >= boxes[None, :, 0]) & (x < boxes[None, :, 0] + boxes[None, :, 2])
            & (y >= boxes[None, :, 1]) & (y < boxes[None, :, 1] + boxes[None, :, 3]))


def person_of_followers(gt: np.ndarray, tracks: np.ndarray, first: dict[int, int]) -> dict[int, int]:
    """follower -> the gt person its hand-started track began on (best IoU, first frame)."""
    out = {}
    for follower in set(first.values()):
        rows = tracks[tracks[:, 1] == follower]
        f = rows[:, 0].min()
        g = gt[gt[:, 0] == f]
        out[follower] = int(g[np.argmax(iou(rows[rows[:, 0] == f, 2:6][:1], g[:, 2:6])[0]), 1])
    return out


def states(gt: np.ndarray, tracks: np.ndarray, first: dict[int, int]) -> tuple[Counter, list]:
    """Counts of STATES over every (person, frame) and (w ratio, h ratio) on the person."""
    counts, ratios = Counter(), []
    follower_of = np.array([first.get(int(i), -1) for i in tracks[:, 1]])
    for follower, person in person_of_followers(gt, tracks, first).items():
        for row in gt[gt[:, 1] == person]:
            f, box = row[0], row[2:6]
            mine = tracks[(tracks[:, 0] == f) & (follower_of == follower), 2:6]
            if not len(mine):
                counts["none"] += 1
                continue
            t = mine[:1]
            centre = t[:, :2] + t[:, 2:] / 2
            others = gt[(gt[:, 0] == f) & (gt[:, 1] != person), 2:6]
            if iou(t, box[None])[0, 0] >= 0.5:
                counts["on"] += 1
            elif inside(centre, box[None])[0, 0]:
                counts["inside, IoU < 0.5"] += 1
            elif len(others) and inside(centre, others)[0].any():
                counts["on another"] += 1
            else:
                counts["off"] += 1
            if inside(centre, box[None])[0, 0]:
                ratios.append((t[0, 2] / box[2], t[0, 3] / box[3]))
    return counts, ratios


def main(gt_path: str, *paths: str) -> None:
    gt = np.loadtxt(gt_path, delimiter=",", ndmin=2)
    for path in paths:
        tracks = np.loadtxt(path, delimiter=",", ndmin=2)
        table = np.loadtxt(Path(path).with_suffix(".followers.csv"), delimiter=",", skiprows=1,
                           ndmin=2, dtype=np.int64)
        counts, ratios = states(gt, tracks, {int(i): int(f) for i, f in table})
        total = sum(counts.values())
        w, h = np.median(np.array(ratios), axis=0) if ratios else (np.nan, np.nan)
        shares = ", ".join(f"{s} {100 * counts[s] / total:.0f} %" for s in STATES)
        print(f"{path}: {total} person-frames: {shares}; box / person on the person: width "
              f"{w:.2f}, height {h:.2f} (medians)")


if __name__ == "__main__":
    main(*sys.argv[1:])
