"""``RegionDetector``'s settings in groups (``fallback``'s module docstring, "regions").

Each group is a frozen dataclass that checks itself when built (``ValueError`` naming
``fallback.<group>.<field>`` and the value, through ``occbench.trackers.common.checks``); the
detector takes one of each, and Hydra builds them as nested ``_target_`` nodes of
``conf/detector/silhouette.yaml`` (``detector.detector.fallback.<group>.<field>``).
"""

from __future__ import annotations

from dataclasses import dataclass

from occbench.trackers.common.checks import at_least, coerce, require, unit

__all__ = ["GROUPS", "RegionFilter", "RegionGrouping"]


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
