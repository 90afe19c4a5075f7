"""``occbench bench``: frames per second of each stage, one core.

Stages, timed separately on the same frames:

* decode: ``Sequence.frame(k)`` (JPEG/video decoding; rendering for synthetic scenes);
* front end: the detection source's ``detect(k, frame)`` plus the foreground handed to the
  trackers (background subtraction, blobs, silhouette/HOG/head detection, or noisy gt);
  the per-sequence warm-up (``source.start``: the background learnt from frames sampled over
  the sequence) is not in it and is printed on its own line;
* for a front-end detector (``FrontendSource`` around a detector with a ``background`` and
  ``detect_on``), the same work stage by stage: ``background`` (the model's raw label image),
  ``cleaning`` (shadow removal and morphology), ``detector`` (blobs and the person search,
  ``detect_on``), ``hand-off`` (detection clean-up and the foreground handed to the trackers);
  and ``foreground only``: background, cleaning and connected-component blobs alone, the
  front end without a person detector, timed in the same run for comparison;
* tracker: each tracker's ``update`` on the cached detections and foreground.

Each stage is run ``--repeats`` times over the first ``--frames`` frames of the chosen
sequence and the median frames/s is reported (with the range). Times are the CPU time of the
benchmarking thread (``time.thread_time``; ``--clock wall`` for elapsed time), so that other
processes on a shared machine do not slow the figures down. Everything runs on one core:
OpenCV with ``cv2.setNumThreads(1)`` and the BLAS/OpenMP pools limited to one thread (set
before numpy is imported). Frames are held in memory between stages, so the tracker stage
measures the tracker alone. Speed targets belong in ``benchmarks/``; this tool only measures.

Examples::

    occbench bench                                   # synthetic suite, first sequence
    occbench bench --frames 150 --repeats 5 -- dataset=caviar detector=silhouette
    occbench bench --sequence crowd -- dataset=synthetic tracker=all
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse
import logging
import statistics
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import pandas as pd
from hydra.errors import HydraException

from occbench.commands.mistakes import explain, refuse
from occbench.config.build import (
    build_source,
    build_tracker,
    compose_config,
    load_sequences,
    tracker_choice,
    tracker_configs,
)
from occbench.pipeline.bank import TrackerBank
from occbench.pipeline.loop import ForegroundProvider, clean_detections, frames as frame_loop
from occbench.pipeline.warmup import warm_up_once
from occbench.progress import log_to_stderr, progress_factory
from occbench.trackers.frontend.blobs import blobs_from_mask

log = logging.getLogger(__name__)


@dataclass
class StageTiming:
    """Frames/s of one stage over the repeats."""

    stage: str
    frames: int
    seconds: list[float]

    @property
    def fps(self) -> list[float]:
        return [self.frames / s if s > 0 else float("inf") for s in self.seconds]

    def row(self) -> dict[str, Any]:
        fps = self.fps
        med = statistics.median(fps)
        return {"stage": self.stage, "frames": self.frames, "runs": len(fps),
                "fps_median": round(med, 2), "fps_min": round(min(fps), 2),
                "fps_max": round(max(fps), 2),
                "ms_per_frame": round(1000.0 / med, 3) if med > 0 else float("nan")}


CLOCKS: dict[str, Callable[[], float]] = {"cpu": time.thread_time, "wall": time.perf_counter}
_clock: Callable[[], float] = time.thread_time


def _time(fn: Callable[[], None]) -> float:
    t0 = _clock()
    fn()
    return _clock() - t0


class _Timed:
    """A stage object (the detector's shape verifier) that adds up the time of its calls
    and of its methods' calls."""

    def __init__(self, obj: Any) -> None:
        self._obj, self.seconds = obj, 0.0

    def _timed(self, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
        t0 = _clock()
        out = fn(*args, **kwargs)
        self.seconds += _clock() - t0
        return out

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return self._timed(self._obj, *args, **kwargs)

    def __getattr__(self, name: str) -> Any:
        attr = getattr(self._obj, name)
        if not callable(attr):
            return attr
        return lambda *args, **kwargs: self._timed(attr, *args, **kwargs)


def _staged_detector(source: Any) -> Any | None:
    """The detector inside a front-end source when its stages can be timed one by one."""
    det = getattr(source, "detector", None)
    bg = getattr(det, "background", None)
    if det is None or not hasattr(det, "detect_on") or not all(
            hasattr(bg, a) for a in ("raw", "clean")):
        return None
    return det


def bench_frontend_stages(sequence: Any, make_source: Callable[[], Any], images: Sequence[Any],
                          repeats: int = 3, foreground: str = "auto",
                          background: Mapping[str, Any] | None = None, bar: Any = None,
                          ) -> tuple[list[StageTiming], list[float]]:
    """Stage-by-stage timings of a front-end detector on ``images`` (frames 1..n), and the
    warm-up seconds of each run (empty lists when the source has no timed stages); ``bar``
    (a progress bar) advances by one after each run, outside the timed code."""
    if _staged_detector(make_source()) is None:
        return [], []
    names = ("background", "cleaning", "detector", "hand-off", "blobs")
    runs: dict[str, list[float]] = {k: [] for k in names}
    verifier_runs: list[float] = []
    warm: list[float] = []
    for _ in range(repeats):
        source = make_source()
        det = _staged_detector(source)
        if getattr(det, "verifier", None) is not None:  # its share of the detector stage
            det.verifier = _Timed(det.verifier)
        warm.append(_time(lambda source=source: source.start(sequence)))
        fg_of = ForegroundProvider(foreground, sequence, background)
        acc = dict.fromkeys(names, 0.0)
        for k, img in enumerate(images, 1):
            t0 = _clock()
            raw = det.background.raw(img)
            t1 = _clock()
            fg = det.background.clean(raw) > 0
            t2 = _clock()
            dets = det.detect_on(img, fg)
            t3 = _clock()
            dets, _ = clean_detections(dets)
            fg_of(k, img, fg)
            t4 = _clock()
            blobs_from_mask(fg, perimeter=False)
            t5 = _clock()
            for name, dt in zip(names, (t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4)):
                acc[name] += dt
        for name in names:
            runs[name].append(acc[name])
        if isinstance(getattr(det, "verifier", None), _Timed):
            verifier_runs.append(det.verifier.seconds)
        _advance(bar)
    n = len(images)
    total = [sum(runs[k][r] for k in names[:4]) for r in range(repeats)]
    fg_only = [runs["background"][r] + runs["cleaning"][r] + runs["blobs"][r]
               for r in range(repeats)]
    out = [StageTiming(f"  {k}", n, runs[k]) for k in names[:4]]
    if verifier_runs:
        out.insert(3, StageTiming("    of which shape verifier", n, verifier_runs))
    out += [StageTiming("front end (staged sum)", n, total),
            StageTiming("foreground only", n, fg_only)]
    return out, warm


def bench_sequence(sequence: Any, make_source: Callable[[], Any],
                   make_trackers: Callable[[], Mapping[str, Any]], frames: int | None = None,
                   repeats: int = 3, foreground: str = "auto",
                   background: Mapping[str, Any] | None = None,
                   progress: Callable[..., Any] | None = None) -> list[StageTiming]:
    """Time decode, front end and every tracker on the first ``frames`` frames of
    ``sequence`` (``repeats`` runs each; fresh source and trackers for every run).

    ``progress``: a progress-bar factory (``occbench.progress.progress_factory``); its bar
    counts the runs of every stage and advances between runs, never inside a timed one.
    """
    if repeats < 1:
        raise ValueError(f"repeats must be >= 1, got {repeats}")
    n = sequence.info.length if frames is None else min(int(frames), sequence.info.length)
    if n < 1:
        raise ValueError(f"frames must be >= 1, got {frames}")
    images: list[Any] = []

    def decode() -> None:
        images.clear()
        images.extend(sequence.frame(k) for k in range(1, n + 1))

    names = list(make_trackers())
    staged = _staged_detector(make_source()) is not None
    bar = None if progress is None else progress(
        total=repeats * (2 + staged + len(names)), desc="bench", unit="run")
    try:
        return _bench_stages(sequence, make_source, make_trackers, names, n, decode, images,
                             repeats, foreground, background, bar)
    finally:
        if bar is not None:
            bar.close()


def _advance(bar: Any) -> None:
    if bar is not None:
        bar.update(1)


def _bench_stages(sequence: Any, make_source: Callable[[], Any],
                  make_trackers: Callable[[], Mapping[str, Any]], names: list[str], n: int,
                  decode: Callable[[], None], images: list[Any], repeats: int,
                  foreground: str, background: Mapping[str, Any] | None,
                  bar: Any) -> list[StageTiming]:
    """``bench_sequence``'s stages in order, ``bar`` advanced after each run."""
    global _clock
    clock, _clock = _clock, (time.process_time if _clock is time.thread_time else _clock)
    decode_s = []
    try:  # decoding may run in a prefetch thread: its CPU time is the process's
        for _ in range(repeats):
            decode_s.append(_time(decode))
            _advance(bar)
    finally:
        _clock = clock
    inputs: list[tuple[Any, Any]] = []

    def front(source: Any) -> None:
        inputs.clear()
        for step in frame_loop(sequence, source, foreground, background, images=images,
                           start=False):
            inputs.append((step.detections, step.foreground))

    front_s = []
    for _ in range(repeats):
        source = make_source()
        source.start(sequence)  # the per-sequence warm-up: timed by bench_frontend_stages
        front_s.append(_time(lambda source=source: front(source)))
        _advance(bar)
    out = [StageTiming("decode", n, decode_s), StageTiming("front end", n, front_s)]
    staged, warm = bench_frontend_stages(sequence, make_source, images, repeats, foreground,
                                         background, bar)
    out += staged
    if warm:  # once per sequence: one "frame" of this row is the whole warm-up
        out.append(StageTiming("warm-up (per sequence)", 1, warm))
    for name in names:
        seconds = []
        for _ in range(repeats):
            seconds.append(bench_tracker(name, make_trackers()[name], images, inputs))
            _advance(bar)
        out.append(StageTiming(f"tracker {name}", n, seconds))
    return out


def bench_tracker(name: str, tracker: Any, images: Sequence[Any],
                  inputs: Sequence[tuple[Any, Any]]) -> float:
    """Seconds ``tracker``'s ``update`` took (the bench's clock, summed by a
    ``TrackerBank``) over ``images`` and their cached (detections, foreground).

    Raises:
        RuntimeError: the tracker failed (its error in the message).
    """
    bank = TrackerBank({name: tracker}, clock=_clock)
    for k, (img, (dets, fg)) in enumerate(zip(images, inputs), 1):
        bank.step(k, img, dets, fg)
    out = bank.outputs[name]
    if out.error is not None:
        raise RuntimeError(f"tracker {name} failed: {out.error}")
    return out.seconds


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="occbench bench",
                                description="Frames/s per stage (decode, front end, trackers), "
                                            "one core, median of several runs.")
    p.add_argument("overrides", nargs="*", help="config overrides, e.g. dataset=caviar")
    p.add_argument("--sequence", help="sequence name (default: the first)")
    p.add_argument("--frames", type=int, default=100, help="frames timed (default 100)")
    p.add_argument("--repeats", type=int, default=3, help="runs per stage (default 3)")
    p.add_argument("--csv", type=Path, help="also write the table here")
    p.add_argument("--clock", choices=sorted(CLOCKS), default="cpu",
                   help="cpu: CPU time of this thread (default); wall: elapsed time")
    args = p.parse_args(argv)
    global _clock
    _clock = CLOCKS[args.clock]
    log_to_stderr(logging.WARNING)

    cv2.setNumThreads(1)

    try:
        cfg = compose_config(args.overrides)
    except HydraException as err:  # a key or choice that does not exist: as `run` says it
        print(explain(err, "config", args.overrides), file=sys.stderr)
        return 1
    try:
        sequences = load_sequences(cfg.dataset)
        by_name = {s.info.name: s for s in sequences}
        if args.sequence and args.sequence not in by_name:
            raise ValueError(f"no sequence {args.sequence!r}; have {sorted(by_name)}")
        seq = by_name[args.sequence] if args.sequence else sequences[0]
        configs = tracker_configs(cfg.tracker, tracker_choice(args.overrides))
        progress = progress_factory()  # on stderr when it is a terminal, else nothing
        warm_up_once({n: (lambda n=n, node=node: build_tracker(n, node))
                      for n, node in configs.items()}, lambda text: print(text, file=sys.stderr),
                     progress)
        timings = bench_sequence(
            seq, lambda: build_source(cfg.detector, cache=False),  # the front end timed
            lambda: {n: build_tracker(n, node) for n, node in configs.items()},
            args.frames, args.repeats, str(cfg.get("foreground", "auto")),
            cfg.get("background") or {}, progress)
    except (OSError, ValueError, RuntimeError) as err:
        return refuse(err)
    table = pd.DataFrame([t.row() for t in timings])
    node = cfg.detector.get("detector") or cfg.detector  # a FrontendSource wraps a detector
    detector = str(node.get("_target_", "?")).rsplit(".", 1)[-1]
    print(f"{seq.info.name} ({seq.info.width}x{seq.info.height}), detector {detector}, "
          f"one core, {args.clock} clock, median of {args.repeats} runs")
    print(table.to_string(index=False))
    rows = {r["stage"]: r["fps_median"] for r in table.to_dict("records")}
    if "foreground only" in rows:
        print("warm-up: once per sequence, not in the front end's frames/s; front end / "
              f"foreground only: {rows['front end'] / rows['foreground only']:.2f} of the frames/s")
    if args.csv:
        args.csv.parent.mkdir(parents=True, exist_ok=True)
        table.to_csv(args.csv, index=False, lineterminator="\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
