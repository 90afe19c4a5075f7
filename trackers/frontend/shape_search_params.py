"""``ShapeSearch``'s settings in groups, one per part of the greedy active-basis search
(Reta 3.1; ``shape_search``'s module docstring).

Each group is a frozen dataclass that checks itself when built (``ValueError`` naming
``search.<group>.<field>`` and the value, through ``occbench.trackers.common.checks``); the
search takes one of each, and Hydra builds them as nested ``_target_`` nodes of
``conf/detector/active_basis.yaml`` (``detector.detector.search.<group>.<field>``).
"""

from __future__ import annotations

from dataclasses import dataclass

from occbench.trackers.common.checks import at_least, coerce, require

__all__ = ["GROUPS", "ShapeAcceptance", "ShapeHeights", "ShapePlacements"]


@dataclass(frozen=True)
class ShapeHeights:
    """The person heights searched.

    Args:
        min_height, max_height: person heights searched, fractions of the frame height.
        n_scales: heights, geometrically spaced.
        height_tolerance: with a perspective, a scale is searched where its height is within
            this factor of the expected person height.
    """

    min_height: float = 0.1
    max_height: float = 0.6
    n_scales: int = 12
    height_tolerance: float = 1.1

    def __post_init__(self) -> None:
        require("search.heights.min_height", 0 < self.min_height <= self.max_height <= 1,
                f"must satisfy 0 < min_height <= max_height {self.max_height} <= 1",
                self.min_height)
        at_least("search.heights", 1, n_scales=self.n_scales,
                 height_tolerance=self.height_tolerance)
        coerce(self, {"min_height": float, "max_height": float, "n_scales": int,
                      "height_tolerance": float})


@dataclass(frozen=True)
class ShapePlacements:
    """Where a person may be placed, and what a fit occupies.

    Args:
        silhouette: ``.npy`` mean person mask in [0, 1] marking what a fit occupies
            (``silhouette_template.load_template``; None: the shipped one).
        occupy_level: silhouette values above which a fit's pixels are marked occupied.
        min_vacant: smallest share of a placement's silhouette on vacant foreground.
        stride: placements searched every ``stride`` template pixels (1: every one).
    """

    silhouette: str | None = None
    occupy_level: float = 0.2
    min_vacant: float = 0.7
    stride: int = 1

    def __post_init__(self) -> None:
        require("search.placements.occupy_level", 0 <= self.occupy_level < 1,
                "must lie in [0, 1)", self.occupy_level)
        require("search.placements.min_vacant", 0 < self.min_vacant <= 1, "must lie in (0, 1]",
                self.min_vacant)
        at_least("search.placements", 1, stride=self.stride)
        coerce(self, {"occupy_level": float, "min_vacant": float, "stride": int})


@dataclass(frozen=True)
class ShapeAcceptance:
    """Which fits are accepted.

    Args:
        threshold: smallest log-likelihood ratio (eq. 22) of an accepted person.
        max_people: bound on the people accepted per frame.
    """

    threshold: float = 10.0
    max_people: int = 20

    def __post_init__(self) -> None:
        at_least("search.acceptance", 1, max_people=self.max_people)
        coerce(self, {"threshold": float, "max_people": int})


#: the search's groups: its argument -> the group's class
GROUPS = {"heights": ShapeHeights, "placements": ShapePlacements,
          "acceptance": ShapeAcceptance}
