"""Two-stage similarity association (Reta 3.3.2, steps 1-8, eqs. 4 and 5).

Predictions are the regions S^{t|t-1} of the nodes of the previous frame (a person may
own several nodes: its hypotheses). All branches of one person share its appearance q,
so the Hungarian method runs over persons x measurements with each pair's cost taken at
the person's best node (our reading of Alg. 1's MaxSimilarity over nodes,
``reading:person_level_hungarian``); the chosen node is returned so the other hypotheses
of that person can be pruned. Boxes are (N, 4) float64 xywh, 0-based pixels.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from occbench.trackers.common.assignment import assign_min_cost
from occbench.trackers.geometry import centre_distance_matrix
from occbench.trackers.three_hypothesis._kernels import stage1_costs
from occbench.trackers.three_hypothesis.features import region_similarity


@dataclass
class Matches:
    """Result of one frame's association.

    Attributes:
        matches: (K, 3) int rows (person, measurement, node).
        stages: (K,) int, 1 or 2: the stage that accepted each match.
        rho: (K,) float appearance similarity of each match (eq. 4).
        unmatched_persons: (P - K,) int person indices.
        unmatched_measurements: (D - K,) int measurement indices.
    """

    matches: np.ndarray
    stages: np.ndarray
    rho: np.ndarray
    unmatched_persons: np.ndarray
    unmatched_measurements: np.ndarray


def absolute_appearance(rho: np.ndarray, admissible: np.ndarray) -> np.ndarray:
    """3.3.2 as written: a stage-1 pair's appearance term is rho itself (eq. 4)."""
    return rho


def appearance_margin(rho: np.ndarray, admissible: np.ndarray) -> np.ndarray:
    """``appearance_margin``'s term (``rules.AppearanceMargin``): what rho says for a pair
    against its rivals, rho_ij - max(max_{k != i} rho_kj, max_{l != j} rho_il) over the
    admissible pairs, floored at 0. (P, D) from rho (P, D) in [0, 1] and admissible (P, D)
    bool (pairs stage 1 may choose; the others count as rho 0). The numpy definition;
    ``associate`` runs it compiled (``_kernels.stage1_costs``)."""
    r = np.where(admissible, rho, 0.0)
    rival = np.maximum(_rival(r, axis=0), _rival(r, axis=1))
    return np.clip(r - rival, 0.0, 1.0)


def _rival(x: np.ndarray, axis: int) -> np.ndarray:
    """For every entry of x, the largest other entry along ``axis`` (0 when alone)."""
    if x.shape[axis] < 2:
        return np.zeros_like(x)
    s = np.sort(x, axis=axis)
    first, second = np.take(s, [-1], axis=axis), np.take(s, [-2], axis=axis)
    return np.where(x >= first, second, first)


def _person_costs(
    cost_nodes: np.ndarray, starts: np.ndarray, owners: np.ndarray
) -> tuple[np.ndarray, np.ndarray | None]:
    """Reduce (B, D) node costs to (P, D) person costs (min over each person's nodes) and
    the (P, D) index of the node attaining it (None when every person owns one node: the
    node is the person). Nodes are grouped by person: person k owns rows
    ``starts[k]:starts[k + 1]``; ``owners`` (B,) is the person of each row."""
    if len(starts) == len(cost_nodes):  # one node per person
        return cost_nodes, None
    cost = np.minimum.reduceat(cost_nodes, starts, axis=0)
    # first node of each person attaining its minimum (as np.argmin; costs are never NaN)
    rows = np.where(cost_nodes == cost[owners], np.arange(len(cost_nodes))[:, None],
                    len(cost_nodes))
    return cost, np.minimum.reduceat(rows, starts, axis=0)


def _rows(*columns: np.ndarray) -> np.ndarray:
    """(K, len(columns)) int array whose columns are the given (K,) arrays."""
    out = np.empty((len(columns[0]), len(columns)), dtype=int)
    for k, column in enumerate(columns):
        out[:, k] = column
    return out


def _hungarian(cost: np.ndarray, leave: float) -> np.ndarray:
    """Hungarian method where leaving a person unmatched costs ``leave``, which is also the
    largest cost an accepted pair can have (``occbench.trackers.common.assignment.assign_min_cost``).
    Returns (K, 2) rows (person, measurement), sorted by person."""
    allowed = np.isfinite(cost) & (cost <= leave)
    if allowed.sum(axis=0).max() <= 1 and allowed.sum(axis=1).max() <= 1:
        return np.argwhere(allowed)  # no competing pairs: the assignment is immediate
    return assign_min_cost(cost, leave)[0]


def associate(
    node_boxes: np.ndarray,
    owners: np.ndarray,
    sqrt_q: np.ndarray,
    measurement_boxes: np.ndarray,
    sqrt_p: np.ndarray,
    mu_rho: float | np.ndarray,
    mu_g: float,
    delta: np.ndarray | None = None,
    gated: np.ndarray | None = None,
    gate: np.ndarray | None = None,
    evidence: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None,
    admissible: np.ndarray | None = None,
    barred: Callable[[np.ndarray], np.ndarray | None] | None = None,
) -> Matches:
    """Match measurements to persons in two stages.

    Stage 1 (steps 1-4): pairs whose predicted and measured regions intersect; cost
    (1 - rho) + (1 - delta) with rho the Bhattacharyya coefficient (eq. 4) and delta the
    region similarity (eq. 5); Hungarian method; accept only rho >= mu_rho.
    Stage 2 (steps 5-8): leftovers whose measurement centre lies inside the gate of radius
    mu_g around a prediction's centre; cost (1 - rho) + d / mu_g with d the centre
    distance; Hungarian method; accept only rho >= mu_rho.

    Pairs with rho < mu_rho are excluded before the Hungarian step, so a rejected best
    pair never blocks an acceptable alternative. Leaving a person unmatched costs 2 in
    both stages, the largest cost of an acceptable pair, so every acceptable pair competes
    and every acceptable isolated pair is matched (the Hungarian method of 3.3.2).

    Args:
        node_boxes: (B, 4) xywh predicted regions of the nodes.
        owners: (B,) int person index of each node, sorted, covering 0..P-1 (every
            person owns at least one node).
        sqrt_q: (P, K) element-wise square roots of the persons' appearance histograms q
            (eq. 1), possibly restricted to K of the bins, e.g. those where some p is
            nonzero (the other terms of eq. 4 are 0).
        measurement_boxes: (D, 4) xywh.
        sqrt_p: (D, K) square roots of the measurements' histograms p, same K bins.
        mu_rho: appearance threshold mu_rho in [0, 1], or (P,) one per person.
        mu_g: gate radius mu_g in pixels.
        delta: optional precomputed (B, D) region similarity of nodes and measurements.
        gated: optional (P,) bool: persons that may take part in stage 2 (default all).
        gate: optional (B,) gate radius of each node in pixels; the node's validation
            region is the circle of radius min(mu_g, gate) (default mu_g for every node).
        evidence: optional map (rho (P, D), admissible (P, D) bool) -> (P, D) appearance
            term a of stage 1, whose cost becomes (1 - a) + (1 - delta); default a = rho
            (e.g. ``rules.AppearanceMargin().evidence``).
        admissible: optional (B, D) bool: node-measurement pairs either stage may match
            (default all; e.g. ``shape_gate.ShapeGate``'s).
        barred: optional map (D,) bool measurements stage 1 matched -> (D,) bool
            measurements stage 2 may not match, or None (e.g. ``contact.SplitParts``).
    """
    owners = _checked_owners(owners, len(sqrt_q))
    n_persons, n_meas = len(sqrt_q), len(measurement_boxes)
    if n_persons == 0 or n_meas == 0:
        return Matches(np.zeros((0, 3), dtype=int), np.zeros(0, dtype=int), np.zeros(0),
                       np.arange(n_persons), np.arange(n_meas))
    rho = _rho(sqrt_q, sqrt_p)
    m1, best1, pairs = _stage1_compiled(node_boxes, owners, rho, measurement_boxes, mu_rho,
                                        admissible, delta, evidence)
    matched_p = np.zeros(n_persons, dtype=bool)
    matched_d = np.zeros(n_meas, dtype=bool)
    matched_p[m1[:, 0]] = True
    matched_d[m1[:, 1]] = True
    eligible = ~matched_p if gated is None else ~matched_p & np.asarray(gated, dtype=bool)
    m2, best2 = np.zeros((0, 2), dtype=int), None
    if eligible.any() and not matched_d.all():
        if pairs is None:  # the compiled stage 1 made none
            pairs = _Pairs.of(node_boxes, owners, rho, measurement_boxes, mu_rho, admissible)
        m2, best2 = _stage2(pairs, eligible, matched_d, mu_g, gate, barred)
        matched_p[m2[:, 0]] = True
        matched_d[m2[:, 1]] = True

    m12 = np.concatenate([m1, m2])
    nodes = np.concatenate([m[:, 0] if best is None else best[m[:, 0], m[:, 1]]
                            for m, best in ((m1, best1), (m2, best2))])
    return Matches(_rows(m12[:, 0], m12[:, 1], nodes),
                   np.array([1] * len(m1) + [2] * len(m2), dtype=int), rho[m12[:, 0], m12[:, 1]],
                   (~matched_p).nonzero()[0], (~matched_d).nonzero()[0])


@dataclass(frozen=True, slots=True)
class _Pairs:
    """What both stages read: the (B, 4) node and (D, 4) measurement boxes, the (B,) owner
    of each node and the (P,) first node of each person, rho (eq. 4) per (P, D) person and
    (B, D) node pair, and the (B, D) node pairs either stage may match (rho >= mu_rho,
    admissible)."""

    nodes: np.ndarray
    measurements: np.ndarray
    owners: np.ndarray
    starts: np.ndarray
    rho: np.ndarray
    rho_nodes: np.ndarray
    ok: np.ndarray

    @classmethod
    def of(cls, node_boxes: np.ndarray, owners: np.ndarray, rho: np.ndarray,
           measurement_boxes: np.ndarray, mu_rho: float | np.ndarray,
           admissible: np.ndarray | None) -> _Pairs:
        """``associate``'s arguments of the same names and rho (P, D) (``_rho``)."""
        n_persons = len(rho)
        one_node = len(owners) == n_persons  # nobody has hypotheses: node k is person k
        rho_nodes = rho if one_node else rho[owners]  # (B, D)
        if np.ndim(mu_rho):  # one threshold per person
            mu_rho = np.asarray(mu_rho, dtype=float)[owners][:, None]
        appearance_ok = rho_nodes >= mu_rho
        if admissible is not None:
            appearance_ok &= admissible
        starts = (np.arange(n_persons) if one_node
                  else np.searchsorted(owners, np.arange(n_persons)))
        return cls(node_boxes, measurement_boxes, owners, starts, rho, rho_nodes, appearance_ok)


def _rho(sqrt_q: np.ndarray, sqrt_p: np.ndarray) -> np.ndarray:
    """(P, D) eq. 4, rho = sum_u sqrt(q_u p_u), clipped to [0, 1]."""
    rho = sqrt_q @ sqrt_p.T
    return np.minimum(np.maximum(rho, 0.0, out=rho), 1.0, out=rho)


def _stage1_compiled(node_boxes: np.ndarray, owners: np.ndarray, rho: np.ndarray,
                     measurement_boxes: np.ndarray, mu_rho: float | np.ndarray,
                     admissible: np.ndarray | None, delta: np.ndarray | None,
                     evidence: Callable | None
                     ) -> tuple[np.ndarray, np.ndarray | None, _Pairs | None]:
    """``_stage1`` over ``_Pairs.of``'s pairs: with the evidence None, ``absolute_appearance``
    (the same costs: cost + (rho - rho)) or ``appearance_margin``, in one compiled pass
    (``_kernels.stage1_costs``, the same bits), the Hungarian method only where pairs
    compete; any other evidence by ``_stage1`` itself. Returns stage 1's rows, its best
    nodes and the ``_Pairs`` made (None: none was)."""
    if delta is None:
        delta = region_similarity(node_boxes, measurement_boxes)  # (B, D) eq. 5
    if not (evidence is None or evidence is absolute_appearance
            or evidence is appearance_margin):
        pairs = _Pairs.of(node_boxes, owners, rho, measurement_boxes, mu_rho, admissible)
        return (*_stage1(pairs, delta, evidence), pairs)
    n_persons, n_meas = rho.shape
    one_node = len(owners) == n_persons
    starts = (np.arange(n_persons) if one_node
              else np.searchsorted(owners, np.arange(n_persons)))
    mu = np.empty(n_persons)
    mu[:] = mu_rho  # one threshold, or one per person
    cost = np.empty((n_persons, n_meas))
    best = np.empty((n_persons, n_meas), dtype=np.int64)
    rows = np.empty((min(n_persons, n_meas), 2), dtype=np.int64)
    k = stage1_costs(rho, owners, starts, mu,
                     _NO_PAIRS if admissible is None else admissible, admissible is not None,
                     delta, evidence is appearance_margin, cost, best, rows)
    m1 = rows[:k] if k >= 0 else assign_min_cost(cost, 2.0)[0]
    return m1, None if one_node else best, None


_NO_PAIRS = np.zeros((1, 1), dtype=bool)
"""The kernel's placeholder ``admissible`` when every pair is."""


def _checked_owners(owners: np.ndarray, n_persons: int) -> np.ndarray:
    """``owners`` as an int array; ValueError unless sorted and covering 0..n_persons-1."""
    owners = np.asarray(owners, dtype=int)
    steps = owners[1:] - owners[:-1]
    if len(owners) and not (owners[0] == 0 and owners[-1] == n_persons - 1
                            and (len(steps) == 0 or (steps.min() >= 0 and steps.max() <= 1))):
        raise ValueError("associate: owners must be sorted and cover persons 0..P-1")
    return owners


def _stage1(s: _Pairs, delta: np.ndarray | None, evidence: Callable | None
            ) -> tuple[np.ndarray, np.ndarray | None]:
    """Stage 1 (steps 1-4): intersecting regions, cost (1 - rho) + (1 - delta) (eqs. 4-5),
    Hungarian method: (K, 2) rows (person, measurement) and ``_person_costs``' best nodes."""
    if delta is None:
        delta = region_similarity(s.nodes, s.measurements)  # (B, D) eq. 5
    c1 = np.where((delta > 0) & s.ok, (1.0 - s.rho_nodes) + (1.0 - delta), np.inf)
    cost1, best1 = _person_costs(c1, s.starts, s.owners)
    if evidence is not None:  # (1 - a) in place of (1 - rho); rho is one per person
        cost1 = cost1 + (s.rho - evidence(s.rho, np.isfinite(cost1)))
    return _hungarian(cost1, 2.0), best1


def _stage2(s: _Pairs, eligible: np.ndarray, matched_d: np.ndarray, mu_g: float,
            gate: np.ndarray | None, barred: Callable | None
            ) -> tuple[np.ndarray, np.ndarray | None]:
    """Stage 2 (steps 5-8): the ``eligible`` persons' nodes and the measurements stage 1
    left (``matched_d`` False, not ``barred``) inside the gate, cost (1 - rho) + d / mu_g,
    Hungarian method: (K, 2) rows (person, measurement) and the best nodes."""
    d = centre_distance_matrix(s.nodes, s.measurements)  # (B, D)
    free = eligible[s.owners][:, None] & ~matched_d[None, :]
    parts = None if barred is None else barred(matched_d)
    if parts is not None:
        free &= ~parts[None, :]
    radius = mu_g if gate is None else np.minimum(mu_g, np.asarray(gate, dtype=float))[:, None]
    c2 = np.where(free & (d <= radius) & s.ok, (1.0 - s.rho_nodes) + d / mu_g, np.inf)
    cost2, best2 = _person_costs(c2, s.starts, s.owners)
    return _hungarian(cost2, 2.0), best2
