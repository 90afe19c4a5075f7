"""Reta 3.1's person detector: the active-basis shape model searched greedily over the free
foreground at the calibrated scales.

Reta et al. 2015, 3.1: "shape filter maps at different scales ... We calculated the local
maximum responses of all of the shape filter maps on the areas that correspond to moving
foreground regions. ... once the global maximum response of the active basis template is
obtained, the foreground region occupied by its silhouette is marked as occupied. Then, to
find more persons in the scene, the search of subsequent maximum responses is repeated over
the vacant areas of the foreground regions."

The shape filter map of one scale (``shape_filter_map``; Wu et al. 2010 sect. 4.1, the
sum-max architecture) scores every placement of the template box (H, W) on a grey image
resized so that a person of that scale is H rows high; placement (y, x) is the box whose
top-left pixel is (y, x), its patch the image around it (``crop_patch``'s pad, the border
replicated):

    SUM1  E_a(p)      = <I, B^cos_{p,a}>^2 + <I, B^sin_{p,a}>^2       (Gabor energy, sect. 3.5)
    MAX1  M_a(p)      = max_{d, delta} E_{a + delta}(p + d n_a)        (eq. 25, shifts and turns)
          sigma^2(y,x) = mean over the box's stride-4 grid and a of E_a (sect. 3.5)
    SUM2  S(y, x)     = sum_i lambda_i h(M_{a_i}(y + r_i, x + c_i) / sigma^2(y, x)) - log Z_i   (eq. 22)

(h(r) = tau tanh(r / tau), eq. 19, is monotone, so the max over perturbations of h(E / sigma^2) is h of the max of E). At
scale 1 S(y, x) equals ``ActiveBasis.score`` of that placement's patch (tested).

The greedy search (``ShapeSearch``): a placement is eligible while at least ``min_vacant`` of
its silhouette (the mean person mask above ``occupy_level``, resized to the box) lies on
vacant foreground; the best-scoring eligible placement over every scale is accepted when it
scores at least ``threshold`` (a log-likelihood ratio, eq. 22), its silhouette's pixels are
marked occupied, and the search repeats until no eligible placement scores enough. With a
scene calibration (``Perspective``: person height linear in the foot row), each scale is
searched only where its height is within ``height_tolerance`` of the expected one.

Arrays: grey images (rows, cols) float32; masks (rows, cols) bool; boxes (N, 4) float64
xywh, 0-based pixels of the frame.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import cv2
import numpy as np

from occbench.trackers.common.checks import parameter_group, refuse_moved, require
from occbench.trackers.frontend.active_basis import GRID, TAU, ActiveBasis, shift_offsets
from occbench.trackers.frontend.calibration import Perspective
from occbench.trackers.frontend.detectors import SilhouetteDetector, _labels_from_boxes
from occbench.trackers.frontend.shape_search_params import (
    GROUPS,
    ShapeAcceptance,
    ShapeHeights,
    ShapePlacements,
)
from occbench.trackers.frontend.silhouette_template import load_template
from occbench.trackers.records import Detections

log = logging.getLogger(__name__)


def energy_maps(grey: np.ndarray, template: ActiveBasis, kernels: np.ndarray | None = None,
                ) -> np.ndarray:
    """(A, rows, cols) float32 Gabor energies E_a (SUM1) of a (rows, cols) float32 image, each
    centred on its pixel (cv2.filter2D correlates, as ``ActiveBasis.scores`` does);
    ``kernels``: ``template.bank.kernels()`` if already made."""
    K = template.bank.kernels() if kernels is None else kernels
    out = np.empty((template.bank.n_orient,) + grey.shape, np.float32)
    for a in range(template.bank.n_orient):
        c = cv2.filter2D(grey, cv2.CV_32F, K[a, 0], borderType=cv2.BORDER_REFLECT)
        s = cv2.filter2D(grey, cv2.CV_32F, K[a, 1], borderType=cv2.BORDER_REFLECT)
        out[a] = c * c + s * s
    return out


def shape_filter_map(grey: np.ndarray, template: ActiveBasis, kernels: np.ndarray | None = None,
                     where: np.ndarray | None = None) -> np.ndarray:
    """(rows - H + 1, cols - W + 1) float64 shape filter map S (eq. 22 at every placement) of a
    (rows, cols) grey image at the template's scale; S[y, x] scores the box [y, y + H) x
    [x, x + W) with the image replicated beyond its border (``crop_patch``'s convention).

    ``where``: an optional bool mask of that shape: S is computed only on the bounding boxes
    of its connected components (-inf elsewhere), the same values as on the whole image."""
    t, p = template, template.pad
    H, W = t.size
    img = cv2.copyMakeBorder(np.asarray(grey, np.float32), p, p, p, p, cv2.BORDER_REPLICATE)
    ny, nx = grey.shape[0] - H + 1, grey.shape[1] - W + 1
    if ny <= 0 or nx <= 0:
        return np.zeros((max(ny, 0), max(nx, 0)))
    if where is None:
        return _padded_map(img, t, kernels)
    S = np.full((ny, nx), -np.inf)
    _n, _lab, stats, _ = cv2.connectedComponentsWithStats(where.astype(np.uint8), connectivity=8)
    for x0, y0, w, h, _area in stats[1:]:
        sub = img[y0 : y0 + h + H - 1 + 2 * p, x0 : x0 + w + W - 1 + 2 * p]
        box = (slice(y0, y0 + h), slice(x0, x0 + w))
        S[box] = np.where(where[box], _padded_map(sub, t, kernels), S[box])
    return S


def _padded_map(img: np.ndarray, t: ActiveBasis, kernels: np.ndarray | None) -> np.ndarray:
    """The shape filter map of every placement whose patch (box plus ``pad``) lies inside the
    float32 image ``img``: (rows - H - 2 pad + 1, cols - W - 2 pad + 1) float64."""
    p = t.pad
    H, W = t.size
    ny, nx = img.shape[0] - H - 2 * p + 1, img.shape[1] - W - 2 * p + 1
    E = energy_maps(img, t, kernels)
    A, b1, b2 = t.bank.n_orient, t.b1, t.b2
    # sigma^2(y, x): mean of E over orientations on the box's stride-GRID grid (sect. 3.5)
    Ebar = E.mean(axis=0)
    sigma2 = np.zeros((ny, nx), np.float32)
    grid = [(r, c) for r in range(0, H, GRID) for c in range(0, W, GRID)]
    for r, c in grid:
        sigma2 += Ebar[p + r : p + r + ny, p + c : p + c + nx]
    inv = 1.0 / (TAU * (sigma2 / len(grid) + 1e-6))  # 1 / (tau sigma^2)
    off = shift_offsets(t.bank, b1)
    S = np.zeros((ny, nx), np.float32)
    M: dict[int, np.ndarray] = {}
    for i in range(t.n):
        a = int(t.orient[i])
        if a not in M:  # MAX1 of orientation a (eq. 25): turns, then shifts along its normal
            turned = np.max([E[(a + d) % A] for d in range(-b2, b2 + 1)], axis=0)
            m = np.full_like(turned, -np.inf)
            rows, cols = turned.shape
            for dy, dx in off[a]:
                src = turned[max(dy, 0) : rows + min(dy, 0), max(dx, 0) : cols + min(dx, 0)]
                dst = m[max(-dy, 0) : rows + min(-dy, 0), max(-dx, 0) : cols + min(-dx, 0)]
                np.maximum(dst, src, out=dst)
            M[a] = m
        r, c = p + int(t.rows[i]), p + int(t.cols[i])
        # h(r) = tau tanh(r / tau) (eq. 19 rewritten), in float32
        S += np.float32(t.lam[i] * TAU) * np.tanh(M[a][r : r + ny, c : c + nx] * inv)
    return S.astype(np.float64) - float(t.log_z.sum())  # eq. 22


@dataclass
class _Scale:
    """One searched scale: the frame crop searched (rows r0:r1, cols c0:c1), resized to
    ``shape`` (rows, cols) by the factors fy, fx (about H / person height), and its shape
    filter map ``S`` (placements of the resized crop; -inf where the scale is not searched)
    and ``cover``, the share of each placement's silhouette on vacant foreground."""

    r0: int
    r1: int
    c0: int
    c1: int
    fy: float
    fx: float
    shape: tuple[int, int]
    S: np.ndarray
    cover: np.ndarray


class ShapeSearch:
    """Greedy multi-scale active-basis search over the vacant foreground (Reta 3.1).

    Args:
        template: the learnt ``ActiveBasis`` (built by the harness from a file).
        heights: the person heights searched (``shape_search_params.ShapeHeights``).
        placements: where a person may be placed, what a fit occupies (``ShapePlacements``).
        acceptance: which fits are accepted (``ShapeAcceptance``).
        Each is its group's defaults when None; a key of the flat arguments before the
        groups is refused with a TypeError naming its group.
    """

    def __init__(self, template: ActiveBasis, heights: ShapeHeights | None = None,
                 placements: ShapePlacements | None = None,
                 acceptance: ShapeAcceptance | None = None, **moved: object) -> None:
        if not isinstance(template, ActiveBasis):
            raise TypeError(f"template must be an ActiveBasis, got {type(template).__name__}")
        refuse_moved("search", moved, GROUPS)
        self.template = template
        self.heights = parameter_group("heights", heights, ShapeHeights)
        self.placements = parameter_group("placements", placements, ShapePlacements)
        self.acceptance = parameter_group("acceptance", acceptance, ShapeAcceptance)
        sil = load_template(self.placements.silhouette)
        H, W = template.size
        self.silhouette = (cv2.resize(sil, (W, H), interpolation=cv2.INTER_AREA)
                           > self.placements.occupy_level)
        self._kernels = template.bank.kernels()
        self._sil = self.silhouette.astype(np.float32)
        self._sil_sum = float(self._sil.sum())

    def pixel_heights(self, frame_rows: int) -> np.ndarray:
        """(n_scales,) person heights searched in a frame ``frame_rows`` high, pixels."""
        h = self.heights
        return np.geomspace(h.min_height, h.max_height, h.n_scales) * frame_rows

    def _top_band(self, h: float, rows: int, perspective: Perspective | None) -> tuple[int, int] | None:
        """Box-top rows [t0, t1) where a person ``h`` high fits the perspective (None: nowhere)."""
        if perspective is None:
            return 0, max(rows - round(h) + 1, 1)
        a, b = perspective.a, perspective.b
        tol = self.heights.height_tolerance
        lo = (h / tol - b) / a - h  # foot row = top + h
        hi = (h * tol - b) / a - h
        t0, t1 = max(int(np.floor(lo)), 0), min(int(np.ceil(hi)) + 1, rows - round(h) + 1)
        return (t0, t1) if t1 > t0 else None

    def _cover(self, vacant: np.ndarray, sc: _Scale) -> np.ndarray:
        """Share of each placement's silhouette on the (rows, cols) bool ``vacant`` foreground,
        at scale ``sc`` (the S map's shape)."""
        v = vacant[sc.r0 : sc.r1, sc.c0 : sc.c1].astype(np.float32)
        vs = cv2.resize(v, (sc.shape[1], sc.shape[0]), interpolation=cv2.INTER_AREA)
        ny, nx = sc.S.shape
        return cv2.matchTemplate(vs, self._sil, cv2.TM_CCORR)[:ny, :nx] / self._sil_sum

    def maps(self, grey: np.ndarray, fg: np.ndarray, perspective: Perspective | None) -> list[_Scale]:
        """The shape filter map of every scale over the (rows, cols) float32 ``grey`` image, at
        the placements a person of that scale could take on the (rows, cols) bool foreground
        ``fg``: box tops in the perspective's band of rows, at least ``min_vacant`` of the
        silhouette on foreground."""
        rows, cols = fg.shape
        rr, cc = np.flatnonzero(fg.any(axis=1)), np.flatnonzero(fg.any(axis=0))
        if not len(rr):
            return []
        Ht, Wt = self.template.size
        out = []
        for h in self.pixel_heights(rows):
            band = self._top_band(h, rows, perspective)
            if band is None:
                continue
            w = h * Wt / Ht
            r0 = max(band[0], int(rr[0] - h + 1), 0)
            r1 = min(band[1] - 1 + int(np.ceil(h)), int(rr[-1] + h), rows)
            c0, c1 = max(int(cc[0] - w + 1), 0), min(int(cc[-1] + w), cols)
            if r1 - r0 < h or c1 - c0 < w:
                continue
            f = Ht / h
            size = (max(round((c1 - c0) * f), Wt), max(round((r1 - r0) * f), Ht))
            fy, fx = size[1] / (r1 - r0), size[0] / (c1 - c0)  # the exact factors of the resize
            sc = _Scale(r0, r1, c0, c1, fy, fx, (size[1], size[0]),
                        np.zeros((size[1] - Ht + 1, size[0] - Wt + 1)), np.zeros(0))
            sc.cover = self._cover(fg, sc)
            ys = r0 + np.arange(sc.S.shape[0]) / fy  # placements' box tops (frame rows)
            where = ((sc.cover >= self.placements.min_vacant)
                     & ((ys >= band[0]) & (ys < band[1]))[:, None])
            if not where.any():
                continue
            interp = cv2.INTER_AREA if f < 1 else cv2.INTER_LINEAR
            sc.S = shape_filter_map(cv2.resize(grey[r0:r1, c0:c1], size, interpolation=interp),
                                    self.template, self._kernels, where)
            out.append(sc)
        return out

    def search(self, grey: np.ndarray, fg: np.ndarray, perspective: Perspective | None = None,
               ) -> tuple[np.ndarray, np.ndarray]:
        """Greedy fits: boxes (N, 4) xywh frame pixels and their log-likelihood ratios (N,),
        in the order found, on a (rows, cols) grey image and bool foreground."""
        vacant = np.asarray(fg, bool).copy()
        scales = self.maps(np.asarray(grey, np.float32), vacant, perspective)
        Ht, Wt = self.template.size
        boxes, scores = [], []
        stride, min_vacant = self.placements.stride, self.placements.min_vacant
        for _ in range(self.acceptance.max_people):
            best, best_s = None, self.acceptance.threshold
            for sc in scales:
                S = np.where(sc.cover >= min_vacant, sc.S, -np.inf)
                if stride > 1:
                    S = S[::stride, ::stride]
                y, x = np.unravel_index(int(np.argmax(S)), S.shape)
                if S[y, x] >= best_s:
                    best, best_s = (sc, y * stride, x * stride), float(S[y, x])
            if best is None:
                break
            sc, y, x = best
            box = np.array([sc.c0 + x / sc.fx, sc.r0 + y / sc.fy, Wt / sc.fx, Ht / sc.fy])
            boxes.append(box), scores.append(best_s)
            self._occupy(vacant, box)
            for other in scales:  # the vacant foreground changed under these scales only
                if (other.r0 < box[1] + box[3] and box[1] < other.r1 and other.c0 < box[0] + box[2]
                        and box[0] < other.c1):
                    other.cover = self._cover(vacant, other)
        if not boxes:
            return np.zeros((0, 4)), np.zeros(0)
        return np.asarray(boxes, np.float64), np.asarray(scores, np.float64)

    def _occupy(self, vacant: np.ndarray, box: np.ndarray) -> None:
        """Mark the silhouette of a fit at the xywh ``box`` occupied (in place)."""
        x, y, w, h = box
        c0, r0 = round(x), round(y)
        ww, hh = max(round(w), 1), max(round(h), 1)
        m = cv2.resize(self.silhouette.astype(np.uint8), (ww, hh), interpolation=cv2.INTER_NEAREST) > 0
        R, C = vacant.shape
        rs, cs = slice(max(r0, 0), min(r0 + hh, R)), slice(max(c0, 0), min(c0 + ww, C))
        if rs.stop > rs.start and cs.stop > cs.start:
            sub = m[rs.start - r0 : rs.stop - r0, cs.start - c0 : cs.stop - c0]
            vacant[rs, cs] &= ~sub


class ActiveBasisDetector(SilhouetteDetector):
    """Reta 3.1's detector: ``ShapeSearch`` on each frame's grey levels over its foreground,
    at the scales the scene's self-calibration allows.

    The warm-up is the silhouette detector's (``SilhouetteDetector``): background learnt from
    frames sampled over the sequence, the live picture, and the perspective (person height
    linear in the foot row) from the silhouette matcher's unconstrained fits (no
    annotations); the matcher detects nothing here. The perspective speaks of the matcher's
    template boxes; it is scaled by the matcher's ``box_scale`` height factor to the
    reported boxes' convention, which is the active-basis template's (learnt from annotated
    boxes). Without a calibration (``calibration: null`` or too little evidence) every scale
    is searched everywhere.

    Args:
        search: the greedy active-basis search.
        **kwargs: ``SilhouetteDetector``'s (background, matcher, calibration, ...); no
            verifier.
    """

    def __init__(self, search: ShapeSearch | None = None, **kwargs) -> None:
        require("search", search is not None, "must be a ShapeSearch (the detector's template)",
                search)
        require("verifier", kwargs.get("verifier") is None,
                "must be null: the active-basis detector has none (it is the shape model)",
                kwargs.get("verifier"))
        super().__init__(**kwargs)
        self.search = search

    def scene_perspective(self) -> Perspective | None:
        """The learnt perspective in reported-box units (None: none learnt)."""
        if self.perspective is None:
            return None
        sh = float(self.matcher.report.box_scale[1])
        p = self.perspective
        return Perspective(p.a * sh, p.b * sh, p.width_ratio, p.samples, p.bins, p.spread)

    def detect_on(self, frame: np.ndarray, fg: np.ndarray) -> Detections:
        grey = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY) if frame.ndim == 3 else frame
        live, r0, c0 = self._live(fg)
        g = grey[r0 : r0 + live.shape[0], c0 : c0 + live.shape[1]].astype(np.float32)
        boxes, scores = self.search.search(g, live, self.scene_perspective())
        if not len(boxes):
            return Detections.empty()
        boxes[:, 0] += c0
        boxes[:, 1] += r0
        p = 1.0 / (1.0 + np.exp(-scores))  # person vs background at even odds (eq. 22's ratio)
        return Detections(boxes, p, _labels_from_boxes(boxes, fg))
