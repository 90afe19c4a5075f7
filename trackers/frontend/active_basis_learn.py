"""Learning an active-basis template: the shared sketch algorithm (Wu et al. 2010, sect. 3.3,
Algorithm 1) over aligned person patches, with the background statistics q it is scored
against (sect. 3.2) and each element's lambda (eq. 16). The template and its score:
``active_basis``."""

from __future__ import annotations

import numpy as np

from occbench.trackers.frontend.active_basis import (
    H_BINS,
    TAU,
    ActiveBasis,
    GaborBank,
    max_map,
    response_maps,
    shift_offsets,
    sigmoid,
)


def background_histogram(patches: list[np.ndarray], bank: GaborBank, size: tuple[int, int],
                         pad: int) -> np.ndarray:
    """(H_BINS,) q: histogram (probabilities) of h(r) over every position and orientation of
    background patches (sect. 3.2: pooled natural-image statistics)."""
    counts = np.zeros(H_BINS, np.float64)
    for p in patches:
        h = sigmoid(response_maps(p, bank, size, pad))
        counts += np.histogram(h, bins=H_BINS, range=(0.0, TAU))[0]
    if counts.sum() == 0:
        raise ValueError("background_histogram: no background patches")
    return counts / counts.sum()


def fit_lambda(mean_h: float, q: np.ndarray) -> tuple[float, float]:
    """(lambda, log Z(lambda)) with E_lambda[h] = mean_h (eq. 16), E and Z under q (eq. 10)."""
    centres = (np.arange(H_BINS) + 0.5) * TAU / H_BINS
    lams = np.linspace(0.0, 20.0, 4001)
    w = q[None, :] * np.exp(lams[:, None] * centres[None, :])
    z = w.sum(axis=1)
    expect = (w * centres[None, :]).sum(axis=1) / z  # increasing in lambda
    lam = float(np.interp(mean_h, expect, lams))
    log_z = float(np.log((q * np.exp(lam * centres)).sum()))
    return lam, log_z


def inhibition_masks(bank: GaborBank, eps: float) -> np.ndarray:
    """(A, A, 2k - 1, 2k - 1) bool: element (0, a) inhibits (offset, a') when the squared
    correlation of the normalised pairs, |<B_a, B_a',offset>|^2, exceeds ``eps`` (Algorithm 1)."""
    K = bank.kernels().astype(np.float64)
    A, k = bank.n_orient, bank.ksize
    out = np.zeros((A, A, 2 * k - 1, 2 * k - 1), bool)
    for a in range(A):
        za = K[a, 0] + 1j * K[a, 1]
        pa = np.pad(za, k - 1)
        for b in range(A):
            zb = K[b, 0] + 1j * K[b, 1]
            win = np.lib.stride_tricks.sliding_window_view(pa, (k, k))  # (2k-1, 2k-1, k, k)
            corr = np.abs(np.einsum("ijkl,kl->ij", win, np.conj(zb))) ** 2 / 4.0  # |za|^2 |zb|^2 = 4
            out[a, b] = corr > eps
    return out


def learn(
    patches: list[np.ndarray],
    background: list[np.ndarray],
    size: tuple[int, int] = (48, 20),
    n_elements: int = 30,
    bank: GaborBank | None = None,
    b1: int = 2,
    b2: int = 1,
    eps: float = 0.1,
) -> ActiveBasis:
    """Shared sketch (Wu et al. Algorithm 1) over aligned person patches.

    Args:
        patches: M (H + 2 pad, W + 2 pad) grey patches (``crop_patch`` of people's boxes).
        background: grey patches of the same shape for the background statistics q.
        size: (H, W) template box.
        n_elements: n, elements selected.
        bank: Gabor scale and orientations.
        b1, b2: shift (pixels along the normal) and turn (orientation steps) ranges.
        eps: correlation above which a selected element inhibits others (explaining away).
    Returns:
        the template; deterministic for the same inputs.
    """
    bank = bank or GaborBank()
    pad = b1 + bank.ksize // 2
    if not patches:
        raise ValueError("learn: no training patches")
    q = background_histogram(background, bank, size, pad)
    A = bank.n_orient
    # r_m: (M, A, H + 2 b1, W + 2 b1) normalised energies of every training image
    R = np.stack([response_maps(np.asarray(p, np.float32), bank, size, pad) for p in patches])
    hR = sigmoid(R)
    off = shift_offsets(bank, b1)
    inhibit = inhibition_masks(bank, eps)
    k1 = bank.ksize - 1
    rows, cols, orient, lam, log_z = [], [], [], [], []
    M = len(patches)
    for _ in range(n_elements):
        mx = max_map(hR, bank, b1, b2)  # (M, A, H, W) eq. 25
        total = mx.sum(axis=0)  # sum_m MAX(I_m) at (x, alpha)
        a, y, x = np.unravel_index(int(np.argmax(total)), total.shape)
        rows.append(int(y)), cols.append(int(x)), orient.append(int(a))
        # each image's own perturbed copy: the argmax over shifts and turns
        cand = [((a + t) % A, b1 + y + dy, b1 + x + dx) for dy, dx in off[a] for t in range(-b2, b2 + 1)]
        ca, cy, cx = (np.asarray(v) for v in zip(*cand))
        vals = hR[:, ca, cy, cx]  # (M, candidates)
        best = vals.argmax(axis=1)
        mean_h = float(vals[np.arange(M), best].mean())
        lm, lz = fit_lambda(mean_h, q)  # eq. 16
        lam.append(lm), log_z.append(lz)
        # explaining away: inhibit what overlaps each image's chosen copy
        Hm, Wm = hR.shape[-2:]
        for m in range(M):
            am, ym, xm = int(ca[best[m]]), int(cy[best[m]]), int(cx[best[m]])
            r0, c0 = ym - k1, xm - k1
            rs = slice(max(r0, 0), min(ym + k1 + 1, Hm))
            cs = slice(max(c0, 0), min(xm + k1 + 1, Wm))
            mrs = slice(rs.start - r0, rs.stop - r0)
            mcs = slice(cs.start - c0, cs.stop - c0)
            for b in range(A):
                sub = hR[m, b, rs, cs]
                sub[inhibit[am, b][mrs, mcs]] = 0.0
    return ActiveBasis(size, np.asarray(rows), np.asarray(cols), np.asarray(orient), np.asarray(lam),
                       np.asarray(log_z), bank, b1, b2, q)
