"""Three-hypothesis tracking graph (Reta et al., J. Electron. Imaging 24(1) 013015, 2015).

``RetaTracker.update`` is the body of Algorithm 1 for frame t, one call per step (the steps
live in one module per part of the paper, ``steps_*``; steps 1-5 are functions of the
values of the steps before them, each returning a frozen value of ``values``; steps 6-9
are still methods mixed into the class):

1. ``measure``: V = PeopleDetection(I^t), each measurement's ellipse S and histogram p
   (3.2, eq. 1): ``Measurements``;
2. ``predict``: S^{t|t-1} of every node of t-1 by its motion model M (Kalman, 3.2),
   hypotheses moving by their case (3.3.3): ``Predictions``;
3. ``occlusions``: O = Occlusion(N^{t-1}, lambda) (3.3.1, eq. 2): ``Occlusions``;
4. ``max_similarity``: MaxSimilarity in two stages (3.3.2, eqs. 4-5, mu_rho, mu_g):
   ``Matching``, a ``Match`` (det, node, stage, rho) per matched person;
5. ``sort_occlusions``: pi = SortOcclusionTargets(O) (eq. 3), once visibility at t is
   known: ``DepthOrder``;
6. ``_update_matched``: UpdateAttributes(N_o^t) (3.3.3);
7. ``_continue_unmatched``: N_h1 for every unmatched person, N_h2 and N_h3 at its first
   total occlusion (Alg. 1, FirstOcclusion);
8. ``_prune``: PruneHypothesis(G, m);
9. ``_start_tracks``: an unmatched measurement starts a tentative track (3.3).

Readings of what the paper leaves open (not switchable; each a row of
``docs/adaptations.md``): shapes are the axis-aligned ellipses inscribed in the detection
boxes, phi = 0 (``reading:axis_aligned_ellipses``); pairs with rho < mu_rho are excluded
before the Hungarian step, and leaving a person unmatched costs the largest acceptable pair
cost (``reading:mu_rho_first``); the Hungarian step pairs persons, not nodes, with
measurements (``reading:person_level_hungarian``); FirstOcclusion is the first frame of an
unmatched spell behind a person matched at t (``reading:first_occlusion``); "contradictory"
hypotheses are those in plain view (less than ``life_cycle.cover`` of the region hidden by a
visible person) for m frames in a row; a hypothesis whose centre leaves the image ends
(``reading:image_exit``); eq. 3 on a tie or unknown order puts the region with the lower
bottom edge in front (``reading:eq3_tie``). Readings with a switch:
``life_cycle.confirm_frames`` and ``life_cycle.reported_hypothesis``. The rules the paper does
not have are ``params.Adaptations``, applied through ``rules``; ``docs/adaptations.md``
lists them all.

Output per person per frame: CONFIRMED (matched), OCCLUDED (one hypothesis of a hidden
confirmed person, ``rules.choice``; ``reported.ReportRule`` decides whether it is reported),
HYPOTHESIS (its other hypotheses), TENTATIVE. ``Track.extra`` holds {'ellipse',
'hypothesis', 'occluder', 'depth', 'node'}. Boxes are (N, 4) float64 xywh, 0-based pixels.
"""

from __future__ import annotations

import numpy as np

from occbench.trackers.common.checks import parameter_group
from occbench.trackers.records import Detections, Track
from occbench.trackers.three_hypothesis.appearance import EllipseHistogrammer
from occbench.trackers.three_hypothesis.graph import TrackingGraph
from occbench.trackers.three_hypothesis.motion import MotionModel
from occbench.trackers.three_hypothesis.params import (
    Adaptations,
    Appearance,
    Association,
    LifeCycle,
    Occlusion,
)
from occbench.trackers.three_hypothesis.rules import build_rules
from occbench.trackers.three_hypothesis.state import Person
from occbench.trackers.three_hypothesis.steps_hypotheses import HypothesisSteps
from occbench.trackers.three_hypothesis.steps_occlusion import (
    max_similarity,
    occlusions,
    sort_occlusions,
)
from occbench.trackers.three_hypothesis.steps_output import OutputSteps
from occbench.trackers.three_hypothesis.steps_predict import measure, predict
from occbench.trackers.three_hypothesis.steps_update import UpdateSteps
from occbench.trackers.three_hypothesis.values import Frame


class RetaTracker(UpdateSteps, HypothesisSteps, OutputSteps):
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

    needs_frames = True  # colour histograms of the measurements (eq. 1)

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
        self._persons: list[Person] = []
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
        if foreground is not None and foreground.shape[:2] != frame.shape[:2]:
            raise ValueError(f"RetaTracker: foreground shape {foreground.shape} != frame {frame.shape[:2]}")
        self._frame += 1
        self.graph.begin_frame(self._frame)
        self._public = {person.key: person.public_id for person in self._persons}
        rules = self.rules
        V = measure(frame, detections, foreground, self.min_score, self.histograms, rules.pixels)
        S = predict(self._persons, rules.motion)
        O = occlusions(S, V, self.occlusion)
        A = max_similarity(S, V, O, self._pi, rules, self.association)
        D = sort_occlusions(S, V, O, A, self._pi)
        f = Frame(V, S, O, A, D)
        survivors = self._update_matched(f)
        survivors += self._prune(f, *self._continue_unmatched(f))
        survivors += self._start_tracks(f)
        alive = {person.key for person in survivors}
        if len(self._pi) > 4 * len(alive) ** 2 + 16:
            self._pi = {k: v for k, v in self._pi.items() if k[0] in alive and k[1] in alive}
        self._persons = survivors
        return self._outputs()
