"""CAVIAR sequences: JPEG frames or the MPEG video, plus the CVML XML ground truth.

CVML (``cols1gt.xml`` etc.) lists, per ``<frame number="n">`` (0-based), the objects
``<object id="i">`` (0-based ids) with ``<box xc yc w h/>`` (integer centre and size) and an
``<appearance>`` label: visible, occluded, appear or disappear. Groups (``<grouplist>``) are
not people and are ignored.

Conversion (worked out from ``CAVIAR-OneLeaveShop1cor/gt/gt.txt``, whose MOT rows are
``frame = n + 1, id = i + 1, left = xc - w / 2, top = yc - h / 2`` in MOT's 1-based pixel
coordinates, e.g. xc=114, w=57 -> left 85.5): the CAVIAR centre is a 1-based coordinate, so
the 0-based box in memory is ``(xc - w/2 - 1, yc - h/2 - 1, w, h)``, exactly what
``occbench.io.mot.read_mot`` gives for gt.txt.

Folder layouts accepted by ``load_caviar(root)``:
  * MOT-style: ``root/img1/000001.jpg ...``, ``root/seqinfo.ini``, ``root/gt/<name>.xml``;
  * original download: ``root/<name>.mpg`` (or another video) and ``root/<xx>gt.xml``;
  * a folder of JPEGs numbered in frame order (``OneLeaveShop1cor0000.jpg ...``).
"""

from __future__ import annotations

import logging
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from occbench.datasets.base import GroundTruth, Sequence, window
from occbench.datasets.images import ImageSequence, numbered_images, read_image
from occbench.datasets.mot import APPEARANCE_LABELS, read_seqinfo, seqinfo_number
from occbench.datasets.video import VIDEO_EXTENSIONS, VideoSequence
from occbench.io.mot import MAX_INT, MotTable, read_mot
from occbench.trackers.records import SequenceInfo

log = logging.getLogger(__name__)

CAVIAR_FPS = 25.0


class CaviarFormatError(ValueError):
    """A CVML file that cannot be read; the message names the file and frame/object."""


def read_cvml(path: str | Path, last_frame: int | None = None) -> GroundTruth:
    """Read CAVIAR CVML ground truth into MOT rows with appearance labels.

    Args:
        path: the CVML file.
        last_frame: the sequence's last frame (1-based, seqinfo.ini's seqLength); an
            object in a later frame is an error, as a gt.txt row past it is.
    Returns:
        ``GroundTruth`` whose table has 1-based frames (n + 1), ids i + 1, 0-based xywh
        boxes ``(xc - w/2 - 1, yc - h/2 - 1, w, h)``, conf 1, class -1, visibility NaN
        (sorted by frame, id); ``labels`` (N,) str appearance labels; ``occluded`` (N,) bool,
        True where the label is ``occluded``.
    Raises:
        FileNotFoundError: no such file.
        CaviarFormatError: malformed XML (line named); a frame number or object id that is
            not an integer in 0..``MAX_INT - 1``, a frame listed twice or past
            ``last_frame``; a missing box attribute, an unknown label, or an object listed
            twice in a frame (frame and object named).
    Boxes with a NaN or non-positive size are skipped with a warning naming frame and object.
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
    frames: set[int] = set()
    for frame_el in root.iter("frame"):
        n = _cvml_int(frame_el.attrib.get("number"))
        if n is None:
            raise CaviarFormatError(f"{path}: <frame> number must be an integer in "
                                    f"0..{MAX_INT - 1}, got {frame_el.attrib.get('number')!r}")
        if n in frames:
            raise CaviarFormatError(f"{path}: frame {n} is listed twice")
        frames.add(n)
        objects = frame_el.find("objectlist")
        if objects is None:
            continue
        if last_frame is not None and n + 1 > last_frame and len(objects.findall("object")):
            raise CaviarFormatError(
                f"{path}: frame {n} (sequence frame {n + 1}) is beyond the sequence's last "
                f"frame {last_frame} (seqLength in seqinfo.ini)")
        seen: set[int] = set()
        for obj in objects.findall("object"):
            found = _cvml_object(obj, f"{path}: frame {n}, object {obj.attrib.get('id', '?')}")
            if found is None:
                continue
            oid, box, label = found
            if oid in seen:
                raise CaviarFormatError(f"{path}: frame {n}, object {oid}: object listed twice "
                                        "in the frame")
            seen.add(oid)
            rows.append((n + 1, oid + 1, *box))
            labels.append(label)
    return _cvml_ground_truth(rows, labels, path)


def _cvml_int(text: str | None) -> int | None:
    """A CVML frame number or object id: an integer in 0..MAX_INT - 1 (1-based it is at
    most ``MAX_INT``), else None."""
    if text is None or not text.strip().isdigit():
        return None
    value = int(text)
    return value if value < MAX_INT else None


def _cvml_object(obj: ET.Element, where: str
                 ) -> tuple[int, tuple[float, float, float, float], str] | None:
    """(0-based id, 0-based xywh box, appearance label) of one ``<object>``; None (logged)
    for a box with a NaN or non-positive size. Raises ``CaviarFormatError`` naming ``where``."""
    oid = _cvml_int(obj.attrib.get("id"))
    box = obj.find("box")
    try:
        xc, yc, w, h = (float(box.attrib[k]) for k in ("xc", "yc", "w", "h"))
    except (KeyError, ValueError, AttributeError):
        oid = None
    if oid is None:
        raise CaviarFormatError(f"{where}: needs an integer id in 0..{MAX_INT - 1} and "
                                "<box xc yc w h> numbers")
    if not (np.isfinite([xc, yc, w, h]).all() and w > 0 and h > 0):
        log.warning("%s: skipped box with NaN or non-positive size", where)
        return None
    label_el = obj.find("appearance")
    label = (label_el.text or "").strip() if label_el is not None else "visible"
    if label not in APPEARANCE_LABELS:
        raise CaviarFormatError(
            f"{where}: appearance {label!r} is not one of {', '.join(APPEARANCE_LABELS)}"
        )
    return oid, (xc - w / 2 - 1.0, yc - h / 2 - 1.0, w, h), label


def _cvml_ground_truth(rows: list[tuple[int, int, float, float, float, float]],
                       labels: list[str], path: Path) -> GroundTruth:
    """MOT rows (1-based frame and id, 0-based xywh) and their labels as ``GroundTruth``,
    sorted by (frame, id)."""
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
            the whole sequence (``occbench.datasets.base.window``); None = all.
    Returns:
        a one-element list (the dataset-config contract) holding the sequence, whose
        ``gt.labels`` are the appearance labels and ``gt.occluded`` flags ``occluded``.
        Its length is seqinfo.ini's seqLength when there is one (gt past it is an error;
        a video with fewer frames fails when read past its end: ``VideoSequence``), else
        the frames' count, or the gt's last frame where that is further (a video cut
        short, JPEGs missing: reading past the frames raises ``FrameError``).
    Raises:
        FileNotFoundError: root, xml or video missing.
        CaviarFormatError: malformed XML, or gt past seqLength.
        SeqInfoError: a malformed seqinfo.ini (file and key named).
    """
    root = Path(root).expanduser()
    if not root.exists():
        raise FileNotFoundError(f"CAVIAR sequence folder not found: {root}")
    if not root.is_dir():
        raise NotADirectoryError(f"CAVIAR root is not a folder: {root}")
    ini_path = root / "seqinfo.ini"
    ini = read_seqinfo(ini_path) if ini_path.is_file() else {}
    length = seqinfo_number(ini, "seqLength", ini_path, int)
    size = (seqinfo_number(ini, "imWidth", ini_path, int),
            seqinfo_number(ini, "imHeight", ini_path, int))
    ini_fps = seqinfo_number(ini, "frameRate", ini_path, float)
    xml_path = Path(xml).expanduser() if xml is not None else _find_xml(root)
    gt = read_cvml(xml_path, last_frame=length)
    seq_name = name or ini.get("name", "").strip() or root.name
    det_path = root / "det" / "det.txt"
    det = read_mot(det_path, kind="det") if det_path.is_file() else None
    video = _find_video(root) if video is None else video
    if video is not None:
        seq = VideoSequence(video, gt=gt, public_detections=det, name=seq_name, fps=fps,
                            length=length)
        return window([seq], frames)
    seq = _image_sequence(root, length, size, gt, det, seq_name,
                          fps if fps is not None else ini_fps, prefetch)
    return window([seq], frames)


def _find_video(root: Path) -> Path | None:
    """The single video file in ``root`` when it has no ``img1/``, else None."""
    if (root / "img1").is_dir():
        return None
    videos = sorted(p for p in root.iterdir() if p.suffix.lower() in VIDEO_EXTENSIONS)
    if len(videos) > 1:
        raise ValueError(f"{root}: several videos ({', '.join(p.name for p in videos)}); "
                         "pass video=<path>")
    return videos[0] if videos else None


def _image_sequence(root: Path, length: int | None, size: tuple[int | None, int | None],
                    gt: GroundTruth, det: MotTable | None, name: str, fps: float | None,
                    prefetch: int) -> ImageSequence:
    """The JPEG frames of ``root/img1/`` (or ``root``) as a sequence, box-only without any."""
    last_gt = int(gt.table.frames.max()) if len(gt.table) else 0
    folder = root / "img1" if (root / "img1").is_dir() else root
    images = numbered_images(folder)
    if images:
        # frame k = the k-th file in numeric order (000001.jpg or the original ...0000.jpg)
        paths = [images[i] for i in sorted(images)]
        first = min(images)
        if sorted(images) != list(range(first, first + len(images))):
            log.warning("%s: frame numbers are not contiguous; frame k is the k-th file", folder)
        if length is not None and length != len(paths):
            raise ValueError(f"{folder}: {len(paths)} frames but seqLength={length} in seqinfo.ini")
        h, w = read_image(paths[0]).shape[:2]
        if last_gt > len(paths):  # JPEGs missing at the end: they fail when read
            log.warning("%s: ground truth reaches frame %d but there are %d frames: reading "
                        "past them raises FrameError", folder, last_gt, len(paths))
            paths += _following_names(paths[-1], last_gt - len(paths))
    else:
        log.warning("%s: no frames (no img1/, video or JPEGs): box-only sequence", root)
        paths = None
        w, h = size
        if w is None or h is None:
            w, h = 384, 288  # every CAVIAR clip is half-PAL 384x288
            log.warning("%s: no frames and no seqinfo.ini size: assuming CAVIAR's 384x288", root)
    length = len(paths) if paths is not None else (length or last_gt)
    rate = float(fps) if fps is not None else CAVIAR_FPS
    info = SequenceInfo(name=name, width=int(w), height=int(h), fps=rate, length=length)
    return ImageSequence(info, paths, gt=gt, public_detections=det, prefetch=prefetch)


def _following_names(last: Path, count: int) -> list[Path]:
    """The ``count`` file names that would follow ``last`` in its numbering
    (``Tiny0002.jpg`` -> ``Tiny0003.jpg`` ...): frames that do not exist, for a
    ``FrameError`` that names the missing file."""
    m = re.search(r"(\d+)$", last.stem)
    start, digits = int(m.group(1)), len(m.group(1))
    stem = last.stem[: m.start()]
    return [last.with_name(f"{stem}{start + j:0{digits}d}{last.suffix}")
            for j in range(1, count + 1)]
