"""Writing files: any text file atomically (``write_atomic``: through a ``.part`` file and a
rename, ``WriteError`` naming the file when it cannot be written) and MOTChallenge's files
(result rows, gt rows, ``seqinfo.ini``, seqmap) with 1-based boxes, as ``occbench.io.mot``
reads them.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from occbench.io.mot import MotTable


def format_mot(frames: np.ndarray, ids: np.ndarray, boxes: np.ndarray,
               scores: np.ndarray | None = None) -> str:
    """MOT result rows ``frame,id,left,top,width,height,conf,-1,-1,-1`` (1-based boxes) as
    text, sorted by (frame, id), numbers with 2 decimals (the same input, the same bytes)."""
    frames = np.asarray(frames, dtype=np.int64).reshape(-1)
    ids = np.asarray(ids, dtype=np.int64).reshape(-1)
    boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    scores = np.ones(len(frames)) if scores is None else np.asarray(scores, dtype=np.float64)
    order = np.lexsort((ids, frames))
    return "".join(
        f"{f},{i},{b[0] + 1:.2f},{b[1] + 1:.2f},{b[2]:.2f},{b[3]:.2f},{s:.3f},-1,-1,-1\n"
        for f, i, b, s in zip(frames[order], ids[order], boxes[order], scores[order])
    )


def write_mot(path: str | Path, frames: np.ndarray, ids: np.ndarray, boxes: np.ndarray,
              scores: np.ndarray | None = None) -> None:
    """Write MOT result rows (``format_mot``) atomically (``write_atomic``).

    Raises:
        WriteError: the file cannot be written (disk full, no permission); nothing is left
            half-written.
    """
    write_atomic(path, format_mot(frames, ids, boxes, scores))


class WriteError(OSError):
    """A file that cannot be written; one line naming the file and the reason
    (``strerror``, also its ``str``); ``errno`` is the underlying error's."""

    def __str__(self) -> str:
        return str(self.strerror)


def write_atomic(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path`` through ``<path>.part`` and a rename, so that a reader
    sees the old file or the whole new one; on failure the ``.part`` file is removed.

    Raises:
        WriteError: disk full, no permission, a folder in the way...: ``cannot write
            <path>: <reason>``.
    """
    path = Path(path)
    tmp = path.with_suffix(path.suffix + ".part")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(tmp, "w") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except OSError as err:
        try:
            tmp.unlink(missing_ok=True)
        except OSError:
            pass
        reason = err.strerror or str(err)
        where = f" ({err.filename})" if err.filename and str(err.filename) not in (
            str(path), str(tmp)) else ""
        raise WriteError(err.errno, f"cannot write {path}: {reason}{where}") from err
    return path


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
    write_atomic(path, "".join(lines))


def write_seqinfo(path: str | Path, name: str, length: int, fps: float, width: int, height: int,
                  im_dir: str = "img1", im_ext: str = ".jpg") -> None:
    """Write a MOTChallenge ``seqinfo.ini`` (``[Sequence]`` name, imDir, frameRate, seqLength,
    imWidth, imHeight, imExt); the frame rate as an integer when it is one."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    rate = int(fps) if float(fps).is_integer() else fps
    write_atomic(path, f"[Sequence]\nname={name}\nimDir={im_dir}\nframeRate={rate}\n"
                    f"seqLength={int(length)}\nimWidth={int(width)}\nimHeight={int(height)}\n"
                    f"imExt={im_ext}\n")


def write_seqmap(path: str | Path, names: list[str]) -> None:
    """Write a MOTChallenge seqmap: the header ``name`` and one sequence name a line."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_atomic(path, "".join(f"{n}\n" for n in ["name", *names]))
