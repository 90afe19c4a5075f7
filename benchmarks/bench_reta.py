"""Benchmark of the three-hypothesis tracker (Reta et al. 2015): speed and accuracy.

Speed: time of ``RetaTracker.update`` (its feature extraction included; frame decoding,
rendering and background subtraction excluded) with N people walking and crossing at
640x480 on one core (``cv2.setNumThreads(1)``, BLAS threads 1), for N = 10, 40, 100
(``--people``); the targets are at least 1,000 frames/s with 10 people, 500 with 40 and
500 with 100 (issue 38); ``--size 1920x1080`` renders the same kind of scene at that size (people
scaled with the frame height; target 50 frames/s with 150 people). Frames are pre-rendered with OpenCV (coloured ellipses on a noisy background,
drawn far to near) and the detections are the boxes of people at least 30 % visible. Per
number of people: the median of ``--repeats`` runs, the time in units of a reference
workload run in the same process, and the CPU time of each step of Alg. 1 (one more,
instrumented run; ``tracker_timing``). ``--check [DIGESTS.json]`` prints the sha256 of the
reported rows (and writes or compares the file): a speed-up must leave them unchanged.
``--vs CHECKOUT`` times this tree's tracker against another checkout's ``three_hypothesis``
(``tracker_timing.import_other``) in this process, on the same scene, ``--rounds`` rounds in
turn ABBA: frames/s of both and the ratio of their median times, and whether their rows agree.
``--instructions`` counts instead of timing (valgrind's callgrind, ``tracker_timing.instructions``;
the count does not move with the machine's load): per number of people, the scene of
``--frames`` frames run to its half and to its end, each in its own process under callgrind,
and the difference over the second half's frames is the instructions a frame of ``update``
(start-up, rendering and the first half cancel out); with ``--vs CHECKOUT`` the other
checkout's too (the whole checkout first on ``PYTHONPATH``) and the ratio (this tree's / the
other's). Each tree runs the scene once outside valgrind first, so numba's cache is warm;
numba compiles for a generic x86-64 there and under valgrind (``NUMBA_CPU_NAME=generic``:
valgrind's CPU looks different from the host's, and with the host's name every kernel was
compiled again under it, some 20e9 instructions a run). Use some 40 frames
(``--frames 40``): a counted run of 40 frames at 100 people takes minutes.

Accuracy: IDF1 and HOTA (``occbench.metrics``) of reta and the baseline on the synthetic
suite (``occbench.datasets.synthetic.load_suite``) with ``NoisyGroundTruth`` detections
(miss rate 0 and 0.3), and on CAVIAR OneLeaveShop1cor (noisy gt, miss 0.3, seed 0) when
the data root (``occbench.config.paths``: shipped, or $OCCBENCH_DATA) holds it.

Usage: ``python benchmarks/bench_reta.py [--speed-only | --accuracy-only] [--frames N]
[--people 10 40 100] [--size 640x480] [--repeats 3] [--check [DIGESTS.json]]
[--vs CHECKOUT [--rounds 3]] [--instructions [--vs CHECKOUT]]``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse
import importlib
import statistics
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from functools import partial
from pathlib import Path

import cv2
import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from tracker_timing import (StageClock, check_digests, cpu_seconds, frame_size, import_other,
                            instructions, paired_seconds, reference_seconds, rows_digest)

from occbench.config.paths import data_path
from occbench.trackers.baseline import BaselineTracker
from occbench.trackers import three_hypothesis
from occbench.trackers.records import Detections
from occbench.trackers.three_hypothesis import Appearance, RetaTracker

WIDTH, HEIGHT = 640, 480


def make_scene(people: int, frames: int, seed: int = 0, size: tuple[int, int] = (WIDTH, HEIGHT)
               ) -> list[tuple[np.ndarray, Detections]]:
    """Pre-rendered frames and exact detections of ``people`` walkers on a ``size`` (width,
    height) frame; at 640x480 the scene of every earlier run, elsewhere the same scene with
    rows, sizes and speeds scaled by height / 480 and columns by width / 640."""
    W, H = size
    sy, sx = H / 480, W / 640
    rng = np.random.default_rng(seed)
    bottom = rng.uniform(200, 470, people) * sy
    height = 60 * sy + (bottom - 200 * sy) * 0.5
    width = height * 0.4
    x = rng.uniform(0, W, people)
    vx = rng.choice([-1, 1], people) * rng.uniform(1.0, 3.0, people) * sx
    colours = rng.integers(30, 230, (people, 2, 3))
    out = []
    for _ in range(frames):
        img = np.full((H, W, 3), 100, np.uint8)
        img += rng.integers(0, 8, img.shape, dtype=np.uint8)
        label = np.zeros((H, W), np.int32)
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
        inside = (x > 0) & (x < W)
        keep = (visible >= 0.3) & inside
        out.append((img, Detections(boxes[keep], np.ones(int(keep.sum())))))
        x = x + vx
        vx = np.where((x < -20) | (x > W + 20), -vx, vx)
    return out


RETA_STAGES = {
    "tracker": ("measure", "predict", "occlusions", "max_similarity", "sort_occlusions",
                "update_matched", "continue_unmatched", "prune", "start_tracks", "outputs"),
    "steps_update": ("add_node", "add_nodes", "_visible_share", "_confirm"),
    "steps_hypotheses": ("add_nodes", "_hidden_share"),
    "steps_output": ("_tracks", "_place_hidden"),
}
"""RetaTracker's steps of Alg. 1 (its module docstring), timed one by one in ``stages``, and
the helpers they call per node or per frame (a graph node, a Track, ``rules.velocity``, the
covered shares, a confirmation): their time is not their callers'. Each by the module of
``three_hypothesis`` that calls it by name (where it is wrapped)."""
TARGETS = {10: 1000, 40: 500, 100: 500}
"""frames/s targets of RetaTracker.update per number of people (640x480; issue 23, 100 people
raised by issue 38)."""
TARGETS_HD = {150: 50}
"""frames/s targets at 1920x1080 (issue 38)."""


def speed(people_counts=(10, 40, 100), frames: int = 300, repeats: int = 3,
          pixel_stride: int = 1, size: tuple[int, int] = (WIDTH, HEIGHT)
          ) -> tuple[pd.DataFrame, dict[str, str], dict[int, str]]:
    """Frames/s of ``RetaTracker.update`` (median of ``repeats`` timed runs after one untimed,
    whose reported rows give the digest) per number of people, with
    the histograms of every ``pixel_stride``-th pixel row and column (``Appearance``).

    Time is the process's CPU time (``time.process_time``), so other jobs sharing the
    machine count less; ``reference`` is the median time of ``reference_seconds`` in the
    same process, ``ref_units`` the time per frame in units of it (comparable across runs
    on a loaded machine). Returns the table, the digest of the reported rows per number of
    people, and per number of people the stage table of one more (instrumented) run."""
    cv2.setNumThreads(1)
    rows, digests, stage_tables = [], {}, {}
    for n in people_counts:
        scene = make_scene(n, frames, seed=n, size=size)

        def run(tracker, scene=scene):
            return [tracker.update(img, dets) for img, dets in scene]

        def build():
            return RetaTracker(appearance=Appearance(pixel_stride=pixel_stride))

        key = f"reta people={n}" + ("" if size == (WIDTH, HEIGHT) else f" {size[0]}x{size[1]}")
        # the digest's run first, untimed: a process's first run also loads the compiled kernels
        digests[key] = rows_digest(run(build()))
        times = [cpu_seconds(lambda: run(build())) for _ in range(repeats)]
        clock, tracker = StageClock(), build()
        for module, names in RETA_STAGES.items():
            for name in names:
                clock.wrap(importlib.import_module(f"{three_hypothesis.__name__}.{module}"), name)
        total = cpu_seconds(lambda t=tracker: run(t))
        clock.unwrap()
        stage_tables[n] = clock.table(total, frames)
        tb = statistics.median(cpu_seconds(lambda: run(BaselineTracker())) for _ in range(repeats))
        ref = reference_seconds()
        med = statistics.median(times)
        rows.append({"people": n, "detections": np.mean([len(d) for _, d in scene]),
                     "reta_fps": frames / med, "reta_fps_min": frames / max(times),
                     "reta_ms_per_frame": 1e3 * med / frames, "ref_units": med / frames / ref,
                     "baseline_fps": frames / tb})
    return pd.DataFrame(rows), digests, stage_tables


def versus(other, people_counts=(100,), frames: int = 150, rounds: int = 3,
           size: tuple[int, int] = (WIDTH, HEIGHT)) -> pd.DataFrame:
    """This tree's ``RetaTracker`` against ``other`` (another checkout's ``three_hypothesis``
    module, ``tracker_timing.import_other``) per number of people: the same scene, each run
    once untimed, then ``rounds`` timed rounds in turn (``paired_seconds``); frames/s of the
    median times, ``ratio`` = this tree's median time / the other's (below 1: this tree is
    faster), the range of the rounds' ratios, and whether the reported rows are the same."""
    cv2.setNumThreads(1)
    rows = []
    trackers = {"this": RetaTracker, "other": other.RetaTracker}
    for n in people_counts:
        scene = make_scene(n, frames, seed=n, size=size)

        def run(label, scene=scene):
            tracker = trackers[label]()
            return [tracker.update(img, dets) for img, dets in scene]

        same = rows_digest(run("this")) == rows_digest(run("other"))
        seconds = paired_seconds({label: partial(run, label) for label in trackers}, rounds)
        this, that = statistics.median(seconds["this"]), statistics.median(seconds["other"])
        pairs = [a / b for a, b in zip(seconds["this"], seconds["other"])]
        rows.append({"people": n, "this_fps": frames / this, "other_fps": frames / that,
                     "ratio": this / that, "ratio_min": min(pairs), "ratio_max": max(pairs),
                     "same_rows": same})
    return pd.DataFrame(rows)


def run_frames(tracker_class, people: int, frames: int, upto: int,
               size: tuple[int, int] = (WIDTH, HEIGHT)) -> list:
    """``tracker_class()``'s reported rows over the first ``upto`` frames of the scene of
    ``frames`` frames (all of them rendered, whatever ``upto``)."""
    cv2.setNumThreads(1)
    scene = make_scene(people, frames, seed=people, size=size)
    tracker = tracker_class()
    return [tracker.update(img, dets) for img, dets in scene[:upto]]


def instructions_per_frame(people_counts=(10, 40, 100), frames: int = 40,
                           size: tuple[int, int] = (WIDTH, HEIGHT), other: Path | None = None
                           ) -> pd.DataFrame:
    """Instructions a frame of ``RetaTracker.update`` per number of people: this script run
    (``--instructions-upto``) over the scene to ``frames // 2`` and to ``frames`` under
    callgrind, the difference over the ``frames - frames // 2`` frames between; with
    ``other`` (a checkout with ``occbench`` linked to its ``harness``, as for a frozen copy)
    the same runs with the other checkout first on ``PYTHONPATH``, so that all of its code
    runs (``trackers/common`` too, which ``--vs``'s timing takes from this tree), and
    ``ratio`` = this tree's instructions a frame / the other's. The counted runs of a
    number of people run at once (the counts do not depend on it)."""
    half = frames // 2
    if half < 1:
        raise ValueError(f"--instructions needs at least 2 frames, got {frames}")
    trees: dict[str, dict[str, str]] = {"this": {}}
    if other is not None:
        trees["other"] = {"PYTHONPATH": os.pathsep.join(
            [str(Path(other).resolve()), *filter(None, [os.environ.get("PYTHONPATH")])])}
    rows = []
    for n in people_counts:
        def argv(upto):
            return [sys.executable, str(Path(__file__).resolve()), "--people", str(n),
                    "--frames", str(frames), "--size", f"{size[0]}x{size[1]}",
                    "--instructions-upto", str(upto)]

        envs = {label: {"NUMBA_CPU_NAME": "generic", **extra} for label, extra in trees.items()}
        for label, env in envs.items():  # numba's cache warm
            ran = Path(subprocess.run(argv(frames), check=True, env={**os.environ, **env},
                                      capture_output=True, text=True).stdout.splitlines()[0])
            tree = ROOT if label == "this" else Path(other).resolve()
            if not ran.is_relative_to(tree):
                raise RuntimeError(f"{label} ran {ran}, not {tree}'s tracker (--vs needs a "
                                   f"checkout with occbench linked to its harness)")
        with ThreadPoolExecutor(2 * len(envs)) as pool:
            counts = {(label, upto): pool.submit(instructions, argv(upto), env)
                      for label, env in envs.items() for upto in (half, frames)}
        row: dict[str, object] = {"people": n}
        for label in envs:
            row[f"{label}_per_frame"] = ((counts[label, frames].result()
                                          - counts[label, half].result()) / (frames - half))
        if other is not None:
            row["ratio"] = row["this_per_frame"] / row["other_per_frame"]
        rows.append(row)
    return pd.DataFrame(rows)


def accuracy(miss_rates=(0.0, 0.3)) -> pd.DataFrame:
    """IDF1 / HOTA / MOTA / IDs of reta and baseline on the synthetic suite and CAVIAR."""
    from occbench import metrics
    from occbench.datasets.synthetic import load_suite
    from occbench.pipeline.loop import run_sequence
    from occbench.pipeline.record import score
    from occbench.sources.annotations import NoisyGroundTruth

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
        from occbench.datasets.caviar import load_caviar

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
    parser.add_argument("--people", type=int, nargs="+", default=[10, 40, 100],
                        help="numbers of people of the speed runs")
    parser.add_argument("--repeats", type=int, default=3, help="speed runs; the median is shown")
    parser.add_argument("--size", type=frame_size, default=(WIDTH, HEIGHT), metavar="WxH",
                        help="frame size of the speed runs (default 640x480; 1920x1080: HD)")
    parser.add_argument("--check", type=Path, nargs="?", const=None, default=False,
                        metavar="DIGESTS.json",
                        help="print the sha256 of the reported rows; with a file: write it when "
                             "absent, else compare (exit 1 when they differ)")
    parser.add_argument("--vs", type=Path, metavar="CHECKOUT",
                        help="time against another checkout's three_hypothesis in this process")
    parser.add_argument("--rounds", type=int, default=3, help="--vs: rounds of each, in turn")
    parser.add_argument("--instructions", action="store_true",
                        help="instructions a frame under callgrind (with --vs: and the ratio)")
    parser.add_argument("--instructions-upto", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.instructions_upto is not None:  # one process counted by --instructions
        print(Path(three_hypothesis.__file__).resolve().parent)  # whose tracker ran
        run_frames(RetaTracker, args.people[0], args.frames, args.instructions_upto, args.size)
        return 0
    if args.instructions:
        table = instructions_per_frame(args.people, args.frames, args.size, args.vs)
        print(f"Instructions a frame of RetaTracker.update under callgrind ({args.size[0]}x"
              f"{args.size[1]}, frames {args.frames // 2 + 1}-{args.frames} of {args.frames}"
              + (f"; ratio: this tree's / {args.vs}'s" if args.vs else "") + ")")
        print(table.to_string(index=False, float_format=lambda v: f"{v:.4f}" if v < 10 else f"{v:,.0f}"))
        return 0
    pd.set_option("display.width", 160)
    status = 0
    if args.vs is not None:
        other = import_other(args.vs, three_hypothesis.__name__, "reta_vs")
        print(f"load average (uptime): {os.getloadavg()}; this: {ROOT}, other: {args.vs}")
        table = versus(other, args.people, args.frames, args.rounds, args.size)
        print(f"RetaTracker.update, this tree against the other ({args.size[0]}x{args.size[1]}, "
              f"{args.frames} frames, {args.rounds} rounds in turn ABBA, CPU time; ratio: this "
              f"tree's median time / the other's)")
        print(table.to_string(index=False, float_format=lambda v: f"{v:.3f}" if v < 10 else f"{v:.1f}"))
        print(f"load average after: {os.getloadavg()}")
        return 0
    if not args.accuracy_only:
        print(f"load average (uptime): {os.getloadavg()}")
        table, digests, stages = speed(args.people, args.frames, args.repeats, args.pixel_stride,
                                       args.size)
        print("Speed of RetaTracker.update (CPU time, median of "
              f"{args.repeats}), {args.size[0]}x{args.size[1]}, one core, "
              f"pixel_stride={args.pixel_stride}; "
              f"ref_units: ms per frame / the reference workload's ms")
        print(table.to_string(index=False, float_format=lambda v: f"{v:.3f}" if v < 1 else f"{v:.1f}"))
        for people in args.people:
            print(f"stages at {people} people (one instrumented run, exclusive CPU time):")
            print(stages[people])
        for people, target in (TARGETS if args.size == (WIDTH, HEIGHT) else TARGETS_HD).items():
            if people in args.people:
                fps = table.loc[table.people == people, "reta_fps"].iloc[0]
                print(f"{people} people: {fps:.0f} frames/s -> target {target}: "
                      f"{'met' if fps >= target else 'NOT met'}")
        if args.check is not False and not check_digests(args.check, digests):
            status = 1
    if not args.speed_only:
        acc = accuracy()
        combined = acc[acc.sequence == "COMBINED"].drop(columns="sequence")
        print("\nAccuracy (COMBINED rows)")
        print(combined.to_string(index=False, float_format=lambda v: f"{v:.3f}"))
        print("\nPer sequence IDF1")
        print(acc.pivot_table(index=["data", "miss", "sequence"], columns="tracker",
                              values=["IDF1", "HOTA"]).to_string(float_format=lambda v: f"{v:.3f}"))
    return status


if __name__ == "__main__":
    raise SystemExit(main())
