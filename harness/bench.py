"""``python -m harness.bench``: frames per second of each stage, one core.

Stages, timed separately on the same frames:

* decode: ``Sequence.frame(k)`` (JPEG/video decoding; rendering for synthetic scenes);
* front end: the detection source's ``detect(k, frame)`` plus the foreground handed to the
  trackers (background subtraction, blobs, silhouette/HOG/head detection, or noisy gt);
* tracker: each tracker's ``update`` on the cached detections and foreground.

Each stage is run ``--repeats`` times over the first ``--frames`` frames of the chosen
sequence and the median frames/s is reported (with the range). Everything runs on one core:
OpenCV with ``cv2.setNumThreads(1)`` and the BLAS/OpenMP pools limited to one thread (set
before numpy is imported). Frames are held in memory between stages, so the tracker stage
measures the tracker alone. Speed targets belong in ``benchmarks/``; this tool only measures.

Examples::

    python -m harness.bench                                   # synthetic suite, first sequence
    python -m harness.bench --frames 150 --repeats 5 -- dataset=caviar detector=silhouette
    python -m harness.bench --sequence crowd -- dataset=synthetic tracker=all
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


def _time(fn: Callable[[], None]) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def bench_sequence(sequence: Any, make_source: Callable[[], Any],
                   make_trackers: Callable[[], Mapping[str, Any]], frames: int | None = None,
                   repeats: int = 3, foreground: str = "auto",
                   background: Mapping[str, Any] | None = None) -> list[StageTiming]:
    """Time decode, front end and every tracker on the first ``frames`` frames of
    ``sequence`` (``repeats`` runs each; fresh source and trackers for every run)."""
    from harness.run import ForegroundProvider, clean_detections

    if repeats < 1:
        raise ValueError(f"repeats must be >= 1, got {repeats}")
    n = sequence.info.length if frames is None else min(int(frames), sequence.info.length)
    if n < 1:
        raise ValueError(f"frames must be >= 1, got {frames}")
    images: list[Any] = []

    def decode() -> None:
        images.clear()
        images.extend(sequence.frame(k) for k in range(1, n + 1))

    decode_s = [_time(decode) for _ in range(repeats)]
    inputs: list[tuple[Any, Any]] = []

    def front() -> None:
        inputs.clear()
        source = make_source()
        source.start(sequence)
        fg_of = ForegroundProvider(foreground, sequence, background)
        for k, img in enumerate(images, 1):
            dets, mask = source.detect(k, img)
            dets, _ = clean_detections(dets)
            inputs.append((dets, fg_of(k, img, mask)))

    front_s = [_time(front) for _ in range(repeats)]
    out = [StageTiming("decode", n, decode_s), StageTiming("front end", n, front_s)]
    names = list(make_trackers())
    for name in names:
        runs = []
        for _ in range(repeats):
            tracker = make_trackers()[name]

            def track(tracker: Any = tracker) -> None:
                for img, (dets, fg) in zip(images, inputs):
                    tracker.update(img, dets, fg)

            runs.append(_time(track))
        out.append(StageTiming(f"tracker {name}", n, runs))
    return out


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m harness.bench",
                                description="Frames/s per stage (decode, front end, trackers), "
                                            "one core, median of several runs.")
    p.add_argument("overrides", nargs="*", help="config overrides, e.g. dataset=caviar")
    p.add_argument("--sequence", help="sequence name (default: the first)")
    p.add_argument("--frames", type=int, default=100, help="frames timed (default 100)")
    p.add_argument("--repeats", type=int, default=3, help="runs per stage (default 3)")
    p.add_argument("--csv", type=Path, help="also write the table here")
    args = p.parse_args(argv)
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")

    import cv2
    import pandas as pd

    cv2.setNumThreads(1)
    from harness.report.video import compose_config, tracker_choice
    from harness.run import build_source, build_tracker, load_sequences, tracker_configs

    try:
        cfg = compose_config(args.overrides)
        sequences = load_sequences(cfg.dataset)
        by_name = {s.info.name: s for s in sequences}
        if args.sequence and args.sequence not in by_name:
            raise ValueError(f"no sequence {args.sequence!r}; have {sorted(by_name)}")
        seq = by_name[args.sequence] if args.sequence else sequences[0]
        configs = tracker_configs(cfg.tracker, tracker_choice(args.overrides))
        timings = bench_sequence(
            seq, lambda: build_source(cfg.detector),
            lambda: {n: build_tracker(n, node) for n, node in configs.items()},
            args.frames, args.repeats, str(cfg.get("foreground", "auto")),
            cfg.get("background") or {})
    except (OSError, ValueError, RuntimeError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    table = pd.DataFrame([t.row() for t in timings])
    node = cfg.detector.get("detector") or cfg.detector  # a FrontendSource wraps a detector
    detector = str(node.get("_target_", "?")).rsplit(".", 1)[-1]
    print(f"{seq.info.name} ({seq.info.width}x{seq.info.height}), detector {detector}, "
          f"one core, median of {args.repeats} runs")
    print(table.to_string(index=False))
    if args.csv:
        args.csv.parent.mkdir(parents=True, exist_ok=True)
        table.to_csv(args.csv, index=False, lineterminator="\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
