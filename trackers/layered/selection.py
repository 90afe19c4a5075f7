"""Selection of each target's candidate (PBM 4 steps 4-5, 4.1): one frame's scores, and
multiple-response pruning by the head template.

Boxes are xywh and heads (x top-centre, y top, width), float64 pixels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.association import ambiguous, ambiguous_rows
from occbench.trackers.layered.params import MatchParams, PruneParams
from occbench.trackers.layered.parts import N_PARTS, PartFeatures
from occbench.trackers.layered.search import Candidates
from occbench.trackers.layered.targets import Targets, dof_from_head
from occbench.trackers.layered.template_match import template_matcher


def _norms(v: np.ndarray) -> np.ndarray:
    """(K,) Euclidean norms of the rows of v (K, 2), each equal bit for bit to
    ``np.linalg.norm(v[k])`` (the same dot product, one per row)."""
    return np.sqrt(np.vecdot(v, v))


@dataclass
class FrameScores:
    """One frame's association of T targets with N candidates.

    Attributes:
        S: (T, N) global scores p (eq. 13); -inf where n is no candidate of t.
        pj: (T, N, 5) part scores p_j (eq. 12) of the unoccluded pairs.
        hyp: (T, N) row of an occluded pair's best searched box in the ``*_h`` arrays, -1
            for an unoccluded pair.
        feats_h: features of the searched boxes (None: none). pj_h: (P, 5) p_j,
            k_h: (P,) each pair's best box in ``feats_h``, dof_h: (P, 6) its global model.
    """

    S: np.ndarray
    pj: np.ndarray
    hyp: np.ndarray
    feats_h: PartFeatures | None = None
    pj_h: np.ndarray | None = None
    k_h: np.ndarray | None = None
    dof_h: np.ndarray | None = None

    @classmethod
    def empty(cls, T: int, N: int) -> FrameScores:
        """No pair scored yet."""
        S = np.empty((T, N))
        S.fill(-np.inf)
        hyp = np.empty((T, N), dtype=np.intp)
        hyp.fill(-1)
        return cls(S, np.zeros((T, N, N_PARTS)), hyp, None, np.zeros((0, N_PARTS)),
                   np.zeros(0, np.intp), np.zeros((0, 6)))


class OwnRow:
    """PBM 4.1 as written: a target's responses are the candidates along its own row of S,
    whatever the other targets score them."""

    def claimed(self, S: np.ndarray, match_threshold: float) -> None:
        return None


class RivalClaims:
    """``rival_claims``: a candidate another target claims (its best, at p >= the match
    threshold, eq. 13, scored higher than this target scores it) is that target's response,
    not this one's. Where the pruning of an ambiguous target would keep its best without
    its head template (the template stale, or the near candidates' heads within
    ``duplicate_radius``: "one response"), it passes over the claimed candidates and leaves
    them to the one-to-one assignment (two people one in front of the other give two
    detections whose heads nearly coincide; they are not one response of each target).
    Where the template decides, it still decides."""

    def claimed(self, S: np.ndarray, match_threshold: float) -> np.ndarray | None:
        """(T, N) bool: candidate n is claimed against target t, read before any row is
        pruned; None when no target claims any."""
        if not S.size:
            return None
        best = np.argmax(S, axis=1)
        rows = np.flatnonzero(S[np.arange(len(S)), best] >= match_threshold)
        if not len(rows):
            return None
        out = np.zeros(S.shape, dtype=bool)
        for r in rows.tolist():
            n = int(best[r])
            out[:, n] |= S[:, n] < S[r, n]  # never against r itself
        return out


class AtThreshold:
    """A weak candidate (p in [weak_threshold, match_threshold)) the head template validates
    (PBM 4.1) enters the assignment at ``match_threshold``: two targets so validated for one
    candidate tie, whatever their own scores."""

    def value(self, p: float, match_threshold: float) -> float:
        return max(p, match_threshold)


class RankedAtThreshold:
    """``weak_ranked``: as ``AtThreshold``, plus ``RANK`` x its own score p (eq. 13), so that
    two targets validated for one candidate are ranked by their scores (the assignment, on
    1 - p, gives it to the one that scores it higher), still below every candidate matched
    above the threshold by more than ``RANK``."""

    RANK = 1e-6

    def value(self, p: float, match_threshold: float) -> float:
        return p if p >= match_threshold else match_threshold + self.RANK * p


class OneResponse:
    """``duplicate_radius`` as it stands: ambiguous candidates whose heads coincide are one
    response of the target, whatever they are."""

    def one_response(self, cand: Candidates, cands: np.ndarray) -> bool:
        return True


class DetectionsApart:
    """``distinct_detections``: coinciding heads are one response only when a blob's head is
    among them; two detections (the detector's boxes, kept apart by its own suppression)
    are two people, one in front of the other, and the target's row is left to the
    one-to-one assignment (its head template cannot tell heads 1 px apart)."""

    def one_response(self, cand: Candidates, cands: np.ndarray) -> bool:
        return bool(cand.blob[cands].any())


class MultipleResponsePruning:
    """PBM 4 steps 4-5 and 4.1 on one frame's scores (``__call__``).

    Args:
        matching: thresholds and margin of a match. pruning: the template's threshold and
            the radius of "nearby". adaptations: ``duplicate_radius`` (with
            ``distinct_detections``: ``DetectionsApart`` / ``OneResponse``),
            ``prune_max_misses`` and ``rival_claims`` (``RivalClaims`` / ``OwnRow``).
    """

    def __init__(self, matching: MatchParams, pruning: PruneParams, adaptations: Adaptations) -> None:
        self.matching = matching
        self.pruning = pruning
        self.adaptations = adaptations
        self.claims = RivalClaims() if adaptations.rival_claims else OwnRow()
        self.weak = RankedAtThreshold() if adaptations.weak_ranked else AtThreshold()
        self.coinciding = DetectionsApart() if adaptations.distinct_detections else OneResponse()
        self.matcher = template_matcher(adaptations.pyramid_template,  # PBM 4.1's match
                                        adaptations.large_head_pyramid,
                                        adaptations.large_head_peaks)

    def __call__(self, scores: FrameScores, cand: Candidates, targets: Targets, frame: np.ndarray,
                 matched: dict | None = None) -> None:
        """PBM 4 steps 4-5, 4.1: a target whose best candidate does not beat the runner-up
        by ``matching.margin_ratio`` (ambiguous), or whose candidates all score in
        [weak_threshold, match_threshold) (weak), keeps the nearby candidate (within
        ``pruning.radius`` head widths; distant rivals are left to the one-to-one
        assignment) nearest its head template's best match (``match_template``), at a score of at
        least ``match_threshold``; the others are struck from its row of S. A weak target
        whose template does not match takes none.

        Adaptations: ambiguous candidates whose heads all lie within
        ``adaptations.duplicate_radius`` head widths of the best's are one response (best
        kept, no template match); a target unfound for more than
        ``adaptations.prune_max_misses`` frames has a stale template: an ambiguous choice
        keeps the best, a weak one takes none. ``matched``: template matches by (row,
        candidates) kept over a block's passes (``merges.FoundElsewhere``), or None.
        """
        S, m, a = scores.S, self.matching, self.adaptations
        bests, _, ambs = ambiguous_rows(S, m.match_threshold, m.margin_ratio)
        weaks = (bests < 0) & (np.maximum.reduce(S, axis=1) >= m.weak_threshold)
        heads_xy = cand.head[:, :2]
        rows = (ambs | weaks).nonzero()[0]
        claimed = self.claims.claimed(S, m.match_threshold) if len(rows) else None
        # every pruned row's responses and their distances at once, read before any row changes
        near_all, hw_all, dist_all = self._nearby(S[rows], ambs[rows], bests[rows], cand.head)
        for k, ti in enumerate(rows.tolist()):  # changes only row ti, after reading it
            row = S[ti]
            best, amb, weak = int(bests[ti]), bool(ambs[ti]), bool(weaks[ti])
            near, hw, dist = near_all[k], hw_all[k], dist_all[k]
            if (amb and claimed is not None and claimed[ti].any()
                    and self._untemplated(row, best, cand.head, int(targets.misses[ti]))):
                row = np.where(claimed[ti], -np.inf, row)  # the pruning's view of the row
                best, _, amb = ambiguous(row, m.match_threshold, m.margin_ratio)
                if not amb:  # one candidate of its own left: the assignment decides
                    continue
                near, hw, dist = (v[0] for v in self._nearby(row[None], np.array([amb]),
                                                                 np.array([best]), cand.head))
            cands = near.nonzero()[0]
            if amb and len(cands) < 2:
                continue
            if targets.misses[ti] > a.prune_max_misses:
                if weak:
                    continue
                chosen, refined = best, None
            elif amb and dist[cands].max() <= a.duplicate_radius * hw:
                if not self.coinciding.one_response(cand, cands):
                    continue  # two detections: two people, left to the assignment
                chosen, refined = best, None  # one response: the heads coincide
            else:
                chosen, refined = self._matched(matched, ti, targets.head_template[ti], cands,
                                                heads_xy[cands], frame)
            if chosen < 0:
                if weak:
                    continue
                chosen = best
            elif refined is not None and scores.hyp[ti, chosen] >= 0:
                # "the matching candidate is then updated accordingly": a carved
                # (occluded) candidate is re-anchored on the refined head
                q = scores.hyp[ti, chosen]
                dof_h = scores.dof_h
                dof_h[q] = dof_from_head(refined, dof_h[q, 4], dof_h[q, 5], targets.alpha[ti],
                                         targets.beta[ti])
            keep = row[chosen]
            S[ti, cands] = -np.inf
            S[ti, chosen] = self.weak.value(keep, m.match_threshold)

    def _nearby(self, S: np.ndarray, amb: np.ndarray, best: np.ndarray, heads: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """PBM 4 steps 4-5 and 4.1's responses of R rows of S (R, N), ambiguous ``amb``
        (R,) with their ``best`` (R,) (-1: weak), candidates' heads (N, 3): the candidates
        at p >= the match threshold (ambiguous) or the weak threshold (eq. 13) within
        ``pruning.radius`` head widths of the reference head r (the best, else the row's
        argmax). Returns near (R, N) bool, r's head width hw (R,) (at least 1) and the
        heads' distances (R, N) from r's head, each as one row's own arrays would give it."""
        m = self.matching
        lo = np.where(amb, m.match_threshold, m.weak_threshold)  # PBM 4 steps 4-5, p of eq. 13
        r = np.where(best >= 0, best, S.argmax(axis=1)) if S.size else best
        hw = np.maximum(heads[r, 2], 1.0)
        xy = heads[:, :2]
        dist = _norms(xy[None, :, :] - xy[r][:, None, :])  # (R, N, 2) -> (R, N)
        near = (S >= lo[:, None]) & (dist <= self.pruning.radius * hw[:, None])  # PBM 4.1: nearby
        return near, hw, dist

    def _untemplated(self, row: np.ndarray, best: int, heads: np.ndarray, misses: int) -> bool:
        """Whether the pruning keeps an ambiguous row's ``best`` without its head template:
        the template is stale (unfound > ``adaptations.prune_max_misses`` frames) or the
        near candidates' heads (N, 3) coincide (``adaptations.duplicate_radius``)."""
        cands = (row >= self.matching.match_threshold).nonzero()[0]
        hw = max(heads[best, 2], 1.0)
        dist = _norms(heads[cands, :2] - heads[best, :2])
        dist = dist[dist <= self.pruning.radius * hw]
        if len(dist) < 2:
            return False
        return misses > self.adaptations.prune_max_misses or bool(
            dist.max() <= self.adaptations.duplicate_radius * hw)

    def _matched(self, matched: dict | None, ti: int, template: np.ndarray | None,
                 cands: np.ndarray, heads: np.ndarray, frame: np.ndarray
                 ) -> tuple[int, np.ndarray | None]:
        """``match_template``, once per (row, candidates) while ``matched`` is kept (row ti's
        template, the candidates' heads and the frame are the same in a block's passes)."""
        if matched is None:
            return self.match_template(template, cands, heads, frame)
        key = (ti, cands.tobytes())
        if key not in matched:
            matched[key] = self.match_template(template, cands, heads, frame)
        return matched[key]

    def match_template(self, template: np.ndarray | None, cands: np.ndarray, heads: np.ndarray,
                       frame: np.ndarray) -> tuple[int, np.ndarray | None]:
        """PBM 4.1: the target's head template is matched
        around the heads (x top-centre, y top) (K, 2) of the candidates ``cands`` (K,)
        (``match_head_template``, on the grey of the BGR ``frame``'s search window only);
        returns the candidate nearest the refined head and that head, or (-1, None) when
        the template does not match.

        The centre is the heads' mean, the radius their largest distance from it (plus
        half the template width and 2 pixels); a few heads are summed as Python floats in
        numpy's order (row by row), more by numpy itself.
        """
        if template is None or not len(cands):
            return -1, None
        tw = template.shape[1]
        if len(cands) < 8:
            hs = heads.tolist()
            cx, cy = hs[0]
            for hx, hy in hs[1:]:
                cx, cy = cx + hx, cy + hy
            cx, cy = cx / len(hs), cy / len(hs)
            radius = max(math.sqrt((hx - cx) * (hx - cx) + (hy - cy) * (hy - cy)) for hx, hy in hs)
        else:
            cx, cy = heads.mean(axis=0).tolist()
            radius = float(np.max(np.linalg.norm(heads - [cx, cy], axis=1)))
        tl, corr = self.matcher(frame, template, (cx - 0.5 * tw, cy), radius + 0.5 * tw + 2)
        if corr < self.pruning.template_threshold:
            return -1, None
        x, ry = tl.tolist()
        rx = x + 0.5 * tw
        if len(cands) < 8:
            dist = [math.sqrt((hx - rx) * (hx - rx) + (hy - ry) * (hy - ry)) for hx, hy in hs]
            nearest = dist.index(min(dist))
        else:
            nearest = int(np.argmin(np.linalg.norm(heads - [rx, ry], axis=1)))
        return int(cands[nearest]), np.array([rx, ry])
