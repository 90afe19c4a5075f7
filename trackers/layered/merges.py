"""PBM 3.1's larger region: a merge of the targets it holds, or one of them grown.

A candidate larger than a target's prediction by more than ``search.occlusion_threshold``
is, in PBM 3.1, a merge: the target is searched for inside it (eqs. 9-10) and its box
carved from the prediction. ``adaptations.lone_growth`` reads a region holding no other
live target as the target grown. ``FoundElsewhere`` (``adaptations.merge_found_elsewhere``)
asks the frame's assignment too: a detection whose other holders all took other
candidates, unoccluded, holds none of them, so the target it was searched in is that target
grown. With ``recent_holder`` (``adaptations.merge_recent_holder``) it also reads the
opposite case: a detection taken as a merge by a target missed longer than a holder that
took nothing is that holder grown. Kinds are ``occlusion_kinds``' (T, N) array (+1
larger, -1 smaller, 0 neither).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Callable

import numpy as np

from occbench.trackers.geometry import overlap_ratio_matrix

if TYPE_CHECKING:  # annotations only
    from occbench.trackers.layered.frame_blocks import Association
    from occbench.trackers.layered.gating import Carved, Gated
    from occbench.trackers.layered.search import Candidates
    from occbench.trackers.layered.selection import FrameScores
    from occbench.trackers.layered.targets import Targets

Block = Callable[..., "Association"]
PairScores = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]
Search = Callable[[], "Carved | None"]


def scored(scores: FrameScores, pairs: Gated, pj: np.ndarray, p: np.ndarray,
           found: Carved | None, rows: np.ndarray | None = None) -> None:
    """Into ``scores``: the unoccluded pairs' p_j and p (eqs. 11-13) and the searched pairs'
    carved candidates ``found`` (PBM 3.1) where kept; ``rows`` (P,): each searched pair's row
    of ``found`` (None: its own)."""
    scores.pj[pairs.ti, pairs.n], scores.S[pairs.ti, pairs.n] = pj, p
    if found is not None:
        rows = np.arange(len(found.kept)) if rows is None else rows
        kept = found.kept[rows]
        ti_s, n_s = pairs.search_ti[kept], pairs.search_n[kept]
        scores.S[ti_s, n_s] = found.p[rows][kept]
        scores.hyp[ti_s, n_s] = rows[kept]
        scores.pj_h, scores.feats_h, scores.k_h, scores.dof_h = found.pj, found.feats, found.k, found.dof


class AllHolders:
    """PBM 3.1 (with ``lone_growth``) as it stands: a larger region holding another live
    target is a merge, whatever that target takes this frame; one assignment per frame."""

    matched = None  # no template matches kept (one pass)

    def apply(self, kinds: np.ndarray, cand: Candidates, targets: Targets, live: np.ndarray,
              overlap: float) -> None:
        """Leaves ``kinds`` as the size test set them."""

    def score(self, scores: FrameScores, pairs: Gated, pair_scores: PairScores,
              search: Search) -> None:
        """``scored`` of ``pair_scores`` (eqs. 11-13) and ``search`` (PBM 3.1)."""
        scored(scores, pairs, *pair_scores(pairs.ti, pairs.n),
               search() if len(pairs.search_ti) else None)

    def strike(self, S: np.ndarray) -> None:
        """Leaves the scores as they are."""

    def associate(self, block: Block, frame: np.ndarray, targets: Targets, cand: Candidates,
                  *rest) -> Association:
        """``block(frame, targets, cand, *rest)``, once."""
        return block(frame, targets, cand, *rest)


class FoundElsewhere:
    """``merge_found_elsewhere``: the frame (or block) is associated as PBM 3.1 reads it;
    where a target t took a detection n as a merge (searched inside it: n larger than t's
    prediction, one head) while every other live target n holds (``overlap`` of its box
    inside n's region, as ``lone_growth`` counts holders) took another candidate as
    measured (unoccluded), the association is run again with those pairs (t, n) as t grown
    (kind 0, scored as measured), as ``lone_growth`` would have read n had those targets not
    stood there. Blobs and regions with several heads keep PBM 3.1's merge (their pixels
    may be two people whatever the detections say).

    Why (docs/generalisation.md, "pbm, eighth round"): on cav1-150 gt seed 1001 frame 35 the
    walking person 5's detection (22 x 63; his target's prediction 13 x 63) also holds the
    box of person 2's target, which takes person 2's own detection that frame; person 5's
    target is searched inside it as a merge and keeps a carved 14 px box that no longer
    follows him, and three frames later person 2's target takes his detection.

    ``recent_holder`` (``adaptations.merge_recent_holder``; ``found_elsewhere`` False: this
    reading alone, ``merge_found_elsewhere`` off): where a target u took a
    detection n as a merge while exactly one other live target t holding n, found more
    recently than u (fewer misses), took nothing, n is t's region: the frame is associated
    again with (t, n) as t grown (kind 0) and u's pair (u, n) struck (a region read as one
    target grown is no merge, PBM 3.1's search of u inside it stands on nothing).

    Why (docs/generalisation.md, "pbm, ninth round"): on ecp1-180 gt seed 1000 frame 161
    person 4, rising through the stairwell, is seen whole (29 x 99; his target 6, found the
    frame before on his 47 px top, predicts 25 x 39); the detection also holds the last box
    of person 3's target 4, unfound two frames (person 3 sank out of view there). Target 6's
    head-anchored box falls outside its gate (the head rose 52 px), target 4's search scores
    0.374 and takes him, target 6 is left unfound and person 4 ends with person 3's id."""

    def __init__(self, recent_holder: bool = False, found_elsewhere: bool = True) -> None:
        self.recent_holder, self.found_elsewhere = recent_holder, found_elsewhere
        self._grown: np.ndarray | None = None  # (G, 2) pairs taken as grown in the second pass
        self._struck: np.ndarray | None = None  # (S, 2) pairs not scored in the second pass
        self._first: tuple[np.ndarray, np.ndarray, float] | None = None  # kinds, live, overlap
        self._scored: tuple | None = None  # the first pass's pairs, p_j, p, search, its DOF
        self.matched: dict = {}  # the block's template matches (PBM 4.1), kept over its passes

    def score(self, scores: FrameScores, pairs: Gated, pair_scores: PairScores,
              search: Search) -> None:
        """``AllHolders.score``; the second pass takes each pair's scores from the first
        (a pair's p_j, p and search are its own: eqs. 9-13 of its target and candidate),
        scoring only the pairs the first did not score alike (a grown pair as measured)."""
        if self._grown is None:
            pj, p = pair_scores(pairs.ti, pairs.n)
            found = search() if len(pairs.search_ti) else None
            scored(scores, pairs, pj, p, found)
            self._scored = (pairs, pj, p, found, None if found is None else found.dof.copy())
            return
        first, pj1, p1, found, dof = self._scored  # dof: before the pruning re-anchored it
        T, N = scores.S.shape
        at = np.full((T, N), -1, dtype=np.intp)
        at[first.ti, first.n] = np.arange(len(first.ti))
        q = at[pairs.ti, pairs.n]
        new = q < 0
        pj, p = np.empty((len(q),) + pj1.shape[1:]), np.empty(len(q))
        pj[~new], p[~new] = pj1[q[~new]], p1[q[~new]]
        if new.any():
            pj[new], p[new] = pair_scores(pairs.ti[new], pairs.n[new])
        at.fill(-1)
        at[first.search_ti, first.search_n] = np.arange(len(first.search_ti))
        rows = at[pairs.search_ti, pairs.search_n]
        if not len(pairs.search_ti):
            found, rows = None, None
        elif found is None or (rows < 0).any() or (first.kind[rows] != pairs.kind).any():
            found, rows = search(), None  # a pair the first pass did not search alike
        else:
            found = found._replace(dof=dof)
        scored(scores, pairs, pj, p, found, rows)

    def apply(self, kinds: np.ndarray, cand: Candidates, targets: Targets, live: np.ndarray,
              overlap: float) -> None:
        """Second pass: the grown pairs' kinds set to 0 in place. First pass: keeps
        ``kinds`` (the array the occlusion test goes on to change in place) to read the
        merges after the assignment."""
        if self._grown is not None:
            kinds[self._grown[:, 0], self._grown[:, 1]] = 0
        else:
            self._first = (kinds, live.copy(), overlap)

    def strike(self, S: np.ndarray) -> None:
        """Second pass: the struck pairs' scores set to -inf in place (no candidate of
        theirs)."""
        if self._struck is not None and len(self._struck):
            S[self._struck[:, 0], self._struck[:, 1]] = -np.inf

    def associate(self, block: Block, frame: np.ndarray, targets: Targets, cand: Candidates,
                  *rest) -> Association:
        """``block`` once, and again with the grown (and struck) pairs when there are any."""
        self._grown, self._struck, self._first, self._scored = None, None, None, None
        self.matched.clear()
        found = block(frame, targets, cand, *rest)
        merges = self._holders(found, targets, cand)  # read by both rules, made once
        grown = (self._grown_of(merges) if self.found_elsewhere
                 else np.empty((0, 2), dtype=np.intp))
        struck = np.empty((0, 2), dtype=np.intp)
        if self.recent_holder:
            held, struck = self._recent_of(merges, targets)
            grown = np.concatenate([grown, held])
        if len(grown):
            self._grown, self._struck = grown, struck
            try:
                found = block(frame, targets, cand, *rest)
            finally:
                self._grown, self._struck = None, None
        self._first, self._scored = None, None
        self.matched.clear()
        return found

    def _merges(self, found: Association, cand: Candidates) -> list[tuple[int, int]]:
        """The first pass's (target, candidate) matches taken as a merge: searched inside a
        candidate larger than the target's prediction (kind +1), neither a blob nor a region
        of several heads (those keep PBM 3.1's merge)."""
        kinds = self._first[0]
        return [(t, n) for (t, n), carved in zip(found.matches.tolist(),
                                                 found.chosen.occluded.tolist())
                if carved and kinds[t, n] > 0 and not cand.blob[n]
                and cand.heads_in_region[n] <= 1]

    def _holders(self, found: Association, targets: Targets, cand: Candidates
                 ) -> tuple[list[tuple[int, int]], np.ndarray, np.ndarray] | None:
        """The first pass's merges (``_merges``, M (target, candidate) pairs), the candidate
        each target took (-1 none, -2 as a merge) and which live targets' boxes each merge's
        region holds (T, M: column m for merge m's candidate); None without a merge."""
        if self._first is None or found.chosen is None:
            return None
        merges = self._merges(found, cand)
        if not merges:
            return None
        _, live, overlap = self._first
        matches, occluded = found.matches, found.chosen.occluded
        taken = np.full(len(targets), -1, dtype=np.intp)
        taken[matches[:, 0]] = np.where(occluded, -2, matches[:, 1])
        regions = cand.region[[n for _, n in merges]]
        holds = overlap_ratio_matrix(targets.dof[:, [0, 1, 4, 5]], regions) >= overlap
        return merges, taken, holds & live[:, None]

    def recent_pairs(self, found: Association, targets: Targets, cand: Candidates
                     ) -> tuple[np.ndarray, np.ndarray]:
        """(t, n) pairs of the first pass's merges to read as the recent holder t grown,
        and the (u, n) pairs to strike (``recent_holder``), each (G, 2)."""
        return self._recent_of(self._holders(found, targets, cand), targets)

    def grown_pairs(self, found: Association, targets: Targets, cand: Candidates) -> np.ndarray:
        """(G, 2) (target, candidate) matches of the first pass that are a target grown."""
        return self._grown_of(self._holders(found, targets, cand))

    @staticmethod
    def _recent_of(merges: tuple | None, targets: Targets) -> tuple[np.ndarray, np.ndarray]:
        """``recent_pairs`` of the first pass's ``_holders``."""
        held, struck = [], []
        if merges is not None:
            pairs, taken, holds = merges
            for m, (u, n) in enumerate(pairs):
                recent = targets.misses < targets.misses[u]
                left = np.flatnonzero(holds[:, m] & (taken == -1) & recent)
                if len(left) == 1:
                    held.append((int(left[0]), n))
                    struck.append((u, n))
        return (np.array(held, dtype=np.intp).reshape(-1, 2),
                np.array(struck, dtype=np.intp).reshape(-1, 2))

    @staticmethod
    def _grown_of(merges: tuple | None) -> np.ndarray:
        """``grown_pairs`` of the first pass's ``_holders`` (taken -2: as a merge)."""
        grown = []
        if merges is not None:
            pairs, taken, holds = merges
            for m, (t, n) in enumerate(pairs):
                others = np.flatnonzero(holds[:, m])
                others = others[others != t]
                if len(others) and np.all((taken[others] >= 0) & (taken[others] != n)):
                    grown.append((t, n))
        return np.array(grown, dtype=np.intp).reshape(-1, 2)
