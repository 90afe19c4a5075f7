"""Plain transcriptions of TrackEval's metric loops, the references the fast metrics are
tested against (tests/harness/metrics)."""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from occbench.metrics.hota import ALPHAS, HotaCounts


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
                loc[a] += sum(s[r, c])  # Python's sum, in TrackEval's order
                mcs[a][g[r], t[c]] += 1
    for a in range(19):
        mc = mcs[a]
        out.ass_a[a] = np.sum(mc * mc / np.maximum(1, gc + tc - mc)) / max(1, out.tp[a])
        out.ass_re[a] = np.sum(mc * mc / np.maximum(1, gc)) / max(1, out.tp[a])
        out.ass_pr[a] = np.sum(mc * mc / np.maximum(1, tc)) / max(1, out.tp[a])
    out.loc_a = np.maximum(1e-10, loc) / np.maximum(1e-10, out.tp)
    return out


def reference_match_rows(gt, res, iou_threshold: float = 0.5) -> np.ndarray:
    """``paper.match_rows`` as a loop over frames and GT rows (dense IoU per frame)."""
    from occbench.trackers.common.assignment import assign
    from occbench.trackers.geometry import iou_matrix

    out = np.full(len(gt), -1, dtype=np.int64)
    if len(gt) == 0 or len(res) == 0:
        return out
    res_index = res.frame_index()
    previous: dict[int, int] = {}
    for frame, g_rows in gt.frame_index().items():
        r_rows = res_index.get(frame)
        if r_rows is None:
            continue
        iou = iou_matrix(gt.boxes[g_rows], res.boxes[r_rows])
        iou = np.where(iou >= iou_threshold, iou, 0.0)
        g_ids, r_ids = gt.ids[g_rows], res.ids[r_rows]
        kept = np.zeros(len(g_rows), dtype=bool)
        taken = np.zeros(len(r_rows), dtype=bool)
        for i, gid in enumerate(g_ids):
            rid = previous.get(int(gid))
            if rid is None:
                continue
            j = np.flatnonzero((r_ids == rid) & ~taken)
            if len(j) and iou[i, j[0]] > 0:
                kept[i], taken[j[0]] = True, True
                out[g_rows[i]] = r_rows[j[0]]
        free_g, free_r = np.flatnonzero(~kept), np.flatnonzero(~taken)
        if len(free_g) and len(free_r):
            cost = 1.0 - iou[np.ix_(free_g, free_r)]
            cost[iou[np.ix_(free_g, free_r)] <= 0] = np.inf
            pairs, _, _ = assign(cost, 1.0 - iou_threshold + 1e-12)
            out[g_rows[free_g[pairs[:, 0]]]] = r_rows[free_r[pairs[:, 1]]]
        hit = out[g_rows] >= 0
        previous.update(zip(g_ids[hit].tolist(), res.ids[out[g_rows[hit]]].tolist()))
    return out


def reference_responses(gt, res, match: np.ndarray, inside: float = 0.5):
    """``paper.responses`` frame by frame on the dense cover matrix."""
    from occbench.trackers.geometry import overlap_ratio_matrix

    g_rows = [np.flatnonzero(match >= 0)]
    r_rows = [match[g_rows[0]]]
    used = np.zeros(len(res), dtype=bool)
    used[r_rows[0]] = True
    gt_index = gt.frame_index()
    for frame, rr in res.frame_index().items():
        rr = rr[~used[rr]]
        gr = gt_index.get(frame)
        if len(rr) == 0 or gr is None:
            continue
        cover = overlap_ratio_matrix(res.boxes[rr], gt.boxes[gr])
        best = np.argmax(cover, axis=1)
        ok = cover[np.arange(len(rr)), best] >= inside
        g_rows.append(gr[best[ok]])
        r_rows.append(rr[ok])
    g, r = np.concatenate(g_rows), np.concatenate(r_rows)
    order = np.lexsort((r, g))
    return g[order], r[order]


def reference_under(gt, res, match: np.ndarray) -> int:
    """PBM's under-segmented trajectories, trajectory by trajectory."""
    hit = match >= 0
    m_g, m_f, m_r = gt.ids[hit], gt.frames[hit], res.ids[match[hit]]
    under = 0
    for g in np.unique(m_g):
        first = np.flatnonzero(m_g == g)[np.argmin(m_f[m_g == g])]
        under += bool(((m_r == m_r[first]) & (m_f < m_f[first]) & (m_g != g)).any())
    return under
