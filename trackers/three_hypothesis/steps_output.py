"""The graph and the output (Reta 3.3, Alg. 1's AddNodeToGraph and AddEdgeToGraph): a node
per branch, and one ``Track`` per node of every person.
"""

from __future__ import annotations

import numpy as np

from occbench.trackers.common.measured_velocity import FilterPrediction, MeasuredVelocity
from occbench.trackers.records import Track, TrackState
from occbench.trackers.three_hypothesis.graph import (HYPOTHESIS, TENTATIVE, VISIBLE,
                                                      TrackingGraph)
from occbench.trackers.three_hypothesis.rules import Rules
from occbench.trackers.three_hypothesis.state import Branch, Memory, Person


def add_node(memory: Memory, person: Person, branch: Branch, box: np.ndarray,
             parent: int | None, stage: int, rho: float) -> int:
    """AddNodeToGraph + AddEdgeToGraph for one branch of ``person`` at ``box`` (its region at
    t), the edge from node ``parent`` of t-1 (None: a new person) with the association's
    ``stage`` and ``rho`` (0, NaN: no match); returns the node key."""
    add_nodes(memory, [person], [branch], [box.tolist()], [parent], [stage], [rho])
    return branch.node


def add_nodes(memory: Memory, people: list[Person], branches: list[Branch],
              boxes: list[list[float]], parents: list[int | None], stages: list[int],
              rhos: list[float], occluders: list[int | None] | None = None) -> None:
    """``add_node`` of many branches in one ``TrackingGraph.add_nodes`` call: row r is
    ``people[r]``'s ``branches[r]`` at ``boxes[r]`` (xywh list), the edge from
    ``parents[r]``; each branch's ``node`` becomes its key. ``occluders``: the occluders'
    public ids read earlier (step 6 reads each when it updates the person behind: a
    confirmation later in the frame does not change it); None: read now."""
    if occluders is None:
        public = memory.public
        occluders = [None if b.occluder is None else public.get(b.occluder) for b in branches]
    first = memory.graph.add_nodes(
        [person.key for person in people], [person.public_id for person in people],
        [(VISIBLE if b.kind == VISIBLE else HYPOTHESIS) if person.confirmed else TENTATIVE
         for person, b in zip(people, branches)],
        [None if b.kind == VISIBLE else b.kind for b in branches], boxes,
        [person.q for person in people], [b.x for b in branches], [b.P for b in branches],
        occluders, [b.depth for b in branches], parents, stages, rhos)
    for key, branch in enumerate(branches, first):
        branch.node = key


def outputs(persons: list[Person], t: int, rules: Rules, graph: TrackingGraph) -> list[Track]:
    """One Track per node of every person of N^t (CONFIRMED, OCCLUDED, HYPOTHESIS,
    TENTATIVE: ``tracker``'s module docstring), in person then branch order; a reported
    hidden person where ``rules.velocity`` places it."""
    report = rules.report
    rows: list[tuple[Person, Branch, TrackState]] = []
    measured: list[int] = []  # rows at their measurement (person.shape)
    for person in persons:
        branches = person.branches
        if branches[0].kind == VISIBLE:
            measured.append(len(rows))
            rows.append((person, branches[0],
                         TrackState.CONFIRMED if person.confirmed else TrackState.TENTATIVE))
            continue
        if not person.confirmed:
            rows.append((person, branches[0], TrackState.TENTATIVE))
            continue
        best = rules.choice.choose([b.kind for b in branches],
                                   [b.exposed for b in branches],
                                   [b.covered for b in branches])
        if not report.reported(branches[best], person.hits, person.misses):
            best = -1  # drawn (HYPOTHESIS), not reported
        for k, b in enumerate(branches):
            rows.append((person, b, TrackState.OCCLUDED if k == best else TrackState.HYPOTHESIS))
    out = _tracks(rows, measured, graph)
    _place_hidden(out, measured, [b for _, b, _ in rows], persons, t, rules.velocity)
    return out


def _tracks(rows: list[tuple[Person, Branch, TrackState]], measured: list[int],
            graph: TrackingGraph) -> list[Track]:
    """The Track of each row's node: at its person's measured region for the ``measured``
    rows, else the box of its ellipse S (all rows' S and boxes as whole-frame arrays)."""
    S_layer, first = graph.ellipses()
    keys = [b.node for _, b, _ in rows]
    S = S_layer[np.array(keys, dtype=np.int64) - first]
    xc, yc, rx, ry = S[:, 0], S[:, 1], S[:, 3], S[:, 4]
    boxes = np.stack([xc - rx, yc - ry, 2 * rx, 2 * ry], axis=1)
    if measured:
        boxes[measured] = np.concatenate([rows[r][0].shape for r in measured]
                                         ).reshape(-1, 4)
    nodes = graph.current_nodes()
    return [Track(person.public_id, box, state, 1.0,
                  {"ellipse": ellipse, "hypothesis": node.hypothesis, "occluder": node.occluder,
                   "depth": node.depth, "node": key})
            for (person, _, state), box, ellipse, key, node
            in zip(rows, boxes, S, keys, [nodes[key - first] for key in keys])]


def _place_hidden(out: list[Track], measured: list[int], branches: list[Branch],
                  persons: list[Person], frame: int,
                  rule: FilterPrediction | MeasuredVelocity) -> None:
    """``rules.velocity`` (``rule``) at frame t: record the found people's boxes and filter
    velocities, and move the reported hidden people's boxes where their measured velocity
    wins."""
    found = [r for r in measured if out[r].state == TrackState.CONFIRMED]
    rule.found(frame, [out[r].id for r in found],
               np.concatenate([out[r].box for r in found] or [np.zeros(0)]).reshape(-1, 4),
               np.concatenate([branches[r].x[4:6] for r in found] or [np.zeros(0)]
                              ).reshape(-1, 2))
    hidden = [t for t in out if t.state == TrackState.OCCLUDED]
    if hidden:
        boxes = np.concatenate([t.box for t in hidden]).reshape(-1, 4)
        rule.place(frame, [t.id for t in hidden], boxes)
        for t, box in zip(hidden, boxes):
            t.box = box
    rule.forget({person.public_id for person in persons})
