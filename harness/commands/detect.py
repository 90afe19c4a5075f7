"""``occbench detect``: run one person detector over a dataset and score it.

Same config tree as the main app (``conf/``, top config ``conf/detect.yaml``) with the
``dataset=`` and ``detector=`` groups. Writes into the Hydra run directory:

* ``det/<sequence>.txt``: MOTChallenge detection rows ``frame,-1,left,top,w,h,score,-1,-1,-1``
  (written by ``occbench.io.write.write_mot``, the one place converting to 1-based boxes);
* ``front_end.txt``: one line per sequence on which the front end fell back to another
  detector (which, and why; also printed);
* ``detection_metrics.csv``: detections (and per frame), TP, FP, FN, precision, recall and
  F1 at IoU >= ``iou_threshold`` per sequence and COMBINED (counts summed, ratios
  recomputed), from a one-to-one Hungarian matching of detections to ground truth per frame;
  a sequence without ground truth is counted, its scores blank, and COMBINED then scores
  the labelled sequences only (``ground_truth``: "2 of 3"; printed below the table);
* a multirun (``-m``) prints one table of every job's COMBINED row when it ends
  (``GatherDetections``), each job one log line;
* the front-end cache (``occbench.sources.cache``, ``OCCBENCH_CACHE``): a front-end
  detector's outputs of each sequence, so that later runs on the same frames with the same
  detector config read them; ``detect`` always computes (its frames/s are the detector's);
* with ``overlays.frames=[first,last]``: ``overlays/<sequence>/<frame>.png`` showing the
  foreground (tinted), blobs (blue), detections (green), ground truth (white) and heads
  (yellow ellipses: the detections' own, else with ``overlays.heads`` the PBM head
  detector's search in each detection box).

Examples::

    occbench detect detector=silhouette
    occbench detect dataset=caviar detector=hog overlays.frames=[10,20]
    occbench detect dataset=synthetic dataset.scenarios=[crowd] detector=foreground
"""

from __future__ import annotations

import logging
import time
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import hydra
import numpy as np
import pandas as pd
import yaml
from hydra.core.hydra_config import HydraConfig
from hydra.experimental.callback import Callback
from hydra.types import RunMode
from omegaconf import DictConfig, OmegaConf

from occbench.config.build import build_source, load_sequences
from occbench.errors import RunError
from occbench.io.write import write_atomic, write_mot
from occbench.pipeline.loop import no_progress
from occbench.progress import progress_factory
from occbench.report.overlays import draw_overlay
from occbench.sources.cache import Store, cache_root, worth_caching
from occbench.sources.cache.source import EntryBuilder, store_outputs
from occbench.trackers.common.assignment import assign
from occbench.trackers.frontend.blobs import blob_boxes, blobs_from_mask
from occbench.trackers.frontend.heads import HeadDetector
from occbench.trackers.geometry import iou_matrix

log = logging.getLogger("occbench.commands.detect")

METRIC_COLUMNS = ("ground_truth", "frames", "detections", "per_frame", "gt", "TP", "FP", "FN",
                  "precision", "recall", "F1", "frames_per_second")
SCORE_COLUMNS = ("gt", "TP", "FP", "FN", "precision", "recall", "F1")  # blank without gt


@dataclass
class DetectionCounts:
    """Matching counts of one sequence (sum them to combine sequences); ``labelled``:
    the sequence has ground truth (else only frames and detections are counted)."""

    frames: int = 0
    gt: int = 0
    detections: int = 0
    tp: int = 0
    seconds: float = 0.0
    labelled: bool = True

    def add(self, other: DetectionCounts) -> None:
        self.frames += other.frames
        self.gt += other.gt
        self.detections += other.detections
        self.tp += other.tp
        self.seconds += other.seconds

    def row(self) -> dict:
        """The row of ``detection_metrics.csv``; without ground truth the score columns are
        None (blank), never zeros or NaN standing for a score."""
        fps = self.frames / self.seconds if self.seconds > 0 else float("nan")
        out = {"ground_truth": "yes" if self.labelled else "no", "frames": self.frames,
               "detections": self.detections,
               "per_frame": self.detections / self.frames if self.frames else float("nan"),
               "frames_per_second": fps}
        if not self.labelled:
            return {**out, **dict.fromkeys(SCORE_COLUMNS)}
        fp, fn = self.detections - self.tp, self.gt - self.tp
        p = self.tp / self.detections if self.detections else float("nan")
        r = self.tp / self.gt if self.gt else float("nan")
        f1 = 2 * self.tp / (self.detections + self.gt) if self.detections + self.gt else float("nan")
        return {**out, "gt": self.gt, "TP": self.tp, "FP": fp, "FN": fn, "precision": p,
                "recall": r, "F1": f1}


def match_count(gt: np.ndarray, det: np.ndarray, iou_threshold: float = 0.5) -> int:
    """True positives of one frame: a one-to-one Hungarian matching maximising the summed IoU
    among pairs with IoU >= ``iou_threshold``. gt (N, 4), det (M, 4) xywh."""
    if len(gt) == 0 or len(det) == 0:
        return 0
    cost = 1.0 - iou_matrix(gt, det)
    matches, _, _ = assign(cost, max_cost=1.0 - iou_threshold)
    return len(matches)


def metrics_table(counts: dict[str, DetectionCounts]) -> pd.DataFrame:
    """One row per sequence plus COMBINED (counts summed, ratios recomputed). COMBINED sums
    the labelled sequences only when there are any (its ``ground_truth``: "2 of 3"), never
    mixing their scores with unlabelled detections; with none labelled it counts them all."""
    labelled = [c for c in counts.values() if c.labelled]
    total = DetectionCounts(labelled=bool(labelled))
    for c in labelled or counts.values():
        total.add(c)
    rows = [{"sequence": name, **c.row()} for name, c in counts.items()]
    combined = total.row()
    if labelled and len(labelled) < len(counts):
        combined["ground_truth"] = f"{len(labelled)} of {len(counts)}"
    rows.append({"sequence": "COMBINED", **combined})
    table = pd.DataFrame(rows, columns=["sequence", *METRIC_COLUMNS])
    return typed(table)


def typed(table: pd.DataFrame) -> pd.DataFrame:
    """``table`` with whole counts as nullable integers and scores as floats, so that a
    sequence without ground truth is blank (CSV) or "-" (printed) and no count turns into a
    float."""
    for col in ("gt", "TP", "FP", "FN"):
        table[col] = table[col].astype("Int64")
    for col in ("precision", "recall", "F1"):
        table[col] = table[col].astype(float)
    return table


def table_notes(table: pd.DataFrame) -> list[str]:
    """What the printed table cannot say itself: which sequences have no ground truth, and
    what COMBINED covers then."""
    rows = table[table["sequence"] != "COMBINED"]
    missing = rows.loc[rows["ground_truth"] == "no", "sequence"].tolist()
    if not missing:
        return []
    if len(missing) == len(rows):
        return ["no ground truth: detections counted (boxes, per frame), not scored"]
    return [(f"no ground truth: {', '.join(missing)} (detections counted, not scored); "
             f"COMBINED scores the {len(rows) - len(missing)} labelled sequence(s) only")]


def table_text(table: pd.DataFrame, notes: list[str] | None = None) -> str:
    """The printed table, "-" for scores without ground truth, then ``notes`` (default:
    ``table_notes``), one a line."""
    shown = table.astype(object).where(table.notna(), "-")
    for col in table.select_dtypes("float").columns:
        shown[col] = [v if v == "-" else f"{v:.3f}" for v in shown[col]]
    with pd.option_context("display.width", 160):
        text = shown.to_string(index=False)
    return "\n".join([text, *(table_notes(table) if notes is None else notes)]) + "\n"


def run_detection(cfg: DictConfig, out_dir: Path, progress: Any = None) -> pd.DataFrame:
    """Run ``cfg.detector`` over ``cfg.dataset``; write det files, metrics and overlays;
    ``progress``: a progress factory (``occbench.progress.progress_factory``) or None."""
    sequences = load_sequences(cfg.dataset)  # RunError naming the cause
    source = build_source(cfg.detector, cache=False)  # RunError naming what cannot be built
    cache = _cache_of(source, cfg.detector)
    iou = cfg.get("iou_threshold", 0.5)
    if isinstance(iou, bool) or not isinstance(iou, int | float) or not 0 < iou <= 1:
        raise ValueError(f"iou_threshold={iou}: must be a number in (0, 1]")
    iou = float(iou)
    ov = cfg.get("overlays") or {}
    ov_frames = ov.get("frames")
    if ov_frames is not None:
        if len(ov_frames) != 2 or int(ov_frames[0]) > int(ov_frames[1]):
            raise ValueError(f"overlays.frames must be [first, last], got {list(ov_frames)}")
        ov_frames = (int(ov_frames[0]), int(ov_frames[1]))
    head_detector = None
    if ov_frames is not None and ov.get("heads", True):
        head_detector = HeadDetector()
    counts: dict[str, DetectionCounts] = {}
    front_end_notes: dict[str, str] = {}
    failures: list[str] = []
    (out_dir / "errors.txt").unlink(missing_ok=True)
    (out_dir / "front_end.txt").unlink(missing_ok=True)
    for seq in sequences:
        try:
            _detect_sequence(seq, source, out_dir, iou, ov_frames, head_detector, progress,
                             counts, cache)
            note = fallback_note(source)
            if note is not None:
                front_end_notes[seq.info.name] = note
        except Exception as err:  # noqa: BLE001 - this sequence fails, the next goes on
            msg = f"sequence {seq.info.name}: {type(err).__name__}: {err}"
            log.error("%s", msg)
            failures.append(msg)
            with (out_dir / "errors.txt").open("a") as fh:
                fh.write(msg + "\n    " + traceback.format_exc().rstrip().replace(
                    "\n", "\n    ") + "\n")
    table = metrics_table(counts)
    notes = [f"{name}: {note}" for name, note in front_end_notes.items()]
    if notes:
        write_atomic(out_dir / "front_end.txt", "\n".join(notes) + "\n")
    write_atomic(out_dir / "detection_metrics.csv",
                 table.to_csv(index=False, float_format="%.4f", lineterminator="\n"))
    if failures:
        raise DetectionFailed(failures, table)
    return table


def fallback_note(source) -> str | None:
    """One line when the source's detector fell back on the last sequence (which detector
    and why: ``SilhouetteDetector.fallback_reason``), else None."""
    detector = getattr(source, "detector", source)
    reason = getattr(detector, "fallback_reason", None)
    if reason is None:
        return None
    return f"detected with {detector.fallback.name}: {reason}"


class DetectionFailed(RuntimeError):
    """Some sequences failed (recorded in errors.txt); the others' outputs are written.

    Attributes:
        failures: one line per failed sequence.
        table: detection_metrics.csv of the sequences that were scored.
    """

    def __init__(self, failures: list[str], table: pd.DataFrame) -> None:
        super().__init__(f"{len(failures)} sequence(s) failed: " + "; ".join(failures))
        self.failures = failures
        self.table = table


def _cache_of(source, node: DictConfig) -> tuple | None:
    """(store, resolved config) when ``source`` is a front-end one and the cache is on."""
    root = cache_root()
    if root is None or not worth_caching(source):
        return None
    return Store(root), OmegaConf.to_container(node, resolve=True)


def _detect_sequence(seq, source, out_dir: Path, iou: float, ov_frames, head_detector,
                     progress: Any, counts: dict[str, DetectionCounts],
                     cache: tuple | None = None) -> None:
    """Detect one sequence: its det file, overlays and counts (added to ``counts``); with
    ``cache`` (store, detector config), its outputs into the front-end cache; ``progress``:
    a progress factory (``occbench.progress.progress_factory``) or None."""
    name = seq.info.name
    built = EntryBuilder() if cache is not None else None
    source.start(seq)
    c = DetectionCounts(labelled=seq.gt is not None)
    frames, boxes, scores = [], [], []
    bar = (progress or no_progress)(total=seq.info.length, desc=name)
    try:
        for k, frame in seq.frames():
            bar.update(1)
            t0 = time.perf_counter()
            dets, fg = source.detect(k, frame)
            c.seconds += time.perf_counter() - t0
            c.frames += 1
            if built is not None:
                built.add(k, dets, fg)
            frames.append(np.full(len(dets), k))
            boxes.append(dets.boxes)
            scores.append(dets.scores)
            gt = None
            c.detections += len(dets)
            if seq.gt is not None:
                rows = seq.gt.rows_of(k)
                rows = rows[seq.gt.table.conf[rows] > 0]
                gt = seq.gt.table.boxes[rows]
                c.gt += len(gt)
                c.tp += match_count(gt, dets.boxes, iou)
            if ov_frames and ov_frames[0] <= k <= ov_frames[1] and frame is not None:
                bb = None if fg is None else blob_boxes(blobs_from_mask(fg, 20, perimeter=False))
                if dets.heads is None and head_detector is not None and len(dets):
                    dets = type(dets)(dets.boxes, dets.scores, dets.labels,
                                      head_detector.detect(frame, fg, dets.boxes))
                path = out_dir / "overlays" / name / f"{k:06d}.png"
                path.parent.mkdir(parents=True, exist_ok=True)
                cv2.imwrite(str(path), draw_overlay(frame, fg, dets, gt, bb))
    finally:
        bar.close()
    n = sum(len(f) for f in frames)
    write_mot(out_dir / "det" / f"{name}.txt",
              np.concatenate(frames) if n else np.zeros(0),
              np.full(n, -1), np.concatenate(boxes) if n else np.zeros((0, 4)),
              np.concatenate(scores) if n else np.zeros(0))
    counts[name] = c
    log.info("%s: %d frames, %d detections", name, c.frames, n)
    if built is not None:
        entry = store_outputs(cache[0], cache[1], seq, source, built)
        log.info("front end of %s: %s", name, "not cached (its frames cannot be fingerprinted)"
                 if entry is None else f"stored in the cache ({cache[0].path(entry.key)})")


# absolute: a relative path resolves against the calling module (pkg://) under `occbench detect`
@hydra.main(version_base="1.3", config_path=str(Path(__file__).resolve().parents[2] / "conf"),
            config_name="detect")
def app(cfg: DictConfig) -> None:
    out_dir = Path(HydraConfig.get().runtime.output_dir)
    failed = None
    try:
        table = run_detection(cfg, out_dir, progress=progress_factory(
            bool(cfg.get("progress", True)), HydraConfig.get().mode == RunMode.MULTIRUN))
    except DetectionFailed as err:
        table, failed = err.table, err
    except (ValueError, OSError, RunError) as err:
        raise RunError(str(err)) from None
    if HydraConfig.get().mode == RunMode.MULTIRUN:  # one table when the multirun ends
        log.info("job %s [%s]: %s", HydraConfig.get().job.num,
                 " ".join(HydraConfig.get().overrides.task), combined_line(table))
    else:
        print(table_text(table), end="")
    if (out_dir / "front_end.txt").is_file():
        print("front end fell back on:\n  " + (out_dir / "front_end.txt").read_text().rstrip()
              .replace("\n", "\n  "))
    print(f"results: {out_dir}")
    if failed is not None:
        raise RunError(f"{len(failed.failures)} sequence(s) failed (the others are written; "
                       f"tracebacks in {out_dir / 'errors.txt'}): "
                       + "; ".join(f.replace("\n", " ") for f in failed.failures))


def combined_line(table: pd.DataFrame) -> str:
    """A multirun job's one log line: its COMBINED precision, recall, F1 or, without
    ground truth, its detections per frame."""
    row = table.iloc[-1]
    if pd.isna(row["precision"]) and row["ground_truth"] == "no":
        return f"{row['detections']} detections, {row['per_frame']:.2f} per frame (no ground truth)"
    return (f"precision {row['precision']:.3f}, recall {row['recall']:.3f}, F1 {row['F1']:.3f}"
            f" (COMBINED, ground truth: {row['ground_truth']})")


def rescored(row: dict) -> dict:
    """A ``detection_metrics.csv`` row with precision, recall and F1 computed again from its
    counts: the file's ratios are rounded to 4 decimals, and printing them at 3 rounded twice
    (F1 0.838 in ``detect -m`` where ``detect`` printed 0.837)."""
    if pd.isna(row.get("TP")):
        return row
    counts = DetectionCounts(frames=int(row["frames"]), gt=int(row["gt"]),
                             detections=int(row["detections"]), tp=int(row["TP"]))
    scores = counts.row()
    return {**row, **{k: scores[k] for k in ("precision", "recall", "F1")}}


class GatherDetections(Callback):
    """At the end of ``occbench detect -m``: one table of every job's COMBINED row (the
    jobs print none of their own), the job's overrides first; per-sequence rows stay in
    each job's ``detection_metrics.csv``. Only jobs of this multirun are read: job folders
    written before it started (a reused sweep folder) are left out."""

    def on_multirun_start(self, config: DictConfig, **kwargs) -> None:
        self.started = time.time()

    def on_multirun_end(self, config: DictConfig, **kwargs) -> None:
        sweep_dir = Path(str(config.hydra.sweep.dir))
        rows = []
        for job in sorted((p for p in sweep_dir.glob("*") if p.name.isdigit()),
                          key=lambda p: int(p.name)):
            path, overrides = job / "detection_metrics.csv", job / ".hydra" / "overrides.yaml"
            if not path.is_file() or path.stat().st_mtime < getattr(self, "started", 0.0):
                continue
            table = pd.read_csv(path, keep_default_na=False, na_values=[""])
            told = yaml.safe_load(overrides.read_text()) if overrides.is_file() else []
            rows.append({"job": int(job.name), "overrides": " ".join(told or []),
                         **rescored(table.iloc[-1].drop("sequence").to_dict())})
        if not rows:
            print(f"no job of {sweep_dir} wrote detection_metrics.csv")
            return
        table = typed(pd.DataFrame(rows))
        mixed = ["ground_truth 'k of n': COMBINED scores the k labelled sequences only"
                 ] if (~table["ground_truth"].isin(["yes", "no"])).any() else []
        print("COMBINED of each job (per sequence: <job>/detection_metrics.csv)")
        print(table_text(table, mixed), end="")
        print(f"sweep: {sweep_dir}")


if __name__ == "__main__":
    app()
