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

import cv2
import numpy as np

from occbench.trackers.common.checks import at_least
from occbench.trackers.comparators.appearance import ColourTarget, Loss, Restart, clip_box
from occbench.trackers.comparators.meanshift import mean_shift, similarity
from occbench.trackers.comparators.particle_filter import ParticleTrackerBase
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


class ConnectedComponentMeanShiftPF(ParticleTrackerBase):
    """CCMSPF: particles moved by mean shift, weighted by colour and connected components.

    Args:
        particles: N, particles per target.
        position_noise: random-walk standard deviation of the centre, in box sizes.
        scale_noise: random-walk standard deviation of the log scale.
        mean_shift_iterations: mean-shift iterations per particle and frame.
        search: half-width of the region a particle's mean shift searches, in box sizes.
        likelihood_lambda: lambda of the colour cue exp(-lambda (1 - rho)).
        component_lambda: lambda_c of the component cue exp(-lambda_c (1 - D)); 0 =
            colour alone.
        seed: seed of the random walk and the resampling (restarted by ``reset``).
        birth_iou, loss, restart, max_targets: life cycle (``ColourTrackerBase``); the
            evidence ``loss`` judges is rho at the posterior-mean box.
    """

    def __init__(self, particles: int = 30, position_noise: float = 0.1,
                 scale_noise: float = 0.05, mean_shift_iterations: int = 2,
                 search: float = 0.5, likelihood_lambda: float = 20.0,
                 component_lambda: float = 1.0, seed: int = 0,
                 birth_iou: float = 0.3, loss: Loss | None = None,
                 restart: Restart | None = None, max_targets: int | None = None) -> None:
        at_least("", 0, mean_shift_iterations=mean_shift_iterations)
        self.position_noise = position_noise
        self.scale_noise = scale_noise
        self.mean_shift_iterations = mean_shift_iterations
        self.search = search
        self.likelihood_lambda = likelihood_lambda
        self.component_lambda = component_lambda
        super().__init__(particles, seed, birth_iou, loss, restart, max_targets,
                         position_noise=position_noise, scale_noise=scale_noise, search=search,
                         likelihood_lambda=likelihood_lambda,
                         component_lambda=component_lambda)

    def reset(self) -> None:
        super().reset()
        self._components: tuple[np.ndarray, np.ndarray] | None = None

    def _follow(self, target: ColourTarget, bins: np.ndarray) -> float:
        x, y, w, h = target.box
        s = self._sets.get(target.id)
        if s is None:  # log scale against the current box, which then becomes the reference
            s = np.tile([x + w / 2, y + h / 2, 0.0], (self.particles, 1))
        s = s + self._rng.normal(0.0, 1.0, s.shape) * [self.position_noise * w,
                                                       self.position_noise * h,
                                                       self.scale_noise]  # x_t = x_{t-1} + e
        boxes = np.column_stack([s[:, 0] - w * np.exp(s[:, 2]) / 2,
                                 s[:, 1] - h * np.exp(s[:, 2]) / 2,
                                 w * np.exp(s[:, 2]), h * np.exp(s[:, 2])])
        if self.mean_shift_iterations:  # each particle moved to its colour mode (eqs. 10, 13)
            boxes = np.array([mean_shift(target.q, b, bins, self.search,
                                         self.mean_shift_iterations) for b in boxes])
            s[:, :2] = boxes[:, :2] + boxes[:, 2:] / 2
        rho = np.array([similarity(target.q, bins, b) for b in boxes])
        cue = np.zeros(len(boxes)) if self._components is None else component_dice(
            boxes, *self._components)
        weight = np.exp(-self.likelihood_lambda * (1.0 - rho)
                        - self.component_lambda * (1.0 - cue))  # p(z|x), two cues
        self._estimate(target, s, weight / weight.sum(), scale=2)
        return similarity(target.q, bins, target.box)

    def update(self, frame: np.ndarray | None, detections: Detections,
               foreground: np.ndarray | None = None) -> list[Track]:
        self._components = components(foreground)
        return super().update(frame, detections, foreground)

    update.__doc__ = ("Advance one frame (``ColourTrackerBase.update``); ``foreground`` is "
                      "the (H, W) bool mask whose connected components weight the particles.")
