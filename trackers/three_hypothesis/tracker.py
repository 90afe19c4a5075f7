"""Three-hypothesis tracking graph (Reta et al., J. Electron. Imaging 24(1) 013015, 2015).

``RetaTracker.update`` is the body of Algorithm 1 for frame t, one line a step. Each step is
a function (one module per part of the paper, ``steps_*``) of the values the steps before it
returned, and returns its own frozen value (``values``); the people of N^{t-1} are updated in
place by steps 6-9 as the paper's UpdateAttributes does, and what lives between frames (the
graph G, pi, the ids) is the tracker's ``state.Memory``:

1. ``measure``: V = PeopleDetection(I^t), each measurement's ellipse S and histogram p
   (3.2, eq. 1): ``Measurements``;
2. ``predict``: S^{t|t-1} of every node of t-1 by its motion model M (Kalman, 3.2),
   hypotheses moving by their case (3.3.3): ``Predictions``;
3. ``occlusions``: O = Occlusion(N^{t-1}, lambda) (3.3.1, eq. 2): ``Occlusions``;
4. ``max_similarity``: MaxSimilarity in two stages (3.3.2, eqs. 4-5, mu_rho, mu_g):
   ``Matching``, a ``Match`` (det, node, stage, rho) per matched person;
5. ``sort_occlusions``: pi = SortOcclusionTargets(O) (eq. 3), once visibility at t is
   known: ``DepthOrder``;
6. ``update_matched``: UpdateAttributes(N_o^t) (3.3.3): ``Updated``;
7. ``continue_unmatched``: N_h1 for every unmatched person, N_h2 and N_h3 at its first
   total occlusion (Alg. 1, FirstOcclusion): a ``Continuation`` per unmatched person;
8. ``prune``: PruneHypothesis(G, m): the people kept;
9. ``start_tracks``: an unmatched measurement starts a tentative track (3.3);

then ``outputs``: a ``Track`` per node (AddNodeToGraph is ``steps_output.add_node``).

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
from occbench.trackers.three_hypothesis.state import Memory, Setting
from occbench.trackers.three_hypothesis.steps_hypotheses import continue_unmatched, prune
from occbench.trackers.three_hypothesis.steps_occlusion import (
    max_similarity,
    occlusions,
    sort_occlusions,
)
from occbench.trackers.three_hypothesis.steps_output import outputs
from occbench.trackers.three_hypothesis.steps_predict import measure, predict
from occbench.trackers.three_hypothesis.steps_update import start_tracks, update_matched


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
        self.setting = Setting(self.rules, self.occlusion, self.life_cycle, self.adaptations,
                               self.histograms)
        self.reset()

    def reset(self) -> None:
        """Forget every person and the graph; ids restart at 1."""
        self.memory = Memory(TrackingGraph(window=self.life_cycle.m + 1))
        self.rules.velocity.reset()

    @property
    def graph(self) -> TrackingGraph:
        """The tracking graph G (the last m + 1 frames)."""
        return self.memory.graph

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
        m, setting, rules = self.memory, self.setting, self.rules
        m.begin_frame()
        V = measure(frame, detections, foreground, self.min_score, self.histograms, rules.pixels)
        S = predict(m.persons, rules.motion)
        O = occlusions(S, V, self.occlusion)
        A = max_similarity(S, V, O, m.pi, rules, self.association)
        D = sort_occlusions(S, V, O, A, m.pi)
        U = update_matched(S, V, O, A, D, setting, m)
        H = continue_unmatched(S, A, D, U, rules)
        kept = prune(S, V, O, U, H, setting, m)
        new = start_tracks(S, V, O, A, setting, m)
        m.end_frame(U.persons + kept + new)
        return outputs(m.persons, m.t, rules, m.graph)
