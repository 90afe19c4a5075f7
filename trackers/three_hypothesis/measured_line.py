"""Hypothesis 1's velocity (Reta 3.3.3, case 1: a missing person keeps its velocity and
direction): M's, or the line through the person's last measured centres; the paper's rule
and ours (``adaptations.measured_hypothesis``), ``rules.build_rules`` picks one. Issue 35: on
PETS a person who turns or speeds up keeps a Kalman velocity a third of its own for ten
frames (M's position noise takes up the motion), and its hypothesis is left behind at the
next contact. ``docs/adaptations.md`` gives the evidence. States are (8,) Kalman vectors
(xc, yc, w, h, vx, vy, vw, vh); boxes (4,) xywh pixels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import chain
from typing import ClassVar

import numpy as np

from occbench.trackers.three_hypothesis._kernels import line_misses


@dataclass(frozen=True)
class FilterVelocity:
    """3.3.3 as written: hypothesis 1 continues M's prediction (M's velocity)."""

    records: ClassVar[bool] = False
    uses_shares: ClassVar[bool] = False
    uses_partners: ClassVar[bool] = False

    def record(self, persons: list, frame: int, boxes: np.ndarray, predicted: np.ndarray,
               own: np.ndarray | None = None, partner: np.ndarray | None = None) -> None:
        return None

    def start(self, person, x_prev: np.ndarray, x_pred: np.ndarray) -> np.ndarray:
        return x_pred


def _line(centres: list[tuple[float, float, float]]) -> tuple[float, float, float, float, float]:
    """Least-squares line (t0, x0, y0, vx, vy) through (frame, xc, yc) rows: the centre at
    the mean frame t0 and the velocity."""
    return _fit(centres)[:5]


def _fit(centres: list[tuple[float, float, float]]) -> tuple[float, ...]:
    """``_line``'s (t0, x0, y0, vx, vy) and the standard errors (se_x, se_y) of the two
    slopes: sqrt(sum of squared residuals / (n - 2) / sum (t - t0)^2) (n >= 3 rows)."""
    c = np.asarray(centres, dtype=np.float64)
    t = c[:, 0] - c[:, 0].mean()
    tt = float((t * t).sum())
    x, y = c[:, 1] - c[:, 1].mean(), c[:, 2] - c[:, 2].mean()
    vx, vy = float((t * x).sum()) / tt, float((t * y).sum()) / tt
    dof = max(len(c) - 2, 1)
    se_x = float(np.sqrt(((x - vx * t) ** 2).sum() / dof / tt))
    se_y = float(np.sqrt(((y - vy * t) ** 2).sum() / dof / tt))
    return (float(c[:, 0].mean()), float(c[:, 1].mean()), float(c[:, 2].mean()), vx, vy,
            se_x, se_y)


def _lines(centres: np.ndarray) -> tuple[np.ndarray, ...]:
    """``_line`` of G histories at once, (G, n, 3) (frame, xc, yc) rows: (G,) t0, x0, y0, vx,
    vy. Each sum runs along a row's n terms in memory order, as ``_line``'s 1-D sums do
    (numpy's pairwise order): the same bits."""
    c = np.ascontiguousarray(centres.transpose(2, 0, 1))  # (3, G, n): frames, xc, yc
    t0, x0, y0 = c.mean(axis=2)
    t, x, y = c[0] - t0[:, None], c[1] - x0[:, None], c[2] - y0[:, None]
    tt = (t * t).sum(axis=1)
    return t0, x0, y0, (t * x).sum(axis=1) / tt, (t * y).sum(axis=1) / tt


def _squares(a: np.ndarray) -> np.ndarray:
    """a ** 2 by the C library's pow, as Python's and numpy's scalar ``** 2`` round it
    (numpy's array ``** 2`` is a * a, which differs in the last bit now and then)."""
    return np.array([math.pow(v, 2) for v in a.tolist()])


@dataclass(frozen=True)
class MeasuredLine:
    """``measured_hypothesis``: hypothesis 1 of a person just missed moves with the velocity
    of the least-squares line through its last ``window`` measured centres (Alg. 1's m), from
    its last estimate, when that line has predicted the person's measurements better than M
    so far (summed squared errors in box heights, each measurement predicted from the ones
    before it: the person's own track record chooses); else M's, as the paper. With
    ``sigmas`` > 0 the line is taken only where it is measured to differ from M's velocity,
    by more than ``sigmas`` standard errors of its slope in x or in y (a standing person's
    jitter draws a line that predicts as well as M by chance). With ``step``
    (``adaptations.measured_step``) a third predictor is scored on the same measurements, the
    last step (the displacement of the last two measured centres per frame), and hypothesis 1
    takes it when its record is the best of the three: a person who has just turned keeps the
    line's and M's old direction for several frames, its last step does not (exact boxes).
    With ``own_only`` (``adaptations.merged_line``) a measurement that held a hidden partner
    (its own share below 1, ``contact.own_shares``) is an occlusion, its centre the pair's: it
    neither enters the person's centres nor scores the predictors, and at a first miss right
    after one, hypothesis 1 starts on the chosen predictor at t from the person's own
    measurements (the line's centre at t, or the last own centre moved by the step per frame
    since), not from the estimate the merged measurement dragged. With ``shift`` > 0
    (``adaptations.merged_line_shift``) such a measurement counts as merged only when it is
    evidence of two people: its centre lies off the line through the person's own last
    centres (at t), towards the hidden partner's predicted centre, by more than ``shift``
    times its width (a box fitted over the pair is pulled towards the partner; a person's own
    box beside a hidden neighbour stays on the person's line). With ``still``
    (``adaptations.measured_still``) a person whose last ``window`` measured centres show no
    motion (the line's slopes within ``sigmas`` standard errors of zero, in x and in y) is
    missed standing: hypothesis 1 stands where it was last estimated, velocity 0 (the state
    of the paper's hypothesis 3, ``hypotheses.spawn``), whatever M's velocity or the step."""

    window: int
    sigmas: float = 0.0
    step: bool = False
    own_only: bool = False
    shift: float = 0.0
    still: bool = False
    records: ClassVar[bool] = True

    @property
    def uses_shares(self) -> bool:
        """Whether ``record`` reads the matched measurements' own shares."""
        return self.own_only

    @property
    def uses_partners(self) -> bool:
        """Whether ``record`` reads the hidden partners' predicted centres."""
        return self.own_only and self.shift > 0

    def pulled(self, persons: list, frame: int, boxes: np.ndarray, partner: np.ndarray,
               rows: np.ndarray) -> np.ndarray:
        """(len(rows),) bool: whether each measurement ``boxes[r]`` (r in ``rows``) lies off
        the line through its person's own last centres at ``frame``, towards ``partner[r]``
        (the hidden partner's predicted centre), by more than ``shift`` times its width; False
        for a person with fewer than 3 centres (no line) or no partner."""
        out = np.zeros(len(rows), dtype=bool)
        for a, r in enumerate(rows.tolist()):
            centres = persons[r].centres
            if len(centres) < 3 or np.isnan(partner[r]).any():
                continue
            t0, x0, y0, vx, vy = _line(centres)
            at = np.array([x0 + vx * (frame - t0), y0 + vy * (frame - t0)])
            u = partner[r] - at
            c = boxes[r, :2] + boxes[r, 2:] / 2
            out[a] = float((c - at) @ u) > self.shift * boxes[r, 2] * float(np.hypot(*u))
        return out

    def stands(self, centres: list[tuple[float, float, float]]) -> bool:
        """Whether the line through (frame, xc, yc) ``centres`` (>= 3 rows) shows no motion:
        each slope within ``sigmas`` standard errors of zero."""
        _, _, _, vx, vy, se_x, se_y = _fit(centres)
        return abs(vx) <= self.sigmas * se_x and abs(vy) <= self.sigmas * se_y

    def record(self, persons: list, frame: int, boxes: np.ndarray, predicted: np.ndarray,
               own: np.ndarray | None = None, partner: np.ndarray | None = None) -> None:
        """Score both predictors on each person's measured box at ``frame`` (``boxes`` (K, 4)
        xywh; M's prediction: ``predicted`` (K, 8) states), then keep its centre. A person
        with at least 3 centres adds, to M's error and to the line's, the squared distance of
        the predicted centre from the measured one over the box height squared (with
        ``step``, the last step's to its own); every person's line and step in one compiled
        call (``_kernels.line_misses``: ``_lines``' bits). With ``own_only``, the rows whose
        ``own`` (K,) share is below 1 are left out and their persons marked
        (``merged_at``); with ``shift``, only those ``pulled`` towards their ``partner``
        ((K, 2) predicted centres)."""
        if self.own_only and own is not None:
            keep = np.asarray(own) >= 1.0
            if self.shift > 0 and partner is not None and not keep.all():
                rows = np.flatnonzero(~keep)
                keep[rows] = ~self.pulled(persons, frame, boxes, partner, rows)
            for person, kept in zip(persons, keep.tolist()):
                person.merged_at = -1 if kept else frame
            if not keep.all():
                persons = [person for person, kept in zip(persons, keep.tolist()) if kept]
                boxes, predicted = boxes[keep], predicted[keep]
        cx, cy = boxes[:, 0] + boxes[:, 2] / 2, boxes[:, 1] + boxes[:, 3] / 2
        sizes = np.fromiter(map(len, (person.centres for person in persons)), np.int64,
                            len(persons))
        k = np.flatnonzero(sizes >= 3)
        if len(k):
            rows = chain.from_iterable(chain.from_iterable(persons[r].centres
                                                           for r in k.tolist()))
            n = sizes[k]
            hist = np.fromiter(rows, np.float64, int(n.sum()) * 3).reshape(-1, 3)
            misses = np.empty((4, len(k)))  # the line's and the last step's, in x and y
            line_misses(hist, n, float(frame), cx[k], cy[k], misses)  # _lines, compiled
            h2, mx, my, lx, ly = _squares(np.concatenate([
                np.maximum(boxes[k, 3], 1.0), predicted[k, 0] - cx[k],
                predicted[k, 1] - cy[k], misses[0], misses[1]])).reshape(5, len(k))
            mine, line = (mx + my) / h2, (lx + ly) / h2
            step = (misses[2] * misses[2] + misses[3] * misses[3]) / h2
            for r, e_m, e_l, e_s in zip(k.tolist(), mine.tolist(), line.tolist(),
                                        step.tolist()):
                persons[r].line_errors[0] += e_m
                persons[r].line_errors[1] += e_l
                if self.step:
                    persons[r].step_error += e_s
        for person, x, y in zip(persons, cx.tolist(), cy.tolist()):
            person.centres.append((frame, x, y))
            del person.centres[:-self.window]

    def start(self, person, x_prev: np.ndarray, x_pred: np.ndarray) -> np.ndarray:
        """(8,) state of hypothesis 1 at a person's first miss, from its last estimate
        ``x_prev`` and M's prediction ``x_pred``."""
        errors = person.line_errors
        if len(person.centres) < 3:
            return x_pred
        if self.still and len(person.centres) == self.window and self.stands(person.centres):
            x = x_prev.copy()  # hypothesis 3's state: the last estimate, velocity 0
            x[len(x) // 2:] = 0.0
            return x
        merged = self.own_only and person.merged_at >= 0  # t - 1's measurement left out
        t = person.merged_at + 1 if merged else 0
        if self.step and person.step_error < min(errors):
            (f1, x1, y1), (f2, x2, y2) = person.centres[-2:]
            vx, vy = (x2 - x1) / max(f2 - f1, 1), (y2 - y1) / max(f2 - f1, 1)
            x = x_pred.copy()  # from the last measured centre (t - 1) one step on
            if merged:  # from the last own centre, a step a frame since
                x[0], x[1], x[4], x[5] = x2 + vx * (t - f2), y2 + vy * (t - f2), vx, vy
            else:
                x[0], x[1], x[4], x[5] = x2 + vx, y2 + vy, vx, vy
            return x
        if errors[1] >= errors[0]:
            return x_pred
        t0, x0, y0, vx, vy, se_x, se_y = _fit(person.centres)
        if self.sigmas > 0 and (abs(vx - x_pred[4]) <= self.sigmas * se_x
                                and abs(vy - x_pred[5]) <= self.sigmas * se_y):
            return x_pred  # the line's velocity is M's within its own error
        x = x_pred.copy()
        if merged:  # the line's centre at t
            x[0], x[1], x[4], x[5] = x0 + vx * (t - t0), y0 + vy * (t - t0), vx, vy
        else:
            x[0], x[1], x[4], x[5] = x_prev[0] + vx, x_prev[1] + vy, vx, vy
        return x
