"""Alg. 1, steps 3-5 (Reta 3.3.1-3.3.2): the occlusion relation O (eq. 2), MaxSimilarity's
two-stage association (eqs. 4-5), and the depth order pi of O's pairs (eq. 3).
"""

from __future__ import annotations

import numpy as np

from occbench.trackers.three_hypothesis._kernels import depth_orders
from occbench.trackers.three_hypothesis.association import associate
from occbench.trackers.three_hypothesis.graph import VISIBLE
from occbench.trackers.three_hypothesis.occlusion import boxes_meet, occlusion_pairs, region_overlaps
from occbench.trackers.three_hypothesis.state import Frame


class OcclusionSteps:
    """``RetaTracker``'s steps 3-5 (a mixin: ``self`` is the tracker)."""

    def _occlusions(self, f: Frame) -> None:
        """O (3.3.1, eq. 2): pairs of predicted regions of different people whose overlap
        ratio |Si & Sj| / (|Si| + |Sj|) = delta / 2 exceeds lambda (``occlusion_pairs``).
        The region similarity delta (eq. 5) of the predictions against each other and
        against the measurements comes from one integration per frame
        (``region_overlaps``); ``f.delta`` keeps the latter for step 4."""
        pred, owners = f.pred, f.owners
        nb = len(pred)
        regions = np.concatenate([pred, f.dets])
        near = boxes_meet(pred, regions)  # only meeting boxes can overlap
        # pairs i < j of nodes of different people: owners is sorted, so owner_i < owner_j
        near[:, :nb] &= owners[:, None] < owners[None, :]
        delta = region_overlaps(pred, regions, self.occlusion.region_samples, near)
        f.near, f.delta = near, delta[:, nb:]
        f.pairs = occlusion_pairs(pred, owners, self.occlusion.lam, ratio=0.5 * delta[:, :nb])

    def _associate(self, f: Frame) -> None:
        """MaxSimilarity (3.3.2): stage 1 over intersecting regions, cost (1 - rho) +
        (1 - delta); stage 2 inside each node's validation gate, cost (1 - rho) + d / mu_g;
        rho = sqrt(q) . sqrt(p) (eq. 4), summed over the measurements' bins only (the other
        terms are 0)."""
        persons, support = f.persons, f.support
        sqrt_q = np.sqrt(np.array([person.q[support] for person in persons]).reshape(
            len(persons), len(support)))
        sqrt_p = np.sqrt(np.array([h[support] for h in f.p]).reshape(len(f.dets), len(support)))
        R = np.array([person.R[0, 0] for person in persons])[f.owners]  # R = (sigma_z h)^2 I
        a, shape = self.association, self.rules.shape
        seen = (np.array([b.kind == VISIBLE for b in f.branches], dtype=bool)
                if shape.uses_seen else None)  # visible nodes of t-1, for the shape rule
        f.matches = m = associate(
            f.pred, f.owners, sqrt_q, f.dets, sqrt_p, a.mu_rho, a.mu_g, delta=f.delta,
            gated=self.rules.stage2.entrants(
                np.array([person.confirmed for person in persons], dtype=bool)),
            gate=self.rules.gate.radii(f.Pp, R),
            evidence=self.rules.contact.evidence(self.rules.stage1_appearance.evidence,
                                                 f.pairs, f.owners),
            admissible=shape.admissible(f.pred, f.dets, f.owners, f.delta, seen),
            barred=lambda matched: self.rules.parts.barred(f.dets, matched))
        f.matched = {pi: (d, n, s, r) for (pi, d, n), s, r
                     in zip(m.matches.tolist(), m.stages.tolist(), m.rho.tolist())}

    def _sort_occlusions(self, f: Frame) -> None:
        """pi (eq. 3) of every pair in O, from who is visible at t: the visible one is in
        front; both visible, the areas of j's region above and below i's centre decide;
        neither, pi^{t-1} is inherited (unknown: the lower region is in front). Fills
        ``f.in_front``: node -> persons in front of it."""
        persons, matched, in_front, pi = f.persons, f.matched, f.in_front, self._pi
        if not len(f.pairs):
            return
        # eq. 3 as far as frame t decides it, every pair in one compiled pass
        nodes = [n for _, n, _, _ in matched.values()]
        visible = np.zeros(len(f.pred), dtype=bool)
        visible[nodes] = True
        shapes = f.pred.copy()  # each node's current region: its measurement when visible
        shapes[nodes] = f.dets[[d for d, _, _, _ in matched.values()]]
        orders = np.empty(len(f.pairs), dtype=np.int64)
        depth_orders(f.pairs, visible, shapes, f.pred, orders)
        own = f.owners.tolist()
        boxes = f.pred.tolist()  # (B,) [x, y, w, h] lists: scalar work below
        for (a, b), order in zip(f.pairs.tolist(), orders.tolist()):
            i, j = own[a], own[b]
            ki, kj = persons[i].key, persons[j].key
            if order == 0:  # undecided at t: pi^{t-1} is inherited
                order = pi.get((ki, kj), 0)
            if order == 0:  # unknown and neither visible: the lower region is in front
                order = 1 if boxes[a][1] + boxes[a][3] >= boxes[b][1] + boxes[b][3] else -1
            pi[(ki, kj)] = order
            pi[(kj, ki)] = -order
            if order > 0:
                in_front.setdefault(b, []).append(i)
            else:
                in_front.setdefault(a, []).append(j)
