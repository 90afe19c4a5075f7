"""Connected-component mean-shift particle filter (CCMSPF), PBM's particle-filter comparator.

PBM (Section 5) names it "the connected-component mean-shift with particle filter tracker
(CCMSPF), representative of particle filters [14,17]"; the text we have gives no reference
list and no equation, so this is our reading of the name (``reading:ccmspf``), built
from the standard parts:

* a particle filter over the box centre and scale (Perez et al. 2002; Nummiaro et al. 2003),
  seeded, with a random-walk prediction x_t = x_{t-1} + e (centre in box sizes, log scale);
* mean shift moving every predicted particle towards its colour mode (the hybrid
  "mean-shift particle filter" of Shan et al. 2004 and Maggio and Cavallaro 2005): a few of
  Comaniciu et al.'s iterations (eqs. 10, 13; ``meanshift.mean_shift``) at the particle's size;
* a likelihood of two cues, colour and the foreground's connected components:
  p(z|x) = exp(-lambda (1 - rho(q, p(x)))) * exp(-lambda_c (1 - D(x))), rho the
  Bhattacharyya coefficient of the target's colour model q and the particle box's, D the
  Dice overlap of the particle box with the connected components of the foreground mask it
  touches (``component_dice``). Colour alone cannot size a box (a box shrunk inside the
  person keeps its colour); the components give the size, whole or in fragments, and
  people merged in one component pull the box over both, as blobs do.

The estimate is the weighted mean of the particles (centre and log scale), then systematic
resampling. Without a foreground mask (``foreground=None``) every particle's component cue
is equal and the filter is colour-only. Life cycle (births, loss, restart) and colour model:
``occbench.trackers.comparators.appearance``.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from occbench.trackers.common.checks import at_least, coerce, parameter_group, refuse_moved
from occbench.trackers.comparators.appearance import ColourTarget, Loss, Restart, clip_box
from occbench.trackers.comparators.meanshift import mean_shift, similarity
from occbench.trackers.comparators.particle_filter import ParticleSampling, ParticleTrackerBase
from occbench.trackers.records import Detections, Track


def components(foreground: np.ndarray | None) -> tuple[np.ndarray, np.ndarray] | None:
    """The foreground's 8-connected components: the (H, W) int32 label image (0 = background)
    and (K + 1,) areas in pixels by label (area 0 for the background); None without a mask."""
    if foreground is None:
        return None
    _, labels, stats, _ = cv2.connectedComponentsWithStats(foreground.astype(np.uint8),
                                                           connectivity=8)
    areas = stats[:, cv2.CC_STAT_AREA].astype(np.float64)
    areas[0] = 0.0
    return labels, areas


def component_dice(boxes: np.ndarray, labels: np.ndarray, areas: np.ndarray) -> np.ndarray:
    """(N,) the Dice overlap of each xywh box B with the connected components it touches, F_B:
    2 |B n F_B| / (|B| + |F_B|) (0 when it touches none). A box around a person's fragments
    covers them all; a box shrunk inside cuts them, one grown past them holds background."""
    out = np.zeros(len(boxes))
    height, width = labels.shape
    for i, b in enumerate(boxes):
        r = clip_box(b, width, height)
        if r is None:
            continue
        lab = labels[r[1]:r[3], r[0]:r[2]]
        inside = np.bincount(lab.ravel(), minlength=len(areas))  # |B n component| by label
        inside[0] = 0
        touched = areas[inside > 0].sum()  # |F_B|
        if touched:
            out[i] = 2.0 * inside.sum() / (b[2] * b[3] + touched)
    return out


@dataclass(frozen=True)
class ParticleShift:
    """The mean shift moving each predicted particle to its colour mode.

    Args:
        mean_shift_iterations: mean-shift iterations per particle and frame (0: none).
        search: half-width of the region a particle's mean shift searches, in box sizes.
    """

    mean_shift_iterations: int = 2
    search: float = 0.5

    def __post_init__(self) -> None:
        at_least("shift", 0, mean_shift_iterations=self.mean_shift_iterations,
                 search=self.search)
        coerce(self, {"mean_shift_iterations": int, "search": float})


@dataclass(frozen=True)
class Cues:
    """The likelihood's two cues, p(z|x) = exp(-lambda (1 - rho)) exp(-lambda_c (1 - D)).

    Args:
        likelihood_lambda: lambda of the colour cue exp(-lambda (1 - rho)).
        component_lambda: lambda_c of the component cue exp(-lambda_c (1 - D)); 0 =
            colour alone.
    """

    likelihood_lambda: float = 20.0
    component_lambda: float = 1.0

    def __post_init__(self) -> None:
        at_least("cues", 0, likelihood_lambda=self.likelihood_lambda,
                 component_lambda=self.component_lambda)
        coerce(self, {"likelihood_lambda": float, "component_lambda": float})


#: the CCMSPF's particle sets unless given: fewer particles than the colour particle
#: filter's (each is moved by mean shift) and a random walk of the scale
CCMSPF_SAMPLING = ParticleSampling(particles=30, scale_noise=0.05)
#: the CCMSPF's groups: its argument -> the group's class
GROUPS = {"sampling": ParticleSampling, "shift": ParticleShift, "cues": Cues}


class ConnectedComponentMeanShiftPF(ParticleTrackerBase):
    """CCMSPF: particles moved by mean shift, weighted by colour and connected components.

    Args:
        sampling: N particles per target, their random walk over centre and log scale, and
            its seed (``ParticleSampling``; None: ``CCMSPF_SAMPLING``).
        shift: each particle's mean shift (``ParticleShift``; None: its defaults).
        cues: the colour and component cues (``Cues``; None: its defaults).
        birth_iou, loss, restart, max_targets: life cycle (``ColourTrackerBase``); the
            evidence ``loss`` judges is rho at the posterior-mean box.
        A key of the flat arguments before the groups is refused with a TypeError naming
        its group.
    """

    def __init__(self, sampling: ParticleSampling | None = None,
                 shift: ParticleShift | None = None, cues: Cues | None = None,
                 birth_iou: float = 0.3, loss: Loss | None = None,
                 restart: Restart | None = None, max_targets: int | None = None,
                 **moved: object) -> None:
        refuse_moved("tracker", moved, GROUPS)
        self.shift = parameter_group("shift", shift, ParticleShift)
        self.cues = parameter_group("cues", cues, Cues)
        sampling = CCMSPF_SAMPLING if sampling is None else sampling
        super().__init__(sampling, birth_iou, loss, restart, max_targets)

    def reset(self) -> None:
        super().reset()
        self._components: tuple[np.ndarray, np.ndarray] | None = None

    def _follow(self, target: ColourTarget, bins: np.ndarray) -> float:
        x, y, w, h = target.box
        walk, shift, cues = self.sampling, self.shift, self.cues
        s = self._sets.get(target.id)
        if s is None:  # log scale against the current box, which then becomes the reference
            s = np.tile([x + w / 2, y + h / 2, 0.0], (walk.particles, 1))
        s = s + self._rng.normal(0.0, 1.0, s.shape) * [walk.position_noise * w,
                                                       walk.position_noise * h,
                                                       walk.scale_noise]  # x_t = x_{t-1} + e
        boxes = np.column_stack([s[:, 0] - w * np.exp(s[:, 2]) / 2,
                                 s[:, 1] - h * np.exp(s[:, 2]) / 2,
                                 w * np.exp(s[:, 2]), h * np.exp(s[:, 2])])
        if shift.mean_shift_iterations:  # each particle moved to its colour mode (eqs. 10, 13)
            boxes = np.array([mean_shift(target.q, b, bins, shift.search,
                                         shift.mean_shift_iterations) for b in boxes])
            s[:, :2] = boxes[:, :2] + boxes[:, 2:] / 2
        rho = np.array([similarity(target.q, bins, b) for b in boxes])
        cue = np.zeros(len(boxes)) if self._components is None else component_dice(
            boxes, *self._components)
        weight = np.exp(-cues.likelihood_lambda * (1.0 - rho)
                        - cues.component_lambda * (1.0 - cue))  # p(z|x), two cues
        self._estimate(target, s, weight / weight.sum(), scale=2)
        return similarity(target.q, bins, target.box)

    def update(self, frame: np.ndarray | None, detections: Detections,
               foreground: np.ndarray | None = None) -> list[Track]:
        self._components = components(foreground)
        return super().update(frame, detections, foreground)

    update.__doc__ = ("Advance one frame (``ColourTrackerBase.update``); ``foreground`` is "
                      "the (H, W) bool mask whose connected components weight the particles.")
