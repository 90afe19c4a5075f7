"""Where IDF1's misses go: each ground-truth box IDF1 does not credit, and each reported box
it counts false, put down to one cause (``bench_reacquisition.py --losses``).

IDF1 (Ristani et al. 2016) credits a ground-truth box when the one tracker id assigned to
its person over the whole sequence (a bipartite matching maximising the frames of IoU >= 0.5)
covers it at IoU >= 0.5. A box it does not credit (IDFN) is put down to the first that holds:
``other_id_found`` / ``other_id_hidden``: a reported box of another id covers it (found, or a
hidden report, OCCLUDED); ``id_elsewhere``: the person's id is reported on something else
that frame; ``tentative``: only an unconfirmed (unreported) box covers it; ``unreported``:
nothing covers it. A reported box IDF1 counts false (IDFP) is ``on_person`` (it covers some
person at IoU >= 0.5, under an id not theirs), ``hidden_nobody`` or ``found_nobody``
(misplaced or on nobody; in brackets of the printout: IoU < 0.1 with every person).
"""

from __future__ import annotations

from collections import Counter

import numpy as np
from scipy.optimize import linear_sum_assignment

from occbench.io.mot import MotTable
from occbench.metrics.paper import considered
from occbench.trackers.geometry import iou_matrix

FN_CAUSES = ("other_id_found", "other_id_hidden", "id_elsewhere", "tentative", "unreported")
FP_CAUSES = ("on_person", "hidden_nobody", "found_nobody", "nobody_empty")


def id_assignment(gt: MotTable, res: MotTable) -> dict[int, int]:
    """IDF1's person -> tracker id assignment (frames at IoU >= 0.5, maximised)."""
    g_ids, r_ids = np.unique(gt.ids), np.unique(res.ids)
    count = np.zeros((len(g_ids), len(r_ids)))
    ri = res.frame_index()
    for f, gr in gt.frame_index().items():
        rr = ri.get(f)
        if rr is None or not len(rr):
            continue
        a, b = np.nonzero(iou_matrix(gt.boxes[gr], res.boxes[rr]) >= 0.5)
        np.add.at(count, (np.searchsorted(g_ids, gt.ids[gr[a]]),
                          np.searchsorted(r_ids, res.ids[rr[b]])), 1)
    rows, cols = linear_sum_assignment(-count)
    return {int(g_ids[i]): int(r_ids[j]) for i, j in zip(rows, cols) if count[i, j] > 0}


def idf1_losses(gt: MotTable, res: MotTable, hidden: np.ndarray,
                tentative: dict[int, np.ndarray]) -> tuple[Counter, Counter]:
    """(IDFN causes, IDFP causes) of a result table (module docstring). ``hidden``
    (len(res),) bool: OCCLUDED rows; ``tentative``: frame -> (K, 4) xywh unreported boxes.
    The second counter also holds ``per_person``-keyed counts: (person, cause) -> boxes."""
    gt = considered(gt)
    assigned = id_assignment(gt, res)
    fn, fp = Counter(), Counter()
    credited = np.zeros(len(res), dtype=bool)
    ri = res.frame_index()
    for f, gr in gt.frame_index().items():
        rr = ri.get(f, np.zeros(0, dtype=np.int64))
        iou = iou_matrix(gt.boxes[gr], res.boxes[rr]) if len(rr) else np.zeros((len(gr), 0))
        for a, r in enumerate(gr.tolist()):
            mine = assigned.get(int(gt.ids[r]))
            over = iou[a] >= 0.5
            own = over & (res.ids[rr] == mine)
            if own.any():
                credited[rr[own.nonzero()[0][0]]] = True
                continue
            if over.any():
                cause = "other_id_hidden" if hidden[rr[over]].all() else "other_id_found"
            elif mine is not None and (res.ids[rr] == mine).any():
                cause = "id_elsewhere"
            else:
                t = tentative.get(f, np.zeros((0, 4)))
                cause = "tentative" if len(t) and iou_matrix(gt.boxes[r][None], t).max() >= 0.5 \
                    else "unreported"
            fn[cause] += 1
            fn[(int(gt.ids[r]), cause)] += 1
    gi = gt.frame_index()
    for r in np.flatnonzero(~credited).tolist():
        g = gi.get(int(res.frames[r]), np.zeros(0, dtype=np.int64))
        best = iou_matrix(res.boxes[r][None], gt.boxes[g]).max() if len(g) else 0.0
        if best >= 0.5:
            fp["on_person"] += 1
        else:
            fp["hidden_nobody" if hidden[r] else "found_nobody"] += 1
            fp["nobody_empty"] += best < 0.1
    return fn, fp


def losses_line(fn: Counter, fp: Counter) -> str:
    """One printable line of the summed causes (and the three persons losing most)."""
    worst = sorted(((n, k) for k, n in fn.items() if isinstance(k, tuple)), reverse=True)[:3]
    return ("IDFN " + " ".join(f"{c} {fn.get(c, 0)}" for c in FN_CAUSES)
            + "; IDFP " + " ".join(f"{c} {fp.get(c, 0)}" for c in FP_CAUSES)
            + "; worst " + ", ".join(f"person {k[0]} {k[1]} {n}" for n, k in worst))
