"""Plain transcriptions of TrackEval's metric loops, the references the fast metrics are
tested against (tests/harness/metrics)."""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from harness.metrics.hota import ALPHAS, HotaCounts


def reference_hota(gt_ids, tr_ids, sims) -> HotaCounts:
    """TrackEval's HOTA.eval_sequence transcribed loop by loop (dense, per alpha)."""
    eps = np.finfo(float).eps
    gu = np.unique(np.concatenate(gt_ids))
    tu = np.unique(np.concatenate(tr_ids))
    gmap = {int(v): k for k, v in enumerate(gu)}
    tmap = {int(v): k for k, v in enumerate(tu)}
    g_t = [np.array([gmap[int(v)] for v in g], dtype=int) for g in gt_ids]
    t_t = [np.array([tmap[int(v)] for v in t], dtype=int) for t in tr_ids]
    pot = np.zeros((len(gu), len(tu)))
    gc = np.zeros((len(gu), 1))
    tc = np.zeros((1, len(tu)))
    for g, t, s in zip(g_t, t_t, sims):
        den = s.sum(0)[np.newaxis, :] + s.sum(1)[:, np.newaxis] - s
        si = np.zeros_like(s)
        mask = den > 0 + eps
        si[mask] = s[mask] / den[mask]
        pot[g[:, np.newaxis], t[np.newaxis, :]] += si
        gc[g] += 1
        tc[0, t] += 1
    gas = pot / (gc + tc - pot)
    out = HotaCounts()
    loc = np.zeros(19)
    mcs = [np.zeros_like(pot) for _ in ALPHAS]
    for g, t, s in zip(g_t, t_t, sims):
        if len(g) == 0:
            out.fp += len(t)
            continue
        if len(t) == 0:
            out.fn += len(g)
            continue
        rows, cols = linear_sum_assignment(-(gas[g[:, np.newaxis], t[np.newaxis, :]] * s))
        for a, alpha in enumerate(ALPHAS):
            ok = s[rows, cols] >= alpha - eps
            r, c = rows[ok], cols[ok]
            out.tp[a] += len(r)
            out.fn[a] += len(g) - len(r)
            out.fp[a] += len(t) - len(r)
            if len(r):
                loc[a] += s[r, c].sum()
                mcs[a][g[r], t[c]] += 1
    for a in range(19):
        mc = mcs[a]
        out.ass_a[a] = np.sum(mc * mc / np.maximum(1, gc + tc - mc)) / max(1, out.tp[a])
        out.ass_re[a] = np.sum(mc * mc / np.maximum(1, gc)) / max(1, out.tp[a])
        out.ass_pr[a] = np.sum(mc * mc / np.maximum(1, tc)) / max(1, out.tp[a])
    out.loc_a = np.maximum(1e-10, loc) / np.maximum(1e-10, out.tp)
    return out
