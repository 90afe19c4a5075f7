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


# ------------------------------------------------------------------ losses by event (issue 35)

#: the events IDF1's lost boxes are put down to (``idf1_causes``), issue 35's five first
CAUSES = ("split", "merged", "dropped_misses", "phantom", "contact", "reacquired_wrong",
          "new_id_other", "handover_other", "double_box", "found_nobody", "tentative",
          "unreported")
#: each cause as docs/generalisation.md's "Diagnosis by cause" names it (table and figure)
LABELS = {"split": "split", "merged": "merged", "dropped_misses": "dropped in misses",
          "phantom": "phantom", "contact": "contact", "reacquired_wrong": "wrong re-acq.",
          "new_id_other": "new id, other", "handover_other": "handover, other",
          "double_box": "double box", "found_nobody": "found on nobody",
          "tentative": "late confirm", "unreported": "unreported"}


def inside(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(len(a), len(b)) share of each box of ``a`` (xywh) that lies inside each box of ``b``."""
    x0 = np.maximum(a[:, None, 0], b[None, :, 0])
    y0 = np.maximum(a[:, None, 1], b[None, :, 1])
    x1 = np.minimum(a[:, None, 0] + a[:, None, 2], b[None, :, 0] + b[None, :, 2])
    y1 = np.minimum(a[:, None, 1] + a[:, None, 3], b[None, :, 1] + b[None, :, 3])
    inter = np.clip(x1 - x0, 0, None) * np.clip(y1 - y0, 0, None)
    return inter / np.maximum(a[:, None, 2] * a[:, None, 3], 1e-9)


def idf1_causes(gt: MotTable, res: MotTable, m: np.ndarray, hidden: np.ndarray,
                tentative: dict[int, np.ndarray], dets: dict[int, np.ndarray],
                run: int = 3, gap: int = 5) -> tuple[Counter, int]:
    """Every box IDF1 does not credit (IDFN and IDFP, as ``idf1_losses``) put down to the
    event that put a wrong id on the person, or to no event; and IDF1's denominator
    (2 IDTP + IDFP + IDFN), so that ``boxes / denominator`` is that cause's share of 1 - IDF1.

    A person's frames are cut into runs of the id the CLEAR matching (``match_rows``) gives
    them. A run under an id that is not the person's IDF1 id is put down to how that id came
    to the person at the run's first frame s (the previous run under id i ended at e < s):

    * the id was on another person q before: ``merged`` if a detection at s - 1 or s holds
      both (each >= half inside it), else ``contact`` if the two people's boxes overlap in
      frames s - ``run``..s (a handover at a contact), else ``reacquired_wrong`` if the id
      was unmatched for more than ``gap`` frames, else ``handover_other``;
    * the id is new to every person: ``split`` if at its first reported frame its box lies
      >= 0.6 inside the person's box while another id holds the person (that frame or the
      one before: a track born from a fragment of a tracked person); else
      ``dropped_misses`` if the person had no detection (IoU >= 0.5) for >= ``run`` frames
      just before s (the old track ended during a run of misses); else, when the person
      had no id before, the run is the person's first id (its loss is the next run's event,
      the one that took the person away from it); else ``new_id_other``;
    * the id was on this person before: its first run's cause.

    A person's uncovered box is ``tentative`` (only an unconfirmed box covers it: late
    confirmation) or ``unreported``. A reported box IDF1 counts false: on a person at
    IoU >= 0.5 that the CLEAR matching gave it, that run's cause; on a person another id
    holds, ``double_box``, or ``split`` if the id was born as a fragment of that person (so
    is a box >= 0.6 inside that person's box); on nobody, ``phantom`` (a hidden report,
    OCCLUDED) or ``found_nobody``.

    ``m``: (len(considered(gt)),) the CLEAR matching of the considered rows
    (``occbench.metrics.paper.match_rows``); ``hidden`` (len(res),) bool: OCCLUDED rows;
    ``tentative``: frame -> (K, 4) xywh unreported boxes; ``dets``: frame -> (N, 4) xywh
    detections the tracker was given.
    """
    gt = considered(gt)
    assigned = id_assignment(gt, res)
    g_rows, r_rows = gt.frame_index(), res.frame_index()
    none = np.zeros(0, dtype=np.int64)

    def detected(f: int, box: np.ndarray) -> bool:
        d = dets.get(f, np.zeros((0, 4)))
        return bool(len(d)) and iou_matrix(box[None], d).max() >= 0.5

    def box_of(f: int, person: int) -> np.ndarray | None:
        r = g_rows.get(f, none)
        r = r[gt.ids[r] == person]
        return gt.boxes[r[0]] if len(r) else None

    # who holds each person each frame, and each id's history of persons
    holder: dict[tuple[int, int], int] = {}  # (person, frame) -> id
    for r in np.flatnonzero(m >= 0):
        holder[(int(gt.ids[r]), int(gt.frames[r]))] = int(res.ids[m[r]])
    born = {int(i): int(res.frames[res.ids == i].min()) for i in np.unique(res.ids)}
    id_visits: dict[int, list[tuple[int, int]]] = {}  # id -> [(frame, person)] in frame order
    for (p, f), i in sorted(holder.items(), key=lambda kv: kv[0][1]):
        id_visits.setdefault(i, []).append((f, p))

    def fragment(i: int, p: int) -> bool:
        """Id i was born on a part of person p while another id held p."""
        b = born[i]
        bp, r = box_of(b, p), r_rows.get(b, none)
        mine = r[res.ids[r] == i]
        held = any(holder.get((p, k), i) != i for k in (b - 1, b) if (p, k) in holder)
        return bp is not None and len(mine) > 0 and held and \
            inside(res.boxes[mine[0]][None], bp[None])[0, 0] >= 0.6

    def start_cause(p: int, i: int, s: int, before: int | None, first_of: dict) -> str | None:
        """How id i came to person p at frame s (None: p's first id, no event)."""
        prev = [(f, q) for f, q in id_visits[i] if f < s]
        if prev and prev[-1][1] != p:
            f_q, q = prev[-1]
            for k in (s - 1, s):
                bp, bq, d = box_of(k, p), box_of(k, q), dets.get(k, np.zeros((0, 4)))
                if bp is not None and bq is not None and len(d):
                    both = inside(np.stack([bp, bq]), d) >= 0.5
                    if (both[0] & both[1]).any():
                        return "merged"
            for k in range(s - run, s + 1):
                bp, bq = box_of(k, p), box_of(k, q)
                if bp is not None and bq is not None and iou_matrix(bp[None], bq[None])[0, 0] > 0:
                    return "contact"
            return "reacquired_wrong" if s - f_q - 1 > gap else "handover_other"
        if prev:  # back on p
            return first_of.get((p, i))
        if fragment(i, p):
            return "split"
        missed = 0
        for k in range(s - 1, s - 1 - run, -1):
            bk = box_of(k, p)
            if bk is None or detected(k, bk):
                break
            missed += 1
        if missed >= run and before is not None:
            return "dropped_misses"
        return None if before is None else "new_id_other"

    causes: Counter = Counter()
    run_cause: dict[tuple[int, int], str | None] = {}  # (person, frame) -> cause of its run
    for p in np.unique(gt.ids).tolist():
        rows = np.flatnonzero(gt.ids == p)
        frames_p = gt.frames[rows].tolist()
        ids_p = [int(res.ids[m[r]]) if m[r] >= 0 else None for r in rows]
        runs = []  # [start index, end index (exclusive), id]
        for k, i in enumerate(ids_p):
            if i is None:
                continue
            if runs and runs[-1][2] == i and runs[-1][1] == k:
                runs[-1][1] = k + 1
            elif runs and runs[-1][2] == i and all(x is None for x in ids_p[runs[-1][1]:k]):
                runs[-1][1] = k + 1  # the same id over a gap: one run
            else:
                runs.append([k, k + 1, i])
        first_of: dict = {}
        cause_of = []
        for n, (a, _, i) in enumerate(runs):
            c = start_cause(p, i, frames_p[a], runs[n - 1][2] if n else None, first_of)
            first_of.setdefault((p, i), c)
            cause_of.append(c)
        for n in range(len(runs) - 1, -1, -1):  # a first id's loss: the event after it
            if cause_of[n] is None:
                cause_of[n] = cause_of[n + 1] if n + 1 < len(runs) else "new_id_other"
        for (a, b, i), c in zip(runs, cause_of):
            for k in range(a, b):
                run_cause[(p, frames_p[k])] = c
    credited = np.zeros(len(res), dtype=bool)
    n_fn = 0
    for f, gr in g_rows.items():
        rr = r_rows.get(f, none)
        iou = iou_matrix(gt.boxes[gr], res.boxes[rr]) if len(rr) else np.zeros((len(gr), 0))
        for a, r in enumerate(gr.tolist()):
            p = int(gt.ids[r])
            own = (iou[a] >= 0.5) & (res.ids[rr] == assigned.get(p))
            if own.any():
                credited[rr[own.nonzero()[0][0]]] = True
                continue
            n_fn += 1
            if m[r] >= 0:
                causes[run_cause[(p, f)]] += 1
            else:
                t = tentative.get(f, np.zeros((0, 4)))
                causes["tentative" if len(t) and iou_matrix(gt.boxes[r][None], t).max() >= 0.5
                       else "unreported"] += 1
    matched_to = {int(m[r]): r for r in np.flatnonzero(m >= 0)}
    for r in np.flatnonzero(~credited).tolist():
        f, i = int(res.frames[r]), int(res.ids[r])
        g = g_rows.get(f, none)
        if r in matched_to:
            causes[run_cause[(int(gt.ids[matched_to[r]]), f)]] += 1
            continue
        iou = iou_matrix(res.boxes[r][None], gt.boxes[g])[0] if len(g) else np.zeros(0)
        share = inside(res.boxes[r][None], gt.boxes[g])[0] if len(g) else np.zeros(0)
        if len(iou) and iou.max() >= 0.5:
            p = int(gt.ids[g[int(iou.argmax())]])
            causes["split" if fragment(i, p) else "double_box"] += 1
        elif len(share) and share.max() >= 0.6 and fragment(i, int(gt.ids[g[share.argmax()]])):
            causes["split"] += 1  # a fragment's box on part of the person
        else:
            causes["phantom" if hidden[r] else "found_nobody"] += 1
    n_fp = int((~credited).sum())
    idtp = len(gt) - n_fn
    return causes, 2 * idtp + n_fp + n_fn
