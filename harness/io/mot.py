"""MOTChallenge text files: the one place that converts between 1-based files and 0-based boxes.

Rows are ``frame, id, left, top, width, height, conf, x, y, z`` (MOT15) or
``frame, id, left, top, width, height, conf, class, visibility`` (MOT16+ gt). Boxes in
memory are xywh with a 0-based top-left (see ``trackers.records``): reading subtracts 1
from left and top, writing adds it back.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np

log = logging.getLogger(__name__)


class MotFormatError(ValueError):
    """A MOT file that cannot be read; the message names the file and line."""


@dataclass
class MotTable:
    """Rows of a MOT file, sorted by (frame, id).

    Attributes:
        frames: (N,) int64 1-based frame numbers.
        ids: (N,) int64 identities (-1 for detections).
        boxes: (N, 4) float64 xywh, 0-based top-left.
        conf: (N,) float64 column 7 (gt: 1 = consider, 0 = ignore; det: score).
        classes: (N,) int64 column 8 when the file is MOT16-style gt, else -1.
        visibility: (N,) float64 column 9 when present, else NaN.
        path: where the rows came from (for messages).
    """

    frames: np.ndarray
    ids: np.ndarray
    boxes: np.ndarray
    conf: np.ndarray
    classes: np.ndarray
    visibility: np.ndarray
    path: str = "<memory>"

    def __len__(self) -> int:
        return len(self.frames)

    def rows(self, keep: np.ndarray) -> MotTable:
        """The table restricted to a boolean mask or index array."""
        return MotTable(
            self.frames[keep], self.ids[keep], self.boxes[keep], self.conf[keep],
            self.classes[keep], self.visibility[keep], self.path,
        )

    def frame_index(self) -> dict[int, np.ndarray]:
        """Map frame number -> row indices of that frame (computed once; use it in loops)."""
        order = np.argsort(self.frames, kind="stable")
        uniq, starts = np.unique(self.frames[order], return_index=True)
        ends = np.r_[starts[1:], len(order)]
        return {int(u): order[a:b] for u, a, b in zip(uniq, starts, ends)}

    @classmethod
    def empty(cls, path: str = "<memory>") -> MotTable:
        z = np.zeros(0)
        return cls(z.astype(np.int64), z.astype(np.int64), np.zeros((0, 4)), z, z.astype(np.int64),
                   z.copy(), path)


def read_mot(path: str | Path, gt: bool = False) -> MotTable:
    """Read a MOT gt, det or result file.

    Args:
        path: text file with comma (or whitespace) separated rows of at least 6 fields.
        gt: interpret columns 8 and 9 as class and visibility (MOT16+ gt with 9 columns).
    Raises:
        FileNotFoundError: no such file.
        MotFormatError: a malformed row; the message gives file and line number.
    Rows with NaN, infinite or non-positive width/height are skipped with a warning
    naming file and line; an empty file gives an empty table.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"MOT file not found: {path}")
    values: list[list[float]] = []
    skipped = 0
    ncols = 0  # most fields on any row, before padding
    with path.open() as fh:
        for lineno, line in enumerate(fh, 1):
            text = line.strip()
            if not text or text.startswith("#"):
                continue
            fields = text.replace(",", " ").split()
            if len(fields) < 6:
                raise MotFormatError(
                    f"{path}:{lineno}: expected at least 6 fields, got {len(fields)}: {text!r}"
                )
            try:
                row = [float(v) for v in fields[:10]]
            except ValueError as err:
                raise MotFormatError(f"{path}:{lineno}: not a number ({err}): {text!r}") from None
            ncols = max(ncols, len(row))
            row += [-1.0] * (10 - len(row))
            if row[0] != int(row[0]) or row[0] < 1:
                raise MotFormatError(f"{path}:{lineno}: frame must be a positive integer: {text!r}")
            if not (np.isfinite(row[2:6]).all() and row[4] > 0 and row[5] > 0):
                log.warning("%s:%d: skipped box with NaN or non-positive size: %r", path, lineno, text)
                skipped += 1
                continue
            values.append(row)
    if skipped:
        log.warning("%s: %d rows skipped", path, skipped)
    if not values:
        log.warning("%s: no rows", path)
        return MotTable.empty(str(path))
    a = np.asarray(values, dtype=np.float64)
    order = np.lexsort((a[:, 1], a[:, 0]))
    a = a[order]
    boxes = a[:, 2:6].copy()
    boxes[:, :2] -= 1.0  # 1-based file -> 0-based memory
    # MOT16+ gt has exactly 9 columns (class, visibility); MOT15 gt has 10 whose columns
    # 8-10 are world coordinates x, y, z (or -1): no class, no visibility.
    mot16_gt = gt and ncols == 9
    classes = a[:, 7].astype(np.int64) if mot16_gt else np.full(len(a), -1, dtype=np.int64)
    visibility = a[:, 8].copy() if mot16_gt else np.full(len(a), np.nan)
    if mot16_gt:
        visibility[visibility < 0] = np.nan
    return MotTable(a[:, 0].astype(np.int64), a[:, 1].astype(np.int64), boxes, a[:, 6].copy(),
                    classes, visibility, str(path))


def write_mot(path: str | Path, frames: np.ndarray, ids: np.ndarray, boxes: np.ndarray,
              scores: np.ndarray | None = None) -> None:
    """Write MOT result rows ``frame,id,left,top,width,height,conf,-1,-1,-1`` (1-based boxes).

    Rows are sorted by (frame, id); numbers are written with 2 decimals so that the same
    input gives the same bytes.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    frames = np.asarray(frames, dtype=np.int64).reshape(-1)
    ids = np.asarray(ids, dtype=np.int64).reshape(-1)
    boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    scores = np.ones(len(frames)) if scores is None else np.asarray(scores, dtype=np.float64)
    order = np.lexsort((ids, frames))
    lines = [
        f"{f},{i},{b[0] + 1:.2f},{b[1] + 1:.2f},{b[2]:.2f},{b[3]:.2f},{s:.3f},-1,-1,-1\n"
        for f, i, b, s in zip(frames[order], ids[order], boxes[order], scores[order])
    ]
    tmp = path.with_suffix(path.suffix + ".part")
    tmp.write_text("".join(lines))
    tmp.replace(path)


def write_mot_gt(path: str | Path, table: MotTable) -> None:
    """Write ground truth as MOT16+ gt rows ``frame,id,left,top,width,height,conf,class,visibility``.

    Boxes 1-based with 6 decimals (reading the file back gives the boxes in memory to within
    5e-7 px); ``conf`` as it is (1 = scored, 0 = ignored); class as it is, except MOT15-style
    rows without a class (-1), which are written as 1 (pedestrian): they are scored as
    pedestrians here and by TrackEval's MOT16/17 rules alike; visibility as it is, -1 where
    unknown (``read_mot(path, gt=True)`` reads -1 back as NaN). Sorted by (frame, id).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    order = np.lexsort((table.ids, table.frames))
    classes = np.where(table.classes < 0, 1, table.classes)
    vis = np.where(np.isfinite(table.visibility), table.visibility, -1.0)
    lines = [
        f"{f},{i},{b[0] + 1:.6f},{b[1] + 1:.6f},{b[2]:.6f},{b[3]:.6f},{c:g},{k},{v:.6g}\n"
        for f, i, b, c, k, v in zip(table.frames[order], table.ids[order], table.boxes[order],
                                    table.conf[order], classes[order], vis[order])
    ]
    tmp = path.with_suffix(path.suffix + ".part")
    tmp.write_text("".join(lines))
    tmp.replace(path)


def write_seqinfo(path: str | Path, name: str, length: int, fps: float, width: int, height: int,
                  im_dir: str = "img1", im_ext: str = ".jpg") -> None:
    """Write a MOTChallenge ``seqinfo.ini`` (``[Sequence]`` name, imDir, frameRate, seqLength,
    imWidth, imHeight, imExt); the frame rate as an integer when it is one."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    rate = int(fps) if float(fps).is_integer() else fps
    path.write_text(f"[Sequence]\nname={name}\nimDir={im_dir}\nframeRate={rate}\n"
                    f"seqLength={int(length)}\nimWidth={int(width)}\nimHeight={int(height)}\n"
                    f"imExt={im_ext}\n")


def write_seqmap(path: str | Path, names: list[str]) -> None:
    """Write a MOTChallenge seqmap: the header ``name`` and one sequence name a line."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("".join(f"{n}\n" for n in ["name", *names]))
