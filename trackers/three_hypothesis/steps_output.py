"""The graph and the output (Reta 3.3, Alg. 1's AddNodeToGraph and AddEdgeToGraph): a node
per branch, and one ``Track`` per node of every person.
"""

from __future__ import annotations

import numpy as np

from occbench.trackers.common.measured_velocity import FilterPrediction, MeasuredVelocity
from occbench.trackers.records import Track, TrackState
from occbench.trackers.three_hypothesis.graph import HYPOTHESIS, TENTATIVE, VISIBLE
from occbench.trackers.three_hypothesis.rules import Rules
from occbench.trackers.three_hypothesis.state import Branch, Memory, Person


def add_node(memory: Memory, person: Person, branch: Branch, box: np.ndarray,
             parent: int | None, stage: int, rho: float) -> int:
    """AddNodeToGraph + AddEdgeToGraph for one branch of ``person`` at ``box`` (its region at
    t), the edge from node ``parent`` of t-1 (None: a new person) with the association's
    ``stage`` and ``rho`` (0, NaN: no match); returns the node key."""
    confirmed = person.confirmed
    if branch.kind == VISIBLE:
        kind = VISIBLE if confirmed else TENTATIVE
        hypothesis = None
    else:
        kind = HYPOTHESIS if confirmed else TENTATIVE
        hypothesis = branch.kind
    occluder = None if branch.occluder is None else memory.public.get(branch.occluder)
    x, y, w, h = box.tolist()
    node = memory.graph.add_node(
        person.key, person.public_id, kind, hypothesis,
        np.array([x + w / 2, y + h / 2, 0.0, w / 2, h / 2]), person.q, branch.x, branch.P,
        occluder, branch.depth, parent, stage, rho,
    )
    branch.graph_node = node
    return node.key


def outputs(persons: list[Person], t: int, rules: Rules) -> list[Track]:
    """One Track per node of every person of N^t (CONFIRMED, OCCLUDED, HYPOTHESIS,
    TENTATIVE: ``tracker``'s module docstring); a reported hidden person where
    ``rules.velocity`` places it."""
    out: list[Track] = []
    report = rules.report
    found, velocities = [], []
    for person in persons:
        branches = person.branches
        if branches[0].kind == VISIBLE:
            state = TrackState.CONFIRMED if person.confirmed else TrackState.TENTATIVE
            out.append(_track(person, branches[0], person.shape, state))
            if person.confirmed:
                found.append(out[-1])
                velocities.append(branches[0].x[4:6])
            continue
        if not person.confirmed:
            out.append(_track(person, branches[0], None, TrackState.TENTATIVE))
            continue
        best = rules.choice.choose([b.kind for b in branches],
                                   [b.exposed for b in branches],
                                   [b.covered for b in branches])
        if not report.reported(branches[best], person.hits, person.misses):
            best = -1  # drawn (HYPOTHESIS), not reported
        for k, b in enumerate(branches):
            state = TrackState.OCCLUDED if k == best else TrackState.HYPOTHESIS
            out.append(_track(person, b, None, state))
    _place_hidden(out, found, velocities, persons, t, rules.velocity)
    return out


def _place_hidden(out: list[Track], found: list[Track], velocities: list,
                  persons: list[Person], frame: int,
                  rule: FilterPrediction | MeasuredVelocity) -> None:
    """``rules.velocity`` (``rule``) at frame t: record the found people's boxes and filter
    velocities, and move the reported hidden people's boxes where their measured velocity
    wins."""
    rule.found(frame, [t.id for t in found],
               np.array([t.box for t in found]).reshape(-1, 4),
               np.array(velocities).reshape(-1, 2))
    hidden = [t for t in out if t.state == TrackState.OCCLUDED]
    if hidden:
        boxes = np.array([t.box for t in hidden])
        rule.place(frame, [t.id for t in hidden], boxes)
        for t, box in zip(hidden, boxes):
            t.box = box
    rule.forget({person.public_id for person in persons})


def _track(person: Person, branch: Branch, box: np.ndarray | None, state: TrackState) -> Track:
    """The Track of one node: at ``box`` (a measurement), else the box of its ellipse."""
    node = branch.graph_node
    S = node.S
    if box is None:
        xc, yc, _, rx, ry = S.tolist()
        box = np.array([xc - rx, yc - ry, 2 * rx, 2 * ry])
    else:
        box = np.array(box, dtype=np.float64)  # a copy: the caller may keep it
    extra = {"ellipse": S, "hypothesis": node.hypothesis, "occluder": node.occluder,
             "depth": node.depth, "node": node.key}
    return Track(person.public_id, box, state, 1.0, extra)
