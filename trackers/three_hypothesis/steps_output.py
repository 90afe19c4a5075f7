"""The graph and the output (Reta 3.3, Alg. 1's AddNodeToGraph and AddEdgeToGraph): a node
per branch, and one ``Track`` per node of every person.
"""

from __future__ import annotations

import numpy as np

from occbench.trackers.records import Track, TrackState
from occbench.trackers.three_hypothesis.graph import HYPOTHESIS, TENTATIVE, VISIBLE
from occbench.trackers.three_hypothesis.state import Branch, Person


class OutputSteps:
    """``RetaTracker``'s graph nodes and tracks (a mixin: ``self`` is the tracker)."""

    def _add_node(self, person: Person, branch: Branch, box: np.ndarray,
                  parent: int | None, stage: int, rho: float) -> int:
        """AddNodeToGraph + AddEdgeToGraph for one branch; returns the node key."""
        confirmed = person.confirmed
        if branch.kind == VISIBLE:
            kind = VISIBLE if confirmed else TENTATIVE
            hypothesis = None
        else:
            kind = HYPOTHESIS if confirmed else TENTATIVE
            hypothesis = branch.kind
        occluder = None if branch.occluder is None else self._public.get(branch.occluder)
        x, y, w, h = box.tolist()
        node = self.graph.add_node(
            person.key, person.public_id, kind, hypothesis,
            np.array([x + w / 2, y + h / 2, 0.0, w / 2, h / 2]), person.q, branch.x, branch.P,
            occluder, branch.depth, parent, stage, rho,
        )
        branch.graph_node = node
        return node.key

    def _outputs(self) -> list[Track]:
        """One Track per node of every person (CONFIRMED, OCCLUDED, HYPOTHESIS, TENTATIVE:
        the module docstring); a reported hidden person where ``rules.velocity`` places it."""
        out: list[Track] = []
        report = self.rules.report
        found, velocities = [], []
        for person in self._persons:
            branches = person.branches
            if branches[0].kind == VISIBLE:
                state = TrackState.CONFIRMED if person.confirmed else TrackState.TENTATIVE
                out.append(self._track(person, branches[0], person.shape, state))
                if person.confirmed:
                    found.append(out[-1])
                    velocities.append(branches[0].x[4:6])
                continue
            if not person.confirmed:
                out.append(self._track(person, branches[0], None, TrackState.TENTATIVE))
                continue
            best = self.rules.choice.choose([b.kind for b in branches],
                                            [b.exposed for b in branches],
                                            [b.covered for b in branches])
            if not report.reported(branches[best], person.hits, person.misses):
                best = -1  # drawn (HYPOTHESIS), not reported
            for k, b in enumerate(branches):
                state = TrackState.OCCLUDED if k == best else TrackState.HYPOTHESIS
                out.append(self._track(person, b, None, state))
        self._place_hidden(out, found, velocities)
        return out

    def _place_hidden(self, out: list[Track], found: list[Track], velocities: list) -> None:
        """``rules.velocity``: record the found people's boxes and filter velocities, and
        move the reported hidden people's boxes where their measured velocity wins."""
        rule = self.rules.velocity
        rule.found(self._frame, [t.id for t in found],
                   np.array([t.box for t in found]).reshape(-1, 4),
                   np.array(velocities).reshape(-1, 2))
        hidden = [t for t in out if t.state == TrackState.OCCLUDED]
        if hidden:
            boxes = np.array([t.box for t in hidden])
            rule.place(self._frame, [t.id for t in hidden], boxes)
            for t, box in zip(hidden, boxes):
                t.box = box
        rule.forget({person.public_id for person in self._persons})

    @staticmethod
    def _track(person: Person, branch: Branch, box: np.ndarray | None, state: TrackState) -> Track:
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
