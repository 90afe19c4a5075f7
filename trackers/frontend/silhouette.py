"""Silhouette-template person detector (Reta 3.1, adapted).

Reta et al. fit an active-basis silhouette template at several scales over the moving
foreground: the best fit marks its silhouette occupied and the search repeats on the
vacant foreground. We keep the greedy occupancy loop and replace the active basis (Gabor
sketch learnt from their training images, which we do not have) with a mean person mask
``T`` (values in [0, 1], learnt by ``occbench fit silhouette`` from exact person
masks, or the shipped default).

Fit of the template (scaled to one of ``n_scales`` heights) centred at a pixel, over the
vacant foreground V and the occupied foreground O (both 0/1 images), with the template's
visible mass M = sum T - sum T O (the part not hidden by people already found):

    E     = sum T V - alpha (M - sum T V) - beta sum (1 - T) V     (explained foreground)
    score = E / M

E rewards foreground under the template, pays ``alpha`` for template pixels without
foreground and ``beta`` for foreground where the template expects background; the greedy
step takes the placement and scale of largest E (the active basis' log-likelihood also
grows with the template's size), among placements with ``score >= threshold`` and
M / sum T >= ``min_visible`` (Reta: people more than 30% visible).

Every sum is a box sum on an integral image, O(1) per placement (``silhouette_search``: the
template as cells, ``greedy_search``, compiled in ``_silhouette_kernel``). The template itself
is ``silhouette_template``'s; the settings are ``silhouette_params``' groups.

Scene knowledge, all optional: a ground-plane height prior (expected height linear in the
foot row; fixed from a calibration, ``heights.height_model``, or learnt by the detector), template
pixels beyond the frame border treated as unknown (``search.frame_border``: people cut by the image
edge), and a box convention (``report.box_scale``: reported box = fitted template box scaled to the
annotations' tighter or looser boxes). On CAVIAR the height prior matters most: without it the
largest-E rule prefers tall fits spanning a group or a person with its floor reflection.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import cv2
import numpy as np

from occbench.trackers.common.checks import parameter_group, refuse_moved
from occbench.trackers.frontend.silhouette_params import GROUPS, Heights, Person, Report, Score, Search
from occbench.trackers.frontend.silhouette_search import _Scales, search_regions
from occbench.trackers.frontend.silhouette_template import load_template
from occbench.trackers.geometry import intersection_matrix

log = logging.getLogger(__name__)


@dataclass
class Candidates:
    """The greedy search's fits over one frame, in the order found (region by region).

    Attributes:
        boxes: (N, 4) float64 xywh fitted template boxes, full-resolution pixels, unclipped.
        tight: (N, 4) float64 xywh boxes of the foreground each fit explains (``box``).
        scores: (N,) float64 E / M.
        region: (N,) int64 the foreground region each was found in.
    """

    boxes: np.ndarray
    tight: np.ndarray
    scores: np.ndarray
    region: np.ndarray

    def __len__(self) -> int:
        return len(self.scores)


class SilhouetteMatcher:
    """Greedy multi-scale silhouette fitting over a foreground mask.

    Args:
        person: the template as matched (``silhouette_params.Person``).
        heights: the heights searched and the height prior (``Heights``).
        score: the fit score E / M and its thresholds (``Score``).
        search: how the foreground is searched (``Search``).
        report: which fits are reported, with which box (``Report``).
        Each is its group's defaults when None; a key of the flat arguments before the
        groups is refused with a TypeError naming its group (``silhouette_params.GROUPS``).
    Attributes:
        template: (h, w) float32 the template as loaded (mirrored when ``symmetric``).
        height_model: the height prior in use, (a, b) or None: ``heights.height_model``
            until ``set_height_model`` gives a learnt one.
    """

    def __init__(self, person: Person | None = None, heights: Heights | None = None,
                 score: Score | None = None, search: Search | None = None,
                 report: Report | None = None, **moved: object) -> None:
        refuse_moved("matcher", moved, GROUPS)
        self.person = parameter_group("person", person, Person)
        self.heights = parameter_group("heights", heights, Heights)
        self.score = parameter_group("score", score, Score)
        self.search = parameter_group("search", search, Search)
        self.report = parameter_group("report", report, Report)
        self.template = load_template(self.person.template)
        if self.person.symmetric:  # people face either way: the mean of the template and its mirror
            self.template = np.ascontiguousarray((self.template + self.template[:, ::-1]) / 2)
        self.height_model: tuple[float, float] | None = self.heights.height_model
        self._cache: dict[int, _Scales] = {}
        self._kernels: _Scales | None = None

    @property
    def fixed_height_model(self) -> tuple[float, float] | None:
        """The height prior given (a camera calibration), which a learnt one overrides."""
        return self.heights.height_model

    def pixel_heights(self, frame_height: int) -> tuple[float, float]:
        """(min, max) person height searched in a frame ``frame_height`` rows high, pixels."""
        f = float(frame_height) if self.heights.height_unit == "frame" else 1.0
        return self.heights.min_height * f, self.heights.max_height * f

    def _kernels_for(self, frame_height: int) -> _Scales:
        key = int(frame_height) if self.heights.height_unit == "frame" else 0
        if key not in self._cache:
            lo, hi = self.pixel_heights(frame_height)
            heights = np.geomspace(lo, hi, self.heights.n_scales) / self.search.downscale
            aspect = self.person.aspect or self.template.shape[1] / self.template.shape[0]
            shapes = [(max(round(h), 3), max(round(h * aspect), 2)) for h in heights]
            self._cache[key] = _Scales(
                [cv2.resize(self.template, (tw, th), interpolation=cv2.INTER_AREA) for th, tw in shapes],
                self.person.occupy_level)
        return self._cache[key]

    def set_height_model(self, model: tuple[float, float] | None) -> None:
        """Expected person height = a * foot_row + b (full-resolution pixels); None: no prior
        (or the fixed ``height_model`` given to the constructor, which a learnt one overrides)."""
        if model is None:
            self.height_model = self.fixed_height_model
        else:
            self.height_model = (float(model[0]), float(model[1]))

    def fit(self, foreground: np.ndarray, template_boxes: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Greedy fits over a (H, W) foreground mask (nonzero = foreground).

        Foreground components closer than ``group_gap`` rows one above the other (a person
        whose middle matches the background: torso and legs apart) are searched together.

        Args:
            foreground: (H, W) mask.
            template_boxes: return the fitted templates' boxes (the sizes the height prior
                speaks of) instead of the reported boxes (``box``, ``box_scale``).
        Returns:
            boxes (N, 4) float64 xywh in full-resolution pixels and scores (N,) float64.
        """
        boxes, tight, scores = self.fit_all(foreground)
        if not len(boxes):
            return boxes, scores
        H, W = np.asarray(foreground).shape
        out = boxes if template_boxes or self.report.box == "template" else tight
        if not template_boxes and self.report.box_scale != (1.0, 1.0):
            sw, sh = self.report.box_scale
            out[:, 0] += out[:, 2] * (1.0 - sw) / 2
            out[:, 2] *= sw
            out[:, 3] *= sh
        if self.search.frame_border:  # clip to the frame
            x0c, y0c = np.clip(out[:, 0], 0, W), np.clip(out[:, 1], 0, H)
            x1c = np.clip(out[:, 0] + out[:, 2], 0, W)
            y1c = np.clip(out[:, 1] + out[:, 3], 0, H)
            out = np.column_stack([x0c, y0c, x1c - x0c, y1c - y0c])
        return out, scores

    def fit_all(self, foreground: np.ndarray, group: bool = True,
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Greedy fits: template boxes (N, 4), the boxes of the foreground each explains
        (N, 4), both xywh full-resolution pixels unclipped, and scores (N,).
        ``group=False`` searches every component alone (``group_gap`` ignored).

        Two steps: ``candidates`` (the greedy search: every fit, in the order found) and
        ``select`` (which of them are reported)."""
        c = self.candidates(foreground, group)
        keep = self.select(c)
        return c.boxes[keep], c.tight[keep], c.scores[keep]

    def candidates(self, foreground: np.ndarray, group: bool = True) -> Candidates:
        """The greedy search over a (H, W) foreground mask (nonzero = foreground): each
        foreground region (a connected component at working resolution, with ``margin``
        and half the largest template around it) searched on its own pixels."""
        d = self.search.downscale
        fg = np.asarray(foreground)
        fg = fg.view(np.uint8) if fg.dtype == np.bool_ else (fg != 0).astype(np.uint8)
        H, W = fg.shape
        sc = self._kernels = self._kernels_for(H)
        small = fg
        if d > 1:  # INTER_AREA on 0/1 uint8 rounds: keep cells at least half foreground
            small = cv2.resize(fg * np.uint8(255), (W // d, H // d), interpolation=cv2.INTER_AREA)
            small = (small >= 128).astype(np.uint8)
        hs, ws = small.shape
        gap = int(round(self.search.group_gap / d)) if group else 0
        grouped = small if gap < 1 else cv2.dilate(small, np.ones((gap + 1, 1), np.uint8),
                                                   anchor=(0, 0))
        _, lab, stats, _ = cv2.connectedComponentsWithStatsWithAlgorithm(
            grouped, 8, cv2.CV_32S, cv2.CCL_GRANA)
        label = 1 + np.flatnonzero(stats[1:, 4] >= 0.15 * sc.tsum[0])
        if not len(label):
            return self._no_candidates()
        x, y, w, h = stats[label, :4].T
        m = max(self.search.margin // d, 1)
        hmax, wmax = sc.size.max(axis=0)
        x0, y0 = np.maximum(x - m - wmax // 2, 0), np.maximum(y - m - hmax // 2, 0)
        x1, y1 = np.minimum(x + w + m + wmax // 2, ws), np.minimum(y + h + m + hmax // 2, hs)
        edges = np.zeros((len(label), 4), dtype=bool)  # crop sides on the frame's border
        cut = np.zeros(len(label), dtype=bool)  # regions cut by (or within margin of) the
        # frame's top or bottom: their height does not bound the template heights tried
        if self.search.frame_border:
            edges = np.column_stack([y0 == 0, y1 == hs, x0 == 0, x1 == ws])
            near = max(self.search.margin // d, 1)  # frames may have a dark border strip
            cut = (edges[:, 0] & (y - y0 < near)) | (edges[:, 1] & (y + h > y1 - near))
        allowed = self._allowed_bands(hs)  # each scale only on its band of centre rows
        if allowed is None:
            bands = np.zeros((len(label), len(sc.size), 2), dtype=np.int64)
            bands[:, :, 1] = (y1 - y0)[:, None]
        else:
            bands = np.clip(allowed[None] - y0[:, None, None], 0, (y1 - y0)[:, None, None])
        bands[~((sc.size[None, :, 0] <= 1.5 * h[:, None] + 4) | cut[:, None])] = 0
        live = bands[:, :, 1] > bands[:, :, 0]
        # zero padding holding every placement: a template is anchored at its centre
        pad = np.where(live[:, :, None], sc.size[None] - sc.size[None] // 2, 0).max(axis=1)
        regions = np.column_stack([label, x0, y0, x1, y1, pad, edges]).astype(np.int64)
        fits = np.zeros((len(label), self.search.max_people, 9))
        counts = np.zeros(len(label), dtype=np.int64)
        if self.search.compiled:
            # start-up: the numba kernels (~9 ms CPU), for the compiled search only
            from occbench.trackers.frontend._silhouette_kernel import search_regions_kernel as search
        else:
            search = search_regions
        search(small, lab, regions, np.ascontiguousarray(bands, dtype=np.int64), sc.ys, sc.xs,
               sc.coef, sc.size, sc.tsum, sc.head, sc.occ, self.score.alpha, self.score.beta,
               self.score.threshold, self.score.min_visible, self.score.head_contrast, fits, counts)
        # one row per fit: scale, top, left (crop), E, score, explained box x0, y0, x1, y1
        which = np.repeat(np.arange(len(label)), counts)
        f = np.concatenate([fits[i, :n] for i, n in enumerate(counts)]) if counts.any() else None
        if f is None:
            return self._no_candidates()
        size = sc.size[f[:, 0].astype(np.int64)]
        ox, oy = x0[which], y0[which]
        boxes = np.column_stack([f[:, 2] + ox, f[:, 1] + oy, size[:, 1], size[:, 0]]).astype(np.float64)
        tight = np.column_stack([f[:, 5] + ox, f[:, 6] + oy, f[:, 7] - f[:, 5], f[:, 8] - f[:, 6]])
        tight = np.where(f[:, 5:6] >= 0, tight, boxes)  # no foreground explained: its box
        if self.report.box == "region":  # the region's foreground inside the template box
            for k, (bx, by, bw, bh) in enumerate(boxes.astype(np.int64)):
                r = regions[which[k]]
                sub = slice(max(by, r[2]), min(by + bh, r[4])), slice(max(bx, r[1]), min(bx + bw, r[3]))
                own = (lab[sub] == r[0]) & (small[sub] > 0)
                rr, cc = np.flatnonzero(own.any(axis=1)), np.flatnonzero(own.any(axis=0))
                if len(rr):
                    tight[k] = [sub[1].start + cc[0], sub[0].start + rr[0], cc[-1] - cc[0] + 1,
                                rr[-1] - rr[0] + 1]
                else:
                    tight[k] = boxes[k]
        return Candidates(boxes * d, tight * d, f[:, 4].copy(), which)

    @staticmethod
    def _no_candidates() -> Candidates:
        return Candidates(np.zeros((0, 4)), np.zeros((0, 4)), np.zeros(0), np.zeros(0, dtype=np.int64))

    def select(self, c: Candidates) -> np.ndarray:
        """Which candidates are reported: (N,) bool.

        A candidate lying more than ``max_overlap`` inside an earlier, taller reported fit of
        its region (its height under ``part_height`` times that fit's) is a part of that
        person (an arm, a bag, a hollow in the foreground): its pixels were used up in the
        search but it is not reported. This is the step a verifier of candidate boxes plugs
        into.
        """
        keep = np.ones(len(c), dtype=bool)
        for k in range(1, len(c)):
            earlier = np.flatnonzero(keep[:k] & (c.region[:k] == c.region[k]))
            if not len(earlier):
                continue
            b = c.boxes[earlier]
            inside = intersection_matrix(c.boxes[k : k + 1], b)[0] / max(c.boxes[k, 2] * c.boxes[k, 3], 1e-9)
            part = c.boxes[k, 3] < self.report.part_height * b[:, 3]
            keep[k] = not ((inside > self.report.max_overlap) & part).any()
        return keep

    def _allowed_bands(self, rows: int) -> np.ndarray | None:
        """(n_scales, 2) int64: for each scale the centre rows [b0, b1) (working resolution,
        of a frame ``rows`` high) where its height fits the height model (an interval: the
        expected height grows with the row); None without one."""
        if self.height_model is None:
            return None
        a, b = self.height_model
        d = self.search.downscale
        th = self._kernels.size[:, :1]
        foot = (np.arange(rows)[None, :] + th - th // 2) * d  # full-resolution foot row
        expected = (a * foot + b) / d
        ratio = th / np.maximum(expected, 1e-6)
        tol = self.heights.height_tolerance
        ok = (expected > 0) & (ratio >= 1 / tol) & (ratio <= tol)
        b0 = np.argmax(ok, axis=1)
        b1 = rows - np.argmax(ok[:, ::-1], axis=1)
        return np.where(ok.any(axis=1)[:, None], np.column_stack([b0, b1]), 0)


def fit_height_model(
    feet: np.ndarray, heights: np.ndarray, min_samples: int = 20, min_span: float = 30.0,
) -> tuple[float, float] | None:
    """Robust line height = a * foot_row + b through single-person samples (pixels).

    Least squares, then twice more without samples further than 2.5 MADs from the line.
    Returns None with fewer than ``min_samples`` samples, a foot-row span under
    ``min_span`` pixels, or a negative slope (a camera above the ground sees nearer people
    lower in the image and larger).
    """
    y = np.asarray(feet, dtype=np.float64)
    h = np.asarray(heights, dtype=np.float64)
    if len(y) < min_samples or np.ptp(y) < min_span:
        return None
    keep = np.ones(len(y), dtype=bool)
    for _ in range(3):
        a, b = np.polyfit(y[keep], h[keep], 1)
        res = np.abs(h - (a * y + b))
        mad = np.median(res[keep]) + 1e-6
        keep = res <= 2.5 * 1.4826 * mad
        if keep.sum() < min_samples // 2:
            return None
    return (float(a), float(b)) if a >= 0 else None
