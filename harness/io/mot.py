"""Reading MOTChallenge text files; ``occbench.io.write`` writes them. These two modules are
the one place that converts between 1-based files and 0-based boxes.

Rows are ``frame, id, left, top, width, height, conf, x, y, z`` (MOT15) or
``frame, id, left, top, width, height, conf, class, visibility`` (MOT16+ gt). Boxes in
memory are xywh with a 0-based top-left (see ``occbench.trackers.records``): reading subtracts 1
from left and top, writing (``occbench.io.write``) adds it back.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from occbench.io.columns import read_columns
from occbench.io.frame_bounds import beyond_frame, why_beyond

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


READ_KINDS = ("any", "gt", "det", "result")

#: largest frame number, id or class accepted: a bigger one is a misprint (``1e20`` would
#: wrap to -9223372036854775808 as int64); TrackEval reads these columns as 32-bit too
MAX_INT = 2**31 - 1
MAX_COORD = 1e9  # |left|, |top|, width, height beyond it: refused (no image is that large,
# and 1e308 overflows the overlap arithmetic: every match of the sequence would be lost)

#: MOTChallenge gt classes (column 8 of MOT16+ gt): 1 is a pedestrian; MOT15-style gt has
#: no class column and its rows get NO_CLASS (scored as pedestrians, as by TrackEval)
PEDESTRIAN_CLASS = 1
NO_CLASS = -1


def scored_gt_mask(gt: MotTable) -> np.ndarray:
    """(N,) bool: gt rows that are scored: conf != 0 and class pedestrian or no class (the
    MOTChallenge rule; ``occbench.metrics.frames`` applies it)."""
    return _scored(gt.conf, gt.classes)


def _scored(conf: np.ndarray, classes: np.ndarray) -> np.ndarray:
    """``scored_gt_mask`` of (N,) conf and class columns."""
    return (conf != 0) & np.isin(classes, (PEDESTRIAN_CLASS, NO_CLASS))


def read_mot(path: str | Path, gt: bool = False, kind: str = "any",
             last_frame: int | None = None, image: tuple[int, int] | None = None) -> MotTable:
    """Read a MOT gt, det or result file, validating every field of every row.

    Args:
        path: UTF-8 text (a byte-order mark is allowed) with comma separated rows of 6 to 10
            fields (whitespace separated when a row has no comma; one trailing comma is
            allowed, as TrackEval allows it), every row with the same number of fields.
        gt: interpret columns 8 and 9 as class and visibility (MOT16+ gt with 9 columns);
            implies ``kind="gt"``.
        kind: what the file holds, for the identity column: ``gt`` and ``result`` need a
            positive integer id; ``det`` any integer (-1 by convention); ``any`` a positive
            integer or -1.
        last_frame: the sequence's last frame number (seqinfo.ini's ``seqLength``); a row
            beyond it is an error, in a gt file as in TrackEval, and in a result file (it
            would silently count as a false positive).
        image: the sequence's frame (width, height) when known: a box wider or taller than
            100 frames is an error, and so is a gt row to score whose box lies wholly
            outside the frame (``frame_bounds``: nobody there can be seen, always a miss).
    Raises:
        FileNotFoundError: no such file.
        MotFormatError: naming file and line and what was expected: text that is not
            UTF-8; fewer than 6 or more than 10 fields, an empty field, or another number
            of fields than the first row's; a field that is not a number; a frame that is
            not an integer in 1..``last_frame`` (or ``MAX_INT``); an id that is not an
            integer as ``kind`` needs; a box coordinate or size beyond +-``MAX_COORD``
            (1e9 pixels); a NaN or infinite confidence/score, class,
            visibility or world coordinate; in gt, a conf other than 0 or 1, a class
            that is not a positive integer, a visibility outside [0, 1] (-1 = unknown),
            or no row to score at all (every row conf 0 or of another class than
            pedestrian: HOTA 0 without a word otherwise).
    Rows whose box has a NaN, infinite or non-positive width/height are skipped with a
    warning naming file and line; an empty file gives an empty table (logged).
    """
    path = Path(path)
    if gt:
        kind = "gt"
    if kind not in READ_KINDS:
        raise ValueError(f"kind must be one of {READ_KINDS}, got {kind!r}")
    if not path.is_file():
        raise FileNotFoundError(f"MOT file not found: {path}")
    return _parse_text(read_utf8(path, MotFormatError), path, kind, last_frame, image)


def read_mot_text(text: str, path: str | Path, kind: str = "any",
                  last_frame: int | None = None, image: tuple[int, int] | None = None
                  ) -> MotTable:
    """``read_mot`` of the text of a MOT file (``path`` names it in messages): the run
    scores exactly the bytes it writes, even when writing them failed."""
    if kind not in READ_KINDS:
        raise ValueError(f"kind must be one of {READ_KINDS}, got {kind!r}")
    return _parse_text(text.removeprefix("\ufeff"), Path(path), kind, last_frame, image)


def read_utf8(path: Path, error: type[ValueError]) -> str:
    """The text of a UTF-8 file (a leading byte-order mark dropped); ``error`` naming file
    and line where the bytes are not UTF-8."""
    data = path.read_bytes()
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        line = data[:err.start].count(b"\n") + 1
        raise error(f"{path}:{line}: not UTF-8 text (byte {err.start}: "
                    f"{data[err.start:err.start + 1]!r})") from None


def text_lines(path: Path, error: type[ValueError]) -> list[str]:
    """The lines of a UTF-8 text file (``read_utf8``)."""
    return read_utf8(path, error).splitlines()


def _parse_text(text: str, path: Path, kind: str, last_frame: int | None,
                image: tuple[int, int] | None = None) -> MotTable:
    """The rows of a MOT file's text: ``_parse_fast`` when it applies, else line by line;
    a gt with no row to score is an error either way."""
    table = _parse_fast(text, path, kind, last_frame, image)
    if table is None:
        table = _parse(text.splitlines(), path, kind, last_frame, image)
    if kind == "gt" and len(table) and not scored_gt_mask(table).any():
        raise MotFormatError(
            f"{path}: nothing to score: none of its {len(table)} rows has conf 1 and class "
            f"{PEDESTRIAN_CLASS} (pedestrian) or no class; a MOT gt row with conf 0 is ignored")
    return table


def _parse_fast(text: str, path: Path, kind: str, last_frame: int | None,
                image: tuple[int, int] | None = None) -> MotTable | None:
    """The common case in one vectorised pass (a C reader, floats parsed as Python parses
    them: ``occbench.io.columns``): comma-separated rows all of one width (6 to 10), no
    comment, every row valid by ``_check_row``'s rules. None for anything else, which
    ``_parse`` then reads line by line with its exact warnings and errors naming the line
    (tests/harness/io/test_mot.py: both give the same table)."""
    if "#" in text or "_" in text or not text.strip():
        return None
    a = read_columns(text)
    if a is None:
        return None
    ncols = a.shape[1]
    if not 6 <= ncols <= 10 or not np.isfinite(a).all():
        return None
    a = np.hstack([a, np.full((len(a), 10 - ncols), -1.0)])
    frame, ident = a[:, 0], a[:, 1]
    top = MAX_INT if last_frame is None else min(last_frame, MAX_INT)
    ok = (frame == np.floor(frame)).all() and (frame >= 1).all() and (frame <= top).all()
    ok = ok and (ident == np.floor(ident)).all() and (np.abs(ident) <= MAX_INT).all()
    ok = ok and (a[:, 4] > 0).all() and (a[:, 5] > 0).all()
    ok = ok and (np.abs(a[:, 2:6]) <= MAX_COORD).all()
    if kind in ("gt", "result"):
        ok = ok and (ident >= 1).all()
    elif kind == "any":
        ok = ok and ((ident >= 1) | (ident == -1)).all()
    if kind == "gt" and ok:
        ok = ncols < 7 or np.isin(a[:, 6], (0.0, 1.0)).all()
        if ncols == 9:
            cls, vis = a[:, 7], a[:, 8]
            ok = ok and ((cls == np.floor(cls)) & (cls >= 1) & (cls <= MAX_INT)).all()
            ok = ok and (((vis >= 0) & (vis <= 1)) | (vis == -1)).all()
    if ok and image is not None:
        ok = not _beyond_image(a, ncols, kind, image).any()
    return _table(a, ncols, kind == "gt", path) if ok else None


def _beyond_image(a: np.ndarray, ncols: int, kind: str, image: tuple[int, int]) -> np.ndarray:
    """(R,) bool rows (R, 10) the frame (width, height) refuses (``frame_bounds``); gt rows
    to score by ``scored_gt_mask``'s rule."""
    boxes = a[:, 2:6] - [1.0, 1.0, 0.0, 0.0]  # 1-based file -> 0-based
    scored = None
    if kind == "gt":  # conf: -1 (padding) without the column; class: as _table reads it
        scored = _scored(a[:, 6], a[:, 7] if ncols == 9 else np.full(len(a), NO_CLASS))
    return beyond_frame(boxes, scored, image)


def _parse(lines: Iterable[str], path: Path, kind: str, last_frame: int | None,
           image: tuple[int, int] | None = None) -> MotTable:
    values: list[list[float]] = []
    skipped = 0
    first: tuple[int, int] | None = None  # (line, fields) of the first row
    for lineno, line in enumerate(lines, 1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        where = f"{path}:{lineno}"
        fields = _fields(text, where)
        if first is None:
            first = (lineno, len(fields))
        elif len(fields) != first[1]:
            raise MotFormatError(
                f"{where}: {len(fields)} fields but line {first[0]} has {first[1]}: every row "
                f"of a MOT file has the same columns: {text!r}")
        try:
            row = [_number(v) for v in fields]
        except ValueError as err:
            raise MotFormatError(f"{where}: not a number ({err}): {text!r}") from None
        _check_row(row, kind, last_frame, where, text)
        row += [-1.0] * (10 - len(row))
        if not (np.isfinite(row[2:6]).all() and row[4] > 0 and row[5] > 0):
            log.warning("%s: skipped box with NaN or non-positive size: %r", where, text)
            skipped += 1
            continue
        if image is not None and _beyond_image(np.array([row]), first[1], kind, image)[0]:
            box = np.array(row[2:6]) - [1.0, 1.0, 0.0, 0.0]
            raise MotFormatError(f"{where}: {why_beyond(box, image)}: {text!r}")
        values.append(row)
    if skipped:
        log.warning("%s: %d rows skipped", path, skipped)
    if not values:
        log.warning("%s: no rows", path)
        return MotTable.empty(str(path))
    return _table(np.asarray(values, dtype=np.float64), first[1], kind == "gt", path)


def _fields(text: str, where: str) -> list[str]:
    """The fields of one row: comma separated (stripped; one trailing comma allowed), else
    whitespace separated; 6 to 10 of them, none empty."""
    if "," in text:
        fields = [f.strip() for f in text.split(",")]
        if len(fields) > 1 and fields[-1] == "":
            fields.pop()  # "1,2,...,-1," as some writers leave it (TrackEval drops it too)
    else:
        fields = text.split()
    if "" in fields:
        raise MotFormatError(f"{where}: field {fields.index('') + 1} is empty: {text!r}")
    if not 6 <= len(fields) <= 10:
        raise MotFormatError(f"{where}: expected 6 to 10 fields, got {len(fields)}: {text!r}")
    return fields


def _table(a: np.ndarray, ncols: int, gt: bool, path: Path) -> MotTable:
    """The table of validated rows (R, 10), sorted by (frame, id); ``ncols`` the fields of
    every row before padding to 10."""
    step, id_step = np.diff(a[:, 0]), np.diff(a[:, 1])
    if not ((step > 0) | ((step == 0) & (id_step >= 0))).all():  # else sorted already
        a = a[np.lexsort((a[:, 1], a[:, 0]))]
    mot16_gt = gt and ncols == 9
    boxes = a[:, 2:6].copy()
    boxes[:, :2] -= 1.0  # 1-based file -> 0-based memory
    # MOT16+ gt has exactly 9 columns (class, visibility); MOT15 gt has 10 whose columns
    # 8-10 are world coordinates x, y, z (or -1): no class, no visibility.
    classes = a[:, 7].astype(np.int64) if mot16_gt else np.full(len(a), NO_CLASS, np.int64)
    visibility = a[:, 8].copy() if mot16_gt else np.full(len(a), np.nan)
    if mot16_gt:
        visibility[visibility < 0] = np.nan
    return MotTable(a[:, 0].astype(np.int64), a[:, 1].astype(np.int64), boxes, a[:, 6].copy(),
                    classes, visibility, str(path))


def _check_row(row: list[float], kind: str, last_frame: int | None, where: str,
               text: str) -> None:
    """Raise ``MotFormatError`` (naming ``where``, i.e. file:line, and what was expected) for
    a row whose frame, id or other non-box field is not what a MOT file of ``kind`` allows."""
    frame, ident = row[0], row[1]
    top = MAX_INT if last_frame is None else last_frame
    if not _is_int(frame, 1, MAX_INT):
        raise MotFormatError(f"{where}: frame must be a positive integer up to {MAX_INT}, got "
                             f"{_shown(frame)}: {text!r}")
    if frame > top:
        raise MotFormatError(f"{where}: frame {int(frame)} is beyond the sequence's last frame "
                             f"{last_frame} (seqLength): {text!r}")
    if not _is_int(ident, -MAX_INT, MAX_INT):
        raise MotFormatError(f"{where}: id must be an integer up to {MAX_INT} in size, got "
                             f"{_shown(ident)}: {text!r}")
    if kind in ("gt", "result") and ident < 1:
        raise MotFormatError(f"{where}: id must be a positive integer in a {kind} file, got "
                             f"{int(ident)}: {text!r}")
    if kind == "any" and ident < 1 and ident != -1:
        raise MotFormatError(f"{where}: id must be a positive integer (or -1 for a detection), "
                             f"got {int(ident)}: {text!r}")
    for col, name in enumerate(("left", "top", "width", "height"), 2):
        if math.isfinite(row[col]) and abs(row[col]) > MAX_COORD:
            raise MotFormatError(f"{where}: box {name} must lie within +-{MAX_COORD:.0e} "
                                 f"pixels, got {_shown(row[col])}: {text!r}")
    for col in range(6, len(row)):
        if not math.isfinite(row[col]):
            name = "confidence/score" if col == 6 else f"column {col + 1}"
            raise MotFormatError(f"{where}: {name} must be a finite number, got "
                                 f"{_shown(row[col])}: {text!r}")
    if kind == "gt":
        _check_gt_fields(row, where, text)


def _check_gt_fields(row: list[float], where: str, text: str) -> None:
    """gt only: conf 0 or 1 (TrackEval reads it as an integer: 0.5 would be ignored there
    and scored here); in 9-column (MOT16+) gt a positive integer class and a visibility in
    [0, 1] or -1 (unknown)."""
    if len(row) > 6 and row[6] not in (0.0, 1.0):
        raise MotFormatError(f"{where}: gt conf must be 0 (ignore) or 1 (score), got "
                             f"{_shown(row[6])}: {text!r}")
    if len(row) == 9:
        if not _is_int(row[7], 1, MAX_INT):
            raise MotFormatError(f"{where}: gt class (column 8) must be a positive integer, "
                                 f"got {_shown(row[7])}: {text!r}")
        if not (0.0 <= row[8] <= 1.0 or row[8] == -1.0):
            raise MotFormatError(f"{where}: gt visibility (column 9) must lie in [0, 1] (or be "
                                 f"-1 = unknown), got {_shown(row[8])}: {text!r}")


def _number(text: str) -> float:
    """``float(text)``, without Python's digit grouping: ``1_000`` is a misprint here."""
    if "_" in text:
        raise ValueError(f"could not convert string to float: {text!r}")
    return float(text)


def _is_int(v: float, low: int, high: int) -> bool:
    return math.isfinite(v) and v == int(v) and low <= v <= high


def _shown(v: float) -> str:
    """``v`` as written: a whole number as an integer, a huge one as 1e+308 (not 309 digits)."""
    return str(int(v)) if math.isfinite(v) and v == int(v) and abs(v) <= 1e20 else repr(v)
