"""``CachedSource``: a front-end detection source whose per-sequence outputs come from the
cache when the same frames, detector config and code were seen before.

``start(sequence)`` looks the sequence up (``occbench.sources.cache.keys.entry_key``); on a
miss it runs the wrapped source over every frame of the sequence, in order, exactly as the
frame loop would (``start``, then ``detect(k, frame)`` for k in ``frame_numbers()``), and
stores what it returned: per frame the detections (boxes, scores, heads, label image) and
the foreground mask. ``detect(k, frame)`` then hands out frame k's stored outputs, so what
the trackers receive is byte for byte what the wrapped source returns, with a cold cache,
a warm one, or none. The detector's learnt scene calibration (``perspective``), when it has
one, is stored in the entry's meta for ``occbench cache`` to show; on a hit the detector
itself is not run.

Images (masks, label images) are stored zlib-compressed, bool ones bit-packed first.
"""

from __future__ import annotations

import dataclasses
import logging
import socket
import time
import zlib
from typing import Any

import numpy as np

from occbench.datasets.base import Sequence
from occbench.sources.cache.keys import entry_key
from occbench.sources.cache.store import Arrays, CorruptEntry, Entry, Store
from occbench.trackers.records import Detections

log = logging.getLogger(__name__)

IMAGES = ("mask", "labels")  # per-frame images stored, each optional frame by frame


def _compress(a: np.ndarray | None) -> tuple[bytes, tuple[int, int], str] | None:
    """One 2-d image as (zlib bytes, shape, dtype), bool ones bit-packed first."""
    if a is None:
        return None
    a = np.asarray(a)
    if a.ndim != 2:
        raise ValueError(f"a cached image must be 2-d, got shape {a.shape}")
    raw = np.packbits(a).tobytes() if a.dtype == bool else np.ascontiguousarray(a).tobytes()
    return zlib.compress(raw, 1), (int(a.shape[0]), int(a.shape[1])), a.dtype.str


def _images(packed: list[tuple[bytes, tuple[int, int], str] | None], name: str) -> Arrays:
    """Per-frame optional images as offsets into one blob of zlib chunks."""
    dtypes = {p[2] for p in packed if p is not None}
    if len(dtypes) > 1:
        raise ValueError(f"{name}: frames of different dtypes {sorted(dtypes)}")
    chunks = [b"" if p is None else p[0] for p in packed]
    return {f"{name}_present": np.array([p is not None for p in packed], dtype=bool),
            f"{name}_shape": np.array([(0, 0) if p is None else p[1] for p in packed],
                                      dtype=np.int64).reshape(-1, 2),
            f"{name}_offsets": np.cumsum([0, *map(len, chunks)]).astype(np.int64),
            f"{name}_blob": np.frombuffer(b"".join(chunks), dtype=np.uint8),
            f"{name}_dtype": np.array(dtypes.pop() if dtypes else "|b1")}


def _unpack_image(arrays: Arrays, name: str, i: int) -> np.ndarray | None:
    if not arrays[f"{name}_present"][i]:
        return None
    o = arrays[f"{name}_offsets"]
    raw = zlib.decompress(arrays[f"{name}_blob"][o[i]:o[i + 1]].tobytes())
    shape = tuple(int(s) for s in arrays[f"{name}_shape"][i])
    dtype = np.dtype(str(arrays[f"{name}_dtype"]))
    if dtype == bool:
        bits = np.unpackbits(np.frombuffer(raw, dtype=np.uint8), count=shape[0] * shape[1])
        return bits.reshape(shape).astype(bool)
    return np.frombuffer(bytearray(raw), dtype=dtype).reshape(shape)


class EntryBuilder:
    """Collects a sequence's per-frame outputs (``add``, in frame order; images compressed
    at once) into the arrays of an entry (``arrays``)."""

    def __init__(self) -> None:
        self.frames: list[int] = []
        self.dets: list[Detections] = []
        self.images: dict[str, list] = {name: [] for name in IMAGES}

    def add(self, index: int, dets: Detections, mask: np.ndarray | None) -> None:
        self.frames.append(int(index))
        self.dets.append(Detections(dets.boxes, dets.scores, None, dets.heads))
        self.images["mask"].append(_compress(mask))
        self.images["labels"].append(_compress(dets.labels))

    def arrays(self) -> Arrays:
        d = self.dets
        heads = [x.heads if x.heads is not None else np.full((len(x), 4), np.nan) for x in d]
        arrays = {
            "frames": np.asarray(self.frames, dtype=np.int64),
            "counts": np.array([len(x) for x in d], dtype=np.int64),
            "boxes": np.concatenate([x.boxes for x in d]) if d else np.zeros((0, 4)),
            "scores": np.concatenate([x.scores for x in d]) if d else np.zeros(0),
            "has_heads": np.array([x.heads is not None for x in d], dtype=bool),
            "heads": np.concatenate(heads) if d else np.zeros((0, 4)),
        }
        for name in IMAGES:
            arrays.update(_images(self.images[name], name))
        return arrays


def check(entry: Entry, numbers: range) -> None:
    """CorruptEntry unless the arrays are consistent with each other and hold the frame
    numbers ``numbers``."""
    a = entry.arrays
    try:
        n_frames, total = len(a["frames"]), int(a["counts"].sum())
        ok = (np.array_equal(a["frames"], np.asarray(numbers)) and a["boxes"].shape == (total, 4) and a["scores"].shape == (total,)
              and a["heads"].shape == (total, 4) and len(a["counts"]) == n_frames
              and len(a["has_heads"]) == n_frames and (a["counts"] >= 0).all())
        for name in IMAGES:
            o = a[f"{name}_offsets"]
            ok = ok and len(a[f"{name}_present"]) == n_frames and len(o) == n_frames + 1
            ok = ok and int(o[-1]) == len(a[f"{name}_blob"]) and bool((np.diff(o) >= 0).all())
    except (KeyError, AttributeError, TypeError, ValueError) as err:
        raise CorruptEntry(f"arrays missing or malformed ({type(err).__name__}: {err})") from None
    if not ok:
        raise CorruptEntry("arrays of inconsistent sizes")


def entry_meta(sequence: Sequence, config: dict[str, Any], source: Any) -> dict[str, Any]:
    """What an entry says of itself (``occbench cache`` lists it): the sequence, its frames,
    the source and detector classes, where and when it was computed, and the detector's
    learnt scene calibration (its ``perspective``) when it has one, and the detector it fell
    back to and why (``fallback``; None when it did not)."""
    numbers = sequence.frame_numbers()
    inner = config.get("detector")
    detector = getattr(source, "detector", source)
    perspective = getattr(detector, "perspective", None)
    reason = getattr(detector, "fallback_reason", None)
    return {"sequence": sequence.info.name, "frames": [numbers[0], numbers[-1]],
            "source": str(config.get("_target_", "?")),
            "detector": str(inner.get("_target_", "")) if isinstance(inner, dict) else "",
            "host": socket.gethostname(), "created": time.time(),
            "calibration": dataclasses.asdict(perspective)
            if dataclasses.is_dataclass(perspective) else None,
            "fallback": None if reason is None else f"{detector.fallback.name}: {reason}"}


def store_outputs(store: Store, config: dict[str, Any], sequence: Sequence, source: Any,
                  built: EntryBuilder) -> Entry | None:
    """Store outputs computed elsewhere (``occbench detect``: timed frame by frame there)
    as ``sequence``'s entry; None when its frames cannot be fingerprinted."""
    key = entry_key(sequence, config)
    if key is None:
        return None
    if built.frames != list(sequence.frame_numbers()):
        raise ValueError(f"{sequence.info.name}: outputs of frames {built.frames[:3]}... are "
                         "not the whole sequence in order")
    return store.write(key, entry_meta(sequence, config, source), built.arrays())


class CachedSource:
    """A detection source whose outputs per sequence are read from (or written to) a cache.

    Args:
        source: the wrapped source (``occbench.sources.frontend.FrontendSource``).
        config: the source's resolved config (a plain dict): part of the key.
        store: the cache folder; None: the cache is off (``OCCBENCH_CACHE=off``) and the
            source runs as it is, the log saying so.
    """

    def __init__(self, source: Any, config: dict[str, Any], store: Store | None) -> None:
        self.source = source
        self.config = config
        self.store = store
        self._arrays: Arrays | None = None
        self._row: dict[int, int] = {}
        self._starts = np.zeros(1, dtype=np.int64)
        self._name = ""
        #: how the last sequence's outputs came: "read", "waited", "computed" or "uncached"
        self.origin = ""

    def start(self, sequence: Sequence) -> None:
        t0 = time.perf_counter()
        self._name = sequence.info.name
        key = None if self.store is None else entry_key(sequence, self.config)
        if key is None:
            self._arrays, self.origin = None, "uncached"
            why = ("the cache is off: OCCBENCH_CACHE=off" if self.store is None
                   else "its frames cannot be fingerprinted")
            log.info("front end of %s: computed, not cached (%s)", self._name, why)
            self.source.start(sequence)
            return
        numbers = sequence.frame_numbers()
        failed: list[BaseException] = []

        def compute() -> tuple[dict[str, Any], Arrays]:
            try:
                return self._compute(sequence)
            except BaseException as err:  # the front end's own failure: raised as it is
                failed.append(err)
                raise

        try:
            entry, self.origin = self.store.get_or_compute(
                key, compute, lambda e: check(e, numbers))
        except OSError as err:
            if failed:
                raise
            log.warning("front end of %s: the cache folder %s cannot be used (%s: %s); "
                        "computed without it", self._name, self.store.root,
                        type(err).__name__, err)
            self._arrays, self.origin = None, "uncached"
            self.source.start(sequence)
            return
        self._arrays = entry.arrays
        self._row = {k: i for i, k in enumerate(numbers)}
        self._starts = np.concatenate([[0], np.cumsum(entry.arrays["counts"])])
        how = {"read": "read from the cache", "waited": "read from the cache (computed by "
               "another job meanwhile)", "computed": "computed and stored in the cache"}
        log.info("front end of %s: %s (%s, %.1f s)", self._name, how[self.origin],
                 self.store.path(key), time.perf_counter() - t0)
        if self.origin != "computed" and entry.meta.get("fallback"):
            log.warning("front end of %s: detected with %s", self._name, entry.meta["fallback"])

    def _compute(self, sequence: Sequence) -> tuple[dict[str, Any], Arrays]:
        """Run the wrapped source over the whole sequence: the entry's meta and arrays."""
        self.source.start(sequence)
        built = EntryBuilder()
        for k in sequence.frame_numbers():
            built.add(k, *self.source.detect(k, sequence.frame(k)))
        return entry_meta(sequence, self.config, self.source), built.arrays()

    def detect(self, index: int, frame: np.ndarray | None) -> tuple[Detections, np.ndarray | None]:
        """Frame ``index``'s stored detections and mask (``frame`` is not looked at)."""
        if self._arrays is None:
            if self.origin == "uncached":
                return self.source.detect(index, frame)
            raise RuntimeError("CachedSource.detect called before start(sequence)")
        i = self._row.get(int(index))
        if i is None:
            raise IndexError(f"{self._name}: frame {index} is not in the sequence")
        a, lo, hi = self._arrays, self._starts[i], self._starts[i + 1]
        dets = Detections(a["boxes"][lo:hi].copy(), a["scores"][lo:hi].copy(),
                          _unpack_image(a, "labels", i),
                          a["heads"][lo:hi].copy() if a["has_heads"][i] else None)
        return dets, _unpack_image(a, "mask", i)
