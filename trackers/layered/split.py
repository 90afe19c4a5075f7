"""PBM 2.1, eqs. 1-2: the centroid ratios alpha and beta, the five parts they split a
box into, and the DOF they give under occlusion, in plain numpy (the definitions:
``centroid_ratios``, ``part_boxes``, ``dof_from_head``) and compiled per box (the forms
the kernels call: ``_centroid_ratios``, ``_part_rects``, ``_dof_from_head``), held equal
to rtol 1e-9 by ``tests/trackers/layered/test_equations.py``.

A global model (DOF) is (xtl, ytl, xc, yc, w, h); boxes are xywh, 0-based, top-left corner.
"""

from __future__ import annotations

import numba
import numpy as np

from occbench.trackers.layered import kernel_cache  # noqa: F401 (before any kernel: one stamp for all)

HEAD_FRACTION = 1.0 / 7.0
"""The head occupies one seventh of the person height (PBM 2.1)."""


# ----------------------------------------------------------------------------- PBM 2.1, plain numpy


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


# ----------------------------------------------------------------------------- PBM 2.1, compiled


@numba.njit(cache=True, inline="always")
def _centroid_ratios(x: float, y: float, w: float, h: float, xc: float, yc: float
                     ) -> tuple[float, float]:
    """Eqs. 1-2 (``centroid_ratios``): alpha = (xc - xtl) / w and
    beta = (yc - ytl - h/7) / (h - h/7) of a centroid in an xywh box, each clipped to
    [0.05, 0.95]."""
    w, h = max(w, 1e-9), max(h, 1e-9)
    alpha = (xc - x) / w                                                      # eq. 1
    beta = (yc - y - HEAD_FRACTION * h) / (h - HEAD_FRACTION * h)             # eq. 2
    return min(max(alpha, 0.05), 0.95), min(max(beta, 0.05), 0.95)


@numba.njit(cache=True, inline="always")
def _part_rects(x: float, y: float, w: float, h: float, alpha: float, beta: float,
                p: np.ndarray) -> None:
    """The five part rectangles (PBM 2.1, Fig. 2; ``part_boxes``) of an xywh box
    split at its centroid xc = x + alpha w (eq. 1), yc = y + h/7 + beta (h - h/7) (eq. 2),
    into p (5, 4) xywh: head, left/right torso-arm, left/right leg."""
    hh = HEAD_FRACTION * h
    xs = x + alpha * w                                                        # eq. 1
    ys = y + hh + beta * (h - hh)                                             # eq. 2
    top, left_w, right_w = y + hh, xs - x, x + w - xs
    torso_h, leg_h = ys - y - hh, y + h - ys
    p[0, 0], p[0, 1], p[0, 2], p[0, 3] = x, y, w, hh
    p[1, 0], p[1, 1], p[1, 2], p[1, 3] = x, top, left_w, torso_h
    p[2, 0], p[2, 1], p[2, 2], p[2, 3] = xs, top, right_w, torso_h
    p[3, 0], p[3, 1], p[3, 2], p[3, 3] = x, ys, left_w, leg_h
    p[4, 0], p[4, 1], p[4, 2], p[4, 3] = xs, ys, right_w, leg_h


@numba.njit(cache=True, inline="always")
def _dof_from_head(hx: float, hy: float, w: float, h: float, alpha: float, beta: float,
                   out: np.ndarray) -> None:
    """The global DOF under occlusion (PBM 2.1; ``dof_from_head``) into out (6,):
    xc, ytl from the head top, xtl from eq. 1 and yc from eq. 2 with the previous
    frame's alpha, beta."""
    out[0] = hx - alpha * w                                                   # eq. 1
    out[1], out[2] = hy, hx
    out[3] = hy + HEAD_FRACTION * h + beta * (h - HEAD_FRACTION * h)          # eq. 2
    out[4], out[5] = w, h
