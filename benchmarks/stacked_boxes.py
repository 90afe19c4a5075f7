"""How many reported boxes lie on one person (issue 37 item 6, pbm_paper's fragmentation):
per tracks file, reported boxes per frame and the ground-truth boxes covered by two or more
reported boxes at IoU >= 0.5. Plain MOT files.

    python benchmarks/stacked_boxes.py GT.txt TRACKS.txt [TRACKS.txt ...]
"""

from __future__ import annotations

import sys

import numpy as np

from box_size_errors import iou


def main(gt_path: str, *tracks: str) -> None:
    gt = np.loadtxt(gt_path, delimiter=",", ndmin=2)
    frames = np.unique(gt[:, 0])
    for path in tracks:
        tr = np.loadtxt(path, delimiter=",", ndmin=2)
        stacked = 0
        for f in frames:
            g, t = gt[gt[:, 0] == f, 2:6], tr[tr[:, 0] == f, 2:6]
            if len(t):
                stacked += int(((iou(g, t) >= 0.5).sum(axis=1) >= 2).sum())
        print(f"{path}: {len(tr) / len(frames):.1f} boxes per frame ({len(gt) / len(frames):.2f} "
              f"people), gt boxes under >= 2 boxes at IoU >= 0.5: {stacked} of {len(gt)} "
              f"({100 * stacked / len(gt):.0f} %)")


if __name__ == "__main__":
    main(*sys.argv[1:])
