"""PBM 4.2, the model update: the global model (DOF replaced, or window-averaged under
occlusion, and the centroid ratios' running average) and the parts models (a running
average weighted by p_j, frozen below the threshold), in plain numpy (the definitions:
``update_global``, ``update_parts``) and compiled for all matched targets at once
(``targets_update``, ``update_parts_kernel``), held equal to rtol 1e-9 by
``tests/trackers/layered/test_equations.py``; with the matched candidates' rows the update
takes (``matched_rows``), the stale parts adaptation (``stale_parts``) and the life
cycle's survivors (ours: ``alive_rows``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numba
import numpy as np

from occbench.trackers.layered import kernel_cache  # noqa: F401 (before any kernel: one stamp for all)
from occbench.trackers.layered.dynamics import cv_update_inplace
from occbench.trackers.layered.split import (
    _centroid_ratios,
    _part_rects,
    centroid_ratios,
    part_boxes,
)

if TYPE_CHECKING:  # annotations only
    from occbench.trackers.layered.adaptations import Adaptations
    from occbench.trackers.layered.parts import PartFeatures
    from occbench.trackers.layered.search import Candidates
    from occbench.trackers.layered.selection import FrameScores
    from occbench.trackers.layered.targets import Targets


# ----------------------------------------------------------------------------- PBM 4.2, plain numpy


def update_global(window: np.ndarray, dof: np.ndarray, occluded: bool,
                  ratio_window: np.ndarray | None = None
                  ) -> tuple[np.ndarray, np.ndarray | None]:
    """Section 4.2, the global model's update from the matched candidate's DOF (6,).

    "If the candidate is unoccluded, such DOF's are simply replaced by those of the
    matching candidate. In the presence of occlusions ... an average over a sliding
    temporal window is used": ``window`` (L, 6) holds the last L DOF, this one last.
    With ``ratio_window`` (L', 2), the last L' measured (alpha, beta) of eqs. 1-2 before
    this frame, an unoccluded candidate adds its own ratios and the target's become the
    window's mean (the running average of PBM 2.1); None: the ratios are not measured.

    Returns:
        the new DOF (6,) and the new (alpha, beta) (2,) or None (kept).
    """
    new = np.mean(window, axis=0) if occluded else np.asarray(dof, dtype=np.float64)  # 4.2
    if ratio_window is None or occluded:
        return new, None
    a, b = centroid_ratios(new[[0, 1, 4, 5]], new[2:4])                      # eqs. 1-2
    ratios = np.vstack([ratio_window, [[a[0], b[0]]]])
    return new, ratios.mean(axis=0)                                          # running average


def update_parts(model: PartFeatures, cand: PartFeatures, pj: np.ndarray, threshold: float,
                 rate: float, shift: np.ndarray, box: np.ndarray, alpha: float, beta: float,
                 relearn: np.ndarray | None = None, relearn_rate: float = 1.0) -> PartFeatures:
    """Section 4.2, the parts model's update of one target (``model`` and ``cand`` one row
    each) from its matched candidate, returning the new model.

    A part whose score p_j (eq. 12) reaches ``threshold`` matches: its area, perimeter and
    colour histograms move towards the candidate's by a running average with weight
    eta = ``rate`` p_j ("the higher the matching probability, the higher is the update
    weight"), and it takes the candidate's centroid. A part below does not match: "all
    features remain unchanged", its centroid following the global model's ``shift`` (2,).
    The rectangles follow the updated global model ``box`` (4,) and its alpha, beta
    (eqs. 1-2). ``relearn`` (5,) bool (our stale-parts adaptation): those parts take
    eta = ``relearn_rate`` and the candidate's centroid whatever p_j.
    """
    pj = np.asarray(pj, dtype=np.float64).reshape(-1)
    relearn = np.zeros(len(pj), bool) if relearn is None else np.asarray(relearn, bool)
    matched = (pj >= threshold) | relearn
    eta = np.where(relearn, relearn_rate, np.where(pj >= threshold, rate * pj, 0.0))
    out = model.copy()
    for name in ("area", "perimeter", "hsv", "xyz"):
        m, c = getattr(out, name)[0], getattr(cand, name)[0]
        e = eta if m.ndim == 1 else eta[:, None]
        m += e * (c - m)                                                     # running average
    out.centroid[0] = np.where(matched[:, None], cand.centroid[0],
                               model.centroid[0] + np.asarray(shift, dtype=np.float64))
    out.parts[0] = part_boxes(np.asarray(box)[None], alpha, beta)[0]         # eqs. 1-2
    out.height[0] = box[3]
    return out


# ----------------------------------------------------------------------------- PBM 4.2, compiled


@numba.njit(cache=True, inline="always")
def _push(window: np.ndarray, count: np.ndarray, n: int, values: np.ndarray) -> np.ndarray:
    """Append ``values`` (K,) as the newest entry of window n of ``window`` (T, L, K) and
    return the mean of its newest ``count[n]`` entries (a sliding temporal window)."""
    L, K = window.shape[1], window.shape[2]
    for j in range(L - 1):
        for k in range(K):
            window[n, j, k] = window[n, j + 1, k]
    for k in range(K):
        window[n, L - 1, k] = values[k]
    c = min(count[n] + 1, L)
    count[n] = c
    mean = np.zeros(K)
    for k in range(K):
        for j in range(L - c, L):
            mean[k] += window[n, j, k]
        mean[k] /= c
    return mean


@numba.njit(cache=True)
def targets_update(state: tuple, kf1: tuple, kf2: tuple, rows: np.ndarray, dof: np.ndarray,
                   flags: tuple, part_scores: np.ndarray, threshold: float, shift: np.ndarray
                   ) -> None:
    """Section 4.2, the global models' update (``update_global``) of the
    targets at ``rows`` from their candidates' DOF (M, 6), then KF1 (eq. 7) with z = (xc,
    yc) and KF2 (eq. 8) with z = (h, w) of the updated DOF (``cv_update_inplace``), then
    p_j, the frozen parts (not p_j >= threshold), the occlusion flag, hits + 1 and misses = 0.

    Per row the DOF enters the occlusion window; an occluded row takes the window's mean,
    an unoccluded one the candidate's DOF; an unoccluded row with a measured centroid
    pushes its ratios (eqs. 1-2, ``_centroid_ratios``) into the ratio window, whose mean
    becomes the target's alpha, beta. ``shift`` (M, 2) gets the centroid moves.

    Args:
        state: ``Targets``' (dof, history, n_history, ratios, n_ratios, alpha, beta,
            part_scores, occluded_parts, occluded, hits, misses), updated.
        kf1, kf2: (x, p, r) of the filters. flags: (measured (M,), occluded (M,)) bool.
    """
    (dof_all, history, n_history, ratios, n_ratios, alpha, beta, part_scores_all,
     occluded_parts, occluded_all, hits, misses) = state
    measured, occluded = flags
    M = rows.shape[0]
    z1, z2 = np.empty((M, 2)), np.empty((M, 2))
    ab = np.empty(2)
    for q in range(M):
        n = rows[q]
        x0, y0 = dof_all[n, 2], dof_all[n, 3]
        mean = _push(history, n_history, n, dof[q])
        for k in range(6):
            dof_all[n, k] = mean[k] if occluded[q] else dof[q, k]            # 4.2
        d = dof_all[n]
        if measured[q] and not occluded[q]:
            ab[0], ab[1] = _centroid_ratios(d[0], d[1], d[4], d[5], d[2], d[3])  # eqs. 1-2
            avg = _push(ratios, n_ratios, n, ab)                             # running average
            alpha[n], beta[n] = avg[0], avg[1]
        shift[q, 0], shift[q, 1] = d[2] - x0, d[3] - y0
        z1[q, 0], z1[q, 1] = d[2], d[3]                                      # eq. 7
        z2[q, 0], z2[q, 1] = d[5], d[4]                                      # eq. 8
    cv_update_inplace(kf1[0], kf1[1], kf1[2], rows, z1)
    cv_update_inplace(kf2[0], kf2[1], kf2[2], rows, z2)
    for q in range(M):
        n = rows[q]
        for j in range(part_scores.shape[1]):
            part_scores_all[n, j] = part_scores[q, j]
            occluded_parts[n, j] = not part_scores[q, j] >= threshold
        occluded_all[n] = occluded[q]
        hits[n] += 1
        misses[n] = 0


@numba.njit(cache=True, inline="always")
def _rect(part: np.ndarray) -> tuple:
    """(x0, y0, x1, y1, area) of an xywh rectangle (4,), the area at least 1e-9."""
    x0, y0 = part[0], part[1]
    return x0, y0, x0 + part[2], y0 + part[3], max(part[2] * part[3], 1e-9)


@numba.njit(cache=True, inline="always")
def _under_others(cover: float, x0: float, y0: float, x1: float, y1: float, size: float, r: int,
                  dof: np.ndarray, misses: np.ndarray, occluder_misses: int) -> float:
    """The largest of ``cover`` and the shares of the rectangle (x0, y0)-(x1, y1) of area
    ``size`` under the box (``dof`` columns 0, 1, 4, 5) of each target but ``r`` unfound for
    at most ``occluder_misses`` frames."""
    for t in range(dof.shape[0]):
        if t == r or misses[t] > occluder_misses:
            continue
        iw = min(x1, dof[t, 0] + dof[t, 4]) - max(x0, dof[t, 0])
        ih = min(y1, dof[t, 1] + dof[t, 5]) - max(y0, dof[t, 1])
        if iw > 0.0 and ih > 0.0:
            cover = max(cover, iw * ih / size)
    return cover


@numba.njit(cache=True)
def contact_parts(dof: np.ndarray, misses: np.ndarray, rows: np.ndarray, c_parts: np.ndarray,
                  ks: np.ndarray, occluder_misses: int, share: float) -> np.ndarray:
    """(M, 5) bool: the parts of the targets at ``rows``, matched to the candidates at ``ks``
    of ``c_parts`` (N, 5, 4) xywh, at least ``share`` of whose rectangle (the candidate's)
    lies under another target's box (``_under_others``: found, or unfound for at most
    ``occluder_misses`` frames, at its global model ``dof``): a part at a contact
    (``contact``: ``adaptations.contact_frozen``, ``contact_colour``, ``contact_occluded``)."""
    out = np.zeros((rows.shape[0], c_parts.shape[1]), np.bool_)
    for q in range(rows.shape[0]):
        r, k = rows[q], ks[q]
        for j in range(c_parts.shape[1]):
            x0, y0, x1, y1, size = _rect(c_parts[k, j])
            out[q, j] = _under_others(0.0, x0, y0, x1, y1, size, r, dof, misses,
                                      occluder_misses) >= share
    return out


@numba.njit(cache=True)
def stale_parts(state: tuple, dof: np.ndarray, misses: np.ndarray, rows: np.ndarray,
                cand: tuple, ks: np.ndarray, part_scores: np.ndarray, rule: tuple,
                relearn: np.ndarray) -> None:
    """Stale parts (our adaptation beyond PBM 4.2; ``model.stale_parts``) in one loop over
    rows x parts x targets; a part's cover is the largest of the fraction outside the
    image and the fractions under each other target's box.

    Args:
        state: (stale (T, 5), occluded_parts (T, 5), model area (T, 5)), updated.
        dof, misses: the targets' (T, 6) DOF and (T,) misses. cand: (parts, area) of the
            candidates. rule: (threshold, occluder_misses, W, H, max_cover, min_fill,
            stale_frames). relearn: (M, 5) bool, written.
    """
    stale, occluded_parts, m_area = state
    c_parts, c_area = cand
    threshold, occluder_misses, W, H, max_cover, min_fill, stale_frames = rule
    for q in range(rows.shape[0]):
        r, k = rows[q], ks[q]
        for j in range(c_parts.shape[1]):
            x0, y0, x1, y1, size = _rect(c_parts[k, j])
            inside = ((min(max(x1, 0.0), W) - min(max(x0, 0.0), W))
                      * (min(max(y1, 0.0), H) - min(max(y0, 0.0), H)))
            cover = _under_others(1.0 - inside / size, x0, y0, x1, y1, size, r, dof, misses,
                                  occluder_misses)
            if part_scores[q, j] >= threshold:
                stale[r, j] = 0
            elif cover <= max_cover and c_area[k, j] >= min_fill * m_area[r, j]:
                stale[r, j] += 1
                if stale[r, j] >= stale_frames:
                    relearn[q, j] = True
                    stale[r, j] = 0
                    occluded_parts[r, j] = False


@numba.njit(cache=True)
def update_parts_kernel(m: tuple, rows: np.ndarray, c: tuple, ks: np.ndarray, part_scores: np.ndarray,
                 rule: tuple, shift: np.ndarray, ratios: tuple, boxes: np.ndarray,
                 relearn: np.ndarray) -> None:
    """Section 4.2, the parts models' update (``update_parts``) of the targets
    at ``rows`` of ``m`` from the candidates at ``ks`` of ``c``, in place: a part with
    p_j >= threshold moves area, perimeter and histograms by eta = rate p_j towards the
    candidate's and takes its centroid; a part below keeps them, its centroid moved by
    ``shift``; a ``relearn`` part takes eta = relearn_rate and the candidate's centroid.
    The rectangles follow the updated global model (``boxes`` (M, 4) and ``ratios``
    (alpha, beta), each (M,); ``_part_rects``, eqs. 1-2).

    ``rule``: (threshold, rate, relearn_rate).
    """
    m_parts, m_area, m_perimeter, m_hsv, m_xyz, m_centroid, m_height = m
    _, c_area, c_perimeter, c_hsv, c_xyz, c_centroid, _ = c
    threshold, rate, relearn_rate = rule
    alpha, beta = ratios
    nb = m_hsv.shape[2]
    for q in range(rows.shape[0]):
        r, k = rows[q], ks[q]
        for j in range(m_area.shape[1]):
            p = part_scores[q, j]
            matched = p >= threshold or relearn[q, j]
            eta = relearn_rate if relearn[q, j] else (rate * p if p >= threshold else 0.0)
            m_area[r, j] += eta * (c_area[k, j] - m_area[r, j])              # running average
            m_perimeter[r, j] += eta * (c_perimeter[k, j] - m_perimeter[r, j])
            for u in range(nb):
                m_hsv[r, j, u] += eta * (c_hsv[k, j, u] - m_hsv[r, j, u])
                m_xyz[r, j, u] += eta * (c_xyz[k, j, u] - m_xyz[r, j, u])
            for a in range(2):
                m_centroid[r, j, a] = c_centroid[k, j, a] if matched else m_centroid[r, j, a] + shift[q, a]
        _part_rects(boxes[q, 0], boxes[q, 1], boxes[q, 2], boxes[q, 3], alpha[q], beta[q],
                    m_parts[r])                                              # eqs. 1-2
        m_height[r] = boxes[q, 3]


@numba.njit(cache=True)
def matched_rows(mt: np.ndarray, mn: np.ndarray, hyp: np.ndarray, boxes: np.ndarray,
                 centroid: np.ndarray, blob: np.ndarray, pred_wh: np.ndarray, alpha: np.ndarray,
                 pj_all: np.ndarray, dof_h: np.ndarray, pj_h: np.ndarray, k_h: np.ndarray
                 ) -> tuple:  # pragma: no cover (compiled)
    """The chosen candidates of M matched (target mt, candidate mn) pairs, as the model
    update (PBM 4.2) takes them: (dof (M, 6), p_j (M, 5), occluded (M,) bool, index (M,)
    in the features the candidate was measured in).

    An occluded pair (``hyp[t, n]`` >= 0, a row of the search's ``dof_h``, ``pj_h``,
    ``k_h``) takes the carved box's; an unoccluded one its own box and centroid
    (xtl, ytl, xc, yc, w, h) and ``pj_all[t, n]``, except that a blob keeps KF2's width
    (its span follows the swinging limbs, PBM 3): w = ``pred_wh[t, 0]``, xtl = xc - alpha w
    (eq. 1).
    """
    M = mt.shape[0]
    dof = np.empty((M, 6))
    pj = np.empty((M, pj_all.shape[2]))
    occluded = np.empty(M, np.bool_)
    ks = np.empty(M, np.int64)
    for q in range(M):
        t, n = mt[q], mn[q]
        h = hyp[t, n]
        occluded[q] = h >= 0
        if h >= 0:
            dof[q] = dof_h[h]
            pj[q] = pj_h[h]
            ks[q] = k_h[h]
            continue
        dof[q, 0], dof[q, 1], dof[q, 4], dof[q, 5] = boxes[n, 0], boxes[n, 1], boxes[n, 2], boxes[n, 3]
        dof[q, 2], dof[q, 3] = centroid[n, 0], centroid[n, 1]
        if blob[n]:
            w = pred_wh[t, 0]
            dof[q, 0] = centroid[n, 0] - alpha[t] * w
            dof[q, 4] = w
        pj[q] = pj_all[t, n]
        ks[q] = n
    return dof, pj, occluded, ks


# ----------------------------------------------------------------------------- life cycle (ours)


@numba.njit(cache=True)
def alive_rows(dof: np.ndarray, shift: np.ndarray, misses: np.ndarray, confirmed: np.ndarray,
               width: int, height: int, margin: float, max_misses: int, exit_misses: int
               ) -> np.ndarray:  # pragma: no cover (compiled)
    """(T,) bool: the targets kept after this frame (the tracker's life cycle): found, or
    confirmed and unfound for at most ``max_misses`` frames, unless unfound for
    ``exit_misses`` frames with the box (dof columns 0, 1, 4, 5) moved by ``shift`` (T, 2)
    (KF1's prediction since it was last found) more than ``margin`` beyond an image border
    (it left; a person standing at the border is not leaving)."""
    T = misses.shape[0]
    alive = np.empty(T, np.bool_)
    for t in range(T):
        x, y = dof[t, 0] + shift[t, 0], dof[t, 1] + shift[t, 1]
        x1, y1 = x + dof[t, 4], y + dof[t, 5]
        gone = x < -margin or y < -margin or x1 > width + margin or y1 > height + margin
        alive[t] = misses[t] == 0 or (confirmed[t] and misses[t] <= max_misses
                                      and not (gone and misses[t] >= exit_misses))
    return alive


# ----------------------------------------------------------------------------- the tracker's steps


class Chosen(NamedTuple):
    """The chosen candidates of M matches as PBM 4.2 updates from them (``matched_rows``):
    ``dof`` (M, 6), ``pj`` (M, 5), ``occluded`` (M,) bool (a carved candidate), ``k`` (M,)
    its row in the features it was measured in (the frame's or the search's)."""

    dof: np.ndarray
    pj: np.ndarray
    occluded: np.ndarray
    k: np.ndarray


def chosen_candidates(matches: np.ndarray, scores: FrameScores, cand: Candidates,
                      targets: Targets, pred_wh: np.ndarray) -> Chosen:
    """``matched_rows`` of the (M, 2) matched (target, candidate) pairs of a frame."""
    return Chosen(*matched_rows(matches[:, 0], matches[:, 1], scores.hyp, cand.box,
                                cand.centroid, cand.blob, pred_wh, targets.alpha, scores.pj,
                                scores.dof_h, scores.pj_h, scores.k_h))


def survivors(targets: Targets, width: int, height: int, a: Adaptations, max_misses: int
              ) -> np.ndarray:
    """``alive_rows`` of the targets in a (width, height) image: (T,) bool."""
    return alive_rows(targets.dof, targets.predicted_shift(), targets.misses, targets.confirmed,
                      width, height, a.exit_margin, max_misses, a.exit_misses)
