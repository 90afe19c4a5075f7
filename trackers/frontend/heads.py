"""Head detector of PBM 2.3: hair and skin colour mixtures plus an elliptical shape fit.

Colour model (PBM eqs. 3-6). Each category c (hair: black, blond, brown, red; skin:
bright, standard, dark) has, per colour space s in {XYZ, HSV} and per channel, a 1-D
Gaussian mixture. Channels are independent:

    p_XYZ(x|c) = p(x_X|c) p(x_Y|c) p(x_Z|c)                     (3)
    p_HSV(x|c) = p(x_H|c) p(x_S|c) p(x_V|c)                     (4)
    p(x|c)     = w1 p_XYZ(x|c) + w2 p_HSV(x|c)                   (5)
    p_hair(x)  = max_c p(x|c) over hair categories              (6), likewise p_skin

and a pixel is a head pixel when p_hair > threshold_hair or p_skin > threshold_skin.
Channel values are scaled to [0, 1] (OpenCV 8-bit XYZ / 255, H / 180, S / 255, V / 255)
and densities are per unit of that scale; the hue density wraps around (hue is circular).
Each channel density is tabulated over its 256 possible byte values, so a frame costs
table look-ups only.

Shape (PBM 2.3.3): the head-pixel mask is closed morphologically, then ellipses of a few
sizes are registered to the top of the head pixels and the one with the highest occupancy
(fraction of its pixels that are head pixels) wins; several heads per region are found
greedily (the winner's pixels are removed and the search repeats).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import cv2
import numpy as np

from occbench.trackers.common.checks import parameter_group, refuse_moved
from occbench.trackers.frontend.blobs import blob_boxes, blobs_from_mask
from occbench.trackers.frontend.heads_params import GROUPS, HeadEllipses, HeadPixels

log = logging.getLogger(__name__)

HAIR = ("black", "blond", "brown", "red")
SKIN = ("bright", "standard", "dark")
SPACES = ("xyz", "hsv")
HUE_SPACE, HUE_CHANNEL = 1, 0  # hsv, channel H: circular


@dataclass
class ColourMixtures:
    """Per-category, per-space, per-channel 1-D Gaussian mixtures on [0, 1] channel scales.

    Attributes:
        names: (C,) category names, hair categories first (``HAIR + SKIN``).
        weights, means, stds: (C, 2, 3, K) float64: category, space (xyz, hsv), channel, component.
        provenance: free text saying where the parameters came from.
    """

    names: tuple[str, ...]
    weights: np.ndarray
    means: np.ndarray
    stds: np.ndarray
    provenance: str = ""

    def __post_init__(self) -> None:
        self.weights = np.asarray(self.weights, dtype=np.float64)
        self.means = np.asarray(self.means, dtype=np.float64)
        self.stds = np.asarray(self.stds, dtype=np.float64)
        shape = (len(self.names), 2, 3)
        for name in ("weights", "means", "stds"):
            a = getattr(self, name)
            if a.ndim != 4 or a.shape[:3] != shape:
                raise ValueError(f"ColourMixtures.{name}: expected shape {shape} + (K,), got {a.shape}")
        if (self.stds <= 0).any():
            raise ValueError("ColourMixtures.stds must be > 0")

    def save(self, path: str | Path) -> None:
        np.savez(path, names=np.array(self.names), weights=self.weights, means=self.means,
                 stds=self.stds, provenance=np.array(self.provenance))

    @classmethod
    def load(cls, path: str | Path | None = None) -> ColourMixtures:
        """Load an ``.npz`` written by ``save``; None loads the shipped default."""
        if path is None:
            path = resources.files("occbench.trackers.frontend") / "data" / "heads.npz"
        path = Path(str(path))
        if not path.is_file():
            raise FileNotFoundError(f"head colour mixtures not found: {path}")
        with np.load(path, allow_pickle=False) as z:
            return cls(tuple(str(n) for n in z["names"]), z["weights"], z["means"], z["stds"],
                       str(z["provenance"]))

    def tables(self) -> np.ndarray:
        """(C, 2, 3, 256) densities of every byte value of every channel."""
        v = np.arange(256, dtype=np.float64)
        scale = np.array([[255.0] * 3, [180.0, 255.0, 255.0]])  # (space, channel)
        x = v[None, None, None, :, None] / scale[None, :, :, None, None]  # (1,2,3,256,1)
        m = self.means[:, :, :, None, :]
        d = np.abs(x - m)
        hue = np.zeros((2, 3), dtype=bool)
        hue[HUE_SPACE, HUE_CHANNEL] = True
        d = np.where(hue[None, :, :, None, None], np.minimum(d, 1.0 - d), d)
        s = self.stds[:, :, :, None, :]
        pdf = np.exp(-0.5 * (d / s) ** 2) / (np.sqrt(2 * np.pi) * s)
        return (self.weights[:, :, :, None, :] * pdf).sum(axis=-1)


def colour_channels(frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(H, W, 3) uint8 BGR -> (XYZ, HSV) uint8 images (OpenCV 8-bit conventions)."""
    return cv2.cvtColor(frame, cv2.COLOR_BGR2XYZ), cv2.cvtColor(frame, cv2.COLOR_BGR2HSV)


def category_likelihoods(
    frame: np.ndarray, tables: np.ndarray, w1: float, w2: float
) -> np.ndarray:
    """(C, H, W) p(x|c) = w1 p_XYZ(x|c) + w2 p_HSV(x|c) (PBM eqs. 3-5) for every pixel."""
    xyz, hsv = colour_channels(frame)
    pxyz = tables[:, 0, 0][:, xyz[..., 0]] * tables[:, 0, 1][:, xyz[..., 1]]
    pxyz *= tables[:, 0, 2][:, xyz[..., 2]]
    phsv = tables[:, 1, 0][:, hsv[..., 0]] * tables[:, 1, 1][:, hsv[..., 1]]
    phsv *= tables[:, 1, 2][:, hsv[..., 2]]
    return w1 * pxyz + w2 * phsv


def _ellipse_kernel(rx: int, ry: int) -> np.ndarray:
    ys, xs = np.mgrid[-ry : ry + 1, -rx : rx + 1]
    k = ((xs / (rx + 0.5)) ** 2 + (ys / (ry + 0.5)) ** 2 <= 1.0).astype(np.float32)
    return k / k.sum()


class HeadDetector:
    """PBM 2.3 head detector.

    Args:
        mixtures: path of an ``.npz`` of ``ColourMixtures`` (None: the shipped default).
        pixels: which pixels are head pixels (``heads_params.HeadPixels``).
        ellipses: which ellipses of them are heads (``heads_params.HeadEllipses``).
        Each group is its defaults when None; a key of the flat arguments before the groups
        is refused with a TypeError naming its group.
    """

    def __init__(self, mixtures: str | None = None, pixels: HeadPixels | None = None,
                 ellipses: HeadEllipses | None = None, **moved: object) -> None:
        refuse_moved("heads", moved, GROUPS)
        self.pixels = parameter_group("pixels", pixels, HeadPixels)
        self.ellipses = parameter_group("ellipses", ellipses, HeadEllipses)
        self.mixtures = ColourMixtures.load(mixtures)
        self._tables = self.mixtures.tables()
        names = self.mixtures.names
        self._hair = np.array([n in HAIR for n in names])
        self._skin = np.array([n in SKIN for n in names])
        k = self.pixels.close_kernel
        self._close = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k)) if k > 1 else None

    def likelihoods(self, frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(H, W) p_hair and p_skin (PBM eq. 6: max over categories)."""
        p = category_likelihoods(frame, self._tables, self.pixels.w1, self.pixels.w2)
        return p[self._hair].max(axis=0), p[self._skin].max(axis=0)

    def head_pixels(self, frame: np.ndarray, foreground: np.ndarray | None = None) -> np.ndarray:
        """(H, W) bool head-pixel mask (hair or skin above threshold, within foreground, closed)."""
        ph, ps = self.likelihoods(frame)
        m = (ph > self.pixels.threshold_hair) | (ps > self.pixels.threshold_skin)
        if foreground is not None:
            m &= np.asarray(foreground) != 0
        m = m.astype(np.uint8)
        if self._close is not None:
            m = cv2.morphologyEx(m, cv2.MORPH_CLOSE, self._close)
        return m.astype(bool)

    def _search(self, pix: np.ndarray, height: float, max_heads: int) -> list[np.ndarray]:
        """Greedy top-registered ellipse fit in a (h, w) head-pixel crop; xywh in crop coords."""
        heads: list[np.ndarray] = []
        pix = pix.astype(np.float32)
        shape = self.ellipses
        hh0 = shape.head_fraction * height
        for _ in range(max_heads):
            if not pix.any():
                break
            cols = pix.any(axis=0)
            top = np.where(cols, pix.argmax(axis=0), -1)  # topmost head pixel per column
            cands: list[tuple[int, float, tuple[int, int, int, int]]] = []
            for f in shape.size_factors:
                hh = max(hh0 * f, shape.min_head_height)
                ry = max(round(hh / 2), 2)
                for a in shape.aspects:
                    rx = max(round(a * hh / 2), 2)
                    occ = cv2.filter2D(pix, cv2.CV_32F, _ellipse_kernel(rx, ry),
                                       borderType=cv2.BORDER_CONSTANT)
                    c = np.flatnonzero(cols)
                    r = top[c] + ry  # ellipse registered to the top of the head pixels
                    ok = r < pix.shape[0]
                    c, r = c[ok], r[ok]
                    vals = occ[r, c]
                    good = vals >= shape.min_occupancy
                    if good.any():
                        # the topmost registration wins; among those, the highest occupancy
                        t = r[good] - ry
                        sel = np.flatnonzero(good)[t <= t.min() + 1]
                        i = sel[np.argmax(vals[sel])]
                        cands.append((int(r[i] - ry), float(vals[i]), (c[i], r[i], rx, ry)))
            if not cands:
                break
            tmin = min(cd[0] for cd in cands)
            best = max((cd for cd in cands if cd[0] <= tmin + 1), key=lambda cd: cd[1])
            c, r, rx, ry = best[2]
            heads.append(np.array([c - rx, r - ry, 2 * rx + 1, 2 * ry + 1], dtype=np.float64))
            cv2.ellipse(pix, (int(c), int(r)), (int(rx) + 1, int(ry) + 1), 0, 0, 360, 0, -1)
        return heads

    def heads_in(
        self, frame: np.ndarray, foreground: np.ndarray | None, box: np.ndarray, max_heads: int = 1
    ) -> np.ndarray:
        """(K, 4) xywh heads (K <= max_heads, best first) in the top of one xywh ``box``."""
        h, w = frame.shape[:2]
        x0, y0 = max(int(np.floor(box[0])), 0), max(int(np.floor(box[1])), 0)
        x1 = min(int(np.ceil(box[0] + box[2])), w)
        y1 = min(int(np.ceil(box[1] + box[3] * self.ellipses.search_fraction)), h)
        if x1 - x0 < 3 or y1 - y0 < 3:
            return np.zeros((0, 4))
        fg = None if foreground is None else foreground[y0:y1, x0:x1]
        pix = self.head_pixels(frame[y0:y1, x0:x1], fg)
        found = self._search(pix, float(box[3]), max_heads)
        out = np.array(found, dtype=np.float64).reshape(-1, 4)
        out[:, :2] += (x0, y0)
        return out

    def detect(
        self,
        frame: np.ndarray,
        foreground: np.ndarray | None = None,
        boxes: np.ndarray | None = None,
        max_heads: int = 1,
    ) -> np.ndarray:
        """Head boxes.

        Args:
            frame: (H, W, 3) uint8 BGR.
            foreground: optional (H, W) mask or label image (nonzero = foreground).
            boxes: optional (N, 4) xywh person (or blob) boxes; the head is searched in the
                top ``search_fraction`` of each. None: every foreground blob (or, without
                foreground, the whole frame) is a region.
            max_heads: heads searched per region (several for a blob holding a group).
        Returns:
            With ``boxes``: (N, 4) xywh head box per box (rows of NaN where none, the best
            one when ``max_heads`` == 1). Without: (M, 4) xywh of all heads found.
        """
        h, w = frame.shape[:2]
        per_box = boxes is not None
        if boxes is None:
            if foreground is None:
                boxes = np.array([[0, 0, w, h]], dtype=np.float64)
            else:
                boxes = blob_boxes(blobs_from_mask(foreground, min_area=20, perimeter=False))
        boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
        out: list[np.ndarray] = []
        per: list[np.ndarray] = []
        for box in boxes:
            found = self.heads_in(frame, foreground, box, max_heads)
            out.extend(found)
            per.append(found[0] if len(found) else np.full(4, np.nan))
        if per_box:
            return np.array(per).reshape(-1, 4)
        return np.array(out).reshape(-1, 4)


def detect_heads(
    frame: np.ndarray, foreground: np.ndarray | None = None, boxes: np.ndarray | None = None,
    detector: HeadDetector | None = None,
) -> np.ndarray:
    """Convenience wrapper: ``(detector or HeadDetector()).detect(frame, foreground, boxes)``."""
    return (detector or HeadDetector()).detect(frame, foreground, boxes)


# --- fitting (EM on 1-D channel mixtures) -------------------------------------------------


def fit_channel_mixture(
    x: np.ndarray, k: int = 2, circular: bool = False, iterations: int = 60,
    min_std: float = 0.01,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """EM fit of a 1-D Gaussian mixture to values ``x`` (N,) on [0, 1].

    ``circular`` (hue): values are rotated so their circular mean sits at 0.5, fitted on the
    line, and the means rotated back. Deterministic: initial means at quantiles.
    Returns (weights, means, stds), each (k,).
    """
    x = np.asarray(x, dtype=np.float64).reshape(-1)
    if len(x) < k:
        raise ValueError(f"fit_channel_mixture: need at least k={k} values, got {len(x)}")
    shift = 0.0
    if circular:
        ang = 2 * np.pi * x
        mean = np.arctan2(np.sin(ang).mean(), np.cos(ang).mean()) / (2 * np.pi)
        shift = 0.5 - mean
        x = np.mod(x + shift, 1.0)
    mu = np.quantile(x, (np.arange(k) + 0.5) / k)
    sd = np.full(k, max(x.std() / k, min_std))
    wt = np.full(k, 1.0 / k)
    for _ in range(iterations):
        logp = -0.5 * ((x[:, None] - mu) / sd) ** 2 - np.log(sd) + np.log(wt)
        logp -= logp.max(axis=1, keepdims=True)
        r = np.exp(logp)
        r /= r.sum(axis=1, keepdims=True)
        n = r.sum(axis=0) + 1e-12
        wt = n / n.sum()
        mu = (r * x[:, None]).sum(axis=0) / n
        sd = np.sqrt((r * (x[:, None] - mu) ** 2).sum(axis=0) / n)
        sd = np.maximum(sd, min_std)
    if circular:
        mu = np.mod(mu - shift, 1.0)
    return wt, mu, sd


def fit_colour_mixtures(
    samples: dict[str, np.ndarray], k: int = 2, provenance: str = ""
) -> ColourMixtures:
    """Fit ``ColourMixtures`` from BGR pixel samples per category.

    Args:
        samples: {category name: (N, 3) uint8 BGR pixels}; names from ``HAIR + SKIN``.
        k: components per channel mixture.
    """
    names = tuple(n for n in HAIR + SKIN if n in samples)
    unknown = set(samples) - set(HAIR + SKIN)
    if unknown:
        raise ValueError(f"unknown head colour categories {sorted(unknown)}; use {HAIR + SKIN}")
    shape = (len(names), 2, 3, k)
    W, M, S = np.zeros(shape), np.zeros(shape), np.zeros(shape)
    scale = np.array([[255.0] * 3, [180.0, 255.0, 255.0]])
    for i, name in enumerate(names):
        px = np.asarray(samples[name], dtype=np.uint8).reshape(-1, 1, 3)
        xyz, hsv = colour_channels(px)
        for s, img in enumerate((xyz, hsv)):
            for c in range(3):
                v = img[:, 0, c] / scale[s, c]
                W[i, s, c], M[i, s, c], S[i, s, c] = fit_channel_mixture(
                    v, k, circular=(s == HUE_SPACE and c == HUE_CHANNEL))
    return ColourMixtures(names, W, M, S, provenance)


# Reference colours (RGB) of the shipped default: common hair swatches and skin tones of
# light, medium and dark complexion (values in the range of the skin-colour literature, e.g.
# Kakumanu et al. 2007's survey: skin hue 0-50 degrees, saturation 0.2-0.7).
REFERENCE_RGB: dict[str, tuple[tuple[int, int, int], ...]] = {
    "black": ((25, 20, 18), (45, 38, 34), (60, 50, 45)),
    "blond": ((220, 190, 130), (185, 155, 100), (235, 215, 170)),
    "brown": ((95, 65, 40), (130, 90, 60), (70, 50, 35)),
    "red": ((165, 75, 40), (125, 50, 30), (190, 100, 60)),
    "bright": ((240, 205, 180), (225, 185, 160), (250, 220, 200)),
    "standard": ((200, 150, 115), (185, 135, 100), (215, 165, 130)),
    "dark": ((120, 80, 55), (90, 60, 45), (140, 95, 70)),
}


def reference_samples(n: int = 400, seed: int = 0) -> dict[str, np.ndarray]:
    """BGR pixel samples around ``REFERENCE_RGB``: shading factor U(0.6, 1.15), noise sd 8."""
    rng = np.random.default_rng(seed)
    out = {}
    for name, refs in REFERENCE_RGB.items():
        rgb = np.repeat(np.asarray(refs, dtype=np.float64), n, axis=0)
        rgb = rgb * rng.uniform(0.6, 1.15, size=(len(rgb), 1)) + rng.normal(0, 8, rgb.shape)
        out[name] = np.clip(rgb[:, ::-1], 0, 255).astype(np.uint8)
    return out
