"""The detections' own box-size errors against the ground truth (issue 37 item 6): pairs
matched one-to-one per frame at IoU >= 0.5, mean |w - wg| / wg and |h - hg| / hg, and the
median detected / ground-truth width. Plain MOT files (gt.txt, a det file of `occbench detect`).

    python benchmarks/box_size_errors.py GT.txt DET.txt
"""
import sys
import numpy as np
from scipy.optimize import linear_sum_assignment
def load(p):
    a = np.loadtxt(p, delimiter=",", ndmin=2); return a
def iou(a, b):
    x1 = np.maximum(a[:, None, 0], b[None, :, 0]); y1 = np.maximum(a[:, None, 1], b[None, :, 1])
    x2 = np.minimum(a[:, None, 0] + a[:, None, 2], b[None, :, 0] + b[None, :, 2])
    y2 = np.minimum(a[:, None, 1] + a[:, None, 3], b[None, :, 1] + b[None, :, 3])
    i = np.clip(x2 - x1, 0, None) * np.clip(y2 - y1, 0, None)
    return i / (a[:, None, 2] * a[:, None, 3] + b[None, :, 2] * b[None, :, 3] - i)


def main(gt_path: str, det_path: str) -> None:
    gt, det = load(gt_path), load(det_path)
    rw, rh, ratio = [], [], []
    for f in np.unique(gt[:, 0]):
        g = gt[gt[:, 0] == f, 2:6]; d = det[det[:, 0] == f, 2:6]
        if not len(d): continue
        m = iou(g, d); r, c = linear_sum_assignment(-m)
        ok = m[r, c] >= 0.5
        for i, j in zip(r[ok], c[ok]):
            rw.append(abs(d[j, 2] - g[i, 2]) / g[i, 2]); rh.append(abs(d[j, 3] - g[i, 3]) / g[i, 3]); ratio.append(d[j, 2] / g[i, 2])
    print(f"pairs {len(rw)}: width error mean {100*np.mean(rw):.1f} %, height {100*np.mean(rh):.1f} %, det/gt width median {np.median(ratio):.2f} (5-95% {np.percentile(ratio,5):.2f}-{np.percentile(ratio,95):.2f})")


if __name__ == "__main__":
    main(*sys.argv[1:3])
