"""The tracking graph G = <N, E> (Reta 3.3): nodes per person per frame and their edges.

N = No u Nh: visible nodes (a person matched by a measurement; tentative ones not yet
confirmed) and hypothesis nodes (where a missing or occluded person may be). Each node
n^t_k carries the attributes Atr = [id, S, q, M] of eq. 1 and Sec. 3.2. A directed edge
(n^{t-1}_i, n^t_j) joins a node to its successor: a similarity match when n^t_j is
visible, a hypothesis trajectory otherwise.

The graph is an output: ``snapshot`` gives the current frame's nodes and edges as plain
records (``occbench.report.graph`` writes and draws them). Only the last ``window`` frames
are kept, so memory stays flat however long the sequence.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np

from occbench.trackers.common.checks import require

VISIBLE = "visible"
TENTATIVE = "tentative"
HYPOTHESIS = "hypothesis"


@dataclass(slots=True)
class Node:
    """One node n^t_k of the tracking graph.

    Attributes:
        key: unique node number within a tracker run (k).
        frame: frame number t (1-based, counted by the tracker).
        person: internal person key (stable, also for tentative tracks).
        id: public identity; negative (-person) while the track is tentative.
        kind: VISIBLE, TENTATIVE or HYPOTHESIS.
        hypothesis: for hypothesis nodes 'velocity', 'occluder' or 'still', else None.
        S: (5,) ellipse (xc, yc, phi, rx, ry), pixels.
        q: (bins,) colour histogram (eq. 1), shared with the person (frozen under occlusion).
        x: (8,) Kalman state (xc, yc, w, h, vx, vy, vw, vh); P: (8, 8) covariance (M).
        occluder: public id of the person this node is hidden behind, or None.
        depth: number of other people in front of this node (eq. 3), 0 = front.
        parent: key of the predecessor node, or None for a first node.
        stage: association stage (1 or 2) of a visible node, 0 otherwise.
        rho: appearance similarity (eq. 4) of the match, NaN otherwise.
    """

    key: int
    frame: int
    person: int
    id: int
    kind: str
    hypothesis: str | None
    S: np.ndarray
    q: np.ndarray
    x: np.ndarray
    P: np.ndarray
    occluder: int | None = None
    depth: int = 0
    parent: int | None = None
    stage: int = 0
    rho: float = float("nan")

    def record(self) -> dict:
        """Plain record (no arrays but the shape) for CSV/JSON export."""
        xc, yc, phi, rx, ry = (float(v) for v in self.S)
        return {
            "frame": self.frame, "node": self.key, "id": self.id, "kind": self.kind,
            "hypothesis": self.hypothesis or "", "xc": xc, "yc": yc, "phi": phi, "rx": rx,
            "ry": ry, "vx": float(self.x[4]), "vy": float(self.x[5]),
            "occluder": -1 if self.occluder is None else int(self.occluder),
            "depth": self.depth, "parent": -1 if self.parent is None else self.parent,
            "stage": self.stage, "rho": self.rho,
        }


@dataclass(slots=True)
class Edge:
    """Directed edge (n^{t-1}_i, n^t_j): kind 'match' (similarity association) or
    'hypothesis' (predicted successor of a missing or occluded person)."""

    frame: int
    source: int
    target: int
    kind: str

    def record(self) -> dict:
        return {"frame": self.frame, "source": self.source, "target": self.target, "kind": self.kind}


@dataclass
class _Layer:
    frame: int
    nodes: list[Node] = field(default_factory=list)
    edges: list[Edge] = field(default_factory=list)


class TrackingGraph:
    """Sliding window over the last ``window`` frames of G.

    Args:
        window: frames kept (at least 1); older layers are pruned as new ones arrive.
    """

    def __init__(self, window: int) -> None:
        require("the graph's window (life_cycle.m + 1)", window >= 1, "must be >= 1", window)
        self._layers: deque[_Layer] = deque(maxlen=window)
        self._next_key = 1

    def begin_frame(self, frame: int) -> None:
        """Open the layer of frame t (drops the oldest layer beyond the window)."""
        self._layers.append(_Layer(frame))

    def add_node(self, *attributes, **named) -> Node:
        """AddNodeToGraph (+ AddEdgeToGraph from its parent): a new node in the current
        layer with the attributes of ``Node`` after ``key`` and ``frame`` (given in that
        order or by name); returns it."""
        layer = self._layers[-1]
        node = Node(self._next_key, layer.frame, *attributes, **named)
        self._next_key += 1
        layer.nodes.append(node)
        if node.parent is not None:
            kind = "hypothesis" if node.kind == HYPOTHESIS else "match"
            layer.edges.append(Edge(node.frame, node.parent, node.key, kind))
        return node

    def snapshot(self) -> dict:
        """Records of the current frame: {'frame', 'nodes': [...], 'edges': [...]}."""
        if not self._layers:
            return {"frame": 0, "nodes": [], "edges": []}
        layer = self._layers[-1]
        return {
            "frame": layer.frame,
            "nodes": [n.record() for n in layer.nodes],
            "edges": [e.record() for e in layer.edges],
        }

    @property
    def node_count(self) -> int:
        """Nodes held in memory (all kept layers)."""
        return sum(len(layer.nodes) for layer in self._layers)

    @property
    def edge_count(self) -> int:
        return sum(len(layer.edges) for layer in self._layers)

    def clear(self) -> None:
        self._layers.clear()
        self._next_key = 1
