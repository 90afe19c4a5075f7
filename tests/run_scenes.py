"""Small runs for the runner's tests: MOT folders of two crossing people, box-only
sequences, trackers and sources that fail or scribble, and the composed configs."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
from hydra import compose, initialize_config_dir

from occbench.datasets.base import GroundTruth, Sequence
from occbench.io.mot import MotTable
from occbench.pipeline.experiment import run_experiment as _run_experiment
from occbench.sources.annotations import NoisyGroundTruth
from occbench.trackers.baseline import BaselineTracker
from occbench.trackers.records import Detections, SequenceInfo

ROOT = Path(__file__).resolve().parents[1]
CONF = ROOT / "conf"
HAVE_SYNTHETIC = (CONF / "dataset" / "synthetic.yaml").is_file()
needs_synthetic = pytest.mark.skipif(not HAVE_SYNTHETIC,
                                     reason="conf/dataset/synthetic.yaml is not built yet")

# ----------------------------------------------------------------------------- fixtures


def crossing_rows(length: int = 30, width: int = 320) -> list[tuple[int, int, float, float]]:
    """Two people walking towards each other along the same line; they cross mid-sequence."""
    rows = []
    for k in range(1, length + 1):
        t = (k - 1) / (length - 1)
        rows.append((k, 1, 10 + t * (width - 60), 60.0))
        rows.append((k, 2, width - 50 - t * (width - 60), 70.0))
    return rows


def write_mot_sequence(root: Path, name: str, length: int = 30, frames: bool = False,
                       gt_text: str | None = None) -> Path:
    """A MOTChallenge folder: seqinfo.ini, gt/gt.txt (two crossing people), img1/ if asked."""
    folder = root / name
    (folder / "gt").mkdir(parents=True)
    (folder / "seqinfo.ini").write_text(
        f"[Sequence]\nname={name}\nimDir=img1\nframeRate=25\nseqLength={length}\n"
        "imWidth=320\nimHeight=240\nimExt=.jpg\n")
    if gt_text is None:
        gt_text = "".join(f"{k},{i},{x + 1:.2f},{y + 1:.2f},40.00,100.00,1,1,1\n"
                          for k, i, x, y in crossing_rows(length))
    (folder / "gt" / "gt.txt").write_text(gt_text)
    if frames:
        (folder / "img1").mkdir()
        img = np.full((240, 320, 3), 90, np.uint8)
        for k in range(1, length + 1):
            cv2.imwrite(str(folder / "img1" / f"{k:06d}.jpg"), img)
    return folder


def compose_cfg(*overrides: str):
    with initialize_config_dir(config_dir=str(CONF), version_base="1.3"):
        return compose("config", overrides=list(overrides))


def mot_cfg(root: Path, *overrides: str):
    return compose_cfg("dataset=mot", "detector=noisy_gt",
                       f"dataset.root={root}", "tracker=baseline", *overrides)


class BoxSequence(Sequence):
    """A sequence without pixels whose gt is given as rows (frame, id, x, y)."""

    def __init__(self, name: str, rows, length: int) -> None:
        a = np.asarray(rows, dtype=float)
        n = len(a)
        boxes = np.c_[a[:, 2:4], np.full(n, 40.0), np.full(n, 100.0)]
        table = MotTable(a[:, 0].astype(np.int64), a[:, 1].astype(np.int64), boxes, np.ones(n),
                         np.ones(n, dtype=np.int64), np.ones(n))
        self.info = SequenceInfo(name, 320, 240, 25.0, length)
        self.gt = GroundTruth(table)

    @property
    def has_pixels(self) -> bool:
        return False

    def frame(self, index: int):
        return None


class FailingSequence(BoxSequence):
    def frame(self, index: int):
        if index == 5:
            raise OSError(f"{self.info.name}: frame 5 is corrupt")


class FailingTracker(BaselineTracker):
    """Raises at frame ``fail_at``: the other trackers must go on."""

    def __init__(self, fail_at: int = 5, **kwargs) -> None:
        self.fail_at = fail_at
        super().__init__(**kwargs)

    def update(self, frame, detections, foreground=None):
        if self._frame + 1 == self.fail_at:
            raise RuntimeError("deliberate failure")
        return super().update(frame, detections, foreground)


class MutatingTracker(BaselineTracker):
    """Scribbles over its inputs: must not disturb the trackers run beside it."""

    def update(self, frame, detections, foreground=None):
        detections.boxes[:] += 50.0
        return super().update(frame, detections, foreground)


class NanSource(NoisyGroundTruth):
    """Exact detections plus one NaN box and one zero-width box per frame."""

    def detect(self, index, frame=None):
        dets, fg = super().detect(index, frame)
        boxes = np.r_[dets.boxes, [[np.nan, 1, 10, 10], [5, 5, 0, 10]]]
        return Detections(boxes, np.r_[dets.scores, 1.0, 1.0]), fg


def run_experiment(cfg, out_dir, tracker_name=None, progress=None):
    """``occbench.pipeline.experiment.run_experiment`` naming a single tracker as the app does (its choice)."""
    if tracker_name is None and "_target_" in cfg.tracker:
        tracker_name = "baseline"
    return _run_experiment(cfg, out_dir, tracker_name=tracker_name, progress=progress)
