"""What Reta's tracker keeps between frames as two column tables (docs/speed.md, "the node
table"): ``People``, one row a person in ``Memory.persons``' order, and ``Nodes``, one row a live node,
grouped by owner ascending and a person's rows in branch order (the order ``Predictions``
uses). ``of(persons)`` makes the tables from ``state.Person`` objects and
``persons(people, nodes)`` makes the objects back, equal field for field and type for type.

A node's kind is a code (``KIND``: 0 visible, then ``hypotheses.KINDS``); "none" is -1 in
the ``node`` and ``occluder`` columns. Tentative or not is ``People.id[owner] > 0``. The
ragged per-person records are padded rows with a count: a person's last measured centres
(``rules.line``, (frame, xc, yc)) and the rho of its last matches (``rules.returning``).
q stays a list of ``Histogram`` (its occupied bins; shared with the graph's nodes).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occbench.trackers.three_hypothesis import hypotheses as hyp
from occbench.trackers.three_hypothesis.appearance import Histogram
from occbench.trackers.three_hypothesis.graph import VISIBLE
from occbench.trackers.three_hypothesis.state import Branch, Person

NAMES = (VISIBLE, *hyp.KINDS)
"""A node's kind by its code: 0 visible, 1 velocity, 2 occluder, 3 still."""
KIND = {name: code for code, name in enumerate(NAMES)}


@dataclass(slots=True)
class Nodes:
    """The live nodes, B rows grouped by ``owner`` (a row of ``People``) ascending."""

    owner: np.ndarray  # (B,) int64 person row
    kind: np.ndarray  # (B,) int8 code of NAMES
    x: np.ndarray  # (B, 8) float64 Kalman states
    P: np.ndarray  # (B, 8, 8) float64 covariances
    node: np.ndarray  # (B,) int64 graph key of its node at t (-1 none)
    occluder: np.ndarray  # (B,) int64 key of the person followed / hidden behind (-1 none)
    exposed: np.ndarray  # (B,) int32 frames in a row in plain view without a detection
    covered: np.ndarray  # (B,) bool hidden behind a visible person this frame
    unseen: np.ndarray  # (B,) bool its region holds (almost) no foreground
    share: np.ndarray  # (B,) float64 foreground share of its ellipse
    depth: np.ndarray  # (B,) int32 people in front of it (eq. 3)

    def __len__(self) -> int:
        return len(self.owner)


@dataclass(slots=True)
class People:
    """The people, P rows (``Memory.persons``' order: matched at t, then hidden, then new)."""

    key: np.ndarray  # (P,) int64
    id: np.ndarray  # (P,) int64 public id once confirmed, 0 tentative
    hits: np.ndarray  # (P,) int32
    misses: np.ndarray  # (P,) int32
    spawned: np.ndarray  # (P,) bool occlusion hypotheses made in this hidden streak
    merged: np.ndarray  # (P,) bool its last measurement held a hidden partner
    shape: np.ndarray  # (P, 4) float64 xywh region of the last visible node
    Q: np.ndarray  # (P, 8, 8) float64
    R: np.ndarray  # (P, 4, 4) float64
    q: list[Histogram]  # P appearances (eq. 1)
    centres: np.ndarray  # (P, w, 3) float64 last measured (frame, xc, yc), oldest first
    n_centres: np.ndarray  # (P,) int64 rows of centres held
    line_errors: np.ndarray  # (P, 2) float64 M's, the line's
    step_error: np.ndarray  # (P,) float64
    matched_rho: np.ndarray  # (P, m) float64 rho of the last matches, oldest first
    n_rho: np.ndarray  # (P,) int64 rows of matched_rho held

    def __len__(self) -> int:
        return len(self.key)

    def public_id(self) -> np.ndarray:
        """(P,) int64 public ids: the id once confirmed, else -key."""
        return np.where(self.id > 0, self.id, -self.key)


def _padded(records: list[list], width: int) -> tuple[np.ndarray, np.ndarray]:
    """Ragged float records (each a list of ``width``-tuples, or of floats when ``width``
    is 0) as a zero-padded (P, w[, width]) array and the (P,) counts."""
    count = np.array([len(r) for r in records], dtype=np.int64)
    w = int(count.max()) if len(count) else 0
    out = np.zeros((len(records), w, width) if width else (len(records), w))
    for i, r in enumerate(records):
        if r:
            out[i, :len(r)] = r
    return out, count


def of(persons: list[Person]) -> tuple[People, Nodes]:
    """The tables of ``persons`` and their branches."""
    branches = [b for p in persons for b in p.branches]
    centres, n_centres = _padded([p.centres for p in persons], 3)
    rho, n_rho = _padded([p.matched_rho for p in persons], 0)
    people = People(
        key=np.array([p.key for p in persons], dtype=np.int64),
        id=np.array([p.id for p in persons], dtype=np.int64),
        hits=np.array([p.hits for p in persons], dtype=np.int32),
        misses=np.array([p.misses for p in persons], dtype=np.int32),
        spawned=np.array([p.spawned for p in persons], dtype=bool),
        merged=np.array([p.merged for p in persons], dtype=bool),
        shape=np.array([p.shape for p in persons], dtype=np.float64).reshape(-1, 4),
        Q=np.array([p.Q for p in persons], dtype=np.float64).reshape(-1, 8, 8),
        R=np.array([p.R for p in persons], dtype=np.float64).reshape(-1, 4, 4),
        q=[p.q for p in persons],
        centres=centres, n_centres=n_centres,
        line_errors=np.array([p.line_errors for p in persons], dtype=np.float64).reshape(-1, 2),
        step_error=np.array([p.step_error for p in persons], dtype=np.float64),
        matched_rho=rho, n_rho=n_rho)
    nodes = Nodes(
        owner=np.array([i for i, p in enumerate(persons) for _ in p.branches], dtype=np.int64),
        kind=np.array([KIND[b.kind] for b in branches], dtype=np.int8),
        x=np.array([b.x for b in branches], dtype=np.float64).reshape(-1, 8),
        P=np.array([b.P for b in branches], dtype=np.float64).reshape(-1, 8, 8),
        node=np.array([-1 if b.node is None else b.node for b in branches], dtype=np.int64),
        occluder=np.array([-1 if b.occluder is None else b.occluder for b in branches],
                          dtype=np.int64),
        exposed=np.array([b.exposed for b in branches], dtype=np.int32),
        covered=np.array([b.covered for b in branches], dtype=bool),
        unseen=np.array([b.unseen for b in branches], dtype=bool),
        share=np.array([b.share for b in branches], dtype=np.float64),
        depth=np.array([b.depth for b in branches], dtype=np.int32))
    return people, nodes


def persons(people: People, nodes: Nodes) -> list[Person]:
    """The ``Person`` objects (and their ``Branch`` objects) the tables hold, their arrays
    rows of the tables' (views: a step writing one writes the table)."""
    kind, node, occluder = nodes.kind.tolist(), nodes.node.tolist(), nodes.occluder.tolist()
    exposed, covered, unseen = nodes.exposed.tolist(), nodes.covered.tolist(), nodes.unseen.tolist()
    share, depth = nodes.share.tolist(), nodes.depth.tolist()
    branches = [Branch(NAMES[kind[r]], nodes.x[r], nodes.P[r],
                       node=None if node[r] < 0 else node[r],
                       occluder=None if occluder[r] < 0 else occluder[r], exposed=exposed[r],
                       covered=covered[r], unseen=unseen[r], share=share[r], depth=depth[r])
                for r in range(len(nodes))]
    bounds = np.searchsorted(nodes.owner, np.arange(len(people) + 1)).tolist()
    n_centres, n_rho = people.n_centres.tolist(), people.n_rho.tolist()
    hits, misses, ids = people.hits.tolist(), people.misses.tolist(), people.id.tolist()
    out = []
    for i, key in enumerate(people.key.tolist()):
        centres = [(int(f), x, y) for f, x, y in people.centres[i, :n_centres[i]].tolist()]
        out.append(Person(
            key, people.q[i], people.Q[i], people.R[i], branches[bounds[i]:bounds[i + 1]],
            shape=people.shape[i], id=ids[i], hits=hits[i], misses=misses[i],
            spawned=bool(people.spawned[i]), centres=centres,
            line_errors=people.line_errors[i].tolist(), step_error=float(people.step_error[i]),
            merged=bool(people.merged[i]), matched_rho=people.matched_rho[i, :n_rho[i]].tolist()))
    return out
