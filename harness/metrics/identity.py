"""Identity metrics (Ristani et al. 2016): IDTP, IDFP and IDFN of one sequence.

The identity mapping is the one-to-one pairing of gt ids with tracker ids that maximises
IDTP, the number of boxes whose pair overlaps with IoU >= the threshold (a gt box and a
tracker box of one frame); every other gt box is an IDFN, every other tracker box an IDFP.
TrackEval's ``Identity`` finds it with one Hungarian step on a dense (G + T) x (G + T) cost
matrix (G gt ids, T tracker ids), whose optimum is the largest IDTP. Here only the id pairs
that overlap at least once are kept (sparse, as sorted pair codes ``g * T + t``); they split
into connected components (a gt id and a tracker id are linked when they overlap), and the
largest IDTP is the sum of each component's maximum-weight matching, found by the Hungarian
method on that component alone. IDTP is the optimum's value, which every optimal pairing
shares, so it equals TrackEval's whatever the tie-breaking.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from occbench.metrics.frames import FramePairs


def overlap_counts(pairs: FramePairs, iou_threshold: float = 0.5
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Frames in which each gt id / tracker id pair overlaps with IoU >= the threshold.

    Returns:
        (P,) int64 gt ids, (P,) int64 tracker ids and (P,) int64 counts of the pairs that
        overlap at least once, sorted by gt id then tracker id.
    """
    ok = pairs.iou >= iou_threshold
    return count_pairs(pairs.gt_ids[pairs.row[ok]], pairs.tracker_ids[pairs.col[ok]])


def count_pairs(g: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Distinct (g, t) pairs of two (K,) int arrays, sorted, with their counts."""
    if len(g) == 0:
        z = np.zeros(0, np.int64)
        return z, z, z
    t_uniq, t_idx = np.unique(t, return_inverse=True)
    codes, counts = np.unique(g.astype(np.int64) * len(t_uniq) + t_idx, return_counts=True)
    gi, ti = np.divmod(codes, len(t_uniq))
    return gi, t_uniq[ti], counts.astype(np.int64)


def max_weight_matching(g: np.ndarray, t: np.ndarray, w: np.ndarray) -> np.ndarray:
    """A one-to-one matching of maximum total weight on a sparse bipartite graph.

    Args:
        g, t: (P,) int ids of the two sides of each edge (each pair at most once).
        w: (P,) positive edge weights.
    Returns:
        (K,) int64 indices of the matched edges, ascending.
    """
    if len(g) == 0:
        return np.zeros(0, np.int64)
    g_uniq, gi = np.unique(g, return_inverse=True)
    t_uniq, ti = np.unique(t, return_inverse=True)
    n = len(g_uniq)
    graph = coo_matrix((np.ones(len(g)), (gi, n + ti)), shape=(n + len(t_uniq),) * 2)
    _, label = connected_components(graph, directed=False)
    order = np.argsort(label[gi], kind="stable")
    bounds = np.flatnonzero(np.diff(label[gi][order])) + 1
    chosen = []
    for edges in np.split(order, bounds):
        if len(edges) == 1:
            chosen.append(edges)
            continue
        rows, r = np.unique(gi[edges], return_inverse=True)
        cols, c = np.unique(ti[edges], return_inverse=True)
        weight = np.zeros((len(rows), len(cols)))
        weight[r, c] = w[edges]
        index = np.full((len(rows), len(cols)), -1)
        index[r, c] = edges
        mr, mc = linear_sum_assignment(weight, maximize=True)
        hit = index[mr, mc]
        chosen.append(hit[hit >= 0])
    return np.sort(np.concatenate(chosen))


def identity_pairs(pairs: FramePairs, iou_threshold: float = 0.5
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The identity mapping: (K,) int64 gt ids, (K,) tracker ids and (K,) int64 IDTP of each
    pair the maximum-weight matching keeps (see the module docstring)."""
    g, t, count = overlap_counts(pairs, iou_threshold)
    kept = max_weight_matching(g, t, count)
    return g[kept], t[kept], count[kept]


def identity_counts(pairs: FramePairs, iou_threshold: float = 0.5) -> tuple[int, int, int]:
    """(IDTP, IDFP, IDFN) of one sequence (see the module docstring)."""
    idtp = int(identity_pairs(pairs, iou_threshold)[2].sum())
    return idtp, len(pairs.tracker_ids) - idtp, len(pairs.gt_ids) - idtp
