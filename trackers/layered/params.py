"""PBM's settings in groups, one per step of the paper's algorithm (PBM Fig. 1).

Each group is a frozen dataclass that checks itself when built (``ValueError`` naming
``<group>.<field>`` and the value); ``PBMTracker`` takes one of each, and Hydra builds them
as nested ``_target_`` nodes (``conf/tracker/pbm.yaml``). What the paper has sits in the
group of its step, with the paper's symbol and section; every rule the paper does not have
sits in ``adaptations.Adaptations`` (``docs/adaptations.md`` has one row per field, with the
evidence); ``tracker=pbm_paper`` sets each to the paper's value.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from occbench.trackers.common.checks import at_least, coerce, require, unit
from occbench.trackers.layered.feature_models import FeatureModels
from occbench.trackers.layered.parts import FEATURES, MAX_GRID_COLS, MIN_GRID, N_PARTS

DEFAULT_FEATURE_WEIGHTS = {"area": 0.15, "perimeter": 0.1, "hsv": 0.25, "xyz": 0.25,
                           "displacement": 0.1, "overlap": 0.15}
DEFAULT_PART_WEIGHTS = (0.3, 0.2, 0.2, 0.15, 0.15)


def _grid(group: str, name: str, value: Sequence[int]) -> tuple[int, int]:
    """(rows, cols), at least ``MIN_GRID``, at most ``MAX_GRID_COLS`` columns
    (``PartFeatureExtractor``'s)."""
    rc = tuple(int(v) for v in value)
    require(f"{group}.{name}", len(rc) == 2 and rc[0] >= MIN_GRID[0]
            and MIN_GRID[1] <= rc[1] <= MAX_GRID_COLS,
            "must be at least {} x {} samples (rows, cols), at most {} columns".format(
                *MIN_GRID, MAX_GRID_COLS), list(value))
    return rc  # type: ignore[return-value]


@dataclass(frozen=True)
class FeatureParams:
    """What a part is measured by and how the layers weigh it (PBM 2.2, 4.1, eqs. 11-13).

    Args:
        models: theta_ij, the feature-difference models p(d | theta) (``FeatureModels``, a
            mapping as written by ``occbench fit pbm``, or None for the shipped
            defaults).
        feature_weights: omega_i of eq. 12, feature name -> weight (normalised to sum 1).
        part_weights: gamma_j of eq. 13, five weights (head, left/right torso-arm,
            left/right leg; normalised to sum 1).
        histogram_bins: bins per channel of the HSV and XYZ part histograms (must match
            the models' fit).
        grid: (rows, cols) samples each candidate box is measured on (rows a multiple of
            7: the head band is whole rows; ``PartFeatureExtractor``).
        search_grid: (rows, cols) coarser samples of the head-anchored search's boxes.
    Attributes:
        omega: (6,) float64 normalised feature weights, ``FEATURES`` order.
        gamma: (5,) float64 normalised part weights.
    """

    models: FeatureModels | Mapping | None = None
    feature_weights: Mapping[str, float] | None = None
    part_weights: Sequence[float] = DEFAULT_PART_WEIGHTS
    histogram_bins: int = 4
    grid: Sequence[int] = (35, 15)
    search_grid: Sequence[int] = (21, 9)
    omega: np.ndarray = field(init=False, repr=False, compare=False)
    gamma: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        models = self.models
        if models is None:
            models = FeatureModels.default()
        elif isinstance(models, Mapping):
            models = FeatureModels.from_dict(dict(models), "features.models")
        require("features.models", isinstance(models, FeatureModels),
                "must be FeatureModels, a mapping or None", type(models).__name__)
        fw = dict(DEFAULT_FEATURE_WEIGHTS if self.feature_weights is None else self.feature_weights)
        unknown = sorted(set(fw) - set(FEATURES))
        require("features.feature_weights", not unknown,
                f"names unknown features {unknown} (known: {FEATURES})", fw)
        omega = np.array([float(fw.get(f, 0.0)) for f in FEATURES])
        require("features.feature_weights", bool((omega >= 0).all() and omega.sum() > 0),
                "must be >= 0 with a positive sum", fw)
        gamma = np.asarray(list(self.part_weights), dtype=np.float64)
        require("features.part_weights", gamma.shape == (N_PARTS,)
                and bool((gamma >= 0).all() and gamma.sum() > 0),
                f"must be {N_PARTS} weights >= 0 with a positive sum", list(self.part_weights))
        at_least("features", 1, histogram_bins=self.histogram_bins)
        set_ = object.__setattr__
        set_(self, "models", models)
        set_(self, "feature_weights", fw)
        set_(self, "part_weights", tuple(float(g) for g in gamma))
        set_(self, "histogram_bins", int(self.histogram_bins))
        set_(self, "grid", _grid("features", "grid", self.grid))
        set_(self, "search_grid", _grid("features", "search_grid", self.search_grid))
        set_(self, "omega", omega / omega.sum())  # eq. 12: sum_i omega_i = 1
        set_(self, "gamma", gamma / gamma.sum())  # eq. 13: sum_j gamma_j = 1


@dataclass(frozen=True)
class CandidateParams:
    """Where candidates come from (PBM 2, 2.3): detection boxes with their heads, and the
    heads of foreground blobs that no detection explains.

    Args:
        min_blob_area: smallest foreground blob used as a candidate (pixels).
        head_separation: smallest distance between two heads of a blob, x blob height.
        blob_downsample: connected components run on the mask subsampled by this factor.
        head_detector: PBM 2.3 hair/skin head detector (``detect(frame, foreground,
            boxes)``, e.g. ``occbench.trackers.frontend.heads.HeadDetector``) for detections without
            heads; None: the top 1/7 band of the box's foreground (``docs/adaptations.md``).
    """

    min_blob_area: int = 300
    head_separation: float = 0.12
    blob_downsample: int = 2
    head_detector: object | None = None

    def __post_init__(self) -> None:
        at_least("candidates", 0, min_blob_area=self.min_blob_area,
                 head_separation=self.head_separation)
        at_least("candidates", 1, blob_downsample=self.blob_downsample)
        require("candidates.head_detector", self.head_detector is None
                or callable(getattr(self.head_detector, "detect", None)),
                "must have a detect(frame, foreground, boxes) method", self.head_detector)
        coerce(self, {"min_blob_area": int, "head_separation": float, "blob_downsample": int})


@dataclass(frozen=True)
class GateParams:
    """KF1's gate (PBM 3, Fig. 5): half-size = speed_factor |v| + min_fraction (w, h),
    x miss_factor after a miss, x growth per further miss, until found or lost (its cap is
    ``Adaptations.gate_max_fraction``).

    Args:
        speed_factor: half-size per unit KF1 speed |v|.
        min_fraction: half-size floor, x target (w, h).
        miss_factor: the gate after one miss, x (the paper: doubled).
        growth: further growth per extra miss.
    """

    speed_factor: float = 3.0
    min_fraction: float = 0.5
    miss_factor: float = 2.0
    growth: float = 1.15

    def __post_init__(self) -> None:
        at_least("gate", 0, speed_factor=self.speed_factor, min_fraction=self.min_fraction)
        at_least("gate", 1, miss_factor=self.miss_factor, growth=self.growth)


@dataclass(frozen=True)
class NoiseParams:
    """Standard deviations of the two Kalman filters (PBM 3, eqs. 7-8), per person height
    / 10 (``dynamics.ConstantVelocity2D``): KF1 of the centre (xc, yc), KF2 of the size
    (h, w).

    Args:
        kf1_position, kf1_velocity, kf1_measurement: KF1's Q (position, rate) and R.
        kf2_position, kf2_velocity, kf2_measurement: KF2's Q (size, size rate) and R.
    """

    kf1_position: float = 0.5
    kf1_velocity: float = 0.2
    kf1_measurement: float = 0.5
    kf2_position: float = 0.2
    kf2_velocity: float = 0.02
    kf2_measurement: float = 0.5

    def __post_init__(self) -> None:
        at_least("noise", 0, kf1_position=self.kf1_position, kf1_velocity=self.kf1_velocity,
                 kf1_measurement=self.kf1_measurement, kf2_position=self.kf2_position,
                 kf2_velocity=self.kf2_velocity, kf2_measurement=self.kf2_measurement)

    @property
    def kf1(self) -> tuple[float, float, float]:
        """(position, velocity, measurement) of KF1."""
        return self.kf1_position, self.kf1_velocity, self.kf1_measurement

    @property
    def kf2(self) -> tuple[float, float, float]:
        """(position, velocity, measurement) of KF2."""
        return self.kf2_position, self.kf2_velocity, self.kf2_measurement


@dataclass(frozen=True)
class SearchParams:
    """Occlusion test and head-anchored search (PBM 3.1, eqs. 9-10).

    Args:
        occlusion_threshold: relative w or h change that flags an occlusion (the paper: 50%).
        step: delta of eqs. 9-10, relative to the predicted size (w (1 + delta i)).
        range: i runs over -range..range in eqs. 9-10.
        overlap: a larger region is searched for a found target only when at least this
            fraction of the target's last box lies inside it ("the target needs to be
            located within the blob"; 0 = always).
        head_min_fill: foreground share of the head rectangle a smaller candidate needs
            to be aligned on its head, else it is dismissed.
    """

    occlusion_threshold: float = 0.5
    step: float = 0.05
    range: int = 2
    overlap: float = 0.5
    head_min_fill: float = 0.2

    def __post_init__(self) -> None:
        require("search.occlusion_threshold", self.occlusion_threshold > 0, "must be > 0",
                self.occlusion_threshold)
        require("search.step", 0 < self.step < 0.5, "must lie in (0, 0.5)", self.step)
        at_least("search", 0, range=self.range)
        unit("search", overlap=self.overlap, head_min_fill=self.head_min_fill)
        coerce(self, {"range": int, "overlap": float})


@dataclass(frozen=True)
class MatchParams:
    """Selection of each target's candidate (PBM 4, steps 4-5).

    Args:
        match_threshold: smallest global score p (eq. 13) of a match.
        weak_threshold: scores in [weak, match) try head-template pruning (PBM 4.1).
        margin_ratio: the best candidate must beat the runner-up by this ratio, else the
            choice is ambiguous and pruned.
    """

    match_threshold: float = 0.25
    weak_threshold: float = 0.1
    margin_ratio: float = 1.1

    def __post_init__(self) -> None:
        unit("matching", match_threshold=self.match_threshold, weak_threshold=self.weak_threshold)
        require("matching.weak_threshold", self.weak_threshold <= self.match_threshold,
                f"must be <= matching.match_threshold {self.match_threshold}",
                self.weak_threshold)
        at_least("matching", 1, margin_ratio=self.margin_ratio)


@dataclass(frozen=True)
class PruneParams:
    """Multiple-response pruning by the head template (PBM 4.1).

    Args:
        template_threshold: normalised correlation a head-template match needs.
        radius: candidates within this many head widths of the best are "nearby"
            (multiple responses of one person); distant rivals are left to the assignment.
    """

    template_threshold: float = 0.6
    radius: float = 3.0

    def __post_init__(self) -> None:
        at_least("pruning", 0, radius=self.radius)


@dataclass(frozen=True)
class UpdateParams:
    """Model update (PBM 4.2) and the running windows of the global model (PBM 2.1).

    Args:
        rate: running-average rate of a matched part, times p_j.
        part_threshold: p_j (eq. 12) below this: the part does not match, its model is
            frozen.
        ratio_window: frames of the running averages of alpha, beta (eqs. 1-2; paper 3-5).
        occluded_window: DOF vectors averaged under occlusion.
    """

    rate: float = 0.3
    part_threshold: float = 0.4
    ratio_window: int = 4
    occluded_window: int = 3

    def __post_init__(self) -> None:
        unit("update", rate=self.rate, part_threshold=self.part_threshold)
        at_least("update", 1, ratio_window=self.ratio_window, occluded_window=self.occluded_window)
        coerce(self, {"ratio_window": int, "occluded_window": int})


@dataclass(frozen=True)
class LifeCycleParams:
    """Births, confirmation and deaths of targets (a multi-target addition: the paper
    initialises each target by hand, PBM 3, and tracks it "until lost").

    Args:
        min_hits: matches in a row that confirm a new target (``adaptations.early_confirm``:
            fewer, or at its birth, for one that overlaps no other).
        max_misses: frames a confirmed target survives unfound.
        min_height: smallest candidate height that starts a target (pixels).
        new_track_iou: a free candidate overlapping a live target by more IoU than this
            starts no target.
        blob_births: free foreground blobs (heads no detection explains) start targets too;
            off, blobs only keep existing targets. With foreground but no detections at all,
            turn it on.
    """

    min_hits: int = 3
    max_misses: int = 90
    min_height: float = 12.0
    new_track_iou: float = 0.6
    blob_births: bool = False

    def __post_init__(self) -> None:
        at_least("life_cycle", 1, min_hits=self.min_hits)
        at_least("life_cycle", 0, max_misses=self.max_misses)
        unit("life_cycle", new_track_iou=self.new_track_iou)
        coerce(self, {"min_hits": int, "max_misses": int, "min_height": float,
                      "blob_births": bool})


@dataclass(frozen=True)
class ReportParams:
    """What each frame's output holds besides the found targets.

    Args:
        occluded: report unfound confirmed targets as OCCLUDED.
        max_misses: frames an unfound target is reported (and counts as an occluder of
            other targets' parts, ``Adaptations.stale``).
    """

    occluded: bool = True
    max_misses: int = 5

    def __post_init__(self) -> None:
        at_least("reporting", 0, max_misses=self.max_misses)
        coerce(self, {"occluded": bool, "max_misses": int})
