"""PBM's equations in plain numpy: the source of truth the compiled kernels are tested
against (``tests/trackers/layered/test_equations.py``, to rtol 1e-9, not bit for bit).

Each function computes one equation or rule of the paper ("Tracking People under Heavy
Occlusions by Layered Data Association"), its number beside the line (filterpy's
manner). A parts model or a candidate is a ``PartFeatures`` (five parts: head,
left/right torso-arm, left/right leg); boxes are xywh, 0-based, top-left corner; a global
model (DOF) is (xtl, ytl, xc, yc, w, h).

- eqs. 1-2, the centroid ratios alpha and beta: ``centroid_ratios``; the part split they
  fix: ``part_boxes``; the DOF they give under occlusion: ``dof_from_head``;
- eq. 7 (KF1, Z1 = (xc, yc)) and eq. 8 (KF2, Z2 = (h, w)): ``kf1_z``,
  ``kf2_z``, both constant-velocity filters ``cv_predicted`` / ``cv_updated``;
- eqs. 9-10, the head-anchored search boxes: ``search_boxes``;
- eq. 11, feature differences: ``differences``;
- eq. 12, part scores: ``part_scores`` (with ``match_probability``, p(d | theta));
- eq. 13, global score: ``global_score``;
- section 4.2, the model update: ``update_global`` (DOF and ratios) and ``update_parts``.

This module imports nothing of the tracker at run time, so every other module may import it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from scipy.special import ndtr

if TYPE_CHECKING:  # annotations only
    from occbench.trackers.layered.feature_models import FeatureModels
    from occbench.trackers.layered.parts import PartFeatures

__all__ = [
    "HEAD_FRACTION",
    "centroid_ratios",
    "cv_predicted",
    "cv_updated",
    "differences",
    "dof_from_head",
    "global_score",
    "kf1_z",
    "kf2_z",
    "match_probability",
    "part_boxes",
    "part_scores",
    "search_boxes",
    "update_global",
    "update_parts",
]

HEAD_FRACTION = 1.0 / 7.0
"""The head occupies one seventh of the person height (PBM 2.1)."""


# ----------------------------------------------------------------------------- PBM 2.1


def centroid_ratios(boxes: np.ndarray, centroids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. 1-2: the ratios alpha and beta of centroids (xc, yc) inside boxes.

    The paper prints eq. 2 as ``(ytl - yc - h/7) / (h - h/7)``, which is negative for any
    centroid below the head; the ratio it describes ("the height of the torso over the body
    height") is ``(yc - ytl - h/7) / (h - h/7)``, used here.

    Args:
        boxes: (N, 4) xywh. centroids: (N, 2) (xc, yc).
    Returns:
        alpha (N,), beta (N,), clipped to [0.05, 0.95].
    """
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    c = np.asarray(centroids, dtype=np.float64).reshape(-1, 2)
    w = np.maximum(b[:, 2], 1e-9)
    h = np.maximum(b[:, 3], 1e-9)
    alpha = (c[:, 0] - b[:, 0]) / w                                          # eq. 1
    beta = (c[:, 1] - b[:, 1] - HEAD_FRACTION * h) / (h - HEAD_FRACTION * h)  # eq. 2
    return np.clip(alpha, 0.05, 0.95), np.clip(beta, 0.05, 0.95)


def part_boxes(boxes: np.ndarray, alpha: np.ndarray | float = 0.5,
               beta: np.ndarray | float = (0.5 - HEAD_FRACTION) / (1.0 - HEAD_FRACTION)
               ) -> np.ndarray:
    """The five part rectangles of each box (PBM 2.1, Fig. 2), split at the centroid that
    eqs. 1-2 place: the head is the top h/7 rows, torso and arms run down to yc, the legs
    from yc to the bottom, left and right divided at xc.

    Args:
        boxes: (N, 4) xywh person boxes. alpha, beta: (N,) or scalar ratios (defaults:
            an upright symmetric person with the centroid at mid-height).
    Returns:
        (N, 5, 4) xywh part boxes: head, left/right torso-arm, left/right leg.
    """
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    n = len(b)
    a = np.broadcast_to(np.asarray(alpha, dtype=np.float64), (n,))
    be = np.broadcast_to(np.asarray(beta, dtype=np.float64), (n,))
    x, y, w, h = b.T
    hh = HEAD_FRACTION * h
    xc = x + a * w                                                           # eq. 1
    yc = y + hh + be * (h - hh)                                              # eq. 2
    top, left_w, right_w = y + hh, xc - x, x + w - xc
    torso_h, leg_h = yc - y - hh, y + h - yc
    return np.stack([x, y, w, hh, x, top, left_w, torso_h, xc, top, right_w, torso_h,
                     x, yc, left_w, leg_h, xc, yc, right_w, leg_h], axis=1).reshape(n, 5, 4)


def dof_from_head(heads: np.ndarray, w: np.ndarray, h: np.ndarray, alpha: np.ndarray,
                  beta: np.ndarray) -> np.ndarray:
    """The DOF under occlusion (PBM 2.1: "we use the values of alpha and beta at frame
    n - 1 to infer xtl from (1) and yc from (2)") of M heads (M, >= 2) (x top-centre,
    y top, ...) with sizes w, h and ratios alpha, beta ((M,) or scalars): (M, 6)."""
    heads = np.asarray(heads, dtype=np.float64)
    xc, ytl = heads[:, 0], heads[:, 1]
    xtl = xc - alpha * w                                                     # eq. 1
    yc = ytl + HEAD_FRACTION * h + beta * (h - HEAD_FRACTION * h)            # eq. 2
    out = np.empty((len(heads), 6))
    out[:, 0], out[:, 1], out[:, 2], out[:, 3], out[:, 4], out[:, 5] = xtl, ytl, xc, yc, w, h
    return out


# ----------------------------------------------------------------------------- PBM 3


def kf1_z(dof: np.ndarray) -> np.ndarray:
    """Eq. 7, KF1: Z1 = (xc, yc) of (..., 6) DOF; its state is X1 = (xc, yc, xc', yc')."""
    return np.asarray(dof)[..., [2, 3]]                                      # eq. 7


def kf2_z(dof: np.ndarray) -> np.ndarray:
    """Eq. 8, KF2: Z2 = (h, w) of (..., 6) DOF; its state is X2 = (h, w, h', w')."""
    return np.asarray(dof)[..., [5, 4]]                                      # eq. 8


_F = np.block([[np.eye(2), np.eye(2)], [np.zeros((2, 2)), np.eye(2)]])
_H = np.hstack([np.eye(2), np.zeros((2, 2))])


def cv_predicted(x: np.ndarray, P: np.ndarray, q_p: float, q_v: float
               ) -> tuple[np.ndarray, np.ndarray]:
    """Predict step of KF1 (eq. 7) and KF2 (eq. 8), constant velocity, unit time step:
    x (4,) = (a, b, a', b'), P (4, 4), Q = diag(q_p, q_p, q_v, q_v) (variances)."""
    Q = np.diag([q_p, q_p, q_v, q_v])
    x = _F @ x                                                               # x = F x
    P = _F @ P @ _F.T + Q                                                    # P = F P F' + Q
    return x, P


def cv_updated(x: np.ndarray, P: np.ndarray, z: np.ndarray, r: float
              ) -> tuple[np.ndarray, np.ndarray]:
    """Update step of KF1 (eq. 7, z = Z1) and KF2 (eq. 8, z = Z2): measurement z (2,),
    R = r I (variance)."""
    y = z - _H @ x                                                           # y = z - H x
    S = _H @ P @ _H.T + r * np.eye(2)                                        # S = H P H' + R
    K = P @ _H.T @ np.linalg.inv(S)                                          # K = P H' S^-1
    x = x + K @ y                                                            # x = x + K y
    P = (np.eye(4) - K @ _H) @ P                                             # P = (I - K H) P
    return x, P


# ----------------------------------------------------------------------------- PBM 3.1


def search_boxes(head: np.ndarray, predicted_wh: np.ndarray, alpha: float, step: float,
                 search_range: int) -> np.ndarray:
    """Eqs. 9-10, the head-anchored boxes: ((2 r + 1)^2, 4) xywh, box i (2 r + 1) + k of
    width w_i and height h_k.

    w_i = w (1 + step i), h_k = h (1 + step k), i, k = -r..r (the paper's delta = 0.05 is
    taken relative to the predicted size); each box hangs from the head top (y = head
    top) with its centroid column on the head (x = head x - alpha w_i, eq. 1).
    """
    i = np.arange(-search_range, search_range + 1, dtype=np.float64)
    ws = predicted_wh[0] * (1.0 + step * i)                                  # eq. 9
    hs = predicted_wh[1] * (1.0 + step * i)                                  # eq. 10
    W, Hh = np.meshgrid(ws, hs, indexing="ij")
    W, Hh = W.ravel(), Hh.ravel()
    return np.column_stack([head[0] - alpha * W, np.full_like(W, head[1]), W, Hh])


# ----------------------------------------------------------------------------- PBM 4.1


def differences(model: PartFeatures, cand: PartFeatures, ti: np.ndarray, n: np.ndarray,
                misses: np.ndarray | None = None) -> np.ndarray:
    """Eq. 11, d_ij = |f_ij - F_ij|, for the pairs (target ti[k], candidate n[k]).

    Features i in ``parts.FEATURES`` order: area and perimeter (absolute differences),
    HSV and XYZ histograms (1 - Bhattacharyya coefficient; 1 when the candidate's part
    has no foreground), displacement of the part centroid over the target's height, and
    1 - IoU of the part rectangles. After a gap of ``misses`` frames the last two are
    divided by 1 + misses (our reading: per-frame differences; ``adaptations.gap_division``).

    Returns:
        (K, 6, 5) differences, >= 0.
    """
    ti, n = np.asarray(ti, dtype=np.intp), np.asarray(n, dtype=np.intp)
    d = np.empty((len(ti), 6, model.area.shape[1]))
    d[:, 0] = np.abs(model.area[ti] - cand.area[n])                          # area
    d[:, 1] = np.abs(model.perimeter[ti] - cand.perimeter[n])                # perimeter
    empty = cand.area[n] <= 0
    for i, name in ((2, "hsv"), (3, "xyz")):
        rho = np.sqrt(getattr(model, name)[ti] * getattr(cand, name)[n]).sum(-1)
        d[:, i] = np.where(empty, 1.0, 1.0 - rho)                            # 1 - rho
    d[:, 4] = (np.linalg.norm(cand.centroid[n] - model.centroid[ti], axis=2)
               / np.maximum(model.height[ti], 1.0)[:, None])                 # |c - C| / H
    a, b = model.parts[ti], cand.parts[n]
    iw = np.clip(np.minimum(a[..., 0] + a[..., 2], b[..., 0] + b[..., 2])
                 - np.maximum(a[..., 0], b[..., 0]), 0.0, None)
    ih = np.clip(np.minimum(a[..., 1] + a[..., 3], b[..., 1] + b[..., 3])
                 - np.maximum(a[..., 1], b[..., 1]), 0.0, None)
    inter = iw * ih
    union = a[..., 2] * a[..., 3] + b[..., 2] * b[..., 3] - inter
    with np.errstate(invalid="ignore", divide="ignore"):
        d[:, 5] = 1.0 - np.where(union > 0, inter / union, 0.0)               # 1 - IoU
    if misses is not None:
        g = 1.0 / (1.0 + np.asarray(misses, dtype=np.float64)[ti])
        d[:, 4:6] *= g[:, None, None]                                        # per frame
    return np.clip(d, 0.0, None)                                             # eq. 11


def match_probability(models: FeatureModels, d: np.ndarray) -> np.ndarray:
    """p(d | theta) of eq. 12 as the survival function P(D >= d) of each fitted folded
    normal mixture: sum_c w_c [Phi((mu_c - d) / s_c) + Phi((-mu_c - d) / s_c)], in [0, 1].

    Args:
        d: (..., 6, 5) differences (negative ones count as 0).
    """
    d = np.maximum(np.asarray(d, dtype=np.float64), 0.0)[..., None]
    s = ndtr((models._mu - d) / models._s) + ndtr((-models._mu - d) / models._s)
    return np.clip((models._w * s).sum(-1), 0.0, 1.0)


def part_scores(models: FeatureModels, d: np.ndarray, omega: np.ndarray,
                spread: float = 1.0) -> np.ndarray:
    """Eq. 12, p_j = sum_i omega_i p(d_ij / spread | theta_ij) (omega normalised to sum 1;
    ``spread`` is our ``model_spread``, 1 in the paper): (..., 5) from d (..., 6, 5)."""
    omega = np.asarray(omega, dtype=np.float64)
    prob = match_probability(models, np.asarray(d, dtype=np.float64) / spread)
    return np.einsum("...ij,i->...j", prob, omega / omega.sum())             # eq. 12


def global_score(pj: np.ndarray, gamma: np.ndarray) -> np.ndarray:
    """Eq. 13, p = sum_j gamma_j p_j (gamma normalised to sum 1): (...,) from (..., 5)."""
    gamma = np.asarray(gamma, dtype=np.float64)
    return np.asarray(pj) @ (gamma / gamma.sum())                            # eq. 13


# ----------------------------------------------------------------------------- PBM 4.2


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
