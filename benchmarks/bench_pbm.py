"""PBM tracker: speed (tracker only) and accuracy against the SORT-like baseline.

Speed: the ``crowd`` preset (10, 40 and 100 people, ``--people``; 640x480) is rendered once
into memory with exact detections (the gt boxes of people at least 30% visible) and the
exact person mask (bool, as the harness hands it to trackers); then only
``PBMTracker.update`` is timed, on one core (``cv2.setNumThreads(1)``), with the foreground
mask and without it (detection boxes as candidates), as CPU time (``time.process_time``,
median of ``--repeats`` runs, and in units of a reference workload run in the same process:
the machine may be shared), with the CPU time of each step (one more, instrumented run;
``tracker_timing``). Targets (foreground mask): >= 1,000 frames/s at 10 people, >= 200 at
100. ``--check [DIGESTS.json]`` prints the sha256 of the reported rows (and writes or
compares the file): a speed-up must leave them unchanged. ``--vs CHECKOUT`` times this tree's
tracker against another checkout's ``trackers/layered`` (``tracker_timing.import_other``, built
from that checkout's ``conf/tracker/pbm.yaml``) in this process, on the same scene, with and
without the mask, ``--rounds`` rounds in turn ABBA: frames/s of both, the ratio of their
median times and whether their rows agree.

Accuracy: IDF1, HOTA, MOTA, IDs and Frag of ``pbm`` and ``baseline`` (both with their
``conf/tracker`` defaults) on the synthetic suite and on the shipped CAVIAR OneLeaveShop1cor, with ``NoisyGroundTruth(miss_rate, seed)`` detections.

    .venv/bin/python benchmarks/bench_pbm.py [--speed-frames 300] [--repeats 3] [--miss 0.3]
        [--seed 0] [--skip-speed] [--skip-accuracy] [--length 150] [--people 10 40 100]
        [--check [DIGESTS.json]] [--vs CHECKOUT [--rounds 3]]
"""

from __future__ import annotations

import argparse
import logging
import os
import statistics
from functools import partial
from pathlib import Path

import cv2
import numpy as np
import pandas as pd
from hydra.utils import instantiate
from omegaconf import OmegaConf
from tracker_timing import (StageClock, check_digests, cpu_seconds, frame_size, import_other,
                            paired_seconds, reference_seconds, rows_digest)

from occbench.datasets.synthetic import DEFAULT_SCENARIOS, load_scenario, load_suite
from occbench.config.paths import data_path
from occbench.pipeline.loop import run_sequence
from occbench.pipeline.record import score
from occbench.pipeline.summary import summary_rows
from occbench.sources.annotations import NoisyGroundTruth
from occbench.config.meta import without_meta
from occbench.trackers import layered

ROOT = Path(__file__).resolve().parents[1]
CAVIAR = data_path("CAVIAR-OneLeaveShop1cor")
SHOWN = ["IDF1", "HOTA", "MOTA", "IDs", "Frag", "Recall", "Precision"]


def build(name: str):
    return instantiate(without_meta(OmegaConf.load(ROOT / "conf" / "tracker" / f"{name}.yaml")))


PBM_STAGES = (("_find_candidates", "candidates + features"), ("_score_in_gates", "gating"),
              ("_search_occluded", "search (3.1; its boxes' 2.2, 11-13)"),
              ("_pruning", "response pruning (4.1)"), ("_update_models", "model update (4.2)"),
              ("_end_targets", "end targets"), ("_start_targets", "start targets"),
              ("_report", "report"))
"""PBMTracker's steps (its module docstring), timed one by one in ``stages``."""
TARGETS = {10: 1000, 100: 200}
"""frames/s targets of PBMTracker.update (with the foreground mask) per number of people."""
TARGETS_HD = {150: 50}
"""frames/s targets at 1920x1080 (issue 38)."""
SIZE = (640, 480)


def scene(frames: int, people: int, seed: int, size: tuple[int, int] = SIZE) -> list[tuple]:
    """The ``crowd`` preset rendered once at ``size`` (width, height): (image, exact
    detections, exact person mask)."""
    seq = load_scenario("crowd", seed=seed, length=frames, people=people, width=size[0],
                        height=size[1])
    src = NoisyGroundTruth(seed=seed)
    src.start(seq)
    data = []
    for k in range(1, frames + 1):
        img = seq.frame(k)
        dets, _ = src.detect(k, img)
        data.append((img, dets, seq.foreground(k) != 0))  # the harness's exact person mask
    return data


def speed(frames: int, people: int, seed: int, repeats: int = 3,
          size: tuple[int, int] = SIZE) -> tuple[list[dict], dict, dict]:
    """Frames/s of ``PBMTracker.update`` with and without the foreground mask (median of
    ``repeats`` timed runs after one untimed, whose reported rows give the digest) and the
    stage table of one more, instrumented run, per mode."""
    data = scene(frames, people, seed, size)
    at = "" if size == SIZE else f" {size[0]}x{size[1]}"
    rows, digests, stages = [], {}, {}
    for label, use_fg in (("foreground mask", True), ("no foreground", False)):
        def run(tracker, use_fg=use_fg):
            return [tracker.update(img, dets, fg if use_fg else None) for img, dets, fg in data]

        # the digest's run first, untimed: a process's first run also loads the compiled kernels
        digests[f"pbm people={people} {label}{at}"] = rows_digest(run(build("pbm")))
        times = [cpu_seconds(lambda: run(build("pbm"))) for _ in range(repeats)]
        clock, tracker = StageClock(), build("pbm")
        for attr, name in PBM_STAGES:
            clock.wrap(tracker, attr, name)
        clock.wrap(tracker.targets, "predict", "predict (eqs. 7-8)")
        clock.wrap(tracker._scores, "pairs", "scores (eqs. 11-13)")
        clock.wrap(tracker._search_extractor, "extract", "search: best boxes' features")
        stages[label] = clock.table(cpu_seconds(lambda t=tracker: run(t)), frames)
        med = statistics.median(times)
        rows.append({"people": people, "mode": label,
                     "detections": np.mean([len(d) for _, d, _ in data]),
                     "fps": frames / med, "fps_min": frames / max(times),
                     "ms_per_frame": 1e3 * med / frames,
                     "ref_units": med / frames / reference_seconds()})
    return rows, digests, stages


def other_builder(tree: Path, alias: str = "pbm_vs"):
    """A builder of another checkout's ``pbm`` (``tree``'s ``trackers/layered`` imported as
    ``alias``, ``tracker_timing.import_other``; its ``conf/tracker/pbm.yaml`` with the
    package's ``_target_`` names renamed to it)."""
    module = import_other(tree, layered.__name__, alias)
    text = (Path(tree) / "conf" / "tracker" / "pbm.yaml").read_text()
    cfg = without_meta(OmegaConf.create(text.replace(layered.__name__, alias)))
    if OmegaConf.select(cfg, "_target_") != f"{alias}.PBMTracker":
        raise ValueError(f"{tree}/conf/tracker/pbm.yaml does not build {layered.__name__}.PBMTracker")
    return module, lambda: instantiate(cfg)


def versus(build_other, people: int, frames: int, rounds: int, seed: int = 0,
           size: tuple[int, int] = SIZE) -> list[dict]:
    """This tree's ``pbm`` against ``build_other()`` (``other_builder``) on one scene, with and
    without the mask: each run once untimed, then ``rounds`` timed rounds in turn
    (``paired_seconds``); frames/s of the median times, ``ratio`` = this tree's median time /
    the other's (below 1: this tree is faster), the rounds' range and whether the rows agree."""
    data = scene(frames, people, seed, size)
    builders = {"this": partial(build, "pbm"), "other": build_other}
    rows = []
    for label, use_fg in (("foreground mask", True), ("no foreground", False)):
        def run(which, use_fg=use_fg):
            tracker = builders[which]()
            return [tracker.update(img, dets, fg if use_fg else None) for img, dets, fg in data]

        same = rows_digest(run("this")) == rows_digest(run("other"))
        seconds = paired_seconds({which: partial(run, which) for which in builders}, rounds)
        this, that = statistics.median(seconds["this"]), statistics.median(seconds["other"])
        pairs = [a / b for a, b in zip(seconds["this"], seconds["other"])]
        rows.append({"people": people, "mode": label, "this_fps": frames / this,
                     "other_fps": frames / that, "ratio": this / that, "ratio_min": min(pairs),
                     "ratio_max": max(pairs), "same_rows": same})
    return rows


def accuracy(sequences, miss: float, seed: int, foreground: str, title: str) -> pd.DataFrame:
    rows = []
    for seq in sequences:
        src = NoisyGroundTruth(miss_rate=miss, seed=seed)
        out = run_sequence({"baseline": build("baseline"), "pbm": build("pbm")}, seq, src,
                           foreground=foreground)
        for name, o in out.items():
            if o.error:
                raise RuntimeError(f"{name} failed on {seq.info.name}: {o.error}")
            rows.append((name, seq.info.name, score(seq.gt, o.table)))
    frames = []
    for name in ("baseline", "pbm"):
        frames.append(summary_rows(name, {s: sc for n, s, sc in rows if n == name}))
    table = pd.concat(frames, ignore_index=True)
    print(f"\n{title}")
    print(table[["tracker", "sequence", *SHOWN]].to_string(index=False, float_format=lambda v: f"{v:.3f}"))
    return table


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speed-frames", type=int, default=300)
    ap.add_argument("--people", type=int, nargs="+", default=[10, 40, 100],
                    help="numbers of people of the speed runs")
    ap.add_argument("--repeats", type=int, default=3, help="speed runs; the median is shown")
    ap.add_argument("--size", type=frame_size, default=SIZE, metavar="WxH",
                    help="frame size of the speed runs (default 640x480; 1920x1080: HD)")
    ap.add_argument("--length", type=int, default=150, help="frames per synthetic scene")
    ap.add_argument("--miss", type=float, default=0.3, help="noisy-gt miss rate")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--skip-speed", action="store_true")
    ap.add_argument("--skip-accuracy", action="store_true")
    ap.add_argument("--check", type=Path, nargs="?", const=None, default=False,
                    metavar="DIGESTS.json",
                    help="print the sha256 of the reported rows; with a file: write it when "
                         "absent, else compare (exit 1 when they differ)")
    ap.add_argument("--vs", type=Path, metavar="CHECKOUT",
                    help="time against another checkout's trackers/layered in this process")
    ap.add_argument("--rounds", type=int, default=3, help="--vs: rounds of each, in turn")
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING)
    cv2.setNumThreads(1)
    if args.vs is not None:
        _, build_other = other_builder(args.vs)
        print(f"load average (uptime): {os.getloadavg()}; this: {ROOT}, other: {args.vs}")
        rows = [r for people in args.people for r in versus(
            build_other, people, args.speed_frames, args.rounds, args.seed, args.size)]
        print(f"PBMTracker.update, this tree against the other ({args.size[0]}x{args.size[1]}, "
              f"{args.speed_frames} frames, {args.rounds} rounds in turn ABBA, CPU time; ratio: "
              "this tree's median time / the other's)")
        print(pd.DataFrame(rows).to_string(index=False, float_format=lambda v: f"{v:.3f}" if v < 10 else f"{v:.1f}"))
        print(f"load average after: {os.getloadavg()}")
        return
    if not args.skip_speed:
        print(f"load average (uptime): {os.getloadavg()}")
        rows, digests = [], {}
        for people in args.people:
            r, d, stages = speed(args.speed_frames, people, args.seed, args.repeats, args.size)
            rows += r
            digests.update(d)
            for label, table in stages.items():
                print(f"stages at {people} people, {label} (one instrumented run, exclusive CPU time):")
                print(table)
        table = pd.DataFrame(rows)
        print(f"Speed of PBMTracker.update (CPU time, median of {args.repeats}), crowd preset "
              f"{args.size[0]}x{args.size[1]}, one core; ref_units: ms per frame / the reference "
              "workload's ms")
        print(table.to_string(index=False, float_format=lambda v: f"{v:.3f}" if v < 1 else f"{v:.1f}"))
        for people, target in (TARGETS if args.size == SIZE else TARGETS_HD).items():
            if people in args.people:
                fps = table.loc[(table.people == people) & (table["mode"] == "foreground mask"), "fps"].iloc[0]
                print(f"{people} people, foreground mask: {fps:.0f} frames/s -> target {target}: "
                      f"{'met' if fps >= target else 'NOT met'}")
        if args.check is not False and not check_digests(args.check, digests):
            raise SystemExit(1)
    if args.skip_accuracy:
        return
    suite = load_suite(DEFAULT_SCENARIOS, seed=args.seed, length=args.length)
    for miss in sorted({0.0, args.miss}):
        accuracy(suite, miss, args.seed, "auto",
                 f"synthetic suite, noisy_gt miss {miss} seed {args.seed}, exact foreground")
    if CAVIAR.is_dir():
        from occbench.datasets.caviar import load_caviar

        cav = load_caviar(CAVIAR)
        for fg in ("none", "mog2"):
            accuracy(cav, args.miss, args.seed, fg,
                     f"CAVIAR OneLeaveShop1cor, noisy_gt miss {args.miss} seed {args.seed}, foreground {fg}")
    else:
        print(f"\nCAVIAR skipped: {CAVIAR} not found")


if __name__ == "__main__":
    main()
