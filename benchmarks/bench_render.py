"""Frames per second of the synthetic renderer on one core.

Renders the ``crowd`` preset (10 people, 640x480, sensor noise and illumination drift on)
with ``cv2.setNumThreads(1)``; every frame is rendered once (no cache hits). Target: at
least 200 frames/s. Also times the label-only ground-truth pass.

    .venv/bin/python benchmarks/bench_render.py [--frames 300] [--people 10]
"""

from __future__ import annotations

import argparse
import time

import cv2

from occbench.datasets.synthetic import load_scenario


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--people", type=int, default=10)
    ap.add_argument("--width", type=int, default=640)
    ap.add_argument("--height", type=int, default=480)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    cv2.setNumThreads(1)
    seq = load_scenario(
        "crowd",
        seed=args.seed,
        width=args.width,
        height=args.height,
        length=args.frames,
        people=args.people,
        noise=2.0,
        illumination=0.1,
    )
    seq.frame(1)  # warm-up: noise bank
    n = args.frames - 1
    t0, c0 = time.perf_counter(), time.process_time()
    for k in range(2, args.frames + 1):
        seq.frame(k)
    dt, dc = time.perf_counter() - t0, time.process_time() - c0
    drawn = sum(len(seq._present(k - 1)) for k in range(2, args.frames + 1)) / n
    t1 = time.perf_counter()
    gt = seq.gt
    dg = time.perf_counter() - t1
    print(
        f"render: {n / dt:.1f} frames/s wall clock, {n / dc:.1f} frames/s of process CPU time "
        f"({args.width}x{args.height}, {drawn:.1f} people drawn per frame, one thread, "
        "noise + illumination on; wall clock < CPU when other processes share the cores)"
    )
    print(f"ground truth pass: {args.frames / dg:.1f} frames/s ({len(gt.table)} rows)")


if __name__ == "__main__":
    main()
