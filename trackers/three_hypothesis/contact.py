"""People in contact (Reta 3.3.1-3.3.3): what a measurement that meets two tracked people
says about each; the paper's rule and ours beside each (``adaptations.merged_appearance``,
``merged_motion``, ``split_parts``, ``visible_region``, ``contact_region``,
``contact_coincident``, ``covered_appearance``, ``split_appearance``, ``merged_unmixed``,
``merged_unmixed_evidence``),
``rules.build_rules`` picks one. Issue 35: on real detections of people walking in groups
one measurement often holds two people, and the person matched to it took the pair's
histogram as its own. ``docs/adaptations.md`` gives the evidence. Boxes are (N, 4) float64
xywh, 0-based pixels."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np
from scipy.sparse import csr_array

from occbench.trackers.common.spatial import meeting_pairs
from occbench.trackers.geometry import iou_matrix
from occbench.trackers.three_hypothesis import _shares as shares
from occbench.trackers.three_hypothesis.appearance import Histogram, holds_both, towards
from occbench.trackers.three_hypothesis.occlusion import covered_fraction, union_cover

if TYPE_CHECKING:  # values imports state, which imports the rules built from this module
    from occbench.trackers.three_hypothesis.values import Match

# --------------------------------------------------------------- 3.3.3: q of a person in front


@dataclass(frozen=True)
class MeasurementAppearance:
    """3.3.3 as written: a matched person behind nobody takes its measurement's histogram p
    as its appearance q."""

    uses_shares: ClassVar[bool] = False
    uses_partners: ClassVar[bool] = False

    def update(self, q: Histogram, p: Histogram, own: float,
               partner: Histogram | None = None) -> Histogram:
        return p


@dataclass(frozen=True)
class MergedAppearance:
    """``merged_appearance``: a measurement merged over two tracked people is an occlusion
    (3.3.1). When the person i matched to measurement d is in O (eq. 2) with a confirmed
    person j left unmatched at t, d's ellipse may hold j's pixels as well as i's: only the
    share ``own`` of d's region that j's predicted region does not cover is i's, so q moves
    towards p by that share, q <- (1 - own) q + own p (``own`` 1: q = p as in the paper; j
    wholly inside d: q kept), and the appearance models of people in contact do not absorb
    each other."""

    uses_shares: ClassVar[bool] = True
    uses_partners: ClassVar[bool] = False

    def update(self, q: Histogram, p: Histogram, own: float,
               partner: Histogram | None = None) -> Histogram:
        if own >= 1.0:
            return p
        return towards(q, p, own) if own > 0 else q


@dataclass(frozen=True)
class UnmixedAppearance(MergedAppearance):
    """``merged_unmixed`` (with ``merged_appearance``): a merged measurement is an
    occlusion, so its histogram p (eq. 1) is the mixture of the two people's by their shares
    of its region, p = own q_i + (1 - own) q_j, and the hidden partner j's appearance q_j is
    known (kept through the occlusion). Person i's part of p is what is left when j's share
    is taken out, r = max(p - (1 - own) q_j, 0) normalised, and q moves towards r (not p) by
    ``own``: q <- (1 - own) q + own r. A person in front of a look-alike, or wholly inside
    the partner's region (own 0), keeps q; with no partner (own 1) q = p as in the paper.
    (PBM keeps a target's parts model when a part does not match, ``update.part_threshold``:
    the colours of the person behind do not enter the model of the person in front.)
    ``evidence`` (``merged_unmixed_evidence``): only where p's colours hold both people,
    eq. 4 of p with the mixture above its rho with q and with q_j alone; else merged."""

    evidence: bool = False
    uses_partners: ClassVar[bool] = True

    def update(self, q: Histogram, p: Histogram, own: float,
               partner: Histogram | None = None) -> Histogram:
        if own >= 1.0 or partner is None or self.evidence and not holds_both(q, p, own, partner):
            return MergedAppearance.update(self, q, p, own)
        r = np.maximum(p.dense() - (1.0 - own) * partner.dense(), 0.0)  # dense: r.sum()'s order
        total = r.sum()
        return towards(q, Histogram.of(r / total), own) if own > 0 and total > 0 else q


@dataclass(frozen=True)
class AnyCover:
    """3.3.3 as written: a person matched in front (eq. 3) takes q from its measurement."""

    covers: ClassVar[bool] = False  # no measurement is read as covered


@dataclass(frozen=True)
class NearerCover:
    """``covered_appearance``: a person partly seen is hypothesis territory. The part of a
    measurement's region a measurement nearer the camera (foot line lower, as
    ``reading:eq3_tie`` orders regions) covers is not its person's evidence: a person eq. 3
    puts in front whose measurement's ellipse one nearer measurement covers for at least
    ``cover`` keeps q, as a person behind others does (3.3.3)."""

    cover: float
    covers: ClassVar[bool] = True

    def behind(self, dets: np.ndarray, boxes: np.ndarray, samples: int) -> np.ndarray:
        """(K,) bool per row ``dets`` of (D, 4) xywh ``boxes``: a lower-footed box covers it."""
        own = boxes[dets]
        ia, ib = meeting_pairs(own, boxes)
        foot = boxes[:, 1] + boxes[:, 3]
        nearer = (ib != dets[ia]) & (foot[ib] > foot[dets[ia]])
        return covered_fraction(own, boxes, samples, (ia[nearer], ib[nearer])) >= self.cover


# --------------------------------------------------------------- 3.3.3: M of a person in front


@dataclass(frozen=True)
class MeasurementMotion:
    """3.3.3 as written: M of a matched person behind nobody is corrected by its measurement
    with the measurement noise R."""

    uses_shares: ClassVar[bool] = False

    def noise(self, R: np.ndarray, own: np.ndarray) -> np.ndarray:
        return R


@dataclass(frozen=True)
class MergedMotion:
    """``merged_motion``: a measurement merged over two tracked people is an occlusion, its
    box the pair's (centre between them, size of both): it measures the matched person only
    by its own share (``own_shares``), so M is corrected with R / own (own 1: R as in the
    paper; own near 0: M keeps its prediction through the contact, as the paper's person
    behind others, 3.3.3)."""

    uses_shares: ClassVar[bool] = True

    def noise(self, R: np.ndarray, own: np.ndarray) -> np.ndarray:
        """(K, 4, 4) R of the matched rows scaled by 1 / own, (K,) shares (floored at 1e-3)."""
        return R / np.maximum(own, 1e-3)[:, None, None]


def own_shares(matches: list[Match], pairs: np.ndarray, owners: np.ndarray,
               hidden: np.ndarray, pred: np.ndarray, dets: np.ndarray,
               delta: csr_array, partners: np.ndarray | None = None) -> np.ndarray:
    """(K,) share of each matched measurement's region that no predicted region of a hidden
    partner covers: 1 - max_m |S_m & S_d| / |S_d| over the nodes m, in O with the row's node,
    of a person with ``hidden`` True (|S_m & S_d| = delta (|S_m| + |S_d|) / 2, eq. 5).

    Args:
        matches: the ``Match`` (measurement d, node n) of each matched person.
        pairs: O, (K', 2) node rows; owners: (B,) person of each node.
        hidden: (P,) bool, persons unmatched at t that may be inside a measurement.
        pred: (B, 4) predicted regions; dets: (D, 4) measurements.
        delta: sparse (B, D) region similarity of ``pred`` and ``dets`` (eq. 5), canonical
            (sorted, no duplicates: as ``steps_occlusion.occlusions`` builds it).
        partners: optional (K,) int array, filled in place with the person whose nodes
            cover most of each row's measurement (left as given where none does).
    """
    own = np.ones(len(matches))
    if not len(pairs) or not hidden.any():
        return own
    row = np.full(len(owners), -1, dtype=np.int64)  # node -> its matched row, -1: none
    row[[match.node for match in matches]] = np.arange(len(matches))
    d = np.array([match.det for match in matches], dtype=np.int64)
    # pi / 4 cancels in the ratio; O's pairs both ways, compiled (the numpy expression's bits)
    shares.own_shares(np.asarray(pairs, dtype=np.int64), np.asarray(owners, dtype=np.int64),
                      np.asarray(hidden, dtype=bool), row, d, pred[:, 2] * pred[:, 3],
                      dets[d, 2] * dets[d, 3], *shares.csr(delta), own,
                      np.zeros(len(matches), np.int64) if partners is None else partners,
                      partners is not None)
    return own


# --------------------------------------------------------------- 3.3.2 steps 5-8: who stage 2 may give a measurement


@dataclass(frozen=True)
class AnyLeftover:
    """3.3.2 as written: every measurement stage 1 left over may be taken in stage 2 by a
    prediction whose validation gate holds it."""

    def barred(self, dets: np.ndarray, matched: np.ndarray) -> None:
        return None


@dataclass(frozen=True)
class SplitParts:
    """``split_parts``: a person partly seen is a split. A measurement stage 1 left over
    whose region lies mostly (at least ``cover`` of its ellipse) on the measurements stage 1
    matched is a second measurement of people already measured (the detector fitted one more
    box across a group), neither a person come back nor a new one: stage 2 may not give it
    to a person through the gate, and it starts no track."""

    cover: float
    samples: int = 12

    def barred(self, dets: np.ndarray, matched: np.ndarray) -> np.ndarray | None:
        """(D,) bool: leftover measurements of (D, 4) xywh ``dets`` lying on the union of the
        ``matched`` (D,) bool ones by at least ``cover``."""
        if not matched.any() or matched.all():
            return None
        out = np.zeros(len(dets), dtype=bool)
        out[~matched] = union_cover(dets[~matched], dets[matched], self.samples) >= self.cover
        return out


# --------------------------------------------------------------- 3.3.2 step 2: the region term of a person behind others


@dataclass(frozen=True)
class WholeRegion:
    """3.3.2 as written: eq. 5 compares a measurement with a node's whole predicted region,
    whoever stands in front of it."""

    uses_order: ClassVar[bool] = False

    def delta(self, delta: np.ndarray, pairs: np.ndarray, ratio: np.ndarray,
              fronts: np.ndarray, pred: np.ndarray) -> np.ndarray:
        return delta


@dataclass(frozen=True)
class VisibleRegion:
    """``visible_region``: a person behind others (eq. 3's order at t - 1) can only be
    measured where the people in front leave it visible, so in stage 1 eq. 5's region term
    of a node behind others is scaled by its visible share, 1 - the largest share of its
    predicted region one node in front covers (from eq. 2's ratio: |S_a & S_b| = ratio
    (|S_a| + |S_b|)). A measurement that meets a pair of O is then the front person's
    unless the colours say otherwise: a measurement merged over two tracked people is an
    occlusion, its person in front the one measured."""

    uses_order: ClassVar[bool] = True  # reads eq. 3's order of the pairs of O

    def delta(self, delta: np.ndarray, pairs: np.ndarray, ratio: np.ndarray,
              fronts: np.ndarray, pred: np.ndarray) -> np.ndarray:
        """(B, D) region terms from (B, D) ``delta``; ``pairs`` (K, 2) node rows of O with
        eq. 2's ``ratio`` (K,) and ``fronts`` (K,) bool, True when the pair's first node is
        in front; ``pred`` (B, 4) predicted regions."""
        if not len(pairs):
            return delta
        area = pred[:, 2] * pred[:, 3]  # pi / 4 cancels
        front = np.where(fronts, pairs[:, 0], pairs[:, 1])
        back = np.where(fronts, pairs[:, 1], pairs[:, 0])
        covered = ratio * (area[front] + area[back]) / np.maximum(area[back], 1e-9)
        hidden = np.zeros(len(pred))
        np.maximum.at(hidden, back, np.clip(covered, 0.0, 1.0))
        return delta * (1.0 - hidden)[:, None]


# --------------------------------------------------------------- 3.3.2 step 2: appearance of a pair of O


@dataclass(frozen=True)
class AppearanceAtContact:
    """3.3.2 as written: at a contact too, stage 1 weighs the appearance term of each pair
    (eq. 4) as for any other pair."""

    uses_seen: ClassVar[bool] = False

    def pairs(self, pairs: np.ndarray, ratio: np.ndarray, pred: np.ndarray,
              seen: np.ndarray | None) -> np.ndarray:
        return pairs

    def evidence(self, appearance, pairs: np.ndarray, owners: np.ndarray):
        return appearance


@dataclass(frozen=True)
class RegionAtContact:
    """``contact_region``: a merged measurement is an occlusion. When two people are in O
    (eq. 2: their predicted regions overlap by more than lambda) and one measurement meets
    both in stage 1, its histogram p (eq. 1, over the measurement's ellipse) holds both
    people's pixels, so eq. 4 cannot tell which of them it is: both pairs get the mean of
    their appearance terms, and the region term (eq. 5, the motion model's prediction)
    decides between them. Pairs of people not in O keep their appearance term.

    ``coincident`` (``contact_coincident``, with ``contact_region`` off): only the pairs of O
    whose two nodes were both seen at t - 1 (visible nodes: each person's q is the histogram
    of its measurement at t - 1, 3.3.3) and whose predicted regions coincide, each holding at
    least ``coincident`` of the larger one (|Si & Sj| >= coincident max(|Si|, |Sj|)): two
    people measured over the same pixels, whose q's both hold both of them. 0: every pair of
    O (``contact_region``)."""

    coincident: float = 0.0
    uses_seen: ClassVar[bool] = True

    def pairs(self, pairs: np.ndarray, ratio: np.ndarray, pred: np.ndarray,
              seen: np.ndarray | None) -> np.ndarray:
        """The rows of O (``pairs`` (K, 2) node rows, eq. 2's ``ratio`` (K,) = |Si & Sj| /
        (|Si| + |Sj|)) whose appearance terms are shared, from ``pred`` (B, 4) predicted
        regions and ``seen`` (B,) bool, visible nodes of t - 1."""
        if self.coincident <= 0 or not len(pairs):
            return pairs
        area = pred[:, 2] * pred[:, 3]  # pi / 4 cancels
        i, j = pairs[:, 0], pairs[:, 1]
        common = ratio * (area[i] + area[j])  # |Si & Sj|
        keep = seen[i] & seen[j] & (common >= self.coincident * np.maximum(area[i], area[j]))
        return pairs[keep]

    def evidence(self, appearance, pairs: np.ndarray, owners: np.ndarray):
        """``appearance`` (rho (P, D), admissible (P, D) bool) -> (P, D) wrapped so that
        the persons of every pair of O (``pairs``: (K, 2) node rows; ``owners``: (B,)
        person of each node) share one term on every measurement admissible to both."""
        if not len(pairs):
            return appearance
        persons = np.unique(np.sort(owners[pairs], axis=1), axis=0)  # (K', 2) i < j
        persons = persons[persons[:, 0] != persons[:, 1]]

        def evidence(rho: np.ndarray, admissible: np.ndarray) -> np.ndarray:
            a = np.array(appearance(rho, admissible), dtype=np.float64)
            for i, j in persons.tolist():
                both = admissible[i] & admissible[j]  # (D,) measurements meeting both
                a[i, both] = a[j, both] = 0.5 * (a[i, both] + a[j, both])
            return a

        return evidence


# --------------------------------------------------------------- 3.3.2 after stage 1: whose is which box where a merged pair parts


@dataclass(frozen=True)
class RegionAtSplit:
    """3.3.2 as written: when two people a measurement held together are measured apart
    again, stage 1's cost (eqs. 4-5) decides who takes which, as for any other pair."""

    uses_merged: ClassVar[bool] = False

    def matches(self, rows: np.ndarray, stages: np.ndarray, rho: Callable,
                pairs: np.ndarray, owners: np.ndarray, delta: csr_array,
                merged: np.ndarray, hidden: np.ndarray, mu_rho: float,
                regions: tuple | None = None) -> np.ndarray:
        return rows


@dataclass(frozen=True)
class AppearanceAtSplit:
    """``split_appearance``: a merged measurement is an occlusion, so the position it gave
    the person matched to it was the pair's, and the hidden partner's regions are
    hypotheses. When person i's measurement at t - 1 held a hidden partner j (i's own share
    below 1, ``own_shares``), i and j are in O, and stage 1 gives each one of two
    measurements that both could take (rho >= mu_rho, each meeting the other's
    measurement), eq. 5 has said that the pair is measured but cannot say which is whose:
    the appearance (eq. 4), which the occlusion did not take from the hidden person, decides
    (the two measurements exchanged when rho_ib + rho_ja > rho_ia + rho_jb + ``margin``:
    like PBM's multiple-response test, colours that fit the exchange only a little better
    are ambiguous and decide nothing). Nobody else's match changes. ``parted`` > 0
    (``split_appearance_parted``): only where stage 1 gives i a measurement that does not
    continue i's region at t - 1 (IoU below it), as no part of a box over two does."""

    margin: float = 0.0
    parted: float = 0.0
    uses_merged: ClassVar[bool] = True

    def matches(self, rows: np.ndarray, stages: np.ndarray, rho: Callable,
                pairs: np.ndarray, owners: np.ndarray, delta: csr_array,
                merged: np.ndarray, hidden: np.ndarray, mu_rho: float,
                regions: tuple | None = None) -> np.ndarray:
        """(K, 3) rows (person, measurement, node) of a frame's matches, with ``stages``
        (K,); ``rho`` (person, measurement) -> eq. 4; ``pairs`` (K', 2) node rows of O,
        ``owners`` (B,); ``delta`` sparse (B, D) eq. 5; per person (P,) bool ``merged``
        (matched at t - 1 to a measurement that held a hidden partner) and ``hidden``
        (confirmed, unmatched at t - 1); ``regions`` (persons, (D, 4) measurements). Returns
        the rows, the pair's measurements exchanged where the colours say so."""
        out = rows
        at = {int(p): k for k, p in enumerate(rows[:, 0].tolist()) if stages[k] == 1}
        done = set()
        for a, b in pairs.tolist():
            i, j = sorted((int(owners[a]), int(owners[b])))
            if (i, j) in done or i not in at or j not in at:
                continue
            if not (merged[i] and hidden[j] or merged[j] and hidden[i]):
                continue
            done.add((i, j))
            di, dj = int(out[at[i], 1]), int(out[at[j], 1])
            own, other = rho(i, di) + rho(j, dj), rho(i, dj) + rho(j, di)
            if (di == dj or min(rho(i, dj), rho(j, di)) < mu_rho or other <= own + self.margin
                    or self.parted > 0 and self._continued(i if merged[i] else j,
                                                           di if merged[i] else dj, regions)):
                continue  # the cheap tests first: the regions' below are sparse slices
            ni, nj = np.flatnonzero(owners == i), np.flatnonzero(owners == j)
            to_j = delta[ni][:, [dj]].toarray()[:, 0]  # i's nodes on j's measurement
            to_i = delta[nj][:, [di]].toarray()[:, 0]
            if not to_j.max() > 0 or not to_i.max() > 0:
                continue
            if out is rows:
                out = rows.copy()
            out[at[i]] = (i, dj, ni[np.argmax(to_j)])  # the node stage 1 would take
            out[at[j]] = (j, di, nj[np.argmax(to_i)])
        return out

    def _continued(self, k: int, d: int, regions: tuple) -> bool:
        """Person ``k``'s region at t - 1 is continued by measurement ``d``: IoU >= parted."""
        persons, dets = regions
        return bool(iou_matrix(persons[k].shape[None], dets[d][None])[0, 0] >= self.parted)
