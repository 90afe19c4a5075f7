"""PBM 4.1, eq. 11: the feature differences d_ij = |f_ij - F_ij| of a candidate's parts
against a target's parts model, in plain numpy (the definition: ``differences``) and
compiled (``_pair_differences``, per pair; ``_differences_kernel``, the pairs of a frame),
held equal to rtol 1e-9 by ``tests/trackers/layered/test_equations.py``.

Grouped arguments are tuples: a feature set is ``(parts, area, perimeter, hsv, xyz,
centroid, height)`` (``PartFeatures``' arrays).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numba
import numpy as np

from occbench.trackers.layered import kernel_cache  # noqa: F401 (before any kernel: one stamp for all)
from occbench.trackers.layered.sampling_kernels import trailing_zeros

if TYPE_CHECKING:  # annotations only
    from occbench.trackers.layered.parts import PartFeatures


# ----------------------------------------------------------------------------- eq. 11, plain numpy


def differences(model: PartFeatures, cand: PartFeatures, ti: np.ndarray, n: np.ndarray,
                misses: np.ndarray | None = None, apart: bool = False) -> np.ndarray:
    """Eq. 11, d_ij = |f_ij - F_ij|, for the pairs (target ti[k], candidate n[k]).

    Features i in ``parts.FEATURES`` order: area and perimeter (absolute differences),
    HSV and XYZ histograms (1 - Bhattacharyya coefficient; 1 when the candidate's part
    has no foreground), displacement of the part centroid over the target's height, and
    1 - IoU of the part rectangles. After a gap of ``misses`` frames the last two are
    divided by 1 + misses (our reading: per-frame differences; ``adaptations.gap_division``),
    except, when ``apart``, the overlap of a pair none of whose parts overlap (every IoU 0:
    1 - IoU = 1 whatever the gap; ``adaptations.apart_undivided``).

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
        iou = np.where(union > 0, inter / union, 0.0)
    d[:, 5] = 1.0 - iou                                                      # 1 - IoU
    if misses is not None:
        g = 1.0 / (1.0 + np.asarray(misses, dtype=np.float64)[ti])
        d[:, 4:6] *= g[:, None, None]                                        # per frame
        if apart:
            d[(iou == 0).all(axis=1), 5] = 1.0                               # parts apart: whole
    return np.clip(d, 0.0, None)                                             # eq. 11


# ----------------------------------------------------------------------------- eq. 11, compiled


@numba.njit(cache=True, inline="always")
def _rho(a: np.ndarray, b: np.ndarray, t: int, n: int, j: int, idx: np.ndarray) -> float:
    """Bhattacharyya coefficient rho = sum_u sqrt(a[t, j, u] b[n, j, u]) of two histograms
    (eq. 11's colour terms), summed in u order over the bins listed in ``idx`` (scratch, at
    least as long as the histograms): those where b is not 0 or a not finite. A bin where b
    is 0 and a finite adds +-0, which leaves the sum as it was (it starts at +0), so the
    sum has the bits of the sum over every bin (``rho_bins``, tested against it) at the
    cost of the few bins a candidate's part occupies."""
    cnt = 0
    for u in range(b.shape[2]):  # the list, without branches
        idx[cnt] = u
        cnt += (b[n, j, u] != 0.0) | (not abs(a[t, j, u]) < math.inf)
    tot = 0.0
    for q in range(cnt):
        u = idx[q]
        tot += math.sqrt(a[t, j, u] * b[n, j, u])
    return tot


@numba.njit(cache=True)
def rho_bins(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> None:
    """``_rho`` of every pair of rows a[t, j] and b[t, j] of two (T, J, U) arrays into
    out (T, J), for its test against the plain sum over every bin."""
    idx = np.empty(b.shape[2], np.int64)
    for t in range(a.shape[0]):
        for j in range(a.shape[1]):
            out[t, j] = _rho(a, b, t, t, j, idx)


@numba.njit(cache=True, inline="always")
def _rho_listed(a: np.ndarray, b: np.ndarray, t: int, n: int, j: int, bits: np.uint64) -> float:
    """``_rho`` when a[t, j] is finite and the bins where b[n, j] is not 0 are the set bits
    of ``bits`` (bin u: bit u): the same terms in the same (u) order, without the scan."""
    tot = 0.0
    while bits != 0:
        u = trailing_zeros(bits)
        tot += math.sqrt(a[t, j, u] * b[n, j, u])
        bits &= bits - np.uint64(1)
    return tot


@numba.njit(cache=True, inline="always")
def _pair_differences(m: tuple, c: tuple, t: int, n: int, gap: tuple, d: np.ndarray, k: int,
                      idx: np.ndarray, listed: tuple) -> None:
    """Eq. 11, d_ij = |f_ij - F_ij| (``differences``), of model t of ``m`` against
    candidate n of ``c`` into d[k] (6, 5) (``idx``: ``_rho``'s scratch).

    Per part j: |area|, |perimeter|, 1 - rho of HSV and XYZ (1 when the candidate part has
    no foreground), |c_n - C_t| / max(H_t, 1) and 1 - IoU (IoU 0 when union <= 0), the
    last two times g = 1 / (1 + misses[t]) (``gap``: (misses (T,) float64, apart)); when
    ``apart`` and no part's IoU is above 0, the overlaps are 1, undivided; all clipped at 0.

    ``listed``: (use, occupied (2, 5) uint64, finite (T, 2, 5) bool): when ``use``, rho of a
    model histogram that is finite (``finite[t]``) is summed over the candidate's occupied
    bins (``_rho_listed``; ``occupied`` as ``_box_scratch``'s) instead of ``_rho``'s scan.
    """
    m_parts, m_area, m_perimeter, m_hsv, m_xyz, m_centroid, m_height = m
    c_parts, c_area, c_perimeter, c_hsv, c_xyz, c_centroid, _ = c
    use_lists, occupied, finite = listed
    misses, apart = gap
    g = 1.0 / (1.0 + misses[t])
    touch = False
    hgt = max(m_height[t], 1.0)
    for j in range(m_area.shape[1]):
        d[k, 0, j] = abs(m_area[t, j] - c_area[n, j])
        d[k, 1, j] = abs(m_perimeter[t, j] - c_perimeter[n, j])
        if c_area[n, j] <= 0:  # an empty histogram (part without foreground) never matches
            d[k, 2, j] = 1.0
            d[k, 3, j] = 1.0
        elif use_lists and finite[t, 0, j] and finite[t, 1, j]:
            d[k, 2, j] = 1.0 - _rho_listed(m_hsv, c_hsv, t, n, j, occupied[0, j])
            d[k, 3, j] = 1.0 - _rho_listed(m_xyz, c_xyz, t, n, j, occupied[1, j])
        else:
            d[k, 2, j] = 1.0 - _rho(m_hsv, c_hsv, t, n, j, idx)
            d[k, 3, j] = 1.0 - _rho(m_xyz, c_xyz, t, n, j, idx)
        dx = c_centroid[n, j, 0] - m_centroid[t, j, 0]
        dy = c_centroid[n, j, 1] - m_centroid[t, j, 1]
        d[k, 4, j] = math.sqrt(dx * dx + dy * dy) / hgt * g
        ax, ay, aw, ah = m_parts[t, j, 0], m_parts[t, j, 1], m_parts[t, j, 2], m_parts[t, j, 3]
        bx, by, bw, bh = c_parts[n, j, 0], c_parts[n, j, 1], c_parts[n, j, 2], c_parts[n, j, 3]
        iw = max(min(ax + aw, bx + bw) - max(ax, bx), 0.0)
        ih = max(min(ay + ah, by + bh) - max(ay, by), 0.0)
        inter = iw * ih
        union = aw * ah + bw * bh - inter
        iou = inter / union if union > 0 else 0.0
        d[k, 5, j] = (1.0 - iou) * g
        touch |= iou != 0.0
        for i in range(d.shape[1]):
            if d[k, i, j] < 0.0:  # np.clip(d, 0, None)  # noqa: PLR1730
                d[k, i, j] = 0.0
    if apart and not touch:  # every part apart from the candidate's: 1 - IoU = 1, undivided
        for j in range(m_area.shape[1]):
            d[k, 5, j] = 1.0


_NO_LISTS = (False, np.zeros((2, 5), np.uint64), np.zeros((1, 2, 5), np.bool_))
"""``_pair_differences``' ``listed`` when the candidates' occupied bins are not known."""


@numba.njit(cache=True)
def _differences_kernel(m: tuple, c: tuple, ti: np.ndarray, n: np.ndarray, gap: tuple,
                        out: np.ndarray) -> None:
    """Eq. 11 (``_pair_differences``) of the pairs (ti[k], n[k]) into out (K, 6, 5);
    gap (misses (T,) float64 per target, g = 1 / (1 + misses); apart)."""
    for k in range(ti.shape[0]):
        if not (0 <= ti[k] < m[1].shape[0] and 0 <= n[k] < c[1].shape[0]):
            raise IndexError("selected pair index out of range")
    idx = np.empty(max(m[3].shape[2], m[4].shape[2]), np.int64)
    for k in range(ti.shape[0]):
        _pair_differences(m, c, ti[k], n[k], gap, out, k, idx, _NO_LISTS)
