"""Benchmark of the three-hypothesis tracker (Reta et al. 2015): speed and accuracy.

Speed: time of ``RetaTracker.update`` (its feature extraction included; frame decoding,
rendering and background subtraction excluded) with N people walking and crossing at
640x480 on one core (``cv2.setNumThreads(1)``, BLAS threads 1), for N = 5, 10, 20, 40;
the targets are at least 1,000 frames/s with 10 people and 500 with 40. Frames are pre-rendered with
OpenCV (coloured ellipses on a noisy background, drawn far to near) and the detections
are the boxes of people at least 30 % visible.

Accuracy: IDF1 and HOTA (``harness.metrics``) of reta and the baseline on the synthetic
suite (``harness.datasets.synthetic.load_suite``) with ``NoisyGroundTruth`` detections
(miss rate 0 and 0.3), and on CAVIAR OneLeaveShop1cor (noisy gt, miss 0.3, seed 0) when
the data root (``harness.paths``: shipped, or $OCCBENCH_DATA) holds it.

Usage: ``python benchmarks/bench_reta.py [--speed-only | --accuracy-only] [--frames N]``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from harness.paths import data_path
from trackers.baseline import BaselineTracker
from trackers.records import Detections
from trackers.three_hypothesis import Appearance, RetaTracker

WIDTH, HEIGHT = 640, 480


def make_scene(people: int, frames: int, seed: int = 0) -> list[tuple[np.ndarray, Detections]]:
    """Pre-rendered frames and exact detections of ``people`` walkers at 640x480."""
    rng = np.random.default_rng(seed)
    bottom = rng.uniform(200, 470, people)
    height = 60 + (bottom - 200) * 0.5
    width = height * 0.4
    x = rng.uniform(0, WIDTH, people)
    vx = rng.choice([-1, 1], people) * rng.uniform(1.0, 3.0, people)
    colours = rng.integers(30, 230, (people, 2, 3))
    out = []
    for _ in range(frames):
        img = np.full((HEIGHT, WIDTH, 3), 100, np.uint8)
        img += rng.integers(0, 8, img.shape, dtype=np.uint8)
        label = np.zeros((HEIGHT, WIDTH), np.int32)
        boxes = np.column_stack([x - width / 2, bottom - height, width, height])
        for k in np.argsort(bottom):
            cx, cy = int(x[k]), int(bottom[k] - height[k] / 2)
            axes = (int(width[k] / 2), int(height[k] / 2))
            cv2.ellipse(img, (cx, cy), axes, 0, 0, 360, colours[k, 1].tolist(), -1)
            cv2.ellipse(img, (cx, cy - axes[1] // 2), (axes[0], axes[1] // 2), 0, 0, 360,
                        colours[k, 0].tolist(), -1)
            cv2.ellipse(label, (cx, cy), axes, 0, 0, 360, int(k + 1), -1)
        area = np.pi * (width / 2) * (height / 2)
        visible = np.bincount(label.ravel(), minlength=people + 1)[1:] / area
        inside = (x > 0) & (x < WIDTH)
        keep = (visible >= 0.3) & inside
        out.append((img, Detections(boxes[keep], np.ones(int(keep.sum())))))
        x = x + vx
        vx = np.where((x < -20) | (x > WIDTH + 20), -vx, vx)
    return out


def speed(people_counts=(5, 10, 20, 40), frames: int = 300, repeats: int = 3,
          pixel_stride: int = 1) -> pd.DataFrame:
    """Frames/s of ``RetaTracker.update`` (best of ``repeats``) per number of people, with
    the histograms of every ``pixel_stride``-th pixel row and column (``Appearance``).

    Time is the process's CPU time (``time.process_time``), so other jobs sharing the
    machine do not count; on an idle machine it equals wall time for this one thread."""
    cv2.setNumThreads(1)
    rows = []
    for n in people_counts:
        scene = make_scene(n, frames, seed=n)
        best = np.inf
        for _ in range(repeats):
            tracker = RetaTracker(appearance=Appearance(pixel_stride=pixel_stride))
            t0 = time.process_time()
            for img, dets in scene:
                tracker.update(img, dets)
            best = min(best, time.process_time() - t0)
        base = BaselineTracker()
        t0 = time.process_time()
        for img, dets in scene:
            base.update(img, dets)
        tb = time.process_time() - t0
        rows.append({"people": n, "reta_fps": frames / best, "reta_ms_per_frame": 1e3 * best / frames,
                     "baseline_fps": frames / tb})
    return pd.DataFrame(rows)


def accuracy(miss_rates=(0.0, 0.3)) -> pd.DataFrame:
    """IDF1 / HOTA / MOTA / IDs of reta and baseline on the synthetic suite and CAVIAR."""
    from harness import metrics
    from harness.datasets.synthetic import load_suite
    from harness.pipeline.experiment import run_sequence, score
    from harness.sources.annotations import NoisyGroundTruth

    rows = []

    def run(label: str, sequences, miss: float) -> None:
        scores: dict[str, dict] = {"reta": {}, "baseline": {}}
        for seq in sequences:
            out = run_sequence({"reta": RetaTracker(), "baseline": BaselineTracker()}, seq,
                               NoisyGroundTruth(miss_rate=miss, seed=0))
            for name, o in out.items():
                if o.error:
                    raise RuntimeError(f"{name} failed on {seq.info.name}: {o.error}")
                scores[name][seq.info.name] = score(seq.gt, o.table)
        for name, sc in scores.items():
            df = metrics.summarize(sc).set_index("sequence")
            for seq_name, row in df.iterrows():
                rows.append({"data": label, "miss": miss, "sequence": seq_name, "tracker": name,
                             **{k: row[k] for k in ("IDF1", "HOTA", "MOTA", "IDs", "Frag", "FP", "FN")}})

    suite = load_suite()
    for miss in miss_rates:
        run("synthetic", suite, miss)
    caviar = data_path("CAVIAR-OneLeaveShop1cor")
    if caviar.is_dir():
        from harness.datasets.caviar import load_caviar

        run("caviar", load_caviar(str(caviar)), 0.3)
    else:
        print(f"CAVIAR skipped: {caviar} not found")
    return pd.DataFrame(rows)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--speed-only", action="store_true")
    parser.add_argument("--accuracy-only", action="store_true")
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--pixel-stride", type=int, default=1,
                        help="Appearance.pixel_stride of the speed run (1 = exact eq. 1)")
    args = parser.parse_args(argv)
    pd.set_option("display.width", 160)
    if not args.accuracy_only:
        table = speed(frames=args.frames, pixel_stride=args.pixel_stride)
        print("Speed of RetaTracker.update (CPU time), 640x480, one core, pixel_stride="
              f"{args.pixel_stride} (targets >= 1000 frames/s at 10 people, >= 500 at 40)")
        print(table.to_string(index=False, float_format=lambda v: f"{v:.1f}"))
        for people, target in ((10, 1000), (40, 500)):
            fps = table.loc[table.people == people, "reta_fps"].iloc[0]
            print(f"{people} people: {fps:.0f} frames/s -> target {target}: "
                  f"{'met' if fps >= target else 'NOT met'}")
    if not args.speed_only:
        acc = accuracy()
        combined = acc[acc.sequence == "COMBINED"].drop(columns="sequence")
        print("\nAccuracy (COMBINED rows)")
        print(combined.to_string(index=False, float_format=lambda v: f"{v:.3f}"))
        print("\nPer sequence IDF1")
        print(acc.pivot_table(index=["data", "miss", "sequence"], columns="tracker",
                              values=["IDF1", "HOTA"]).to_string(float_format=lambda v: f"{v:.3f}"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
