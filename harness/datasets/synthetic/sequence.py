"""``SyntheticSequence``: renders frames, exact label images, ground truth and head boxes
of a cast of people over a static background.

Ground truth (``gt``, computed on first use by a label-only pass over all frames):

- box: the person's full (amodal) box **clipped to the image**; a row exists for every frame
  in which at least one pixel of the person, drawn alone, falls inside the image.
- conf 1 (replay copies the source file's conf), class 1 (pedestrian).
- visibility (MOT16 column 9) = visible pixels / pixels of the person drawn alone, both
  counted inside the image, from the rendered label images (people painted far to near).
- ``occluded`` = visibility < ``occluded_below`` (0.3 by default).

Head boxes (``head_boxes(k)``, aligned with ``gt.rows_of(k)``; ``head_table``, aligned with
``gt.table``) are the amodal head boxes clipped to the image; whether the head is visible
follows from ``foreground(k)`` (pixels equal to the id).

Shadows darken the floor only: they are not part of a person's label. Floor reflections
(``reflection`` > 0: each person mirrored about its foot row and blended into the floor below
it, strength fading to 0 over half its height, as on CAVIAR's shiny floor) are not either;
``reflection_mask(k)`` gives their exact pixels for measuring a background model.
"""

from __future__ import annotations

import logging
import math
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field

import cv2
import numpy as np

from occbench.datasets.base import GroundTruth, Sequence
from occbench.datasets.synthetic.appearance import Appearance
from occbench.datasets.synthetic.people import ShadowPainter, draw_person, head_box
from occbench.io.mot import MotTable
from occbench.trackers.records import SequenceInfo

log = logging.getLogger(__name__)


@dataclass
class Cast:
    """Who is drawn where, per person ``p`` and frame index ``i`` (0-based, frame i + 1).

    Attributes:
        ids: (P,) int64 gt ids (positive, distinct).
        appearances: P appearances.
        boxes: (P, L, 4) float64 amodal xywh boxes in pixels, NaN where absent.
        depth: (P, L) float64 painting key: larger is farther (painted first).
        phase: (P, L) float64 walking phase, radians.
        facing: (P, L) float64 lateral direction in [-1, 1].
        away: (P, L) bool seen from behind.
        swing: (P, L) float64 swing amplitude in [0, 1].
        conf: (P, L) float64 gt conf column (1 unless a replayed file says otherwise).
    """

    ids: np.ndarray
    appearances: list[Appearance]
    boxes: np.ndarray
    depth: np.ndarray
    phase: np.ndarray
    facing: np.ndarray
    away: np.ndarray
    swing: np.ndarray
    conf: np.ndarray = field(default=None)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        self.ids = np.asarray(self.ids, dtype=np.int64)
        P = len(self.ids)
        if self.boxes.ndim != 3 or self.boxes.shape[0] != P or self.boxes.shape[2] != 4:
            raise ValueError(f"Cast: boxes must be (P, L, 4) with P={P}, got {self.boxes.shape}")
        if len(self.appearances) != P:
            raise ValueError(f"Cast: {P} ids but {len(self.appearances)} appearances")
        if (self.ids <= 0).any() or len(set(self.ids.tolist())) != P:
            raise ValueError(f"Cast: ids must be positive and distinct, got {self.ids.tolist()}")
        if self.conf is None:
            self.conf = np.ones(self.boxes.shape[:2])

    @property
    def length(self) -> int:
        return int(self.boxes.shape[1])


class SyntheticSequence(Sequence):
    """A rendered sequence.

    Args:
        name: sequence name.
        cast: the people and their per-frame boxes and poses.
        background: (H, W, 3) uint8 BGR static background, or a callable painting it with a
            ``shape`` (H, W, 3) (``scene.DeferredBackground``): painted when first needed, so
            that a suite's later scenes do not delay the first frame of the first.
        fps: frame rate.
        seed: seed of the per-frame randomness (sensor noise).
        noise: standard deviation of the additive Gaussian sensor noise, grey levels (0 = off).
        gains: optional (L, 3) per-frame B, G, R illumination gains in [0, 2) applied in
            steps of 1/128 (None = constant light).
        shadows: draw soft cast shadows.
        occluded_below: visibility under which a gt row is flagged occluded.
        reflection: opacity r in [0, 1) of a floor reflection under each person's feet (0 = none):
            the person mirrored about the foot row, blended with weight r (1 - d / (h / 2)) at
            d rows below the feet (h: the person's height).
        cache_frames: how many rendered frames (with their label images) are kept.
    Frames are rendered on demand: ``frame(k)`` works in any order, and ``frame(k)`` followed
    by ``foreground(k)`` renders once.
    """

    def __init__(
        self,
        name: str,
        cast: Cast,
        background: np.ndarray | Callable[[], np.ndarray],
        fps: float = 25.0,
        seed: int = 0,
        noise: float = 2.0,
        gains: np.ndarray | None = None,
        shadows: bool = True,
        occluded_below: float = 0.3,
        cache_frames: int = 4,
        reflection: float = 0.0,
    ) -> None:
        if isinstance(background, np.ndarray):
            _check_background(background)
            self._background, self._paint = background, None
        else:
            self._background, self._paint = None, background
        if noise < 0:
            raise ValueError(f"SyntheticSequence: noise must be >= 0, got {noise}")
        if fps <= 0:
            raise ValueError(f"SyntheticSequence: fps must be > 0, got {fps}")
        if not 0.0 <= reflection < 1.0:
            raise ValueError(f"SyntheticSequence: reflection must be in [0, 1), got {reflection}")
        if cache_frames < 1:
            raise ValueError(f"SyntheticSequence: cache_frames must be >= 1, got {cache_frames}")
        H, W = background.shape[:2]
        L = cast.length
        if gains is not None:
            gains = np.asarray(gains, dtype=np.float64)
            if gains.shape != (L, 3):
                raise ValueError(f"SyntheticSequence: gains must be ({L}, 3), got {gains.shape}")
        self.info = SequenceInfo(name=name, width=W, height=H, fps=float(fps), length=L)
        self.cast = cast
        self.seed = int(seed)
        self.noise = float(noise)
        self.gains = gains
        self.shadows = ShadowPainter() if shadows else None
        self.occluded_below = float(occluded_below)
        self.reflection = float(reflection)
        self.public_detections: MotTable | None = None
        self._cache: OrderedDict[int, list] = OrderedDict()
        self._cache_frames = int(cache_frames)
        self._noise_bank: tuple[np.ndarray, np.ndarray] | None = None
        self._gt: GroundTruth | None = None
        self._heads: np.ndarray | None = None

    # ------------------------------------------------------------------ public API
    @property
    def background(self) -> np.ndarray:
        """(H, W, 3) uint8 BGR static background (painted on the first use when deferred)."""
        if self._background is None:
            shape = (self.info.height, self.info.width, 3)
            self._background = _check_background(self._paint(), shape)
            self._paint = None
        return self._background

    @property
    def gt(self) -> GroundTruth:  # type: ignore[override]
        if self._gt is None:
            self._gt, self._heads = self._ground_truth()
        return self._gt

    @property
    def head_table(self) -> np.ndarray:
        """(N, 4) float64 xywh head boxes (clipped to the image) aligned with ``gt.table`` rows."""
        if self._heads is None:
            self._gt, self._heads = self._ground_truth()
        return self._heads

    def head_boxes(self, index: int) -> np.ndarray:
        """(n, 4) float64 xywh head boxes (clipped to the image) of frame ``index``, aligned
        with ``gt.rows_of(index)`` (row j is the head of gt row ``rows_of(index)[j]``)."""
        self._check(index)
        return self.head_table[self.gt.rows_of(index)].copy()

    def frame(self, index: int) -> np.ndarray:
        """Frame ``index`` (1-based): (H, W, 3) uint8 BGR (a fresh copy)."""
        return self._entry(index, colour=True)[0].copy()

    def foreground(self, index: int) -> np.ndarray:
        """Exact label image of frame ``index``: (H, W) int32, gt id at each visible person
        pixel, 0 elsewhere (shadows are background)."""
        return self._entry(index, colour=False)[1].copy()

    def reflection_mask(self, index: int) -> np.ndarray:
        """(H, W) bool: pixels of frame ``index`` changed by a floor reflection (weight > 0)
        and not covered by a person; all False without reflections."""
        k = self._check(index)
        H, W = self.info.height, self.info.width
        weight = np.zeros((H, W), np.float32)
        for p in self._present(k - 1):
            self._reflect(p, k - 1, None, weight)
        return (weight > 0) & (self.foreground(k) == 0)

    # ------------------------------------------------------------------ rendering
    def _reflect(self, p: int, i: int, img: np.ndarray | None, weight: np.ndarray | None) -> None:
        """Blend person ``p``'s mirror image into ``img`` below its feet (see ``reflection``);
        ``weight`` (H, W) float32 gets the largest blending weight of each pixel."""
        H, W = self.info.height, self.info.width
        x, y, w, h = (float(v) for v in self.cast.boxes[p, i])
        x0, x1 = max(math.floor(x), 0), min(math.ceil(x + w), W)
        y0, foot = max(math.floor(y), 0), math.ceil(y + h)
        n = min(foot - y0, H - foot, math.ceil(h / 2))  # rows of reflection inside the image
        if self.reflection <= 0 or n <= 0 or x1 <= x0:
            return
        crop = np.zeros((foot - y0, x1 - x0, 3), np.uint8) if img is not None else None
        lab = np.zeros((foot - y0, x1 - x0), np.int32)
        c = self.cast
        draw_person(crop, lab, 1, c.boxes[p, i], c.appearances[p], float(c.phase[p, i]),
                    float(c.facing[p, i]), bool(c.away[p, i]), float(c.swing[p, i]), (x0, y0))
        d = np.arange(n, dtype=np.float32)
        fade = self.reflection * np.maximum(1.0 - d / (h / 2), 0.0)  # weight at d rows down
        a = (lab[::-1][:n] > 0) * fade[:, None]  # mirrored: row foot + d shows row foot - 1 - d
        if weight is not None:
            np.maximum(weight[foot : foot + n, x0:x1], a, out=weight[foot : foot + n, x0:x1])
        if img is not None:
            roi = img[foot : foot + n, x0:x1].astype(np.float32)
            mir = crop[::-1][:n].astype(np.float32)
            img[foot : foot + n, x0:x1] = np.clip(
                roi + a[..., None] * (mir - roi) + 0.5, 0, 255).astype(np.uint8)

    def _check(self, index: int) -> int:
        k = int(index)
        if k != index or not 1 <= k <= self.info.length:
            raise IndexError(f"{self.info.name}: frame {index} outside 1..{self.info.length}")
        return k

    def _present(self, i: int) -> list[int]:
        """Persons drawn in frame index ``i`` (0-based), far to near (ties by id)."""
        c = self.cast
        b = c.boxes[:, i]
        W, H = self.info.width, self.info.height
        ok = (
            np.isfinite(b).all(1)
            & (b[:, 2] > 0)
            & (b[:, 3] > 0)
            & (b[:, 0] < W)
            & (b[:, 1] < H)
            & (b[:, 0] + b[:, 2] > 0)
            & (b[:, 1] + b[:, 3] > 0)
        )
        idx = np.flatnonzero(ok)
        order = np.lexsort((c.ids[idx], -c.depth[idx, i]))
        return [int(p) for p in idx[order]]

    def _draw(self, p: int, i: int, img, label, value=None, origin=(0, 0)) -> None:
        c = self.cast
        draw_person(
            img,
            label,
            int(c.ids[p]) if value is None else value,
            c.boxes[p, i],
            c.appearances[p],
            float(c.phase[p, i]),
            float(c.facing[p, i]),
            bool(c.away[p, i]),
            float(c.swing[p, i]),
            origin,
        )

    def _entry(self, index: int, colour: bool) -> list:
        """Cached [frame, label image] of frame ``index``, rendering what is missing."""
        k = self._check(index)
        entry = self._cache.get(k)
        if entry is None:
            entry = self._cache[k] = [None, None]
            if len(self._cache) > self._cache_frames:
                self._cache.popitem(last=False)
        else:
            self._cache.move_to_end(k)
        if colour and entry[0] is None:
            entry[0] = self._render_colour(k)
        if not colour and entry[1] is None:
            label = np.zeros((self.info.height, self.info.width), np.int32)
            for p in self._present(k - 1):
                self._draw(p, k - 1, None, label)
            entry[1] = label
        return entry

    def _render_colour(self, k: int) -> np.ndarray:
        i = k - 1
        img = self.background.copy()
        people = self._present(i)
        if self.shadows is not None:
            for p in people:
                self.shadows.paint(img, self.cast.boxes[p, i], 0.15)
        if self.reflection > 0:
            for p in people:
                self._reflect(p, i, img, None)
        for p in people:
            self._draw(p, i, img, None)
        if self.gains is not None:
            # per-channel gain in steps of 1/128 (uint8 multiply: fast and saturating)
            row = np.empty((1, img.shape[1], 3), np.uint8)
            row[:] = np.clip(np.round(self.gains[i] * 128.0), 0, 255).astype(np.uint8)
            img = cv2.multiply(img, cv2.repeat(row, img.shape[0], 1), scale=1.0 / 128.0)
        if self.noise > 0:
            img = self._add_noise(img, k)
        return img

    def _add_noise(self, img: np.ndarray, k: int) -> np.ndarray:
        """Add Gaussian sensor noise: a shifted window of one of two precomputed noise
        images chosen by (seed, k), so any frame is reproducible on its own."""
        H, W = img.shape[:2]
        pad = 64
        if self._noise_bank is None:
            rng = np.random.default_rng([self.seed, 0x5E45])
            bank = np.round(rng.normal(0.0, self.noise, (2, H + pad, W + pad, 3)))
            # positive and negative parts as uint8: two saturating uint8 operations
            self._noise_bank = (
                np.clip(bank, 0, 255).astype(np.uint8),
                np.clip(-bank, 0, 255).astype(np.uint8),
            )
        r = np.random.default_rng([self.seed, k, 0x701])
        b, dy, dx = int(r.integers(2)), int(r.integers(pad)), int(r.integers(pad))
        pos, neg = self._noise_bank
        img = cv2.add(img, pos[b, dy : dy + H, dx : dx + W])
        return cv2.subtract(img, neg[b, dy : dy + H, dx : dx + W])

    # ------------------------------------------------------------------ ground truth
    def _ground_truth(self) -> tuple[GroundTruth, np.ndarray]:
        c = self.cast
        W, H = self.info.width, self.info.height
        label = np.zeros((H, W), np.int32)  # scratch, cleared per frame
        frames, ids, boxes, conf, vis, heads = [], [], [], [], [], []
        for i in range(c.length):
            people = self._present(i)
            if not people:
                continue
            label[:] = 0
            alone: dict[int, tuple[int, tuple[int, int, int, int]]] = {}
            for p in people:
                self._draw(p, i, None, label)
                x, y, w, h = c.boxes[p, i]
                x0, y0 = max(math.floor(x), 0), max(math.floor(y), 0)
                x1, y1 = min(math.ceil(x + w), W), min(math.ceil(y + h), H)
                crop = np.zeros((y1 - y0, x1 - x0), np.uint8)
                self._draw(p, i, None, crop, 1, (x0, y0))
                alone[p] = (int(cv2.countNonZero(crop)), (x0, y0, x1, y1))
            for p in people:
                n, (x0, y0, x1, y1) = alone[p]
                if n == 0:
                    continue
                pid = int(c.ids[p])
                seen = int(np.count_nonzero(label[y0:y1, x0:x1] == pid))
                x, y, w, h = c.boxes[p, i]
                bx0, by0 = max(x, 0.0), max(y, 0.0)
                bx1, by1 = min(x + w, float(W)), min(y + h, float(H))
                frames.append(i + 1)
                ids.append(pid)
                boxes.append((bx0, by0, bx1 - bx0, by1 - by0))
                conf.append(float(c.conf[p, i]))
                vis.append(min(seen / n, 1.0))
                hb = head_box(c.boxes[p, i], float(c.facing[p, i]))
                hx0, hy0 = min(max(hb[0], 0.0), W), min(max(hb[1], 0.0), H)
                hx1, hy1 = min(max(hb[0] + hb[2], 0.0), W), min(max(hb[1] + hb[3], 0.0), H)
                heads.append((hx0, hy0, hx1 - hx0, hy1 - hy0))
        n = len(frames)
        table = MotTable(
            np.asarray(frames, np.int64).reshape(n),
            np.asarray(ids, np.int64).reshape(n),
            np.asarray(boxes, np.float64).reshape(n, 4),
            np.asarray(conf, np.float64).reshape(n),
            np.ones(n, np.int64),
            np.asarray(vis, np.float64).reshape(n),
            f"<synthetic:{self.info.name}>",
        )
        order = np.lexsort((table.ids, table.frames))
        table = table.rows(order)
        heads_a = np.asarray(heads, np.float64).reshape(n, 4)[order]
        gt = GroundTruth(table, occluded=table.visibility < self.occluded_below)
        log.debug("%s: %d gt rows, %d occluded", self.info.name, n, int(gt.occluded.sum()))
        return gt, heads_a


def _check_background(image: np.ndarray, shape: tuple[int, ...] | None = None) -> np.ndarray:
    if (image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8
            or (shape is not None and image.shape != shape)):
        raise ValueError(f"SyntheticSequence: background must be {shape or '(H, W, 3)'} uint8, "
                         f"got {image.shape} {image.dtype}")
    return image
