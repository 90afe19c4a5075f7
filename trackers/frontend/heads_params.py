"""``HeadDetector``'s settings in groups, one per step of PBM 2.3 (``heads``' module
docstring): which pixels are head pixels, and which ellipses of them are heads.

Each group is a frozen dataclass that checks itself when built (``ValueError`` naming
``heads.<group>.<field>`` and the value, through ``occbench.trackers.common.checks``); the
detector takes one of each, and Hydra builds them as nested ``_target_`` nodes of
``conf/detector/foreground.yaml`` (``detector.detector.heads.<group>.<field>``).
"""

from __future__ import annotations

from dataclasses import dataclass

from occbench.trackers.common.checks import coerce, require, unit

__all__ = ["GROUPS", "HeadEllipses", "HeadPixels"]


@dataclass(frozen=True)
class HeadPixels:
    """Head pixels: hair or skin colour above a threshold, closed (PBM 2.3.1-2.3.3).

    Args:
        w1: weight of the XYZ likelihood (PBM eq. 5, w1).
        w2: weight of the HSV likelihood (PBM eq. 5, w2).
        threshold_hair: th_hair on p_hair (PBM 2.3.1).
        threshold_skin: threshold on p_skin (PBM 2.3.2).
        close_kernel: size of the elliptic closing applied to head pixels (PBM 2.3.3).
    """

    w1: float = 0.5
    w2: float = 0.5
    threshold_hair: float = 10.0
    threshold_skin: float = 10.0
    close_kernel: int = 3

    def __post_init__(self) -> None:
        unit("heads.pixels", w1=self.w1, w2=self.w2)
        coerce(self, {"w1": float, "w2": float, "threshold_hair": float,
                      "threshold_skin": float, "close_kernel": int})


@dataclass(frozen=True)
class HeadEllipses:
    """The ellipses fitted to the head pixels at the top of a person (PBM 2.3.3).

    Args:
        head_fraction: head height as a fraction of person height (PBM 2.1: 1/7).
        size_factors: head-height multipliers tried around ``head_fraction * height``.
        aspects: ellipse width / height ratios tried.
        min_occupancy: smallest occupancy ratio accepted as a head.
        search_fraction: fraction of a box's height (from its top) searched for the head.
        min_head_height: smallest head height in pixels searched.
    """

    head_fraction: float = 1 / 7
    size_factors: tuple[float, ...] = (0.8, 1.0, 1.25)
    aspects: tuple[float, ...] = (0.75, 0.9)
    min_occupancy: float = 0.5
    search_fraction: float = 0.35
    min_head_height: int = 5

    def __post_init__(self) -> None:
        g = "heads.ellipses"
        require(f"{g}.min_occupancy", 0.0 < self.min_occupancy <= 1.0, "must lie in (0, 1]",
                self.min_occupancy)
        require(f"{g}.head_fraction", 0.0 < self.head_fraction < 1.0, "must lie in (0, 1)",
                self.head_fraction)
        object.__setattr__(self, "size_factors", tuple(float(f) for f in self.size_factors))
        object.__setattr__(self, "aspects", tuple(float(a) for a in self.aspects))
        coerce(self, {"head_fraction": float, "min_occupancy": float, "search_fraction": float,
                      "min_head_height": int})


#: the detector's groups: its argument -> the group's class
GROUPS = {"pixels": HeadPixels, "ellipses": HeadEllipses}
