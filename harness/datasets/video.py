"""Video files (anything ``cv2.VideoCapture`` opens) as sequences, with optional MOT gt.

Frame k (1-based) is the k-th decoded frame. Sequential reading keeps the capture open and
remembers its position, so reading frames in order decodes each frame once; a jump back or
far ahead seeks (``CAP_PROP_POS_FRAMES``), a short jump ahead decodes through the gap
(``grab``), which is exact for every codec.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path

import cv2
import numpy as np

from occbench.datasets.base import GroundTruth, Sequence, window
from occbench.datasets.images import FrameError
from occbench.datasets.mot import ground_truth_from_table
from occbench.errors import verbose
from occbench.io.mot import MotTable, read_mot
from occbench.trackers.records import SequenceInfo

log = logging.getLogger(__name__)

VIDEO_EXTENSIONS = (".mpg", ".mpeg", ".mp4", ".avi", ".mov", ".mkv", ".m4v", ".webm", ".wmv")

#: a forward jump of at most this many frames is decoded through instead of seeking
GRAB_AHEAD = 32

#: containers whose frame count FFmpeg estimates from the duration and in which seeking by
#: frame number lands on wrong frames (measured: an MPEG-1 program stream of 295 frames
#: reports 293, and seeking to frame 290 returns frame 288): their frames are counted by
#: decoding once, and a jump back reopens the file and decodes forward (exact, slower).
UNRELIABLE_SEEK = (".mpg", ".mpeg", ".mpe", ".m1v", ".m2v", ".vob", ".ts", ".m2ts")


def quiet_libav() -> None:
    """OpenCV's FFmpeg says nothing on stderr unless ``occbench -v``: a broken video's
    FFmpeg lines ('moov atom not found', 'error while decoding MB') came before the one line
    ``occbench: ...`` that names the file and the frame (``FrameError``). OpenCV reads
    ``OPENCV_FFMPEG_LOGLEVEL`` when it first opens a video in the process; a value the user
    set is kept."""
    if not verbose():
        os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")  # AV_LOG_QUIET


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
        length: the sequence's frame count as stated elsewhere (seqinfo.ini's seqLength);
            None = the video's frame count, or the ground truth's last frame where that is
            further. Past the video's decodable frames (a video cut short) ``frame`` raises
            ``FrameError``, as a missing image file does: the sequence fails, recorded.
    Raises:
        FileNotFoundError: no such video (or gt/det file).
        FrameError: OpenCV cannot open or decode the video, or PyAV cannot read its frame
            sizes.
    """

    def __init__(self, path: str | Path, gt: GroundTruth | str | Path | None = None,
                 public_detections: MotTable | str | Path | None = None,
                 name: str | None = None, fps: float | None = None,
                 exact: bool | None = None, length: int | None = None) -> None:
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
        width = int(cap.get(cv2.CAP_PROP_FRAME_WIDTH))
        height = int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT))
        rate = float(fps) if fps is not None else float(cap.get(cv2.CAP_PROP_FPS))
        if not np.isfinite(rate) or rate <= 0:
            log.warning("%s: the container reports no frame rate; assuming 25 fps", self.path)
            rate = 25.0
        #: frames OpenCV decodes (counted when the container's count is unreliable)
        self.decodable = self._frame_count(cap)
        if self.decodable <= 0 or width <= 0 or height <= 0:
            raise FrameError(f"{self.path}: video holds no decodable frames")
        #: why every frame is refused (the frame size changes mid-stream), or None
        self.refused = frame_size_change(self.path, every_frame=self.exact)
        if isinstance(gt, (str, Path)):  # boxes the frame refuses are errors (read_mot)
            gt = ground_truth_from_table(read_mot(gt, gt=True, last_frame=length,
                                                  image=(width, height)))
        self.gt = gt
        if isinstance(public_detections, (str, Path)):
            public_detections = read_mot(public_detections, kind="det", image=(width, height))
        self.public_detections = public_detections
        self.info = SequenceInfo(name=name or self.path.stem, width=width, height=height,
                                 fps=rate, length=self._length(length))

    def _frame_count(self, cap: cv2.VideoCapture) -> int:
        length = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
        if self.exact:
            reported, length = length, self._count_frames()
            if reported != length:
                log.info("%s: %d frames, counted by decoding (its container reports %d, an "
                         "estimate in this format)", self.path, length, reported)
        elif length <= 0:
            length = self._count_frames()
            log.warning("%s: the container reports no frame count; counted %d frames",
                        self.path, length)
        return length

    def _length(self, length: int | None) -> int:
        """The sequence's length: ``length`` (seqLength), else the furthest of the video's
        frames and the ground truth's; a video shorter than that is logged as cut short."""
        last_gt = int(self.gt.table.frames.max()) if self.gt is not None and len(
            self.gt.table) else 0
        what = "seqLength"
        if length is None:
            length, what = max(self.decodable, last_gt), "the ground truth's last frame"
        if length > self.decodable:
            log.warning("%s: %d decodable frames but the sequence has %d (%s): the video is cut "
                        "short; reading frame %d raises FrameError and the sequence fails",
                        self.path, self.decodable, length, what, self.decodable + 1)
        elif length < self.decodable:
            log.warning("%s: %d frames; the sequence is the first %d (seqLength)", self.path,
                        self.decodable, length)
        return int(length)

    def _capture(self) -> cv2.VideoCapture:
        if self._cap is None:
            quiet_libav()
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
        if self.refused is not None:
            raise FrameError(self.refused)
        if k > self.decodable:
            raise FrameError(f"{self.path}: no frame {k}: the video holds {self.decodable} "
                             f"decodable frames but the sequence has {self.info.length}; is it "
                             "cut short?")
        if self._last is not None and self._last[0] == k:
            return self._last[1].copy()
        cap = self._capture()
        if k < self._next and self.exact:
            self.close()  # no seeking: reopen and decode forward
            cap = self._capture()
        if self._next < k and (self.exact or k <= self._next + GRAB_AHEAD):
            while self._next < k:
                if not cap.grab():
                    failed = self._next  # close() starts the count again at 1
                    self.close()
                    raise FrameError(f"{self.path}: cannot decode frame {failed} "
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


def frame_size_change(path: Path, every_frame: bool = False) -> str | None:
    """None when every decoded frame of the video's first video stream has the first one's
    size, else why the video is refused, naming the file and both sizes.

    OpenCV's FFmpeg reader scales every frame to the first frame's size without a word (and
    reports that size throughout), so the sizes are read by PyAV: from every frame with
    ``every_frame`` (MPEG program and transport streams, which join by concatenating files
    and whose keyframe flags PyAV's keyframe-only decoding can miss; ``VideoSequence``
    decodes those once anyway, to count them), else from the keyframes only (cheap; MPEG-4
    and H.264/5 change size only at one). Sizes are compared with each other, not with
    OpenCV's, which is turned for a video with rotation metadata (a phone's portrait clip).

    Raises:
        FrameError: PyAV cannot open the file or finds no video stream in it.
    """
    import av  # start-up: PyAV, ~50 ms CPU; only a video dataset opens one

    try:
        container = av.open(str(path))
    except av.error.FFmpegError as err:
        raise FrameError(f"{path}: cannot read the frame sizes (PyAV: {err})") from None
    with container:
        if not container.streams.video:
            raise FrameError(f"{path}: cannot read the frame sizes: no video stream")
        stream = container.streams.video[0]
        if not every_frame:
            stream.codec_context.skip_frame = "NONKEY"
        j, first, unit = 0, None, "frame" if every_frame else "keyframe"
        try:
            for j, frame in enumerate(container.decode(stream), 1):
                size = (frame.width, frame.height)
                first = first or size
                if size != first:
                    return (f"{path}: the frame size changes mid-stream: {first[0]}x{first[1]}, "
                            f"then {size[0]}x{size[1]} from decoded {unit} {j}; OpenCV would "
                            "rescale those frames to the first size without a word: re-encode "
                            "the video at one size")
        except av.error.FFmpegError as err:  # damage: decoding it fails in frame() too
            log.warning("%s: frame sizes checked up to decoded frame %d only (PyAV: %s)", path,
                        j, err)
    return None

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
            the whole video (``occbench.datasets.base.window``); None = all.
    """
    path = Path(path).expanduser()
    if not path.exists():
        raise FileNotFoundError(f"video file not found: {path}")
    seq = VideoSequence(path, gt=gt, public_detections=det, name=name, fps=fps, exact=exact)
    return window([seq], frames)
