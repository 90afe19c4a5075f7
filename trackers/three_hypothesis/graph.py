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
from functools import partial
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from occbench.trackers.common.checks import require

if TYPE_CHECKING:
    from occbench.trackers.three_hypothesis.appearance import Histogram

VISIBLE = "visible"
TENTATIVE = "tentative"
HYPOTHESIS = "hypothesis"


class Node(NamedTuple):
    """One node n^t_k of the tracking graph, as its layer keeps it (its key k and frame t are
    its place in the layer; its ellipse S, (5,) (xc, yc, phi, rx, ry) pixels, is computed for
    the whole layer at once from ``box``: ``TrackingGraph.ellipses``).

    Attributes:
        person: internal person key (stable, also for tentative tracks).
        id: public identity; negative (-person) while the track is tentative.
        kind: VISIBLE, TENTATIVE or HYPOTHESIS.
        hypothesis: for hypothesis nodes 'velocity', 'occluder' or 'still', else None.
        box: [x, y, w, h] the region the ellipse S is inscribed in, pixels.
        q: colour histogram (eq. 1, ``appearance.Histogram``: its occupied bins), shared
            with the person (frozen under occlusion).
        x: (8,) Kalman state (xc, yc, w, h, vx, vy, vw, vh); P: (8, 8) covariance (M).
        occluder: public id of the person this node is hidden behind, or None.
        depth: number of other people in front of this node (eq. 3), 0 = front.
        parent: key of the predecessor node, or None for a first node.
        stage: association stage (1 or 2) of a visible node, 0 otherwise.
        rho: appearance similarity (eq. 4) of the match, NaN otherwise.
    """

    person: int
    id: int
    kind: str
    hypothesis: str | None
    box: list
    q: Histogram
    x: np.ndarray
    P: np.ndarray
    occluder: int | None
    depth: int
    parent: int | None
    stage: int
    rho: float


def ellipses(boxes: np.ndarray) -> np.ndarray:
    """(N, 5) ellipses S = (xc, yc, phi, rx, ry) inscribed in (N, 4) xywh ``boxes``, phi = 0
    (``reading:axis_aligned_ellipses``)."""
    x, y, w, h = boxes.T
    S = np.zeros((len(boxes), 5))
    S[:, 0] = x + w / 2
    S[:, 1] = y + h / 2
    S[:, 3] = w / 2
    S[:, 4] = h / 2
    return S


@dataclass(slots=True)
class _Layer:
    """The nodes of frame t, keys ``first`` on; their ellipses once asked for."""

    frame: int
    first: int
    nodes: list[Node] = field(default_factory=list)
    S: np.ndarray | None = None

    def record(self, k: int) -> dict:
        """Plain record of the layer's k-th node (no arrays) for CSV/JSON export."""
        n = self.nodes[k]
        xc, yc, phi, rx, ry = self.S[k].tolist()
        return {
            "frame": self.frame, "node": self.first + k, "id": n.id, "kind": n.kind,
            "hypothesis": n.hypothesis or "", "xc": xc, "yc": yc, "phi": phi, "rx": rx,
            "ry": ry, "vx": float(n.x[4]), "vy": float(n.x[5]),
            "occluder": -1 if n.occluder is None else int(n.occluder),
            "depth": n.depth, "parent": -1 if n.parent is None else n.parent,
            "stage": n.stage, "rho": n.rho,
        }

    def edges(self) -> list[dict]:
        """Directed edges (n^{t-1}_i, n^t_j) into this layer: kind 'match' (similarity
        association) or 'hypothesis' (predicted successor of a missing or occluded person)."""
        return [{"frame": self.frame, "source": n.parent, "target": self.first + k,
                 "kind": "hypothesis" if n.kind == HYPOTHESIS else "match"}
                for k, n in enumerate(self.nodes) if n.parent is not None]


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
        self._layers.append(_Layer(frame, self._next_key))

    def add_node(self, *attributes) -> int:
        """AddNodeToGraph (+ AddEdgeToGraph from its parent): a new node in the current
        layer with the attributes of ``Node``, in that order; returns its key k."""
        layer = self._layers[-1]
        layer.nodes.append(Node(*attributes))
        layer.S = None
        self._next_key += 1
        return self._next_key - 1

    def add_nodes(self, *columns) -> int:
        """``add_node`` for several nodes at once: ``columns``, one sequence per attribute of
        ``Node`` in its order (node r's attributes their r-th items); returns the first
        node's key (node r's: that + r)."""
        require("add_nodes' columns", len(columns) == len(Node._fields),
                f"must be the {len(Node._fields)} of Node", len(columns))
        layer = self._layers[-1]
        count = len(layer.nodes)
        layer.nodes.extend(map(partial(tuple.__new__, Node), zip(*columns, strict=True)))
        layer.S = None
        first = self._next_key
        self._next_key += len(layer.nodes) - count
        return first

    def ellipses(self) -> tuple[np.ndarray, int]:
        """The current layer's ellipses S, (N, 5) in node order, and its first node's key
        (node k's S is row k - first)."""
        layer = self._layers[-1]
        if layer.S is None:
            boxes = np.array([n.box for n in layer.nodes], dtype=np.float64).reshape(-1, 4)
            layer.S = ellipses(boxes)
        return layer.S, layer.first

    def current_nodes(self) -> list[Node]:
        """The current layer's nodes, in key order."""
        return self._layers[-1].nodes

    def snapshot(self) -> dict:
        """Records of the current frame: {'frame', 'nodes': [...], 'edges': [...]}."""
        if not self._layers:
            return {"frame": 0, "nodes": [], "edges": []}
        layer = self._layers[-1]
        self.ellipses()
        return {
            "frame": layer.frame,
            "nodes": [layer.record(k) for k in range(len(layer.nodes))],
            "edges": layer.edges(),
        }

    @property
    def node_count(self) -> int:
        """Nodes held in memory (all kept layers)."""
        return sum(len(layer.nodes) for layer in self._layers)

    @property
    def edge_count(self) -> int:
        return sum(n.parent is not None for layer in self._layers for n in layer.nodes)

    def clear(self) -> None:
        self._layers.clear()
        self._next_key = 1
