"""Alg. 1, steps 3-5 (Reta 3.3.1-3.3.2): the occlusion relation O (eq. 2), MaxSimilarity's
two-stage association (eqs. 4-5), and the depth order pi of O's pairs (eq. 3).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import NamedTuple

import numpy as np
from scipy.sparse import csr_array

from occbench.trackers.common.spatial import blocks, meeting_pairs
from occbench.trackers.three_hypothesis._kernels import depth_orders
from occbench.trackers.three_hypothesis.appearance import columns
from occbench.trackers.three_hypothesis.association import Matches, associate
from occbench.trackers.three_hypothesis.graph import VISIBLE
from occbench.trackers.three_hypothesis.occlusion import region_overlap_values
from occbench.trackers.three_hypothesis.params import Association, Occlusion
from occbench.trackers.three_hypothesis.rules import Rules
from occbench.trackers.three_hypothesis.values import (
    DepthOrder,
    Match,
    Matching,
    Measurements,
    Occlusions,
    Predictions,
)

Pi = dict[tuple[int, int], int]
"""pi (eq. 3) between frames: (key i, key j) -> 1 when i is in front of j, -1 behind."""


def occlusions(S: Predictions, V: Measurements, occlusion: Occlusion) -> Occlusions:
    """O (3.3.1, eq. 2): pairs of predicted regions of different people whose overlap
    ratio |Si & Sj| / (|Si| + |Sj|) = delta / 2 exceeds lambda (``occlusion_pairs``).
    The region similarity delta (eq. 5) of the predictions against each other and
    against the measurements comes from one integration per frame, over the pairs
    whose boxes meet (the only ones that can overlap; ``region_overlap_values``);
    ``Occlusions.delta`` keeps the latter, sparse, for step 4."""
    pred, owners = S.boxes, S.owners
    nb = len(pred)
    regions = np.concatenate([pred, V.boxes])
    ia, ib = meeting_pairs(pred, regions)
    node = ib < nb
    # pairs i < j of nodes of different people: owners is sorted, so owner_i < owner_j
    keep = ~node | (owners[ia] < owners[np.where(node, ib, 0)])
    ia, ib, node = ia[keep], ib[keep], node[keep]
    delta = region_overlap_values(pred, regions, ia, ib, occlusion.region_samples)
    delta_v = _csr(delta[~node], ia[~node], ib[~node] - nb, (nb, len(V.boxes)))
    ratio = 0.5 * delta[node]  # eq. 2's ratio of the node pairs
    pairs = np.column_stack([ia[node], ib[node]])[ratio > occlusion.lam].astype(int)
    return Occlusions(pairs, ratio[ratio > occlusion.lam], delta_v)


def _csr(values: np.ndarray, rows: np.ndarray, cols: np.ndarray, shape: tuple[int, int]
         ) -> csr_array:
    """The CSR matrix of entries (rows[k], cols[k]) = values[k], given sorted by row then
    column without repeats (``meeting_pairs``' order): the arrays scipy's
    ``csr_array((values, (rows, cols)))`` builds, int64 indices, without its COO pass."""
    indptr = np.zeros(shape[0] + 1, np.int64)
    np.cumsum(np.bincount(rows, minlength=shape[0]), out=indptr[1:])
    return csr_array((values, cols.astype(np.int64), indptr), shape=shape)


def max_similarity(S: Predictions, V: Measurements, O: Occlusions, pi: Pi, rules: Rules,
                   association: Association) -> Matching:
    """MaxSimilarity (3.3.2): stage 1 over intersecting regions, cost (1 - rho) +
    (1 - delta); stage 2 inside each node's validation gate, cost (1 - rho) + d / mu_g;
    rho = sqrt(q) . sqrt(p) (eq. 4), summed over the measurements' bins only (the other
    terms are 0). Persons x measurements up to ``spatial.DENSE_LIMIT`` (every ordinary
    frame): one ``associate`` over the frame. Beyond it, memory grows with the pairs:
    stage 1 is solved block by block (``spatial.blocks``) over the pairs of ``O.delta``
    (the only ones it may match), then stage 2 block by block over the pairs of its
    entrants and the measurements left whose distance is within the gate: the same
    optimum as the whole frame's. ``pi``: pi^{t-1}, read where ``rules.region`` orders."""
    persons, support = S.persons, V.support
    sqrt_qp = np.sqrt(columns([*(person.q for person in persons), *V.p], support))  # one lookup
    sqrt_q, sqrt_p = sqrt_qp[:len(persons)], sqrt_qp[len(persons):]  # (P, K), (D, K)
    R = np.array([person.R.item(0) for person in persons])[S.owners]  # R = (sigma_z h)^2 I
    visible = (np.array([b.kind == VISIBLE for b in S.branches], dtype=bool)
               if rules.shape.uses_seen or rules.contact.uses_seen else None)  # nodes of t-1
    seen = visible if rules.shape.uses_seen else None  # for the shape rule
    contacts = rules.contact.pairs(O.pairs, O.ratio, S.boxes,  # O's pairs sharing eq. 4's term
                                   visible if rules.contact.uses_seen else None)
    entrants = rules.stage2.entrants(np.array([person.confirmed for person in persons],
                                              dtype=bool))
    inp = _Inputs(S, V, O, rules, association, sqrt_q, sqrt_p, seen, entrants,
                  rules.gate.radii(S.Pp, R),
                  rules.returning.floors(persons, association.mu_rho),
                  lambda matched: rules.parts.barred(V.boxes, matched),
                  lambda: _fronts(S, O, pi), contacts)
    n_p, n_d = len(persons), len(V.boxes)
    parts = blocks(n_p, n_d, lambda: (S.owners[O.delta.tocoo().row], O.delta.tocoo().col))
    if len(parts) == 1:
        found = [_associate_block(inp, *parts[0], stages=(1, 2))]
    else:
        found = [_associate_block(inp, rows, cols, stages=(1,)) for rows, cols in parts]
        first = _merge(found, n_p, n_d)
        left = first.unmatched_persons
        left = left if entrants is None else left[entrants[left]]
        free = first.unmatched_measurements
        matched = np.ones(n_d, dtype=bool)
        matched[free] = False
        barred = rules.parts.barred(V.boxes, matched)  # as the whole frame's stage 2 sees it
        inp = inp._replace(barred=None if barred is None else lambda _: barred)
        found += [_associate_block(inp, left[r], free[c], stages=(2,))
                  for r, c in blocks(len(left), len(free),
                                     lambda: _gate_pairs(inp, left, free))]
    m = found[0].matches if len(parts) == 1 else _merge(found, n_p, n_d)  # one: the frame's
    if rules.split.uses_merged and len(O.pairs) and len(m.matches):
        _split(S, V, O, rules, m, sqrt_q, sqrt_p, association.mu_rho)
    return Matching({i: Match(d, n, s, r) for (i, d, n), s, r
                     in zip(m.matches.tolist(), m.stages.tolist(), m.rho.tolist())},
                    m.unmatched_measurements)


def _associate_block(s: _Inputs, rows: np.ndarray, cols: np.ndarray, stages: tuple[int, ...]
                     ) -> _Block:
    """``associate`` of persons ``rows`` and measurements ``cols`` (sorted frame
    indices) in ``stages``, in the block's indices. A stage-2 block sees no region term
    (delta 0: no stage 1); the shape rule judges its pairs among every person meeting
    its measurements."""
    S, V, O, rules, a = s.S, s.V, s.O, s.rules, s.association
    whole = len(rows) == len(S.persons) and len(cols) == len(V.boxes)
    if whole:  # every node, the persons' own indices
        nodes, owners = np.arange(len(S.owners)), S.owners
    else:
        nodes = np.flatnonzero(np.isin(S.owners, rows))
        owners = np.searchsorted(rows, S.owners[nodes])
    delta = O.delta.toarray() if whole else O.delta[nodes][:, cols].toarray()
    if 1 in stages and rules.region.uses_order and len(O.pairs) and len(nodes):
        at = np.minimum(np.searchsorted(nodes, O.pairs), len(nodes) - 1)
        inside = (nodes[at] == O.pairs).all(axis=1)  # pairs of O within the block
        delta = rules.region.delta(delta, at[inside], O.ratio[inside],
                                   s.fronts()[inside], S.boxes[nodes])
    pred, dets = S.boxes[nodes], V.boxes[cols]
    admissible = rules.shape.admissible(pred, dets, owners, delta,
                                        None if s.seen is None else s.seen[nodes])
    if 1 not in stages and admissible is not None:  # rivals: all who meet cols
        rivals = np.union1d(rows, S.owners[O.delta[:, cols].tocoo().row])
        wide = np.flatnonzero(np.isin(S.owners, rivals))
        admissible = rules.shape.admissible(
            S.boxes[wide], dets, np.searchsorted(rivals, S.owners[wide]),
            O.delta[wide][:, cols].toarray(), s.seen[wide])[np.isin(wide, nodes)]
    entrants = None if s.entrants is None else s.entrants[rows]
    if 2 not in stages:
        entrants = np.zeros(len(rows), dtype=bool)
    m = associate(
        pred, owners, s.sqrt_q[rows], dets, s.sqrt_p[cols],
        a.mu_rho if s.mu_rho is None else s.mu_rho[rows], a.mu_g,
        delta=delta if 1 in stages else np.zeros_like(delta), gated=entrants,
        gate=None if s.gate is None else s.gate[nodes],
        evidence=rules.contact.evidence(rules.stage1_appearance.evidence,
                                        _local_pairs(s.contacts, nodes), owners),
        admissible=admissible,
        barred=None if s.barred is None else partial(_barred, s.barred, cols))
    return _Block(m, rows, cols, nodes)


def _split(S: Predictions, V: Measurements, O: Occlusions, rules: Rules, m: Matches,
           sqrt_q: np.ndarray, sqrt_p: np.ndarray, mu_rho: float) -> None:
    """``rules.split`` on the frame's matches ``m`` (its rows and rho, in place): a person
    seen at t - 1 (a visible node) is ``merged`` when its measurement held a hidden
    partner, ``hidden`` when confirmed and seen at t - 1 nowhere."""
    persons = S.persons
    seen = np.zeros(len(persons), dtype=bool)
    seen[S.owners[[b.kind == VISIBLE for b in S.branches]]] = True
    merged = np.array([p.merged for p in persons], dtype=bool) & seen
    hidden = np.array([p.confirmed for p in persons], dtype=bool) & ~seen

    def rho(i: int, d: int) -> float:  # eq. 4, clipped to [0, 1] as stage 1's (a scalar:
        return min(max(float(sqrt_q[i] @ sqrt_p[d]), 0.0), 1.0)  # no np.clip call a pair)

    rows = rules.split.matches(m.matches, m.stages, rho, O.pairs, S.owners, O.delta,
                               merged, hidden, mu_rho, (persons, V.boxes))
    for k in np.flatnonzero((rows != m.matches).any(axis=1)).tolist():
        m.rho[k] = rho(int(rows[k, 0]), int(rows[k, 1]))
    m.matches = rows


def _gate_pairs(s: _Inputs, left: np.ndarray, free: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """(index into ``left``, index into ``free``) pairs of stage-2 entrants and the
    measurements left whose box meets the square of side 2 r around one of the
    person's node centres, r = min(mu_g, gate): a superset of the pairs inside the
    gate (the distance of centres at most r)."""
    S = s.S
    nodes = np.flatnonzero(np.isin(S.owners, left))
    r = np.full(len(nodes), s.association.mu_g)
    if s.gate is not None:
        r = np.minimum(r, s.gate[nodes])
    centre = S.boxes[nodes, :2] + 0.5 * S.boxes[nodes, 2:]
    square = np.column_stack([centre - r[:, None], 2 * r, 2 * r])
    ia, ib = meeting_pairs(square, s.V.boxes[free], pad=1.0)
    return np.searchsorted(left, S.owners[nodes[ia]]), ib


def _fronts(S: Predictions, O: Occlusions, pi: Pi) -> np.ndarray:
    """(K,) bool per pair (a, b) of O: a in front of b by pi^{t-1} (eq. 3), unknown:
    the lower region in front (``reading:eq3_tie``)."""
    keys = [person.key for person in S.persons]
    own = S.owners.tolist()
    bottom = S.boxes[:, 1] + S.boxes[:, 3]
    out = np.empty(len(O.pairs), dtype=bool)
    for k, (a, b) in enumerate(O.pairs.tolist()):
        order = pi.get((keys[own[a]], keys[own[b]]), 0)
        out[k] = order > 0 if order else bottom[a] >= bottom[b]
    return out


def sort_occlusions(S: Predictions, V: Measurements, O: Occlusions, A: Matching, pi: Pi
                    ) -> DepthOrder:
    """pi (eq. 3) of every pair in O, from who is visible at t: the visible one is in
    front; both visible, the areas of j's region above and below i's centre decide;
    neither, pi^{t-1} is inherited (unknown: the lower region is in front). ``pi`` (the
    tracker's, pi^{t-1}) becomes pi^t in place; the result says, per node, who is in
    front of it."""
    persons, matched = S.persons, A.matched
    in_front: dict[int, list[int]] = {}
    if not len(O.pairs):
        return DepthOrder(in_front)
    # eq. 3 as far as frame t decides it, every pair in one compiled pass
    nodes = [m.node for m in matched.values()]
    visible = np.zeros(len(S.boxes), dtype=bool)
    visible[nodes] = True
    shapes = S.boxes.copy()  # each node's current region: its measurement when visible
    shapes[nodes] = V.boxes[[m.det for m in matched.values()]]
    orders = np.empty(len(O.pairs), dtype=np.int64)
    depth_orders(O.pairs, visible, shapes, S.boxes, orders)
    own = S.owners.tolist()
    keys = [person.key for person in persons]
    boxes = S.boxes.tolist()  # (B,) [x, y, w, h] lists: scalar work below
    for (a, b), order in zip(O.pairs.tolist(), orders.tolist()):
        i, j = own[a], own[b]
        ki, kj = keys[i], keys[j]
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
    return DepthOrder(in_front)


def _local_pairs(pairs: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """The rows of O (``pairs``: (K, 2) node indices) with both nodes among the sorted
    ``nodes`` of a block, in the block's node indices (a pair across blocks shares no
    measurement either stage may match)."""
    if len(nodes) == 0 or len(pairs) == 0:
        return np.zeros((0, 2), dtype=int)
    at = np.minimum(np.searchsorted(nodes, pairs), len(nodes) - 1)
    inside = (nodes[at] == pairs).all(axis=1)
    return at[inside].astype(int)


class _Inputs(NamedTuple):
    """What every block of a frame's association reads: the frame's values, rules and
    parameters, (P, K) sqrt q, (D, K) sqrt p, (B,) seen or None, (P,) stage-2 entrants or
    None, (B,) gate radii or None, the frame's rules.parts, eq. 3's order of O's pairs
    by pi^{t-1} (``_fronts``, read where ``rules.region`` orders) and the pairs of O
    ``rules.contact`` reads."""

    S: Predictions
    V: Measurements
    O: Occlusions
    rules: Rules
    association: Association
    sqrt_q: np.ndarray
    sqrt_p: np.ndarray
    seen: np.ndarray | None
    entrants: np.ndarray | None
    gate: np.ndarray | None
    mu_rho: np.ndarray | None  # (P,) per person (rules.returning), None: mu_rho
    barred: Callable[[np.ndarray], np.ndarray | None] | None  # the frame's rules.parts
    fronts: Callable[[], np.ndarray]
    contacts: np.ndarray  # (K', 2) the node pairs of O whose appearance terms rules.contact shares


class _Block(NamedTuple):
    """One block's ``associate`` result and the frame indices of its persons (rows),
    measurements (cols) and nodes."""

    matches: Matches
    rows: np.ndarray
    cols: np.ndarray
    nodes: np.ndarray


def _barred(frame: Callable, cols: np.ndarray, matched: np.ndarray) -> np.ndarray | None:
    """A block's measurements stage 2 may not match: the frame's verdict (``frame``, of the
    frame's (D,) matched measurements; the whole frame's block, or stage 2's blocks, whose
    verdict was taken once after stage 1) on the block's ``cols``."""
    barred = frame(matched)
    return None if barred is None else barred[cols]


def _merge(found: list[_Block], n_persons: int, n_meas: int) -> Matches:
    """One ``Matches`` in frame indices from the blocks': as the whole frame's would be,
    stage 1's rows then stage 2's, each sorted by person, the unmatched ascending."""
    rows = [np.column_stack([b.rows[b.matches.matches[:, 0]], b.cols[b.matches.matches[:, 1]],
                             b.nodes[b.matches.matches[:, 2]]]) for b in found]
    matches = np.concatenate(rows).reshape(-1, 3).astype(int)
    stages = np.concatenate([b.matches.stages for b in found]).astype(int)
    rho = np.concatenate([b.matches.rho for b in found]).astype(float)
    order = np.lexsort((matches[:, 0], stages))
    return Matches(matches[order], stages[order], rho[order],
                   _left(n_persons, matches[:, 0]), _left(n_meas, matches[:, 1]))


def _left(n: int, taken: np.ndarray) -> np.ndarray:
    """0..n-1 without ``taken``, ascending."""
    left = np.ones(n, dtype=bool)
    left[taken] = False
    return np.flatnonzero(left)
