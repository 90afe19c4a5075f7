"""Three-hypothesis tracking graph (Reta et al., J. Electron. Imaging 24(1) 013015, 2015).

``RetaTracker.update`` is the body of Algorithm 1 for frame t, one method per step:

1. ``_measure``: V = PeopleDetection(I^t), each measurement's ellipse S and histogram p
   (3.2, eq. 1);
2. ``_predict``: S^{t|t-1} of every node of t-1 by its motion model M (Kalman, 3.2),
   hypotheses moving by their case (3.3.3);
3. ``_occlusions``: O = Occlusion(N^{t-1}, lambda) (3.3.1, eq. 2);
4. ``_associate``: MaxSimilarity in two stages (3.3.2, eqs. 4-5, mu_rho, mu_g);
5. ``_sort_occlusions``: pi = SortOcclusionTargets(O) (eq. 3), once visibility at t is
   known;
6. ``_update_matched``: UpdateAttributes(N_o^t) (3.3.3);
7. ``_continue_unmatched``: N_h1 for every unmatched person, N_h2 and N_h3 at its first
   total occlusion (Alg. 1, FirstOcclusion);
8. ``_prune``: PruneHypothesis(G, m);
9. ``_start_tracks``: an unmatched measurement starts a tentative track (3.3).

Readings of what the paper leaves open (not switchable): shapes are the axis-aligned
ellipses inscribed in the detection boxes (phi = 0); pairs with rho < mu_rho are excluded
before the Hungarian step, and leaving a person unmatched costs the largest acceptable pair
cost (``association``); "contradictory" hypotheses are those in plain view (less than
``LifeCycle.cover`` of the region hidden by a visible person) for m frames in a row; a
hypothesis whose centre leaves the image ends; eq. 3 on a tie or unknown order puts the
region with the lower bottom edge in front. Readings with a switch: ``LifeCycle``'s
``confirm_frames`` and ``reported_hypothesis``. The rules the paper does not have are
``params.Adaptations``, applied through ``rules``; ``docs/adaptations.md`` lists them all.

Output per person per frame: CONFIRMED (matched), OCCLUDED (one hypothesis of a hidden
confirmed person, ``rules.choice``; ``rules.ReportRule`` decides whether it is reported),
HYPOTHESIS (its other hypotheses), TENTATIVE. ``Track.extra`` holds {'ellipse',
'hypothesis', 'occluder', 'depth', 'node'}. Boxes are (N, 4) float64 xywh, 0-based pixels.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from trackers.common.checks import parameter_group
from trackers.geometry import valid_boxes
from trackers.records import Detections, Track, TrackState
from trackers.three_hypothesis import hypotheses as hyp
from trackers.three_hypothesis._kernels import depth_orders
from trackers.three_hypothesis.appearance import EllipseHistogrammer
from trackers.three_hypothesis.association import Matches, associate
from trackers.three_hypothesis.graph import HYPOTHESIS, TENTATIVE, VISIBLE, Node, TrackingGraph
from trackers.three_hypothesis.motion import MotionModel, box_measurements, state_boxes
from trackers.three_hypothesis.occlusion import (
    boxes_meet,
    covered_fraction,
    occlusion_pairs,
    region_overlaps,
)
from trackers.three_hypothesis.params import (
    Adaptations,
    Appearance,
    Association,
    LifeCycle,
    Occlusion,
)
from trackers.three_hypothesis.rules import build_rules

log = logging.getLogger(__name__)


@dataclass(slots=True)
class _Branch:
    """One live node of a person: kind is 'visible' or a hypothesis kind."""

    kind: str
    x: np.ndarray
    P: np.ndarray
    node: int | None = None  # graph key of the node in the last frame
    occluder: int | None = None  # person key followed / hidden behind
    exposed: int = 0  # consecutive frames in plain view without a detection
    covered: bool = False  # hidden behind a visible person this frame
    unseen: bool = False  # its region holds (almost) no foreground this frame
    share: float = 1.0  # foreground share of its ellipse (measured when ``rules.report`` asks)
    depth: int = 0  # people in front of this node (eq. 3)
    graph_node: Node | None = None  # this frame's graph node


@dataclass
class _Person:
    key: int
    q: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    branches: list[_Branch]
    shape: np.ndarray  # (4,) xywh region of the last visible node
    id: int = 0  # public id once confirmed
    hits: int = 1
    misses: int = 0
    spawned: bool = False  # occlusion hypotheses created in this hidden streak

    @property
    def confirmed(self) -> bool:
        return self.id > 0

    @property
    def public_id(self) -> int:
        return self.id if self.id > 0 else -self.key


@dataclass(slots=True)
class _Frame:
    """What the steps of one frame t share (Alg. 1's variables), filled step by step:
    ``_measure`` sets dets, p, support; ``_predict`` branches .. pred; ``_occlusions`` delta,
    near, pairs; ``_associate`` matches, matched; ``_sort_occlusions`` in_front;
    ``_update_matched`` visible, visible_dets and absorbed."""

    foreground: np.ndarray | None  # (H, W) mask or label image
    width: int
    height: int
    persons: list[_Person]  # tracked at t-1, in key order
    dets: np.ndarray = None  # (D, 4) measurements V
    p: list[np.ndarray] = None  # D histograms (eq. 1)
    support: np.ndarray = None  # (K,) bins where some p is nonzero
    branches: list[_Branch] = None  # the B nodes of t-1, grouped by person
    owners: np.ndarray = None  # (B,) person index of each node
    x_prev: np.ndarray = None  # (B, 8) states at t-1
    Xp: np.ndarray = None  # (B, 8) predicted states
    Pp: np.ndarray = None  # (B, 8, 8) predicted covariances
    pred: np.ndarray = None  # (B, 4) predicted regions S^{t|t-1}
    delta: np.ndarray = None  # (B, D) region similarity (eq. 5) of predictions and V
    near: np.ndarray = None  # (B, B + D) pairs whose boxes meet (node pairs: i < j, two people)
    pairs: np.ndarray = None  # O (eq. 2): (K, 2) node index rows (a, b), a < b
    matches: Matches = None
    matched: dict[int, tuple[int, int, int, float]] = None  # person -> (det, node, stage, rho)
    in_front: dict[int, list[int]] = field(default_factory=dict)  # node -> persons in front
    visible: np.ndarray = None  # (K, 4) measurements of the matched persons (the front)
    visible_dets: list[int] = field(default_factory=list)  # their measurement indices
    absorbed: set[int] = field(default_factory=set)  # hidden persons a new track confirmed


class RetaTracker:
    """Three-hypothesis tracking graph with occlusion reasoning (Reta et al. 2015).

    Args:
        association: mu_rho and mu_g of the two-stage association (3.3.2).
        occlusion: lambda of eq. 2 and the integration of ellipse overlaps.
        appearance: histogram bins (eq. 1), foreground share, pixel stride.
        motion: Kalman noises of the motion model M (3.2).
        life_cycle: m (pruning), cover (contradicted hypotheses), confirm_frames.
        adaptations: every rule of ours the paper does not have
            (``Adaptations.paper()``: the paper as written).
        min_score: detections below this score are ignored.
    """

    def __init__(
        self,
        association: Association | None = None,
        occlusion: Occlusion | None = None,
        appearance: Appearance | None = None,
        motion: MotionModel | None = None,
        life_cycle: LifeCycle | None = None,
        adaptations: Adaptations | None = None,
        min_score: float = 0.0,
    ) -> None:
        self.association = parameter_group("association", association, Association)
        self.occlusion = parameter_group("occlusion", occlusion, Occlusion)
        self.appearance = parameter_group("appearance", appearance, Appearance)
        self.motion = parameter_group("motion", motion, MotionModel)
        self.life_cycle = parameter_group("life_cycle", life_cycle, LifeCycle)
        self.adaptations = parameter_group("adaptations", adaptations, Adaptations)
        self.min_score = min_score
        self.histograms = EllipseHistogrammer(bins=self.appearance.bins,
                                              min_foreground=self.appearance.min_foreground,
                                              stride=self.appearance.pixel_stride)
        self.rules = build_rules(self.adaptations, self.histograms, self.motion, self.life_cycle)
        self.reset()

    def reset(self) -> None:
        """Forget every person and the graph; ids restart at 1."""
        self._persons: list[_Person] = []
        self._next_key = 1
        self._next_id = 1
        self._frame = 0
        self._pi: dict[tuple[int, int], int] = {}
        self.graph = TrackingGraph(window=self.life_cycle.m + 1)
        self.rules.velocity.reset()

    def graph_snapshot(self) -> dict:
        """The current frame's graph: {'frame', 'nodes': [records], 'edges': [records]}."""
        return self.graph.snapshot()

    # ------------------------------------------------------------------ update
    def update(
        self, frame: np.ndarray | None, detections: Detections, foreground: np.ndarray | None = None
    ) -> list[Track]:
        """Advance one frame (Alg. 1 body).

        Args:
            frame: (H, W, 3) uint8 image (needed for colour histograms).
            detections: person boxes of this frame.
            foreground: optional (H, W) bool mask or label image.
        Raises:
            ValueError: when ``frame`` is None or not an (H, W, 3) uint8 image.
        """
        if frame is None:
            raise ValueError("RetaTracker needs frame pixels (colour histograms); got frame=None")
        if frame.ndim != 3 or frame.shape[2] != 3 or frame.dtype != np.uint8:
            raise ValueError(f"RetaTracker: frame must be (H, W, 3) uint8, got {frame.shape} {frame.dtype}")
        height, width = frame.shape[:2]
        if foreground is not None and foreground.shape[:2] != (height, width):
            raise ValueError(f"RetaTracker: foreground shape {foreground.shape} != frame {(height, width)}")
        self._frame += 1
        self.graph.begin_frame(self._frame)
        self._public = {person.key: person.public_id for person in self._persons}
        f = _Frame(foreground, width, height, self._persons)
        self._measure(f, frame, detections)
        self._predict(f)
        self._occlusions(f)
        self._associate(f)
        self._sort_occlusions(f)
        survivors = self._update_matched(f)
        survivors += self._prune(f, *self._continue_unmatched(f))
        survivors += self._start_tracks(f)
        alive = {person.key for person in survivors}
        if len(self._pi) > 4 * len(alive) ** 2 + 16:
            self._pi = {k: v for k, v in self._pi.items() if k[0] in alive and k[1] in alive}
        self._persons = survivors
        return self._outputs()

    # ------------------------------------------------------------------ Alg. 1, steps
    def _measure(self, f: _Frame, frame: np.ndarray, detections: Detections) -> None:
        """V = PeopleDetection(I^t) (3.1-3.2): the detections kept and, per measurement,
        its histogram p over the ellipse S inscribed in its box (eq. 1), and ``support``,
        the bins where some measurement has pixels."""
        keep = valid_boxes(detections.boxes) & (detections.scores >= self.min_score)
        f.dets = detections.boxes[keep]
        f.p, f.support = self.histograms.measure(frame, f.dets, self.rules.pixels.mask(f.foreground))

    def _predict(self, f: _Frame) -> None:
        """S^{t|t-1} of every node of t-1 (3.2: Kalman x = F x, P = F P F' + Q); hypotheses
        first take the velocity of their case (3.3.3): keep it, the occluder's, or none."""
        persons = f.persons
        f.branches = branches = [b for person in persons for b in person.branches]
        f.owners = np.array([i for i, person in enumerate(persons) for _ in person.branches],
                            dtype=int)
        if not branches:
            f.x_prev = f.Xp = np.zeros((0, 8))
            f.Pp = np.zeros((0, 8, 8))
            f.pred = np.zeros((0, 4))
            return
        f.x_prev = np.array([b.x for b in branches])
        P_prev = np.array([b.P for b in branches])
        kinds = [b.kind for b in branches]
        occ_v = np.zeros((len(branches), 2))  # read by 'occluder' hypotheses only
        if hyp.OCCLUDER in kinds:
            velocity = {person.key: person.branches[0].x[4:6] for person in persons}
            for r, b in enumerate(branches):
                if b.kind == hyp.OCCLUDER and b.occluder in velocity:
                    occ_v[r] = velocity[b.occluder]
        x_set = hyp.set_motion(f.x_prev, kinds, occ_v)
        Qs = np.array([person.Q for person in persons])[f.owners]
        f.Xp, f.Pp = self.rules.motion.predict(x_set, P_prev, Qs)
        f.pred = state_boxes(f.Xp)

    def _occlusions(self, f: _Frame) -> None:
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

    def _associate(self, f: _Frame) -> None:
        """MaxSimilarity (3.3.2): stage 1 over intersecting regions, cost (1 - rho) +
        (1 - delta); stage 2 inside each node's validation gate, cost (1 - rho) + d / mu_g;
        rho = sqrt(q) . sqrt(p) (eq. 4), summed over the measurements' bins only (the other
        terms are 0)."""
        persons, support = f.persons, f.support
        sqrt_q = np.sqrt(np.array([person.q[support] for person in persons]).reshape(
            len(persons), len(support)))
        sqrt_p = np.sqrt(np.array([h[support] for h in f.p]).reshape(len(f.dets), len(support)))
        R = np.array([person.R[0, 0] for person in persons])[f.owners]  # R = (sigma_z h)^2 I
        a = self.association
        f.matches = m = associate(
            f.pred, f.owners, sqrt_q, f.dets, sqrt_p, a.mu_rho, a.mu_g, delta=f.delta,
            gated=self.rules.stage2.entrants(
                np.array([person.confirmed for person in persons], dtype=bool)),
            gate=self.rules.gate.radii(f.Pp, R),
            evidence=self.rules.stage1_appearance.evidence)
        f.matched = {pi: (d, n, s, r) for (pi, d, n), s, r
                     in zip(m.matches.tolist(), m.stages.tolist(), m.rho.tolist())}

    def _sort_occlusions(self, f: _Frame) -> None:
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

    def _update_matched(self, f: _Frame) -> list[_Person]:
        """UpdateAttributes(N_o^t) (3.3.3) of every matched person, in person order.

        M is corrected by the measurement (``rules.motion``; one behind others by
        ``rules.motion_behind``). A person absent from any occlusion takes the measurement's
        q and S; one behind another keeps q and takes S from its prediction area
        (``rules.appearance_behind`` and ``rules.shape_behind``). A person matched through a
        hypothesis keeps its id and loses its other hypotheses; a tentative track is
        confirmed after ``confirm_frames`` matches, with the id ``rules.identity`` gives."""
        rows = sorted(f.matched.items())
        f.visible = np.zeros((0, 4))
        if not rows:
            return []
        persons, dets, p, pred, in_front = f.persons, f.dets, f.p, f.pred, f.in_front
        rules = self.rules
        idx = np.array([n for _, (_, n, _, _) in rows])
        f.visible_dets = [d for _, (d, _, _, _) in rows]
        f.visible = dbox = dets[f.visible_dets]
        behind = np.array([n in in_front for _, (_, n, _, _) in rows])
        z = box_measurements(dbox)
        Rs = np.array([persons[i].R for i, _ in rows])
        predicted = f.Xp[idx], f.Pp[idx]
        Xc, Pc = rules.motion_behind.update(rules.motion.correct(*predicted, z, Rs), predicted,
                                            behind)  # x = x + K y, Joseph P
        estimate = state_boxes(Xc).tolist()
        tent = [d for i, (d, _, _, _) in rows if not persons[i].confirmed]
        empty = rules.support.empty(f.foreground, dets[tent]) if tent else None
        # a detection on no foreground does not confirm a tentative track
        empty_dets = set() if empty is None else {d for d, e in zip(tent, empty.tolist()) if e}
        visible_share = self._visible_share(f, rows, behind)
        for r, (i, (d, n, stage, rho)) in enumerate(rows):
            person = persons[i]
            if not behind[r]:
                person.q = p[d]
                shape = dbox[r]
            else:
                shape = rules.shape_behind.region(estimate[r], pred[n])
                person.q = rules.appearance_behind.update(person.q, p[d], visible_share[r])
            if person.confirmed or d not in empty_dets:
                person.hits += 1
            person.misses = 0
            person.spawned = False
            if not person.confirmed and person.hits >= self.life_cycle.confirm_frames:
                self._confirm(f, person, shape)
            fronts = in_front.get(n, [])
            branch = _Branch(VISIBLE, Xc[r], Pc[r], depth=len(fronts),
                             occluder=persons[fronts[0]].key if fronts else None)
            branch.node = self._add_node(person, branch, shape, f.branches[n].node, stage, rho)
            person.shape = shape
            person.branches = [branch]
        return [persons[i] for i in sorted(f.matched)]

    def _continue_unmatched(self, f: _Frame) -> tuple[list, list[int]]:
        """Alg. 1's loop over a_i in N^{t-1} \\ Assoc: every unmatched person continues each
        hypothesis (N_h1: a visible node becomes 'velocity', keeping its velocity and
        direction); at its first total occlusion (FirstOcclusion: behind a person visible
        at t) a confirmed person also gets N_h2 (follows the occluder) and N_h3 (stands
        still). A tentative track keeps one branch.

        Returns:
            (person, new branches) per unmatched person, and per new branch the node of
            t-1 it continues (-1 when spawned).
        """
        persons, matched, in_front = f.persons, f.matched, f.in_front
        pending: list[tuple[_Person, list[_Branch]]] = []
        sources: list[int] = []
        # owners is sorted: person i owns nodes bounds[i]:bounds[i + 1]
        bounds = np.searchsorted(f.owners, np.arange(len(persons) + 1)).tolist()
        for i, person in enumerate(persons):
            if i in matched or i in f.absorbed:
                continue
            person.misses += 1
            new: list[_Branch] = []
            for n in range(bounds[i], bounds[i + 1]):
                old = f.branches[n]
                kind = hyp.VELOCITY if old.kind == VISIBLE else old.kind
                fronts = in_front.get(n, [])
                occluder = old.occluder if kind == hyp.OCCLUDER else (
                    persons[fronts[0]].key if fronts else None)
                new.append(_Branch(kind, f.Xp[n], f.Pp[n], node=old.node, occluder=occluder,
                                   exposed=old.exposed, depth=len(fronts)))
                sources.append(n)
                seen = [j for j in fronts if j in matched]
                if person.confirmed and not person.spawned and seen:
                    occ = persons[seen[0]]
                    velocity = occ.branches[0].x[4:6].copy()  # the occluder's visible node
                    for kind2, x2 in hyp.spawn(f.x_prev[n], velocity).items():
                        new.append(_Branch(kind2, x2, f.Pp[n].copy(), node=old.node,
                                           occluder=occ.key, depth=len(fronts)))
                        sources.append(-1)
                    person.spawned = True
            if not person.confirmed:
                del sources[len(sources) - len(new) + 1:]
                new = new[:1]
            pending.append((person, new))
        return pending, sources

    def _prune(self, f: _Frame, pending: list, sources: list[int]) -> list[_Person]:
        """PruneHypothesis(G, m): a hypothesis whose centre left the image ends; one in
        plain view (less than ``cover`` of it hidden by a person visible at t, or, with
        ``rules.support``, seen empty) for m frames in a row is contradicted by the missing
        detection and removed (with ``rules.presence``, frames it spends on foreground do not
        count); of two at the same place ``rules.duplicates`` may keep one; a
        tentative track missed more than ``tentative_misses`` frames is a false positive;
        a person hidden more than ``max_hidden`` frames, or with no hypothesis left, ends.
        Returns the persons kept, their hypotheses added to the graph."""
        if not pending:
            return []
        hyp_boxes = state_boxes(np.array([b.x for _, new in pending for b in new]))
        gone = hyp.outside_image(hyp_boxes, f.width, f.height).tolist()
        cover = (self._hidden_share(f, hyp_boxes, np.array(sources))
                 >= self.life_cycle.cover)
        empty = self.rules.support.empty(f.foreground, hyp_boxes)
        held = self.rules.presence.held(f.foreground, hyp_boxes, empty)
        share = self.rules.report.shares(self.histograms, f.foreground, hyp_boxes)
        held = [False] * len(cover) if held is None else held.tolist()
        if empty is None:
            unseen = np.zeros(len(cover), dtype=bool)
        else:  # nobody can be seen where the region holds no foreground
            unseen = empty
            cover &= ~unseen
        cover, unseen, corners = cover.tolist(), unseen.tolist(), hyp_boxes.tolist()
        m, a = self.life_cycle.m, self.adaptations
        survivors: list[_Person] = []
        k = 0
        for person, new in pending:
            kept: list[_Branch] = []
            kept_boxes: list[np.ndarray] = []
            kept_corners: list[list[float]] = []
            for b in new:
                box, corner, g, c, held_k = hyp_boxes[k], corners[k], gone[k], cover[k], held[k]
                b.unseen = unseen[k]
                b.share = 1.0 if share is None else float(share[k])
                k += 1
                b.covered = c
                b.exposed = 0 if c else b.exposed + (0 if held_k else 1)
                if g or b.exposed >= m:
                    continue
                if kept_corners and self.rules.duplicates.duplicate(corner, kept_corners):
                    continue
                kept.append(b)
                kept_boxes.append(box)
                kept_corners.append(corner)
            if not person.confirmed and person.misses > a.tentative_misses:
                kept = []  # false-positive track
            if person.misses > a.max_hidden:
                kept = []
            if not kept:
                log.debug("person %d ended at frame %d", person.public_id, self._frame)
                continue
            person.branches = kept
            for b, box in zip(kept, kept_boxes):
                b.node = self._add_node(person, b, box, b.node, 0, float("nan"))
            survivors.append(person)
        return survivors

    def _start_tracks(self, f: _Frame) -> list[_Person]:
        """Each unmatched measurement starts a tentative track (3.3), confirmed in later
        frames (at once when ``confirm_frames`` is 1)."""
        out: list[_Person] = []
        for d in f.matches.unmatched_measurements:
            x0, P0, Q0, R0 = self.rules.motion.init(f.dets[d])
            person = _Person(self._next_key, f.p[d], Q0, R0, [_Branch(VISIBLE, x0, P0)],
                             shape=f.dets[d])
            self._next_key += 1
            if self.life_cycle.confirm_frames <= 1:
                person.id = self._next_id
                self._next_id += 1
            person.branches[0].node = self._add_node(person, person.branches[0], f.dets[d],
                                                     None, 0, float("nan"))
            out.append(person)
        return out

    # ------------------------------------------------------------------ helpers
    def _visible_share(self, f: _Frame, rows: list, behind: np.ndarray) -> list[float]:
        """Per matched row, the share v of its measured region left visible by the matched
        people in front of it (1 - the largest share one of them covers; 1 for rows not
        behind anyone), all pairs integrated in one ``region_overlaps`` call. Only
        computed for a rule that reads it."""
        share = [1.0] * len(rows)
        if not self.rules.appearance_behind.uses_visible_share or not behind.any():
            return share
        k = behind.nonzero()[0]
        near = np.zeros((len(k), len(f.dets)), dtype=bool)
        for a, r in enumerate(k.tolist()):
            n = rows[r][1][1]
            near[a, [f.matched[j][0] for j in f.in_front[n] if j in f.matched]] = True
        covered = covered_fraction(f.visible[k], f.dets, self.occlusion.region_samples, near)
        for a, r in enumerate(k.tolist()):
            share[r] = 1.0 - float(covered[a])
        return share

    def _hidden_share(self, f: _Frame, boxes: np.ndarray, src: np.ndarray) -> np.ndarray:
        """(N,) largest share of each new hypothesis region hidden by one person visible at
        t. A branch that continues node ``src`` sits at its prediction, whose eq. 5 delta
        against every measurement is known: |S_n & S_v| = delta (|S_n| + |S_v|) / 2;
        spawned ones (src -1) are integrated."""
        fraction = np.zeros(len(src))
        cont = src >= 0
        visible = f.visible
        if len(visible) and cont.any():
            delta = f.delta[src[cont]][:, np.array(f.visible_dets)]
            pred = f.pred
            area_n = pred[src[cont], 2] * pred[src[cont], 3]
            area_v = visible[:, 2] * visible[:, 3]
            fraction[cont] = (delta * (area_n[:, None] + area_v[None, :]) / 2
                              / np.maximum(area_n, 1e-9)[:, None]).max(axis=1)
        if (~cont).any():
            fraction[~cont] = covered_fraction(boxes[~cont], visible,
                                               self.occlusion.region_samples)
        return fraction

    def _confirm(self, f: _Frame, person: _Person, shape: np.ndarray) -> None:
        """A tentative track reaches ``confirm_frames``: it takes a new id, or (by
        ``rules.identity``) the id of a hidden confirmed person, unmatched this frame, one of
        whose hypotheses lies where it stands; that person's hypotheses then end."""
        persons = f.persons
        candidate = np.array([person.confirmed and i not in f.matched and i not in f.absorbed
                              for i, person in enumerate(persons)], dtype=bool)
        best = self.rules.identity.returning(shape, f.pred, f.owners, candidate)
        if best is not None:
            person.id = persons[best].id
            f.absorbed.add(best)
            log.debug("tentative %d confirms hidden person %d", person.key, person.id)
        else:
            person.id = self._next_id
            self._next_id += 1
        self._public[person.key] = person.id

    def _add_node(self, person: _Person, branch: _Branch, box: np.ndarray,
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
            if not report.reported(branches[best]):
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
    def _track(person: _Person, branch: _Branch, box: np.ndarray | None, state: TrackState) -> Track:
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
