"""Frame decoding shared by the dataset readers: image files, image-folder sequences.

Frames are (H, W, 3) uint8 BGR arrays (OpenCV's order). A frame that cannot be read raises
``FrameError`` naming the file, so that the runner can record which sequence failed and why;
readers never substitute black frames silently.
"""

from __future__ import annotations

import logging
import re
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path

import cv2
import numpy as np
import simplejpeg

from occbench.datasets.base import GroundTruth, Sequence
from occbench.io.mot import MotTable
from occbench.trackers.records import SequenceInfo

log = logging.getLogger(__name__)

IMAGE_EXTENSIONS = (".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff", ".webp", ".ppm", ".pgm")


class FrameError(RuntimeError):
    """A frame that is missing or cannot be decoded; the message names the file."""


JPEG_EXTENSIONS = (".jpg", ".jpeg", ".jpe", ".jfif")


def read_image(path: str | Path) -> np.ndarray:
    """Decode one image file as (H, W, 3) uint8 BGR (grey and 16-bit images are converted).

    JPEG files are decoded by libjpeg-turbo through ``simplejpeg`` in strict mode, so that a
    file libjpeg decodes only with a warning (a truncated file, "premature end of data
    segment", "N extraneous bytes before marker": the frame would be grey or smeared from
    the damage down) is an error like an undecodable one; the pixels equal ``cv2.imread``'s
    (same library, same settings). OpenCV's own decoder only prints such warnings, naming
    no file, and returns the damaged picture.

    Raises:
        FrameError: the file does not exist, cannot be read, or does not decode cleanly
            (corrupt, truncated or unsupported); the message names the file.
    """
    path = Path(path)
    if not path.is_file():
        raise FrameError(f"missing frame file: {path}")
    try:
        data = path.read_bytes()
    except OSError as err:
        raise FrameError(f"cannot read frame file {path}: {err.strerror or err}") from None
    if path.suffix.lower() in JPEG_EXTENSIONS or data[:2] == b"\xff\xd8":
        image = _decode_jpeg(data, path)
        if image is not None:
            return image
    image = cv2.imdecode(np.frombuffer(data, dtype=np.uint8), cv2.IMREAD_COLOR)
    if image is None:
        raise FrameError(f"cannot decode image (corrupt or unsupported format): {path}")
    return image


def _decode_jpeg(data: bytes, path: Path) -> np.ndarray | None:
    """Strict JPEG decoding (BGR); None when libjpeg-turbo's TurboJPEG API cannot handle the
    file at all (e.g. CMYK) but it is not damaged, so that OpenCV decodes it instead.

    Raises:
        FrameError: the file is damaged (libjpeg reports an error or a warning).
    """
    if not data.startswith(b"\xff\xd8"):
        raise FrameError(f"not a JPEG file (no start-of-image marker): {path}")
    try:
        return simplejpeg.decode_jpeg(data, colorspace="BGR", strict=True)
    except ValueError as err:
        strict_msg = str(err)
    try:  # decodes without strictness: the strict failure was a warning, i.e. damage
        simplejpeg.decode_jpeg(data, colorspace="BGR", strict=False)
    except ValueError as err:
        if "color" in str(err).lower():  # e.g. CMYK: not damage, OpenCV converts it
            return None
        truncated = "" if data.rstrip(b"\x00").endswith(b"\xff\xd9") else (
            "; no end-of-image marker: truncated?")
        raise FrameError(f"corrupt JPEG (libjpeg: {err}{truncated}): {path}") from None
    raise FrameError(f"corrupt JPEG (libjpeg: {strict_msg}): {path}")


def image_size(path: str | Path) -> tuple[int, int]:
    """(width, height) of an image file, by decoding it (raises ``FrameError``)."""
    h, w = read_image(path).shape[:2]
    return int(w), int(h)


def numbered_images(folder: str | Path) -> dict[int, Path]:
    """Image files of ``folder`` whose name ends in a number, keyed by that number.

    ``img1/000001.jpg`` -> {1: ...}; ``OneLeaveShop1cor0000.jpg`` -> {0: ...}. Files of
    other extensions are ignored.
    """
    found: dict[int, Path] = {}
    for p in Path(folder).iterdir():
        if p.suffix.lower() not in IMAGE_EXTENSIONS:
            continue
        m = re.search(r"(\d+)$", p.stem)
        if m:
            found[int(m.group(1))] = p
    return found


class ImageSequence(Sequence):
    """A sequence whose frame k is the image file ``paths[k - 1]``, or without pixels.

    Args:
        info: sequence metadata (the frame size is checked against each decoded frame).
        paths: one path per frame (length ``info.length``), or None for a box-only
            sequence (ground truth and detections but no frames: ``frame`` returns None).
        gt: ground truth or None.
        public_detections: the sequence's public detections or None.
        prefetch: frames decoded ahead in a background thread after each ``frame(k)``
            (OpenCV releases the GIL while decoding, so decoding overlaps the tracker);
            0 disables.
    """

    def __init__(self, info: SequenceInfo, paths: list[Path] | None,
                 gt: GroundTruth | None = None, public_detections: MotTable | None = None,
                 prefetch: int = 2) -> None:
        if paths is not None and len(paths) != info.length:
            raise ValueError(f"{info.name}: {len(paths)} frame paths for {info.length} frames")
        if prefetch < 0:
            raise ValueError(f"prefetch must be >= 0, got {prefetch}")
        self.info = info
        self.paths = None if paths is None else [Path(p) for p in paths]
        self.gt = gt
        self.public_detections = public_detections
        self.prefetch = int(prefetch)
        self._pool: ThreadPoolExecutor | None = None
        self._pending: dict[int, Future] = {}

    @property
    def has_pixels(self) -> bool:
        return self.paths is not None

    def _check_index(self, index: int) -> int:
        k = int(index)
        if not 1 <= k <= self.info.length:
            raise IndexError(f"{self.info.name}: frame {index} outside 1..{self.info.length}")
        return k

    def frame(self, index: int) -> np.ndarray | None:
        """Frame ``index`` (1-based) as (H, W, 3) uint8 BGR; None for a box-only sequence.

        After frame k, frames k+1..k+prefetch are decoded in a background thread, so
        reading in order (the runner's pattern) overlaps decoding with the caller's work.

        Raises:
            IndexError: index outside 1..length.
            FrameError: the file is missing, corrupt, or has another size than the sequence.
        """
        k = self._check_index(index)
        if self.paths is None:
            return None
        if self.prefetch == 0:
            return self._decode(k)
        pending = self._pending
        fut = pending.pop(k, None)
        for j in [j for j in pending if j < k or j > k + self.prefetch]:
            pending.pop(j).cancel()
        if self._pool is None:
            self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="occbench-decode")
        for j in range(k + 1, min(self.info.length, k + self.prefetch) + 1):
            if j not in pending:  # frame k, decoded below, is not waited for by the pool
                pending[j] = self._pool.submit(self._decode, j)
        image = self._decode(k) if fut is None else fut.result()
        if k == self.info.length:
            self.close()  # the last frame: do not keep an idle thread per finished sequence
        return image

    def _decode(self, k: int) -> np.ndarray:
        path = self.paths[k - 1]
        image = read_image(path)
        h, w = image.shape[:2]
        if (w, h) != (self.info.width, self.info.height):
            raise FrameError(
                f"{path}: frame is {w}x{h} but sequence {self.info.name!r} is "
                f"{self.info.width}x{self.info.height}"
            )
        return image

    def close(self) -> None:
        """Stop the background decoder (it restarts on the next ``frame`` call)."""
        for fut in self._pending.values():
            fut.cancel()
        self._pending = {}
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)
        self._pool = None

    def __getstate__(self) -> dict:
        # threads and futures cannot be pickled (joblib workers): restart them on first use
        state = self.__dict__.copy()
        state.update(_pool=None, _pending={})
        return state

    def __del__(self) -> None:
        pool = getattr(self, "_pool", None)
        if pool is not None:
            pool.shutdown(wait=False, cancel_futures=True)
