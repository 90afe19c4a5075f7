"""MOTChallenge sequence folders: ``<root>/<sequence>/{seqinfo.ini, img1/, gt/gt.txt, det/det.txt}``.

Layout of one sequence folder (MOT15/16/17/20 and the shipped ``datasets/trajectories/``)::

    seqinfo.ini          [Sequence] name, imDir, frameRate, seqLength, imWidth, imHeight, imExt
    img1/000001.jpg ...  frame k is ``<imDir>/<k:06d><imExt>`` (optional: box-only without it)
    gt/gt.txt            ground truth (MOT15 10 columns, or MOT16+ with class and visibility)
    gt/gt_caviar_appearance.txt   optional ``frame,id,label`` CAVIAR appearance labels
    det/det.txt          public detections (optional)

Boxes are converted to 0-based xywh by ``occbench.io.mot.read_mot`` only.
"""

from __future__ import annotations

import configparser
import logging
import math
import re
from pathlib import Path

import numpy as np

from occbench.datasets.base import GroundTruth, Sequence, window
from occbench.datasets.images import ImageSequence, numbered_images
from occbench.datasets.images import image_size as read_image_size
from occbench.io.mot import MAX_INT, MotFormatError, MotTable, read_mot, text_lines
from occbench.trackers.records import SequenceInfo

log = logging.getLogger(__name__)

APPEARANCE_LABELS = ("visible", "occluded", "appear", "disappear")


class SeqInfoError(ValueError):
    """A seqinfo.ini that cannot be used; the message names the file and key."""


def load_mot(root: str | Path, sequences: list[str] | None = None,
             image_size: list[int] | tuple[int, int] | None = None, fps: float | None = None,
             occlusion_threshold: float = 0.5, prefetch: int = 2,
             frames: list[int] | None = None) -> list[Sequence]:
    """Read MOTChallenge sequence folders.

    Args:
        root: folder holding sequence folders (e.g. ``MOT17/train``), or one sequence folder
            itself (recognised by its ``seqinfo.ini``, ``img1/``, ``gt/`` or ``det/``).
        sequences: names of sequence folders under ``root``; None = every sequence folder,
            sorted by name.
        image_size: [width, height] for sequences whose size is neither in seqinfo.ini nor
            readable from a frame (box-only folders without seqinfo.ini, e.g. TUD-Campus).
        fps: frame rate overriding seqinfo.ini (needed only where seqinfo.ini has none;
            25 is assumed with a warning otherwise).
        occlusion_threshold: gt rows whose visibility is below it are flagged
            ``GroundTruth.occluded``; CAVIAR ``occluded`` labels are flagged too.
        prefetch: frames decoded ahead while iterating ``frames()``.
        frames: [first, last] (1-based, inclusive) to keep only those frames of every
            sequence, numbered as in the whole sequence (``occbench.datasets.base.window``).
    Returns:
        one ``ImageSequence`` per folder; without ``img1/`` the sequence is box-only
        (``has_pixels`` False, ``frame`` returns None): only box-only trackers can run on it.
    Raises:
        FileNotFoundError: ``root`` or a named sequence folder does not exist.
        SeqInfoError: a malformed seqinfo.ini, or a length/size that cannot be inferred.
        MotFormatError: a malformed gt/det line (file and line named).
    """
    root = Path(root).expanduser()
    if not root.exists():
        raise FileNotFoundError(f"MOT dataset root not found: {root}")
    if not root.is_dir():
        raise NotADirectoryError(f"MOT dataset root is not a folder: {root}")
    if image_size is not None and (len(image_size) != 2 or min(image_size) <= 0):
        raise ValueError(f"image_size must be [width, height] > 0, got {image_size!r}")
    if sequences is None:
        if _is_sequence_folder(root):
            folders = [root]
        else:
            folders = sorted((p for p in root.iterdir() if p.is_dir() and _is_sequence_folder(p)),
                             key=lambda p: p.name)
        if not folders:
            raise FileNotFoundError(
                f"no MOT sequence folders (with seqinfo.ini, img1/, gt/ or det/) under {root}"
            )
    else:
        if isinstance(sequences, str):
            sequences = [sequences]
        folders = []
        for name in sequences:
            folder = root / str(name)
            if not folder.is_dir():
                raise FileNotFoundError(f"MOT sequence folder not found: {folder}")
            folders.append(folder)
    return window([load_mot_sequence(f, image_size=image_size, fps=fps,
                                     occlusion_threshold=occlusion_threshold, prefetch=prefetch)
                   for f in folders], frames)


def _is_sequence_folder(folder: Path) -> bool:
    return any((folder / n).exists() for n in ("seqinfo.ini", "img1", "gt", "det"))


def read_seqinfo(path: Path) -> dict[str, str]:
    """The ``[Sequence]`` section of a seqinfo.ini as a dict (keys as written, e.g. imWidth).

    UTF-8 (a byte-order mark is allowed). Raises ``SeqInfoError`` naming the file (and the
    line, for bytes that are not UTF-8 or an ini syntax error, e.g. a key given twice)."""
    parser = configparser.ConfigParser(interpolation=None)
    parser.optionxform = str  # keep imWidth's case
    try:
        parser.read_string("\n".join(text_lines(path, SeqInfoError)), source=str(path))
    except configparser.Error as err:
        raise SeqInfoError(f"{path}: not an ini file: {err}") from None
    if not parser.has_section("Sequence"):
        raise SeqInfoError(f"{path}: no [Sequence] section")
    return dict(parser["Sequence"])


_INTEGER = re.compile(r"\+?\d+")


def seqinfo_number(info: dict[str, str], key: str, path: Path, kind: type) -> float | int | None:
    """A positive number of a seqinfo dict, None when absent; ``SeqInfoError`` naming file and
    key. ``kind=int`` (seqLength, imWidth, imHeight) takes only an integer up to ``MAX_INT``
    written as one (``seqLength=10.5`` is refused, as by TrackEval's ``int()``);
    ``kind=float`` (frameRate) any finite number."""
    text = info.get(key, "").strip()
    if not text:
        return None
    if kind is int:
        if not _INTEGER.fullmatch(text) or not 0 < int(text) <= MAX_INT:
            raise SeqInfoError(f"{path}: key {key!r} must be a positive integer up to "
                               f"{MAX_INT}, got {info[key]!r}")
        return int(text)
    try:
        value = kind(text)
    except ValueError:
        raise SeqInfoError(f"{path}: key {key!r} is not a number: {info[key]!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise SeqInfoError(f"{path}: key {key!r} must be a positive finite number, got "
                           f"{info[key]!r}")
    return value


def load_mot_sequence(folder: str | Path, image_size: list[int] | tuple[int, int] | None = None,
                      fps: float | None = None, occlusion_threshold: float = 0.5,
                      prefetch: int = 2) -> ImageSequence:
    """Read one MOTChallenge sequence folder (see ``load_mot`` for the arguments).

    The length is seqinfo.ini's ``seqLength``: a gt row beyond it is an error (TrackEval
    refuses such gt too; scoring it, or dropping it unseen, would both misreport the
    sequence), det rows beyond it are never used (logged). Without a ``seqLength`` the
    length is the furthest of the image files, gt and det rows; frame files missing in
    1..length raise ``FrameError`` when read (the sequence fails, the run goes on).
    """
    folder = Path(folder).expanduser()
    if not folder.is_dir():
        raise FileNotFoundError(f"MOT sequence folder not found: {folder}")
    ini_path = folder / "seqinfo.ini"
    ini = read_seqinfo(ini_path) if ini_path.is_file() else None
    if ini is None:
        log.warning("%s: no seqinfo.ini; inferring length and size from the files", folder)
        ini = {}
    name = ini.get("name", "").strip() or folder.name
    length = seqinfo_number(ini, "seqLength", ini_path, int)
    im_dir = folder / (ini.get("imDir", "").strip() or "img1")
    images = numbered_images(im_dir) if im_dir.is_dir() else {}
    if im_dir.is_dir() and not images:
        log.warning("%s: image folder holds no numbered images", im_dir)
    width, height = _frame_size(folder, ini, ini_path, images, image_size)
    gt, det = _annotations(folder, length, occlusion_threshold, (width, height))
    if length is None:
        length = _inferred_length(folder, images, [gt and gt.table, det])
    info = SequenceInfo(name=name, width=int(width), height=int(height),
                        fps=_frame_rate(folder, ini, ini_path, fps), length=int(length))
    if det is not None and len(det) and det.frames.max() > length:
        log.warning("%s: det has rows after the last frame %d (up to %d); they are never used",
                    folder, length, int(det.frames.max()))
    paths = _frame_paths(im_dir, images, ini, length, name)
    return ImageSequence(info, paths, gt=gt, public_detections=det, prefetch=prefetch)


def _annotations(folder: Path, length: int | None, occlusion_threshold: float,
                 image: tuple[int, int]) -> tuple[GroundTruth | None, MotTable | None]:
    """gt/gt.txt (rows up to ``length``, with appearance labels when present) and
    det/det.txt of a sequence folder, None where absent; boxes the (width, height) frame
    ``image`` refuses are errors (``read_mot``)."""
    gt = None
    gt_path = folder / "gt" / "gt.txt"
    if gt_path.is_file():
        gt = ground_truth_from_table(read_mot(gt_path, gt=True, last_frame=length, image=image),
                                     occlusion_threshold)
        labels_path = folder / "gt" / "gt_caviar_appearance.txt"
        if labels_path.is_file():
            attach_appearance_labels(gt, labels_path)
    det = None
    det_path = folder / "det" / "det.txt"
    if det_path.is_file():
        det = read_mot(det_path, kind="det", image=image)
        if len(det) == 0:
            log.warning("%s: empty detection file: no public detections in any frame", det_path)
    return gt, det


def _inferred_length(folder: Path, images: dict[int, Path],
                     tables: list[MotTable | None]) -> int:
    """The length without a seqLength: the furthest image file, gt or det frame."""
    candidates = [max(images)] if images else []
    candidates += [int(t.frames.max()) for t in tables if t is not None and len(t)]
    if not candidates:
        raise SeqInfoError(
            f"{folder}: cannot infer the sequence length: no seqLength in seqinfo.ini, "
            "no frames in img1/ and no rows in gt/gt.txt or det/det.txt"
        )
    log.warning("%s: length %d inferred from %s", folder, max(candidates),
                "the image files" if images else "the largest gt/det frame")
    return max(candidates)


def _frame_size(folder: Path, ini: dict[str, str], ini_path: Path, images: dict[int, Path],
                image_size: list[int] | tuple[int, int] | None) -> tuple[int, int]:
    """(width, height): seqinfo.ini's, else the first frame's, else ``image_size``."""
    width = seqinfo_number(ini, "imWidth", ini_path, int)
    height = seqinfo_number(ini, "imHeight", ini_path, int)
    if width is not None and height is not None:
        return width, height
    if images:
        width, height = read_image_size(images[min(images)])
        log.warning("%s: frame size %dx%d read from %s", folder, width, height,
                    images[min(images)].name)
        return width, height
    if image_size is not None:
        log.warning("%s: frame size %dx%d taken from the image_size argument", folder,
                    int(image_size[0]), int(image_size[1]))
        return int(image_size[0]), int(image_size[1])
    raise SeqInfoError(
        f"{folder}: cannot infer the frame size: no imWidth/imHeight in seqinfo.ini "
        "and no frames; write a seqinfo.ini or pass image_size=[width,height] "
        "(dataset.image_size=[W,H])"
    )


def _frame_rate(folder: Path, ini: dict[str, str], ini_path: Path, fps: float | None) -> float:
    """``fps`` when given, else seqinfo.ini's frameRate, else 25 (logged)."""
    if fps is not None:
        if fps <= 0:
            raise ValueError(f"fps must be positive, got {fps}")
        return float(fps)
    rate = seqinfo_number(ini, "frameRate", ini_path, float)
    if rate is None:
        log.warning("%s: no frameRate in seqinfo.ini; assuming 25 fps", folder)
        return 25.0
    return float(rate)


def _frame_paths(im_dir: Path, images: dict[int, Path], ini: dict[str, str], length: int,
                 name: str) -> list[Path] | None:
    """Frame k's file ``<imDir>/<k:06d><imExt>`` for k in 1..length; None (box-only) when
    the image folder is absent or empty."""
    if not images:
        log.warning("%s: no frames (%s/ absent or empty): box-only sequence, frame() returns "
                    "None; only trackers that need no pixels can run on it", name, im_dir.name)
        return None
    ext = ini.get("imExt", "").strip() or images[min(images)].suffix
    if not ext.startswith("."):
        ext = "." + ext
    paths = [im_dir / f"{k:06d}{ext}" for k in range(1, length + 1)]
    missing = sum(not p.is_file() for p in paths)
    if missing:
        log.warning("%s: %d of %d frame files missing; reading them raises FrameError",
                    im_dir, missing, length)
    return paths


def ground_truth_from_table(table: MotTable, occlusion_threshold: float = 0.5) -> GroundTruth:
    """Wrap gt rows: ``occluded`` = visibility < threshold where visibility is known, else
    False; None when no row has a visibility."""
    if not 0.0 <= occlusion_threshold <= 1.0:
        raise ValueError(f"occlusion_threshold must be in [0, 1], got {occlusion_threshold}")
    known = np.isfinite(table.visibility)
    occluded = None
    if known.any():
        occluded = np.zeros(len(table), dtype=bool)
        occluded[known] = table.visibility[known] < occlusion_threshold
    return GroundTruth(table=table, occluded=occluded)


def read_appearance_labels(path: str | Path) -> dict[tuple[int, int], str]:
    """``frame,id,label`` rows (frame and id as in gt.txt) -> {(frame, id): label}.

    Raises:
        FileNotFoundError: no such file.
        MotFormatError: a malformed line or an unknown label (file and line named).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"appearance label file not found: {path}")
    labels: dict[tuple[int, int], str] = {}
    for lineno, line in enumerate(text_lines(path, MotFormatError), 1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        fields = [f.strip() for f in text.split(",")]
        if len(fields) != 3:
            raise MotFormatError(f"{path}:{lineno}: expected frame,id,label: {text!r}")
        if not all(_INTEGER.fullmatch(f) and 0 < int(f) <= MAX_INT for f in fields[:2]):
            raise MotFormatError(f"{path}:{lineno}: frame and id must be positive integers up "
                                 f"to {MAX_INT}: {text!r}")
        if fields[2] not in APPEARANCE_LABELS:
            raise MotFormatError(
                f"{path}:{lineno}: label {fields[2]!r} is not one of {', '.join(APPEARANCE_LABELS)}"
            )
        key = (int(fields[0]), int(fields[1]))
        if key in labels:
            raise MotFormatError(f"{path}:{lineno}: frame {key[0]}, id {key[1]} labelled twice")
        labels[key] = fields[2]
    return labels


def attach_appearance_labels(gt: GroundTruth, path: str | Path) -> None:
    """Set ``gt.labels`` from an appearance label file and flag ``occluded`` rows (in place).

    Rows without a label get "" (logged); the ``occluded`` label sets ``gt.occluded``.
    """
    labels = read_appearance_labels(path)
    t = gt.table
    per_row = np.array([labels.get((int(f), int(i)), "") for f, i in zip(t.frames, t.ids)],
                       dtype=object)
    unlabelled = int(np.sum(per_row == ""))
    if unlabelled:
        log.warning("%s: %d gt rows have no appearance label", path, unlabelled)
    gt.labels = per_row.astype(str)
    flag = gt.labels == "occluded"
    gt.occluded = flag if gt.occluded is None else (gt.occluded | flag)
