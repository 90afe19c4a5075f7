"""CAVIAR sequences: JPEG frames or the MPEG video, plus the CVML XML ground truth.

CVML (``cols1gt.xml`` etc.) lists, per ``<frame number="n">`` (0-based), the objects
``<object id="i">`` (0-based ids) with ``<box xc yc w h/>`` (integer centre and size) and an
``<appearance>`` label: visible, occluded, appear or disappear. Groups (``<grouplist>``) are
not people and are ignored.

Conversion (worked out from ``CAVIAR-OneLeaveShop1cor/gt/gt.txt``, whose MOT rows are
``frame = n + 1, id = i + 1, left = xc - w / 2, top = yc - h / 2`` in MOT's 1-based pixel
coordinates, e.g. xc=114, w=57 -> left 85.5): the CAVIAR centre is a 1-based coordinate, so
the 0-based box in memory is ``(xc - w/2 - 1, yc - h/2 - 1, w, h)``, exactly what
``harness.io.mot.read_mot`` gives for gt.txt.

Folder layouts accepted by ``load_caviar(root)``:
  * MOT-style: ``root/img1/000001.jpg ...``, ``root/seqinfo.ini``, ``root/gt/<name>.xml``;
  * original download: ``root/<name>.mpg`` (or another video) and ``root/<xx>gt.xml``;
  * a folder of JPEGs numbered in frame order (``OneLeaveShop1cor0000.jpg ...``).
"""

from __future__ import annotations

import logging
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from harness.datasets.base import GroundTruth, Sequence, window
from harness.datasets.images import ImageSequence, numbered_images, read_image
from harness.datasets.mot import APPEARANCE_LABELS, read_seqinfo, seqinfo_number
from harness.datasets.video import VIDEO_EXTENSIONS, VideoSequence
from harness.io.mot import MotTable, read_mot
from trackers.records import SequenceInfo

log = logging.getLogger(__name__)

CAVIAR_FPS = 25.0


class CaviarFormatError(ValueError):
    """A CVML file that cannot be read; the message names the file and frame/object."""


def read_cvml(path: str | Path) -> GroundTruth:
    """Read CAVIAR CVML ground truth into MOT rows with appearance labels.

    Returns:
        ``GroundTruth`` whose table has 1-based frames (n + 1), ids i + 1, 0-based xywh
        boxes ``(xc - w/2 - 1, yc - h/2 - 1, w, h)``, conf 1, class -1, visibility NaN
        (sorted by frame, id); ``labels`` (N,) str appearance labels; ``occluded`` (N,) bool,
        True where the label is ``occluded``.
    Raises:
        FileNotFoundError: no such file.
        CaviarFormatError: malformed XML (line named), a missing attribute or non-positive
            size (frame and object named), an unknown label, or a duplicated object.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"CAVIAR ground-truth file not found: {path}")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as err:
        raise CaviarFormatError(f"{path}: malformed XML at line {err.position[0]}: {err}") from None
    rows: list[tuple[int, int, float, float, float, float]] = []
    labels: list[str] = []
    seen: set[tuple[int, int]] = set()
    for frame_el in root.iter("frame"):
        try:
            n = int(frame_el.attrib["number"])
        except (KeyError, ValueError):
            raise CaviarFormatError(
                f"{path}: <frame> without an integer number attribute: {frame_el.attrib}"
            ) from None
        objects = frame_el.find("objectlist")
        if objects is None:
            continue
        for obj in objects.findall("object"):
            where = f"{path}: frame {n}, object {obj.attrib.get('id', '?')}"
            box = obj.find("box")
            try:
                oid = int(obj.attrib["id"])
                xc, yc, w, h = (float(box.attrib[k]) for k in ("xc", "yc", "w", "h"))
            except (KeyError, ValueError, AttributeError):
                raise CaviarFormatError(
                    f"{where}: needs an integer id and <box xc yc w h> numbers"
                ) from None
            if not (np.isfinite([xc, yc, w, h]).all() and w > 0 and h > 0):
                log.warning("%s: skipped box with NaN or non-positive size", where)
                continue
            label_el = obj.find("appearance")
            label = (label_el.text or "").strip() if label_el is not None else "visible"
            if label not in APPEARANCE_LABELS:
                raise CaviarFormatError(
                    f"{where}: appearance {label!r} is not one of {', '.join(APPEARANCE_LABELS)}"
                )
            key = (n + 1, oid + 1)
            if key in seen:
                raise CaviarFormatError(f"{where}: object listed twice in the frame")
            seen.add(key)
            rows.append((n + 1, oid + 1, xc - w / 2 - 1.0, yc - h / 2 - 1.0, w, h))
            labels.append(label)
    if not rows:
        log.warning("%s: no objects", path)
        table = MotTable.empty(str(path))
        return GroundTruth(table, np.zeros(0, dtype=bool), np.zeros(0, dtype=str))
    a = np.asarray(rows, dtype=np.float64)
    order = np.lexsort((a[:, 1], a[:, 0]))
    a = a[order]
    n_rows = len(a)
    table = MotTable(
        frames=a[:, 0].astype(np.int64), ids=a[:, 1].astype(np.int64), boxes=a[:, 2:6].copy(),
        conf=np.ones(n_rows), classes=np.full(n_rows, -1, dtype=np.int64),
        visibility=np.full(n_rows, np.nan), path=str(path),
    )
    label_arr = np.asarray(labels, dtype=str)[order]
    return GroundTruth(table=table, occluded=label_arr == "occluded", labels=label_arr)


def _find_xml(root: Path) -> Path:
    candidates = sorted((root / "gt").glob("*.xml")) if (root / "gt").is_dir() else []
    candidates += sorted(root.glob("*.xml"))
    preferred = [p for p in candidates if p.stem.lower().endswith("gt")]
    found = preferred or candidates
    if not found:
        raise FileNotFoundError(f"no CAVIAR XML ground truth (*.xml) in {root} or {root / 'gt'}")
    if len(found) > 1:
        raise ValueError(
            f"{root}: several XML files ({', '.join(p.name for p in found)}); pass xml=<path>"
        )
    return found[0]


def load_caviar(root: str | Path, xml: str | Path | None = None, video: str | Path | None = None,
                name: str | None = None, fps: float | None = None,
                prefetch: int = 2, frames: list[int] | None = None) -> list[Sequence]:
    """Read one CAVIAR sequence: frames (JPEG folder or video) plus CVML ground truth.

    Args:
        root: the sequence folder (see the module docstring for the layouts).
        xml: CVML ground truth; None = the single ``*gt.xml`` (or ``*.xml``) in
            ``root/gt/`` or ``root``.
        video: the MPEG (or any OpenCV-readable) video; None = ``root/img1/`` frames if
            present, else the single video file in ``root``, else the numbered JPEGs in
            ``root``; without any frames the sequence is box-only (logged).
        name: sequence name; None = seqinfo.ini's name, else the folder name.
        fps: frame rate; None = seqinfo.ini's, else the video's, else CAVIAR's 25.
        prefetch: frames decoded ahead while iterating a JPEG sequence.
        frames: [first, last] (1-based, inclusive) to keep only those frames, numbered as in
            the whole sequence (``harness.datasets.base.window``); None = all.
    Returns:
        a one-element list (the dataset-config contract) holding the sequence, whose
        ``gt.labels`` are the appearance labels and ``gt.occluded`` flags ``occluded``.
    Raises:
        FileNotFoundError: root, xml or video missing.
        CaviarFormatError: malformed XML.
    """
    root = Path(root).expanduser()
    if not root.exists():
        raise FileNotFoundError(f"CAVIAR sequence folder not found: {root}")
    if not root.is_dir():
        raise NotADirectoryError(f"CAVIAR root is not a folder: {root}")
    xml_path = Path(xml).expanduser() if xml is not None else _find_xml(root)
    gt = read_cvml(xml_path)
    ini_path = root / "seqinfo.ini"
    ini = read_seqinfo(ini_path) if ini_path.is_file() else {}
    ini_length = seqinfo_number(ini, "seqLength", ini_path, int)
    ini_width = seqinfo_number(ini, "imWidth", ini_path, int)
    ini_height = seqinfo_number(ini, "imHeight", ini_path, int)
    ini_fps = seqinfo_number(ini, "frameRate", ini_path, float)
    seq_name = name or ini.get("name", "").strip() or root.name
    last_gt = int(gt.table.frames.max()) if len(gt.table) else 0

    if video is None and not (root / "img1").is_dir():
        videos = sorted(p for p in root.iterdir() if p.suffix.lower() in VIDEO_EXTENSIONS)
        if len(videos) > 1:
            raise ValueError(f"{root}: several videos ({', '.join(p.name for p in videos)}); "
                             "pass video=<path>")
        video = videos[0] if videos else None
    det_path = root / "det" / "det.txt"
    det = read_mot(det_path, kind="det") if det_path.is_file() else None
    if video is not None:
        seq = VideoSequence(video, gt=gt, public_detections=det, name=seq_name, fps=fps)
        if last_gt > seq.info.length:
            log.warning("%s: ground truth reaches frame %d but the video has %d frames",
                        xml_path, last_gt, seq.info.length)
        return window([seq], frames)

    folder = root / "img1" if (root / "img1").is_dir() else root
    images = numbered_images(folder)
    if images:
        # frame k = the k-th file in numeric order (000001.jpg or the original ...0000.jpg)
        paths = [images[i] for i in sorted(images)]
        first = min(images)
        if sorted(images) != list(range(first, first + len(images))):
            log.warning("%s: frame numbers are not contiguous; frame k is the k-th file", folder)
        length = ini_length or len(paths)
        if length != len(paths):
            raise ValueError(f"{folder}: {len(paths)} frames but seqLength={length} in seqinfo.ini")
        h, w = read_image(paths[0]).shape[:2]
    else:
        log.warning("%s: no frames (no img1/, video or JPEGs): box-only sequence", root)
        paths = None
        if ini_width is None or ini_height is None:
            w, h = 384, 288  # every CAVIAR clip is half-PAL 384x288
            log.warning("%s: no frames and no seqinfo.ini size: assuming CAVIAR's 384x288", root)
        else:
            w, h = ini_width, ini_height
        length = ini_length or last_gt
    rate = float(fps) if fps is not None else float(ini_fps or CAVIAR_FPS)
    if last_gt > length:
        log.warning("%s: ground truth reaches frame %d but the sequence has %d frames",
                    xml_path, last_gt, length)
    info = SequenceInfo(name=seq_name, width=int(w), height=int(h), fps=rate, length=length)
    return window([ImageSequence(info, paths, gt=gt, public_detections=det, prefetch=prefetch)],
                  frames)
