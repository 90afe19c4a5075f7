"""Three-hypothesis tracking graph (Reta et al., J. Electron. Imaging 24(1) 013015, 2015).

Algorithm 1 per frame t:
1. predict every node of frame t-1 with its motion model M (Kalman, 3.2); hypothesis nodes
   move by their case (3.3.3): keep velocity, follow the occluder, stand still;
2. occlusion relations O between predicted regions of different people (eq. 2, lambda);
3. measurements: ellipse S from each detection box (3.2), colour histogram q (eq. 1)
   over the ellipse, restricted to foreground pixels when a mask is given;
4. two-stage similarity association with the Hungarian method (3.3.2, eqs. 4, 5,
   mu_rho, mu_g);
5. depth order pi of every pair in O (eq. 3), inherited when neither is visible;
6. attribute update (3.3.3): a matched person not occluded takes the measurement's q, S
   and corrects M; a matched person behind another keeps q (or, with ``blend_visible``,
   blends in the measurement by the share of it left visible) and takes S from its
   prediction area corrected by the (possibly partial) measurement (the Kalman estimate:
   a bare prediction would carry a size rate nothing corrects); a person matched through
   a hypothesis keeps its id and loses its other hypotheses;
7. an unmatched person continues each hypothesis; at its first total occlusion (behind a
   visible person in O) hypotheses 2 (occluder) and 3 (still) are added;
8. an unmatched measurement starts a tentative track (3.3), confirmed after
   ``confirm_frames`` matches and dropped as a false positive after more than
   ``tentative_misses`` frames without one; a tentative track is matched in stage 1 only
   (it has no velocity yet to justify a jump through the gate). A track confirmed where a
   hidden person's hypothesis stands (IoU >= 0.5) is that person come back (the paper's
   Fig. 3, ID -14): the person keeps its id and its other hypotheses are pruned;
9. pruning after m frames (PruneHypothesis): a hypothesis in plain view (less than
   ``cover`` of its region hidden by a visible person) for m consecutive frames is
   contradicted by the missing detection and removed; a hypothesis whose centre leaves
   the image ends (the person left the scene); a person with no hypothesis left ends.

Adaptations of what the paper leaves open (also listed in the README):
* the person detector is whatever ``detector=`` provides; shapes are the axis-aligned
  ellipses inscribed in the boxes (phi = 0);
* pairs with rho < mu_rho are excluded before the Hungarian step rather than rejected
  after it, and leaving a person unmatched costs the largest acceptable pair cost, so a
  good pair is never split into two poor ones just to match more;
* "contradictory" hypotheses are read as hypotheses in plain view without a detection
  (``cover``), and their pruning as m such frames in a row;
* ``max_hidden`` bounds how long a hidden person is kept (the paper sets no limit);
* the stage-2 validation gate is the circle approximating each node's Kalman validation
  region: radius ``gate_sigmas`` x the larger standard deviation of its predicted centre
  (innovation covariance H P H' + R), capped at mu_g. A fixed radius in pixels is too wide
  for small, far people (a standing person's track jumps onto a neighbour whose own track
  is not yet confirmed), while the Kalman region grows with
  speed uncertainty and with every frame a person stays hidden (``gate_sigmas: 0`` gives
  the paper's fixed radius mu_g);
* ``blend_visible``: the appearance q of a matched person behind others is not kept
  constant but moved towards its measurement by the share v of the measured region left
  visible by the people in front (q <- (1 - v) q + v p, v = 1 - the largest share of the
  region one of them covers): v = 1 (absent from any occlusion) replaces q as the paper
  does, v -> 0 (fully hidden) keeps it constant as the paper does. A fully frozen q goes
  stale when an occlusion lasts: the person behind keeps an old model while the one in
  front, its model refreshed every frame, matches the hidden one's detection better
  whenever its own is missed, and takes it;
* eq. 3 on a tie or an unknown order puts the region with the lower bottom edge in front.
* ``foreground_support``: a hypothesis whose ellipse holds (almost) no foreground is seen
  to be empty (nobody is there to be occluded): it counts as in plain view, is pruned after
  m such frames and is never reported. A false alarm's track, or a person who left,
  otherwise left hypotheses reported on the bare floor (the paper's "hypotheses generated
  by FPs are eliminated", decided from the image rather than from time alone). For the
  same reason a detection on an (almost) empty region does not count towards confirming a
  tentative track: a false alarm that flickers on the bare floor never becomes a person;
* ``report_spread``: a hidden person's best hypothesis is reported only while its centre
  is known to within ``report_spread`` person widths (one standard deviation of the Kalman
  prediction); past that it stays in the graph (and can be re-identified) but is not
  reported: a box placed by a guess that uncertain is more often wrong than right;
* ``stage1_unmatched_cost`` (an option, off by default: 2, the paper's reading, where the
  Hungarian method matches every acceptable pair): leaving a person unmatched in stage 1
  may cost less, e.g. 1, the cost of a pair whose similarities rho and delta average 1/2.
  Stage 1 has no distance gate, and at 2 the Hungarian method trades one good pair and a
  person left over for two poor pairs (cost < 1 each): in crowds a person whose detection
  was missed takes a neighbour's and pushes the neighbour onto a third person's, and a
  hidden person comes back on a found neighbour's detection. A person left over in stage
  1 still competes in stage 2 inside its Kalman validation gate. At 1 crowds gain and
  real detections with badly placed boxes lose (docs/adaptations.md), so it stays 2;
* ``shape_estimate`` and ``foreground_histograms`` (see the arguments).

Output per person per frame: CONFIRMED (matched), OCCLUDED (the best hypothesis of a
hidden confirmed person: covered by a visible person first, then fewest frames in plain
view, then velocity > occluder > still; one in plain view for more than ``report_exposed``
frames is contradicted by the missing detection and only drawn), HYPOTHESIS (its other
hypotheses), TENTATIVE.
``Track.extra`` holds {'ellipse', 'hypothesis', 'occluder', 'depth', 'node'}.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from trackers.geometry import iou_matrix, valid_boxes
from trackers.records import Detections, Track, TrackState
from trackers.three_hypothesis import hypotheses as hyp
from trackers.three_hypothesis.appearance import EllipseHistogrammer
from trackers.three_hypothesis.association import associate
from trackers.three_hypothesis.graph import HYPOTHESIS, TENTATIVE, VISIBLE, Node, TrackingGraph
from trackers.three_hypothesis.motion import (
    MotionModel,
    box_measurements,
    correct,
    predict,
    state_boxes,
)
from trackers.three_hypothesis.occlusion import (
    boxes_meet,
    depth_order,
    region_overlaps,
)
from trackers.three_hypothesis.params import (
    Adaptations,
    Appearance,
    Association,
    LifeCycle,
    Occlusion,
)

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


class RetaTracker:
    """Three-hypothesis tracking graph with occlusion reasoning (Reta et al. 2015).

    Args:
        association: mu_rho and mu_g of the two-stage association (3.3.2).
        occlusion: lambda of eq. 2 and the integration of ellipse overlaps.
        appearance: histogram bins (eq. 1), foreground share, pixel stride.
        motion: Kalman noises of the motion model M (3.2).
        lifecycle: m (pruning), cover (contradicted hypotheses), confirm_frames.
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
        lifecycle: LifeCycle | None = None,
        adaptations: Adaptations | None = None,
        min_score: float = 0.0,
    ) -> None:
        self.association = association = association or Association()
        self.occlusion = occlusion = occlusion or Occlusion()
        self.appearance = appearance = appearance or Appearance()
        self.motion = motion or MotionModel()
        self.lifecycle = lifecycle = lifecycle or LifeCycle()
        self.adaptations = adaptations = adaptations or Adaptations()
        for name, group, kind in (("association", association, Association),
                                  ("occlusion", occlusion, Occlusion),
                                  ("appearance", appearance, Appearance),
                                  ("motion", self.motion, MotionModel),
                                  ("lifecycle", lifecycle, LifeCycle),
                                  ("adaptations", adaptations, Adaptations)):
            if not isinstance(group, kind):
                raise ValueError(f"{name}: expected a {kind.__name__}, got {group!r}")
        self.min_score = min_score
        self.mu_rho = association.mu_rho
        self.mu_g = association.mu_g
        self.lam = occlusion.lam
        self.region_samples = occlusion.region_samples
        self.m = lifecycle.m
        self.cover = lifecycle.cover
        self.confirm_frames = lifecycle.confirm_frames
        self.gate_sigmas = adaptations.gate_sigmas
        self.blend_visible = adaptations.blend_visible
        self.foreground_support = adaptations.foreground_support
        self.report_spread = adaptations.report_spread
        self.shape_estimate = adaptations.shape_estimate
        self.foreground_histograms = adaptations.foreground_histograms
        self.stage1_unmatched_cost = adaptations.stage1_unmatched_cost
        self.tentative_misses = adaptations.tentative_misses
        self.report_exposed = adaptations.report_exposed
        self.max_hidden = adaptations.max_hidden
        self.histograms = EllipseHistogrammer(bins=appearance.bins,
                                              min_foreground=appearance.min_foreground,
                                              stride=appearance.pixel_stride)
        _, _, self._F, self._H, _, _ = self.motion.init(np.array([0.0, 0.0, 10.0, 10.0]))
        self.reset()

    def reset(self) -> None:
        """Forget every person and the graph; ids restart at 1."""
        self._persons: list[_Person] = []
        self._next_key = 1
        self._next_id = 1
        self._frame = 0
        self._pi: dict[tuple[int, int], int] = {}
        self.graph = TrackingGraph(window=self.m + 1)

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
        keep = valid_boxes(detections.boxes) & (detections.scores >= self.min_score)
        dets = detections.boxes[keep]
        # eq. 1 per measurement (one array each); ``support``: the bins where some
        # measurement has pixels
        p, support = self.histograms.measure(
            frame, dets, foreground if self.foreground_histograms else None)
        persons = self._persons
        self._public = {person.key: person.public_id for person in persons}

        # 1. prediction of every node of t-1 (hypotheses move by their case, 3.3.3)
        branches = [b for person in persons for b in person.branches]
        owners = np.array([i for i, person in enumerate(persons) for _ in person.branches], dtype=int)
        if branches:
            x_prev = np.array([b.x for b in branches])
            P_prev = np.array([b.P for b in branches])
            kinds = [b.kind for b in branches]
            occ_v = np.zeros((len(branches), 2))  # read by 'occluder' hypotheses only
            if hyp.OCCLUDER in kinds:
                velocity = {person.key: person.branches[0].x[4:6] for person in persons}
                for r, b in enumerate(branches):
                    if b.kind == hyp.OCCLUDER and b.occluder in velocity:
                        occ_v[r] = velocity[b.occluder]
            x_set = hyp.set_motion(x_prev, kinds, occ_v)
            Qs = np.array([person.Q for person in persons for _ in person.branches])
            Xp, Pp = predict(x_set, P_prev, self._F, Qs)
            pred = state_boxes(Xp)
        else:
            x_prev = Xp = np.zeros((0, 8))
            Pp = np.zeros((0, 8, 8))
            pred = np.zeros((0, 4))
        # eq. 5 region similarity delta of the predictions against the measurements and
        # against each other (eq. 2's ratio is delta / 2), in one integration per frame
        nb = len(pred)
        regions = np.concatenate([pred, dets])
        near = boxes_meet(pred, regions)  # only meeting boxes can overlap
        # pairs i < j of nodes of different people: owners is sorted, so owner_i < owner_j
        near[:, :nb] &= owners[:, None] < owners[None, :]
        delta = region_overlaps(pred, regions, self.region_samples, near)
        rs = delta[:, nb:]

        # 2. occlusion relations O over predicted regions (eq. 2: ratio = delta / 2 > lambda,
        # as ``occlusion_pairs``; ``near`` holds its pairs i < j of different people)
        first, second = ((0.5 * delta[:, :nb] > self.lam) & near[:, :nb]).nonzero()

        # 4. two-stage association (3.3.2)
        # rho = sqrt(q) . sqrt(p) (eq. 4), summed over the support of the measurements only
        # (the other terms are 0)
        sqrt_q = np.sqrt(np.array([person.q[support] for person in persons]).reshape(
            len(persons), len(support)))
        sqrt_p = np.sqrt(np.array([h[support] for h in p]).reshape(len(dets), len(support)))
        assoc = associate(pred, owners, sqrt_q, dets, sqrt_p, self.mu_rho, self.mu_g,
                          delta=rs, sqrt_q=sqrt_q, sqrt_p=sqrt_p,
                          gated=np.array([person.confirmed for person in persons], dtype=bool),
                          gate=self._gate_radii(Pp, owners, persons),
                          stage1_unmatched_cost=self.stage1_unmatched_cost)
        matched_det = {pi: (d, n, s, r) for (pi, d, n), s, r
                       in zip(assoc.matches.tolist(), assoc.stages.tolist(), assoc.rho.tolist())}

        # 5. depth order pi (eq. 3) of the pairs in O; who is hidden behind whom
        visible_node = {matched_det[pi][1] for pi in matched_det}
        in_front: dict[int, list[int]] = {}  # node index -> person indices in front of it
        own = owners.tolist()
        boxes = pred.tolist()  # (B,) [x, y, w, h] lists: scalar work below
        for a, b in zip(first.tolist(), second.tolist()):
            i, j = own[a], own[b]
            ki, kj = persons[i].key, persons[j].key
            vi, vj = a in visible_node, b in visible_node
            shape_i = dets[matched_det[i][0]] if vi else boxes[a]
            prev = self._pi.get((ki, kj), 0)
            order = depth_order(vi, vj, shape_i, boxes[b], prev)
            if order == 0:  # unknown and neither visible: the lower region is in front
                order = 1 if boxes[a][1] + boxes[a][3] >= boxes[b][1] + boxes[b][3] else -1
            self._pi[(ki, kj)] = order
            self._pi[(kj, ki)] = -order
            if order > 0:
                in_front.setdefault(b, []).append(i)
            else:
                in_front.setdefault(a, []).append(j)

        # 6. attribute update of matched persons (3.3.3)
        rows = sorted(matched_det.items())
        absorbed: set[int] = set()  # hidden persons whose hypothesis a new track confirmed
        visible_boxes = np.zeros((0, 4))
        if rows:
            idx = np.array([n for _, (_, n, _, _) in rows])
            dbox = dets[[d for _, (d, _, _, _) in rows]]
            visible_boxes = dbox
            behind = np.array([n in in_front for _, (_, n, _, _) in rows])
            # every matched node corrects its motion model M with the whole measurement
            # (centre and size), so the size and its rate stay tied to what is measured
            z = box_measurements(dbox)
            Rs = np.array([persons[i].R for i, _ in rows])
            Xc, Pc = correct(Xp[idx], Pp[idx], z, self._H, Rs)
            # the region of a person behind another (3.3.3: "updated with the model of his
            # prediction area"): the prediction corrected by the (possibly partial)
            # measurement. The prediction alone drifts: its size rate could never be
            # corrected while hidden, so a person half behind another shrank or swelled.
            estimate = state_boxes(Xc).tolist()
            empty_dets: set[int] = set()
            if foreground is not None and self.foreground_support:
                tent = [d for i, (d, _, _, _) in rows if not persons[i].confirmed]
                if tent:
                    share = self.histograms.foreground_share(foreground, dets[tent])
                    empty_dets = {d for d, f in zip(tent, share.tolist())
                                  if f < self.histograms.min_foreground}
            visible_share = self._visible_share(rows, behind, dbox, dets, in_front, matched_det)
            for r, (i, (d, n, stage, rho)) in enumerate(rows):
                person = persons[i]
                if not behind[r]:
                    person.q = p[d]  # appearance updated only when not occluded
                    shape = dbox[r]
                else:
                    # the Kalman estimate (adaptation) or the bare prediction (the paper)
                    shape = np.array(estimate[r]) if self.shape_estimate else pred[n].copy()
                    if self.blend_visible:
                        v = visible_share[r]
                        if v > 0:
                            person.q = (1.0 - v) * person.q + v * p[d]
                if person.confirmed or d not in empty_dets:
                    person.hits += 1  # a detection on no foreground does not confirm
                person.misses = 0
                person.spawned = False
                if not person.confirmed and person.hits >= self.confirm_frames:
                    hidden = self._hypothesis_under(shape, persons, owners, pred, matched_det,
                                                    absorbed)
                    if hidden is not None:
                        # the tentative track confirms a hypothesis of a hidden person: that
                        # person keeps its id, its other hypotheses are pruned (Fig. 3, ID -14)
                        person.id = persons[hidden].id
                        absorbed.add(hidden)
                        log.debug("tentative %d confirms hidden person %d", person.key, person.id)
                    else:
                        person.id = self._next_id
                        self._next_id += 1
                    self._public[person.key] = person.id
                fronts = in_front.get(n, [])
                branch = _Branch(VISIBLE, Xc[r], Pc[r], depth=len(fronts),
                                 occluder=persons[fronts[0]].key if fronts else None)
                branch.node = self._add_node(person, branch, shape, branches[n].node, stage, rho)
                person.shape = shape
                person.branches = [branch]

        # 7. unmatched persons: continue each hypothesis, spawn at the first total occlusion
        pending: list[tuple[_Person, list[_Branch]]] = []
        sources: list[int] = []  # node of t-1 each new branch continues, -1 when spawned
        for i, person in enumerate(persons):
            if i in matched_det or i in absorbed:
                continue
            person.misses += 1
            new: list[_Branch] = []
            for n in (owners == i).nonzero()[0]:
                old = branches[n]
                kind = hyp.VELOCITY if old.kind == VISIBLE else old.kind
                fronts = in_front.get(n, [])
                occluder = old.occluder if kind == hyp.OCCLUDER else (
                    persons[fronts[0]].key if fronts else None)
                new.append(_Branch(kind, Xp[n], Pp[n], node=old.node, occluder=occluder,
                                   exposed=old.exposed, depth=len(fronts)))
                sources.append(int(n))
                seen = [f for f in fronts if f in matched_det]
                if person.confirmed and not person.spawned and seen:
                    # FirstOcclusion: hidden behind a visible person for the first time
                    occ = persons[seen[0]]
                    for kind2, x2 in hyp.spawn(x_prev[n], matched_velocity(occ)).items():
                        new.append(_Branch(kind2, x2, Pp[n].copy(), node=old.node,
                                           occluder=occ.key, depth=len(fronts)))
                        sources.append(-1)
                    person.spawned = True
            if not person.confirmed:
                del sources[len(sources) - len(new) + 1:]
                new = new[:1]
            pending.append((person, new))

        # 9. pruning after m frames: left the scene, contradicted in plain view, duplicates
        survivors = [persons[i] for i in sorted(matched_det)]
        if pending:
            hyp_boxes = state_boxes(np.array([b.x for _, new in pending for b in new]))
            gone = hyp.outside_image(hyp_boxes, width, height)
            src = np.array(sources)
            fraction = np.zeros(len(src))
            cont = src >= 0
            if len(visible_boxes) and cont.any():
                # continuing branches sit at their prediction: reuse eq. 5's delta
                d_cols = np.array([d for _, (d, _, _, _) in rows])
                delta = rs[src[cont]][:, d_cols]
                area_n = pred[src[cont], 2] * pred[src[cont], 3]
                area_v = visible_boxes[:, 2] * visible_boxes[:, 3]
                fraction[cont] = (delta * (area_n[:, None] + area_v[None, :]) / 2
                                  / np.maximum(area_n, 1e-9)[:, None]).max(axis=1)
            if (~cont).any():
                fraction[~cont] = covered_fraction(hyp_boxes[~cont], visible_boxes,
                                                   self.region_samples)
            cover = fraction >= self.cover
            unseen = np.zeros(len(cover), dtype=bool)
            if foreground is not None and self.foreground_support:
                # nobody can be seen where the region holds no foreground: the missing
                # detection is not explained by an occluder (adaptation)
                unseen = (self.histograms.foreground_share(foreground, hyp_boxes)
                          < self.histograms.min_foreground)
                cover &= ~unseen
            cover = cover.tolist()
            unseen = unseen.tolist()
            gone = gone.tolist()
            corners = hyp_boxes.tolist()
            k = 0
            for person, new in pending:
                kept: list[_Branch] = []
                kept_boxes: list[np.ndarray] = []
                kept_corners: list[list[float]] = []
                for b in new:
                    box, corner, g, c = hyp_boxes[k], corners[k], gone[k], cover[k]
                    b.unseen = unseen[k]
                    k += 1
                    b.covered = c
                    b.exposed = 0 if c else b.exposed + 1
                    if g or b.exposed >= self.m:
                        continue
                    if any(max(abs(u - v) for u, v in zip(corner, kc)) < 0.5
                           for kc in kept_corners):
                        continue  # the same place twice: keep the preferred kind
                    kept.append(b)
                    kept_boxes.append(box)
                    kept_corners.append(corner)
                if not person.confirmed and person.misses > self.tentative_misses:
                    kept = []  # false-positive track
                if person.misses > self.max_hidden:
                    kept = []
                if not kept:
                    log.debug("person %d ended at frame %d", person.public_id, self._frame)
                    continue
                person.branches = kept
                for b, box in zip(kept, kept_boxes):
                    b.node = self._add_node(person, b, box, b.node, 0, float("nan"))
                survivors.append(person)

        # 8. unmatched measurements start tentative tracks (3.3)
        for d in assoc.unmatched_measurements:
            x0, P0, _, _, Q0, R0 = self.motion.init(dets[d])
            person = _Person(self._next_key, p[d], Q0, R0,
                             [_Branch(VISIBLE, x0, P0)],
                             shape=dets[d])
            self._next_key += 1
            if self.confirm_frames <= 1:
                person.id = self._next_id
                self._next_id += 1
            person.branches[0].node = self._add_node(person, person.branches[0], dets[d], None,
                                                     0, float("nan"))
            survivors.append(person)

        alive = {person.key for person in survivors}
        if len(self._pi) > 4 * len(alive) ** 2 + 16:
            self._pi = {k: v for k, v in self._pi.items() if k[0] in alive and k[1] in alive}
        self._persons = survivors
        return self._outputs()

    # ------------------------------------------------------------------ helpers
    def _gate_radii(self, Pp: np.ndarray, owners: np.ndarray,
                    persons: list[_Person]) -> np.ndarray | None:
        """(B,) stage-2 gate radius of each predicted node: ``gate_sigmas`` times the larger
        standard deviation of its centre's innovation (P + R over xc, yc); None (every
        node gets mu_g) when ``gate_sigmas`` is 0."""
        if self.gate_sigmas <= 0 or len(Pp) == 0:
            return None
        r = np.array([person.R[0, 0] for person in persons])[owners]  # R = (sigma_z h)^2 I
        var = np.maximum(Pp[:, 0, 0], Pp[:, 1, 1]) + r
        return self.gate_sigmas * np.sqrt(var)

    def _visible_share(self, rows: list, behind: np.ndarray, dbox: np.ndarray,
                       dets: np.ndarray, in_front: dict, matched_det: dict) -> list[float]:
        """Per matched row, the share v of its measured region left visible by the matched
        people in front of it (1 - the largest share one of them covers; 1 for rows not
        behind anyone), all pairs integrated in one ``region_overlaps`` call."""
        share = [1.0] * len(rows)
        if not self.blend_visible or not behind.any():
            return share
        k = behind.nonzero()[0]
        near = np.zeros((len(k), len(dets)), dtype=bool)
        for a, r in enumerate(k.tolist()):
            n = rows[r][1][1]
            near[a, [matched_det[j][0] for j in in_front[n] if j in matched_det]] = True
        covered = covered_fraction(dbox[k], dets, self.region_samples, near)
        for a, r in enumerate(k.tolist()):
            share[r] = 1.0 - float(covered[a])
        return share

    def _hypothesis_under(self, shape: np.ndarray, persons: list[_Person], owners: np.ndarray,
                          pred: np.ndarray, matched: dict, taken: set[int]) -> int | None:
        """Index of the hidden confirmed person (unmatched this frame) one of whose
        hypotheses lies where a newly confirmed track stands (IoU >= 0.5), else None."""
        best, best_iou = None, 0.5
        ious = iou_matrix(shape[None], pred)[0].tolist()
        for i, iou in zip(owners.tolist(), ious):
            if i in matched or i in taken or not persons[i].confirmed:
                continue
            if iou >= best_iou:
                best, best_iou = i, iou
        return best

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
        out: list[Track] = []
        for person in self._persons:
            branches = person.branches
            if branches[0].kind == VISIBLE:
                state = TrackState.CONFIRMED if person.confirmed else TrackState.TENTATIVE
                out.append(self._track(person, branches[0], person.shape, state))
                continue
            if not person.confirmed:
                out.append(self._track(person, branches[0], None, TrackState.TENTATIVE))
                continue
            best = hyp.best_hypothesis([b.kind for b in branches], [b.exposed for b in branches],
                                       [b.covered for b in branches])
            top = branches[best]
            if top.unseen or (not top.covered and top.exposed > self.report_exposed):
                best = -1
            elif self.report_spread > 0 and (max(top.P[0, 0], top.P[1, 1])
                                             > (self.report_spread * top.x[2]) ** 2):
                best = -1  # centre no longer known to within report_spread widths  # in plain view without a detection: drawn, not reported
            for k, b in enumerate(branches):
                state = TrackState.OCCLUDED if k == best else TrackState.HYPOTHESIS
                out.append(self._track(person, b, None, state))
        return out

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


def covered_fraction(boxes: np.ndarray, visible: np.ndarray, samples: int = 24,
                     near: np.ndarray | None = None) -> np.ndarray:
    """(N,) largest fraction |S_i & S_v| / |S_i| of each hypothesis region S_i hidden by one
    visible region S_v (from eq. 5: |S_i & S_v| = delta (|S_i| + |S_v|) / 2); ``near``
    (N, M) bool restricts the visible regions each S_i is compared with (default: all)."""
    if len(boxes) == 0 or len(visible) == 0:
        return np.zeros(len(boxes))
    if near is not None:
        near = near & boxes_meet(boxes, visible)
    area_i = np.pi / 4 * boxes[:, 2] * boxes[:, 3]
    area_v = np.pi / 4 * visible[:, 2] * visible[:, 3]
    ratio = 0.5 * region_overlaps(boxes, visible, samples, near)  # eq. 2's ratio
    inter = ratio * (area_i[:, None] + area_v[None, :])
    return (inter / np.maximum(area_i, 1e-9)[:, None]).max(axis=1)


def matched_velocity(person: _Person) -> np.ndarray:
    """(2,) velocity (vx, vy) of a person's current (visible) node."""
    return person.branches[0].x[4:6].copy()
