"""``SilhouetteMatcher``'s settings in groups, one per part of the search (Reta 3.1 adapted).

Each group is a frozen dataclass that checks itself when built (``ValueError`` naming
``<group>.<field>`` and the value, through ``occbench.trackers.common.checks``; every number
checked refuses NaN); the matcher takes one of each, and Hydra builds them as nested
``_target_`` nodes of ``conf/detector/silhouette.yaml`` (``detector.matcher.<group>.<field>``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields

from occbench.trackers.common.checks import at_least, coerce, require

__all__ = ["GROUPS", "MOVED", "Heights", "Person", "Report", "Score", "Search"]


@dataclass(frozen=True)
class Person:
    """The person template as matched.

    Args:
        template: path of a template ``.npy`` (None: the shipped default).
        aspect: width / height of the template as matched (None: the template's own); the
            template is resized to it, so boxes follow a tighter or looser box convention.
        symmetric: match the mean of the template and its mirror image (people face either
            way; a template learnt from few walkers leans to their side).
        occupy_level: template values above which a fit's pixels are marked occupied (its
            silhouette; lower marks a wider region, so arms and bags are not fitted again).
    """

    template: str | None = None
    aspect: float | None = None
    symmetric: bool = False
    occupy_level: float = 0.2

    def __post_init__(self) -> None:
        if self.aspect is not None:
            require("person.aspect", 0.05 <= self.aspect <= 2.0, "must lie in [0.05, 2] or be None",
                    self.aspect)
            coerce(self, {"aspect": float})
        require("person.occupy_level", 0.0 <= self.occupy_level < 1.0, "must lie in [0, 1)",
                self.occupy_level)
        coerce(self, {"symmetric": bool, "occupy_level": float})


@dataclass(frozen=True)
class Heights:
    """The person heights searched, and the ground-plane height prior.

    Args:
        min_height: smallest person height searched (see ``height_unit``).
        max_height: largest person height searched (see ``height_unit``).
        n_scales: number of heights, geometrically spaced.
        height_unit: "pixels" (full resolution) or "frame" (fractions of the frame height,
            so that one config serves every frame size).
        height_tolerance: with a height model (expected person height as a linear function
            of the foot row, a ground-plane prior), a fit of height h whose expected height
            is e is allowed only when 1/tol <= h / e <= tol.
        height_model: fixed ground-plane height prior [a, b] (expected height = a * foot row
            + b, full-resolution pixels), e.g. from a camera calibration; None: no prior
            until ``SilhouetteMatcher.set_height_model`` gives one.
    """

    min_height: float = 30.0
    max_height: float = 120.0
    n_scales: int = 12
    height_unit: str = "pixels"
    height_tolerance: float = 1.4
    height_model: Sequence[float] | None = None

    def __post_init__(self) -> None:
        require("heights.min_height", self.min_height > 0, "must be > 0", self.min_height)
        require("heights.max_height", self.max_height >= self.min_height,
                f"must be >= min_height {self.min_height}", self.max_height)
        require("heights.height_unit", self.height_unit in ("pixels", "frame"),
                "must be 'pixels' or 'frame'", self.height_unit)
        require("heights.max_height", self.height_unit != "frame" or self.max_height <= 1,
                "must be <= 1 (a fraction) with height_unit 'frame'", self.max_height)
        at_least("heights", 1, n_scales=self.n_scales, height_tolerance=self.height_tolerance)
        if self.height_model is not None:
            require("heights.height_model", len(self.height_model) == 2, "must be [a, b]",
                    self.height_model)
            object.__setattr__(self, "height_model",
                               (float(self.height_model[0]), float(self.height_model[1])))
        coerce(self, {"min_height": float, "max_height": float, "n_scales": int,
                      "height_tolerance": float})


@dataclass(frozen=True)
class Score:
    """The fit score E / M (``silhouette``'s module docstring) and what a fit must show.

    Args:
        alpha: penalty weight for template pixels without foreground.
        beta: penalty weight for foreground where the template expects background.
        threshold: smallest accepted score E / M (at most 1).
        min_visible: smallest fraction of template mass not already occupied, in (0, 1].
        head_contrast: head evidence a fit needs: in the template's head rows (the top 1/7),
            the foreground fill of the head minus the fill beside it (-1: no test). A
            half-body (no head), a box straddling two people (a gap where the head should
            be) and a floor reflection or shadow smear (as wide at the top as below) lack it.
    """

    alpha: float = 1.0
    beta: float = 0.3
    threshold: float = 0.3
    min_visible: float = 0.3
    head_contrast: float = -1.0

    def __post_init__(self) -> None:
        require("score.min_visible", 0.0 < self.min_visible <= 1.0, "must lie in (0, 1]",
                self.min_visible)
        require("score.head_contrast", -1.0 <= self.head_contrast <= 1.0, "must lie in [-1, 1]",
                self.head_contrast)
        coerce(self, {"alpha": float, "beta": float, "threshold": float, "min_visible": float,
                      "head_contrast": float})


@dataclass(frozen=True)
class Search:
    """How the foreground is searched.

    Args:
        downscale: work on the foreground reduced by this integer factor (speed), >= 1.
        margin: pixels (full resolution) added around each foreground region searched.
        max_people: safety bound of fits per region.
        group_gap: foreground components less than this many rows (full resolution) apart
            vertically are searched as one region (a person cut in two by the background).
        frame_border: template pixels outside the frame are unknown rather than background:
            they are left out of the visible mass M (a person cut by the image border is
            scored on its visible part) and boxes are clipped to the frame.
        compiled: run the greedy search compiled (``_silhouette_kernel``, tested against
            ``silhouette_search.greedy_search``); False runs the numpy equations.
    """

    downscale: int = 2
    margin: int = 8
    max_people: int = 20
    group_gap: float = 0.0
    frame_border: bool = False
    compiled: bool = True

    def __post_init__(self) -> None:
        at_least("search", 1, downscale=self.downscale)
        at_least("search", 0, group_gap=self.group_gap)
        coerce(self, {"downscale": int, "margin": int, "max_people": int, "group_gap": float,
                      "frame_border": bool, "compiled": bool})


@dataclass(frozen=True)
class Report:
    """Which fits are reported, with which box.

    Args:
        box: the reported box: "template" (the fitted template's box) or "foreground" (the
            bounding box of the foreground pixels the fit explains: its silhouette's pixels
            that are foreground, as an annotator boxes the visible person) or "region" (the
            bounding box of the region's foreground inside the template box: arms and feet
            outside the mean silhouette included).
        box_scale: [width, height] factors in (0.2, 2] mapping a fitted template box to the
            reported box (the box convention of the annotations): the width about the box
            centre, the height from the top (the head stays put).
        max_overlap: a fit whose box lies more than this fraction inside an earlier fit's box
            in the same region, and is shorter than ``part_height`` times it, is a part of
            that person (an arm, a bag, a hollow in the foreground): its pixels are marked
            occupied but it is not reported (1 keeps every fit), in (0, 1].
        part_height: see ``max_overlap``.
    """

    box: str = "template"
    box_scale: Sequence[float] = (1.0, 1.0)
    max_overlap: float = 0.5
    part_height: float = 0.8

    def __post_init__(self) -> None:
        require("report.box", self.box in ("template", "foreground", "region"),
                "must be 'template', 'foreground' or 'region'", self.box)
        bs = tuple(float(v) for v in self.box_scale)
        require("report.box_scale", len(bs) == 2 and all(0.2 < v <= 2.0 for v in bs),
                "must be [w, h] factors in (0.2, 2]", list(self.box_scale))
        require("report.max_overlap", 0.0 < self.max_overlap <= 1.0, "must lie in (0, 1]",
                self.max_overlap)
        object.__setattr__(self, "box_scale", bs)
        coerce(self, {"max_overlap": float, "part_height": float})


#: the matcher's groups: its argument -> the group's class
GROUPS = {"person": Person, "heights": Heights, "score": Score, "search": Search,
          "report": Report}
#: a flat key of the matcher before the groups -> its group (``SilhouetteMatcher`` names the
#: new place of a moved key)
MOVED = {f.name: group for group, kind in GROUPS.items() for f in fields(kind)}
