"""Alg. 1, steps 7-8 (Reta 3.3.3): the hypotheses N_h1-N_h3 of the unmatched people, and
PruneHypothesis(G, m).
"""

from __future__ import annotations

import logging

import numpy as np

from occbench.trackers.three_hypothesis import _shares as shares
from occbench.trackers.three_hypothesis import hypotheses as hyp
from occbench.trackers.three_hypothesis.graph import VISIBLE
from occbench.trackers.three_hypothesis.motion import state_boxes
from occbench.trackers.three_hypothesis.occlusion import covered_fraction
from occbench.trackers.three_hypothesis.rules import Rules
from occbench.trackers.three_hypothesis.state import Branch, Memory, Person, Setting
from occbench.trackers.three_hypothesis.steps_output import add_nodes
from occbench.trackers.three_hypothesis.values import (
    Continuation,
    DepthOrder,
    Matching,
    Measurements,
    Occlusions,
    Predictions,
    Updated,
)

log = logging.getLogger(__name__)


def continue_unmatched(S: Predictions, A: Matching, D: DepthOrder, U: Updated, rules: Rules
                       ) -> list[Continuation]:
    """Alg. 1's loop over a_i in N^{t-1} \\ Assoc: every unmatched person continues each
    hypothesis (N_h1: a visible node becomes 'velocity', keeping its velocity and
    direction); at its first total occlusion (FirstOcclusion, our reading
    ``reading:first_occlusion``: the first frame of its spell unmatched in which a node
    lies behind a person matched at t) a confirmed person also gets N_h2 (follows the
    occluder) and N_h3 (stands still). A tentative track keeps one branch. A person whose
    id a new track took (``U.absorbed``) ends.

    Returns:
        per unmatched person, its new branches and the node of t-1 each continues.
    """
    persons, matched, in_front = S.persons, A.matched, D.in_front
    pending: list[Continuation] = []
    # owners is sorted: person i owns nodes bounds[i]:bounds[i + 1]
    bounds = np.searchsorted(S.owners, np.arange(len(persons) + 1)).tolist()
    for i, person in enumerate(persons):
        if i in matched or i in U.absorbed:
            continue
        person.misses += 1
        new: list[Branch] = []
        sources: list[int] = []
        for n in range(bounds[i], bounds[i + 1]):
            old = S.branches[n]
            kind = hyp.VELOCITY if old.kind == VISIBLE else old.kind
            fronts = in_front.get(n, [])
            occluder = old.occluder if kind == hyp.OCCLUDER else (
                persons[fronts[0]].key if fronts else None)
            x = (rules.line.start(person, S.x_prev[n], S.Xp[n]) if old.kind == VISIBLE
                 else S.Xp[n])  # hypothesis 1's velocity at the first miss
            new.append(Branch(kind, x, S.Pp[n], node=old.node, occluder=occluder,
                              exposed=old.exposed, depth=len(fronts)))
            sources.append(n)
            seen = [j for j in fronts if j in matched]
            if person.confirmed and not person.spawned and seen:
                occ = persons[seen[0]]
                velocity = occ.branches[0].x[4:6].copy()  # the occluder's visible node
                for kind2, x2 in hyp.spawn(S.x_prev[n], velocity).items():
                    new.append(Branch(kind2, x2, S.Pp[n].copy(), node=old.node,
                                      occluder=occ.key, depth=len(fronts)))
                    sources.append(-1)
                person.spawned = True
        if not person.confirmed:
            new, sources = new[:1], sources[:1]
        pending.append(Continuation(person, new, sources))
    return pending


def prune(S: Predictions, V: Measurements, O: Occlusions, U: Updated,
          H: list[Continuation], setting: Setting, memory: Memory) -> list[Person]:
    """PruneHypothesis(G, m): a hypothesis whose centre left the image ends; one in
    plain view (less than ``cover`` of it hidden by a person visible at t, or, with
    ``rules.support``, seen empty) for m frames in a row is contradicted by the missing
    detection and removed (with ``rules.presence``, frames it spends on foreground do not
    count); of two at the same place ``rules.duplicates`` may keep one; a
    tentative track missed more than ``tentative_misses`` frames is a false positive;
    a person hidden more than ``max_hidden`` frames, or with no hypothesis left, ends.
    Returns the persons kept, their hypotheses added to ``memory.graph``."""
    if not H:
        return []
    rules, foreground = setting.rules, V.foreground
    hyp_boxes = state_boxes(np.array([b.x for c in H for b in c.branches]))
    gone = hyp.outside_image(hyp_boxes, V.width, V.height).tolist()
    sources = np.array([n for c in H for n in c.sources])
    cover = _hidden_share(S, O, U, hyp_boxes, sources, setting) >= setting.life_cycle.cover
    empty = rules.support.empty(foreground, hyp_boxes)
    held = rules.presence.held(foreground, hyp_boxes, empty)
    share = rules.report.shares(setting.histograms, foreground, hyp_boxes)
    held = [False] * len(cover) if held is None else held.tolist()
    if empty is None:
        unseen = np.zeros(len(cover), dtype=bool)
    else:  # nobody can be seen where the region holds no foreground
        unseen = empty
        cover &= ~unseen
    cover, unseen, corners = cover.tolist(), unseen.tolist(), hyp_boxes.tolist()
    m, a = setting.life_cycle.m, setting.adaptations
    survivors: list[Person] = []
    rows: tuple[list, list, list] = ([], [], [])  # people, branches, boxes of the nodes
    k = 0
    for c in H:
        person = c.person
        kept: list[Branch] = []
        kept_corners: list[list[float]] = []
        kept_rates: list[list[float]] = []
        dropped = None  # its first hypothesis contradicted this frame (rules.ending)
        for b in c.branches:
            corner, g, hidden, held_k = corners[k], gone[k], cover[k], held[k]
            b.unseen = unseen[k]
            b.share = 1.0 if share is None else float(share[k])
            k += 1
            b.covered = hidden
            b.exposed = 0 if hidden else b.exposed + (0 if held_k else 1)
            if g or b.exposed >= m:
                if not g and dropped is None:
                    dropped = (b, corner)
                continue
            rates = b.x[len(b.x) // 2:].tolist()  # the state's velocities (3.2)
            if kept_corners and rules.duplicates.duplicate(corner, kept_corners, rates,
                                                           kept_rates):
                rules.ending.merged(person, b)
                continue
            kept.append(b)
            kept_corners.append(corner)
            kept_rates.append(rates)
        if not person.confirmed and person.misses > a.tentative_misses:
            kept = []  # false-positive track
        if not kept and dropped is not None:
            holder = rules.ending.hold(person, dropped[0])
            if holder is not None:
                kept, kept_corners = [holder], [dropped[1] if holder is dropped[0] else
                                                state_boxes(holder.x[None])[0].tolist()]
        if person.misses > a.max_hidden:
            kept = []
        if not kept:
            log.debug("person %d ended at frame %d", person.public_id, memory.t)
            continue
        person.branches = kept
        rows[0].extend([person] * len(kept))
        rows[1].extend(kept)
        rows[2].extend(kept_corners)
        survivors.append(person)
    add_nodes(memory, *rows, [b.node for b in rows[1]], [0] * len(rows[1]),
              [float("nan")] * len(rows[1]))  # from each hypothesis's node at t-1
    return survivors


def _hidden_share(S: Predictions, O: Occlusions, U: Updated, boxes: np.ndarray,
                  src: np.ndarray, setting: Setting) -> np.ndarray:
    """(N,) largest share of each new hypothesis region hidden by one person visible at
    t. A branch that continues node ``src`` sits at its prediction, whose eq. 5 delta
    against every measurement is known: |S_n & S_v| = delta (|S_n| + |S_v|) / 2;
    spawned ones (src -1) are integrated."""
    fraction = np.zeros(len(src))
    cont = src >= 0
    visible = U.visible
    if len(visible) and cont.any():
        column = np.full(O.delta.shape[1], -1)  # measurement -> its row of U.visible
        column[U.visible_dets] = np.arange(len(U.visible_dets))
        pred = S.boxes  # the pairs that meet, compiled (numpy's bits)
        shares.hidden_shares(src.astype(np.int64), pred[:, 2] * pred[:, 3], *shares.csr(O.delta),
                             column.astype(np.int64), visible[:, 2] * visible[:, 3], fraction)
    if (~cont).any():
        fraction[~cont] = covered_fraction(boxes[~cont], visible,
                                           setting.occlusion.region_samples)
    return fraction
