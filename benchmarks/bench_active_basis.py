"""Reta 3.1's active-basis detector (``detector=active_basis``) beside the silhouette matcher on
real CAVIAR frames: precision / recall / F1 at IoU >= 0.5 (``occbench detect``'s matching).

Sets, fixed before looking: *choosing* = OneLeaveShop1cor frames 1-150 and
EnterExitCrossingPaths1cor frames 1-180; *reporting* = OneLeaveShop1cor 151-295 and
EnterExitCrossingPaths1cor 181-383 (``--report`` prints them; choose with it off). Each
sequence is run once over all its frames (the front end's warm-up samples the whole
sequence, no annotation) and scored by frame range, as the README's detection table is.

The greedy search's scores never increase from one fit to the next (the eligible placements
only shrink while the maps stay), so the detections at a threshold T are the fits scoring >= T
of one run at a lower threshold: ``--thresholds`` scores several from one run (exact).

Run: ``python benchmarks/bench_active_basis.py [--thresholds 8 10 12] [--report]
[--set search.placements.min_vacant=0.6 ...]``. Reads the not-shipped data (``shared_data.use_shared_data()``,
$OCCBENCH_SHARED) for
EnterExitCrossingPaths1cor; exits with a message when a sequence is absent.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hydra.utils import instantiate
from shared_data import use_shared_data

from occbench.commands.detect import match_count
from occbench.config.build import compose_config, dataset_sequences as load_sequences

DATA = use_shared_data()  # $OCCBENCH_SHARED: the sets not shipped

#: (sequence folder, choosing range, reporting range)
SETS = [("CAVIAR-OneLeaveShop1cor", (1, 150), (151, 295)),
        ("CAVIAR-EnterExitCrossingPaths1cor", (1, 180), (181, 383))]


def run(folder: str, detector: str, overrides: list[str]) -> tuple[dict, dict]:
    """Per frame: detections (boxes, scores) and gt boxes of one whole sequence."""
    root = DATA / folder
    if not root.is_dir():
        sys.exit(f"{root}: not found (set OCCBENCH_SHARED)")
    # CAVIAR XML where the folder has it (OneLeaveShop1cor, as the README's table), else MOT gt
    xml = list(root.glob("*.xml")) + list((root / "gt").glob("*.xml"))
    ds = [f"dataset={'caviar' if xml else 'mot'}", f"dataset.root={root}"]
    seq = load_sequences(ds)[0]
    src = instantiate(compose_config(ds + [f"detector={detector}"]
                                     + [f"detector.detector.{o}" for o in overrides]).detector)
    src.start(seq)
    dets, gts = {}, {}
    for k, frame in seq.frames():
        d, _ = src.detect(k, frame)
        # active_basis: the log-likelihood ratio back from its score 1 / (1 + exp(-LLR))
        llr = np.log(d.scores) - np.log1p(-np.minimum(d.scores, 1 - 1e-16))
        dets[k] = (d.boxes, llr if detector == "active_basis" else d.scores)
        rows = seq.gt.rows_of(k)
        gts[k] = seq.gt.table.boxes[rows[seq.gt.table.conf[rows] > 0]]  # as occbench detect
    return dets, gts


def score(dets: dict, gts: dict, frames: tuple[int, int], threshold: float | None) -> tuple:
    tp = nd = ng = 0
    for k in range(frames[0], frames[1] + 1):
        if k not in dets:
            continue
        b, s = dets[k]
        if threshold is not None:
            b = b[s >= threshold]
        g = gts[k]
        tp += match_count(g, b)
        nd += len(b)
        ng += len(g)
    p, r = tp / max(nd, 1), tp / max(ng, 1)
    return p, r, 2 * p * r / max(p + r, 1e-9), tp, nd - tp, ng - tp


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--thresholds", type=float, nargs="*", default=[])
    ap.add_argument("--report", action="store_true", help="also score the reporting ranges")
    ap.add_argument("--set", nargs="*", default=[], help="detector.detector.<key>=<value> overrides")
    ap.add_argument("--silhouette", action="store_true", help="score the silhouette matcher too")
    a = ap.parse_args()
    rows = []
    for folder, choose, report in SETS:
        ranges = [("choose", choose)] + ([("report", report)] if a.report else [])
        t0 = time.process_time()
        dets, gts = run(folder, "active_basis", a.set)
        cpu = (time.process_time() - t0) / max(len(dets), 1)
        ths = a.thresholds or [None]
        for name, fr in ranges:
            for th in ths:
                rows.append((folder, name, fr, f"active_basis T={th}", score(dets, gts, fr, th), cpu))
        if a.silhouette:
            dets, gts = run(folder, "silhouette", [])
            for name, fr in ranges:
                rows.append((folder, name, fr, "silhouette", score(dets, gts, fr, None), 0.0))
    print(f"overrides: {a.set}")
    print("| sequence | set | frames | detector | P / R / F1 | TP / FP / FN | CPU s/frame |")
    print("|---|---|---|---|---|---|---|")
    for folder, name, fr, det, (p, r, f1, tp, fp, fn), cpu in rows:
        print(f"| {folder} | {name} | {fr[0]}-{fr[1]} | {det} | {p:.3f} / {r:.3f} / {f1:.3f} | "
              f"{tp} / {fp} / {fn} | {cpu:.2f} |")


if __name__ == "__main__":
    main()
