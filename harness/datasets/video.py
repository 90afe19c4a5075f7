"""Video files (anything ``cv2.VideoCapture`` opens) as sequences, with optional MOT gt.

Frame k (1-based) is the k-th decoded frame. Sequential reading keeps the capture open and
remembers its position, so reading frames in order decodes each frame once; a jump back or
far ahead seeks (``CAP_PROP_POS_FRAMES``), a short jump ahead decodes through the gap
(``grab``), which is exact for every codec.
"""

from __future__ import annotations

import logging
from pathlib import Path

import cv2
import numpy as np

from harness.datasets.base import GroundTruth, Sequence, window
from harness.datasets.images import FrameError
from harness.datasets.mot import ground_truth_from_table
from harness.io.mot import MotTable, read_mot
from trackers.records import SequenceInfo

log = logging.getLogger(__name__)

VIDEO_EXTENSIONS = (".mpg", ".mpeg", ".mp4", ".avi", ".mov", ".mkv", ".m4v", ".webm", ".wmv")

#: a forward jump of at most this many frames is decoded through instead of seeking
GRAB_AHEAD = 32

#: containers whose frame count FFmpeg estimates from the duration and in which seeking by
#: frame number lands on wrong frames (measured: an MPEG-1 program stream of 295 frames
#: reports 293, and seeking to frame 290 returns frame 288): their frames are counted by
#: decoding once, and a jump back reopens the file and decodes forward (exact, slower).
UNRELIABLE_SEEK = (".mpg", ".mpeg", ".mpe", ".m1v", ".m2v", ".vob", ".ts", ".m2ts")


class VideoSequence(Sequence):
    """A video file as a sequence.

    Args:
        path: video file.
        gt: ground truth (a ``GroundTruth``, or a MOT gt file path) or None.
        public_detections: a ``MotTable`` or MOT det file path, or None.
        name: sequence name; None = the file stem.
        fps: frame rate; None = the container's (25 when it reports none, logged).
        exact: count frames by decoding and never seek by frame number (slower random
            access, always right); None = only for ``UNRELIABLE_SEEK`` containers (MPEG).
    Raises:
        FileNotFoundError: no such video (or gt/det file).
        FrameError: OpenCV cannot open or decode the video.
    """

    def __init__(self, path: str | Path, gt: GroundTruth | str | Path | None = None,
                 public_detections: MotTable | str | Path | None = None,
                 name: str | None = None, fps: float | None = None,
                 exact: bool | None = None) -> None:
        self.path = Path(path).expanduser()
        if not self.path.is_file():
            raise FileNotFoundError(f"video file not found: {self.path}")
        if fps is not None and fps <= 0:
            raise ValueError(f"fps must be positive, got {fps}")
        self._cap: cv2.VideoCapture | None = None
        self._next = 1  # frame the capture decodes on the next read()
        self._last: tuple[int, np.ndarray] | None = None
        self.exact = self.path.suffix.lower() in UNRELIABLE_SEEK if exact is None else bool(exact)
        cap = self._capture()
        length = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
        width = int(cap.get(cv2.CAP_PROP_FRAME_WIDTH))
        height = int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT))
        rate = float(fps) if fps is not None else float(cap.get(cv2.CAP_PROP_FPS))
        if not np.isfinite(rate) or rate <= 0:
            log.warning("%s: the container reports no frame rate; assuming 25 fps", self.path)
            rate = 25.0
        if self.exact:
            reported, length = length, self._count_frames()
            if reported != length:
                log.info("%s: %d frames (the container estimates %d)", self.path, length, reported)
        elif length <= 0:
            length = self._count_frames()
            log.warning("%s: the container reports no frame count; counted %d frames",
                        self.path, length)
        if length <= 0 or width <= 0 or height <= 0:
            raise FrameError(f"{self.path}: video holds no decodable frames")
        self.info = SequenceInfo(name=name or self.path.stem, width=width, height=height,
                                 fps=rate, length=length)
        if isinstance(gt, (str, Path)):
            gt = ground_truth_from_table(read_mot(gt, gt=True))
        self.gt = gt
        if isinstance(public_detections, (str, Path)):
            public_detections = read_mot(public_detections, kind="det")
        self.public_detections = public_detections

    def _capture(self) -> cv2.VideoCapture:
        if self._cap is None:
            cap = cv2.VideoCapture(str(self.path))
            if not cap.isOpened():
                raise FrameError(f"cannot open video (corrupt or unsupported codec): {self.path}")
            self._cap = cap
            self._next = 1
        return self._cap

    def _count_frames(self) -> int:
        cap = self._capture()
        n = 0
        while cap.grab():
            n += 1
        self.close()
        return n

    def close(self) -> None:
        """Release the capture (it is reopened on the next ``frame`` call)."""
        if self._cap is not None:
            self._cap.release()
        self._cap = None
        self._next = 1

    def __getstate__(self) -> dict:
        # a VideoCapture cannot be pickled (joblib workers): reopen it on first use
        state = self.__dict__.copy()
        state.update(_cap=None, _next=1, _last=None)
        return state

    def __del__(self) -> None:
        cap = getattr(self, "_cap", None)
        if cap is not None:
            cap.release()

    def frame(self, index: int) -> np.ndarray:
        """Frame ``index`` (1-based) as (H, W, 3) uint8 BGR.

        Raises:
            IndexError: index outside 1..length.
            FrameError: the video cannot be decoded at that frame.
        """
        k = int(index)
        if not 1 <= k <= self.info.length:
            raise IndexError(f"{self.info.name}: frame {index} outside 1..{self.info.length}")
        if self._last is not None and self._last[0] == k:
            return self._last[1].copy()
        cap = self._capture()
        if k < self._next and self.exact:
            self.close()  # no seeking: reopen and decode forward
            cap = self._capture()
        if self._next < k and (self.exact or k <= self._next + GRAB_AHEAD):
            while self._next < k:
                if not cap.grab():
                    self.close()
                    raise FrameError(f"{self.path}: cannot decode frame {self._next} "
                                     f"of {self.info.length}")
                self._next += 1
        elif k != self._next:
            cap.set(cv2.CAP_PROP_POS_FRAMES, k - 1)
            self._next = k
        ok, image = cap.read()
        if not ok or image is None:
            self.close()
            raise FrameError(f"{self.path}: cannot decode frame {k} of {self.info.length}")
        self._next = k + 1
        if image.ndim == 2:
            image = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
        self._last = (k, image)
        return image.copy()


def load_video(path: str | Path, gt: str | Path | None = None, name: str | None = None,
               fps: float | None = None, det: str | Path | None = None,
               exact: bool | None = None, frames: list[int] | None = None) -> list[Sequence]:
    """One video file as a one-sequence dataset.

    Args:
        path: any file ``cv2.VideoCapture`` reads.
        gt: optional MOT ground-truth file (1-based frames matching the video's frames).
        name: sequence name (default: the file stem; results are written as <name>.txt).
        fps: frame rate overriding the container's.
        det: optional MOT detection file (public detections).
        exact: never seek by frame number (see ``VideoSequence``); None = only for MPEG.
        frames: [first, last] (1-based, inclusive) to keep only those frames, numbered as in
            the whole video (``harness.datasets.base.window``); None = all.
    """
    path = Path(path).expanduser()
    if not path.exists():
        raise FileNotFoundError(f"video file not found: {path}")
    seq = VideoSequence(path, gt=gt, public_detections=det, name=name, fps=fps, exact=exact)
    if seq.gt is not None and len(seq.gt.table) and seq.gt.table.frames.max() > seq.info.length:
        log.warning("%s: gt reaches frame %d but the video has %d frames", gt,
                    int(seq.gt.table.frames.max()), seq.info.length)
    return window([seq], frames)
