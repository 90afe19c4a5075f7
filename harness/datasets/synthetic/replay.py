"""Replay: draw synthetic people along the boxes of a real MOT ground-truth file, so that
trackers that need pixels run on real human motion with its real occlusion structure.

Each gt box becomes a person that fills it (the amodal box); people are painted far to
near by the bottom edge of their box (lower in the image = nearer). The sequence's gt
reproduces the file's boxes (clipped to the image) with visibility computed from the
rendered masks. When a MOTChallenge ``det/det.txt`` sits beside the gt, it is attached as
``sequence.public_detections``.
"""

from __future__ import annotations

import logging
import math
import zlib
from pathlib import Path

import numpy as np

from occbench.datasets.base import Sequence, window
from occbench.datasets.mot import read_seqinfo, seqinfo_number
from occbench.datasets.synthetic.appearance import random_appearance
from occbench.datasets.synthetic.scenarios import walking_poses
from occbench.datasets.synthetic.scene import Camera, render_background
from occbench.datasets.synthetic.sequence import Cast, SyntheticSequence
from occbench.io.mot import MotTable, read_mot

log = logging.getLogger(__name__)


def _locate(gt_path: str | Path) -> tuple[Path, Path]:
    """(gt file, sequence folder) of a MOTChallenge folder or a gt file."""
    path = Path(gt_path)
    if path.is_dir():
        gt = path / "gt" / "gt.txt"
        if not gt.is_file():
            raise FileNotFoundError(f"replay: no gt/gt.txt in sequence folder {path}")
        return gt, path
    if path.is_file():
        root = path.parent.parent if path.parent.name == "gt" else path.parent
        return path, root
    raise FileNotFoundError(
        f"replay: ground truth not found: {path} (expected a MOTChallenge "
        "sequence folder with gt/gt.txt, or a MOT gt file)"
    )


def _seqinfo(root: Path) -> tuple[dict[str, str], Path]:
    """The ``[Sequence]`` keys of ``root/seqinfo.ini`` ({} without one) and its path."""
    ini = root / "seqinfo.ini"
    return (read_seqinfo(ini) if ini.is_file() else {}), ini


def load_replay(
    gt_path: str | Path,
    seed: int = 0,
    max_frames: int | None = None,
    width: int | None = None,
    height: int | None = None,
    fps: float | None = None,
    noise: float = 2.0,
    shadows: bool = True,
    occluded_below: float = 0.3,
    name: str | None = None,
    frames: list[int] | None = None,
) -> list[Sequence]:
    """Replay a MOT gt file as a synthetic sequence.

    Args:
        gt_path: a MOTChallenge sequence folder (``gt/gt.txt``, optional ``seqinfo.ini`` and
            ``det/det.txt``) or a gt file.
        seed: seed of appearances, background and sensor noise.
        max_frames: keep frames 1..max_frames only (None: all).
        width, height, fps: frame size and rate; default from ``seqinfo.ini`` (imWidth,
            imHeight, frameRate), else the size is the boxes' extent and fps 25.
        noise: sensor noise standard deviation, grey levels.
        shadows, occluded_below: as in ``SyntheticSequence``.
        name: sequence name (default seqinfo's name, else the folder name).
        frames: [first, last] (1-based, inclusive) to run only those frames, numbered as in
            the file (``occbench.datasets.base.window``; the people are drawn as in the
            whole replay); None = all.
    Returns:
        A one-element list (the dataset interface returns lists of sequences).
    Raises:
        FileNotFoundError: naming the missing path.
        SeqInfoError: a malformed seqinfo.ini key; MotFormatError: a malformed gt row, or
            one past seqLength (file and line named).
    """
    gt_file, root = _locate(gt_path)
    info, ini = _seqinfo(root)
    seq_length = seqinfo_number(info, "seqLength", ini, int)
    table = _read_gt(gt_file, max_frames, seq_length)
    b = table.boxes
    W = int(width or seqinfo_number(info, "imWidth", ini, int)
            or math.ceil(np.max(b[:, 0] + b[:, 2]) / 16) * 16)
    H = int(height or seqinfo_number(info, "imHeight", ini, int)
            or math.ceil(np.max(b[:, 1] + b[:, 3]) / 16) * 16)
    rate = float(fps or seqinfo_number(info, "frameRate", ini, float) or 25.0)
    length = int(seq_length or table.frames.max())
    if max_frames is not None:
        length = min(length, int(max_frames))
    seq_name = name or info.get("name") or root.name
    rng = np.random.default_rng([int(seed), zlib.crc32(seq_name.encode())])

    ids, boxes, conf = _person_arrays(table, length)
    P = len(ids)
    foot_y = boxes[..., 1] + boxes[..., 3]
    vx, vz, speed = _velocities(boxes, foot_y, rate)
    phase, facing, away, swing = walking_poses(vx, vz, speed, rate, rng.uniform(0, 2 * math.pi, P))
    apps = [random_appearance(rng) for _ in range(P)]
    cast = Cast(ids, apps, boxes, -foot_y, phase, facing, away, swing, conf)
    # put the floor's far edge just above the highest feet so people stand on the floor
    feet = foot_y[np.isfinite(foot_y)]
    horizon = float(np.clip(np.min(feet) - 0.1 * H, 0.05 * H, 0.6 * H))
    background = render_background(Camera(W, H, float(H), horizon), rng)
    seq = SyntheticSequence(
        seq_name, cast, background, rate, int(seed), noise, None, shadows, occluded_below
    )
    det = root / "det" / "det.txt"
    if det.is_file():
        dets = read_mot(det, kind="det")
        seq.public_detections = dets.rows(dets.frames <= length)
        log.info(
            "%s: attached %d public detections from %s", seq_name, len(seq.public_detections), det
        )
    log.info("%s: replaying %d people over %d frames from %s", seq_name, P, length, gt_file)
    return window([seq], frames)


def _read_gt(gt_file: Path, max_frames: int | None, seq_length: int | None) -> MotTable:
    """The ground truth of ``gt_file``, frames 1..max_frames (None: all).

    Raises:
        ValueError: ``max_frames`` below 1, or no box in the kept frames.
        MotFormatError: a malformed row, or one past ``seq_length`` (file and line named).
    """
    table = read_mot(gt_file, gt=True, last_frame=seq_length)  # rows past it: an error
    if max_frames is not None:
        if max_frames < 1:
            raise ValueError(f"replay: max_frames must be >= 1, got {max_frames}")
        table = table.rows(table.frames <= max_frames)
    if len(table) == 0:
        raise ValueError(
            f"replay: {gt_file} has no boxes"
            + (f" in frames 1..{max_frames}" if max_frames else "")
        )
    return table


def _person_arrays(table: MotTable, length: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Ground-truth ids (P,), boxes (P, length, 4) xywh (NaN where absent) and confidences
    (P, length) per person and frame."""
    ids = np.unique(table.ids)
    P = len(ids)
    col = {int(i): p for p, i in enumerate(ids)}
    boxes = np.full((P, length, 4), np.nan)
    conf = np.ones((P, length))
    rows_p = np.array([col[int(i)] for i in table.ids])
    boxes[rows_p, table.frames - 1] = table.boxes
    conf[rows_p, table.frames - 1] = table.conf
    return ids, boxes, conf


def _velocities(boxes: np.ndarray, foot_y: np.ndarray, rate: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lateral and depth velocity and walking speed (P, L) in metres per second, motion in
    body heights (1.75 m per box height; depth from the feet's image motion, x3)."""
    P, length = foot_y.shape
    cx = boxes[..., 0] + boxes[..., 2] / 2
    hgt = boxes[..., 3]
    vx = np.zeros((P, length))
    vz = np.zeros((P, length))
    if length > 1:
        vx[:, 1:] = np.diff(cx, axis=1) / hgt[:, 1:] * 1.75 * rate
        vz[:, 1:] = -np.diff(foot_y, axis=1) / hgt[:, 1:] * 1.75 * rate * 3.0
    vx = np.nan_to_num(vx)
    vz = np.nan_to_num(vz)
    speed = np.clip(np.hypot(vx, vz / 3.0), 0.0, 3.0)
    return vx, vz, speed
