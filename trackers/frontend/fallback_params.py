"""The fallback's settings in groups (``fallback``'s module docstring): ``RegionDetector``'s
("regions") and its ``MedianBackground``'s ("background").

Each group is a frozen dataclass that checks itself when built (``ValueError`` naming
``fallback.<group>.<field>`` or ``fallback.background.<group>.<field>`` and the value,
through ``occbench.trackers.common.checks``); the detector and the background take one of
each, and Hydra builds them as nested ``_target_`` nodes of ``conf/detector/silhouette.yaml``
(``detector.detector.fallback.<group>.<field>``,
``detector.detector.fallback.background.<group>.<field>``).
"""

from __future__ import annotations

from dataclasses import dataclass

from occbench.trackers.common.checks import at_least, coerce, require, unit

__all__ = ["BACKGROUND_GROUPS", "GROUPS", "DifferenceThreshold", "Glare", "MaskMorphology",
           "RegionFilter", "RegionGrouping", "UpdateRates"]


@dataclass(frozen=True)
class RegionFilter:
    """Which foreground regions are kept.

    Args:
        min_area: smallest region, pixels (smaller components are dropped first).
        min_share: smallest region, as a share of the typical person area.
        max_unsteady: a region with more than this share of its pixels where the background
            footage's clips disagree (``MedianBackground.unsteady``: glare, plants) is dropped
            (1: never; without footage: never).
    """

    min_area: int = 40
    min_share: float = 0.0
    max_unsteady: float = 1.0

    def __post_init__(self) -> None:
        at_least("fallback.regions", 1, min_area=self.min_area)
        require("fallback.regions.min_share", 0 <= self.min_share < 1, "must lie in [0, 1)",
                self.min_share)
        unit("fallback.regions", max_unsteady=self.max_unsteady)
        coerce(self, {"min_area": int, "min_share": float, "max_unsteady": float})


@dataclass(frozen=True)
class RegionGrouping:
    """How the kept regions become person-sized boxes.

    Args:
        merge_gap: fragments whose boxes are closer than this times the typical person's
            side (square root of its area) are merged.
        split_ratio: a region larger than this times the typical area is split (None: never).
        initial_area: typical person area before the scene has shown any, pixels.
        seed: k-means seed of the splits.
    """

    merge_gap: float = 0.3
    split_ratio: float | None = None
    initial_area: float = 600.0
    seed: int = 0

    def __post_init__(self) -> None:
        at_least("fallback.grouping", 0, merge_gap=self.merge_gap)
        require("fallback.grouping.split_ratio", self.split_ratio is None or self.split_ratio > 1,
                "must be > 1 or None", self.split_ratio)
        require("fallback.grouping.initial_area", self.initial_area > 0, "must be > 0",
                self.initial_area)
        if self.split_ratio is not None:
            coerce(self, {"split_ratio": float})
        coerce(self, {"merge_gap": float, "initial_area": float, "seed": int})


#: the detector's groups: its argument -> the group's class
GROUPS = {"regions": RegionFilter, "grouping": RegionGrouping}


@dataclass(frozen=True)
class UpdateRates:
    """How fast the median background learns from each frame.

    Args:
        fast_rate, slow_rate: update rates where the frame is background / foreground.
    """

    fast_rate: float = 0.02
    slow_rate: float = 0.002

    def __post_init__(self) -> None:
        unit("fallback.background.rates", fast_rate=self.fast_rate)
        require("fallback.background.rates.slow_rate", 0.0 <= self.slow_rate <= self.fast_rate,
                f"must lie in [0, fast_rate {self.fast_rate}]", self.slow_rate)
        coerce(self, {"fast_rate": float, "slow_rate": float})


@dataclass(frozen=True)
class DifferenceThreshold:
    """When a pixel differs from the background: the difference of the blurred frames
    against a per-pixel threshold.

    Args:
        k_sigma: threshold in units of each pixel's noise (1.4826 MAD of the first frames).
        min_difference: smallest threshold, grey levels (max over the channels).
        blur: Gaussian kernel (odd) applied to every frame before differencing (0/1: none).
    """

    k_sigma: float = 4.0
    min_difference: float = 20.0
    blur: int = 3

    def __post_init__(self) -> None:
        g = "fallback.background.threshold"
        require(f"{g}.k_sigma", self.k_sigma > 0, "must be > 0", self.k_sigma)
        at_least(g, 0, min_difference=self.min_difference)
        require(f"{g}.blur", self.blur <= 1 or self.blur % 2 == 1, "must be odd (or 0/1: none)",
                self.blur)
        coerce(self, {"k_sigma": float, "min_difference": float, "blur": int})


@dataclass(frozen=True)
class Glare:
    """Which pixels are glare, never foreground.

    Args:
        saturation: a channel value at or above which a pixel is glare.
        chroma_tolerance: largest chromaticity change of a brightening counted as glare
            (0: off).
    """

    saturation: int = 245
    chroma_tolerance: float = 0.0

    def __post_init__(self) -> None:
        coerce(self, {"saturation": int, "chroma_tolerance": float})


@dataclass(frozen=True)
class MaskMorphology:
    """The morphology of the foreground mask.

    Args:
        open_kernel, close_kernel: elliptic opening and closing of the mask (0/1: none).
    """

    open_kernel: int = 3
    close_kernel: int = 7

    def __post_init__(self) -> None:
        at_least("fallback.background.morphology", 0, open_kernel=self.open_kernel,
                 close_kernel=self.close_kernel)
        coerce(self, {"open_kernel": int, "close_kernel": int})


#: the median background's groups: its argument -> the group's class
BACKGROUND_GROUPS = {"rates": UpdateRates, "threshold": DifferenceThreshold, "glare": Glare,
                     "morphology": MaskMorphology}
