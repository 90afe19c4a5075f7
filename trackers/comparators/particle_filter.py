"""Colour particle filter (Perez, Hue, Vermaak and Gangnet 2002): Reta Table 2's "basic particle filter"
row and a plain particle filter beside PBM's CCMSPF (``ccmspf``), with the particle sets they share.

Each target carries N particles over its box centre, velocity and scale. Per frame (the
bootstrap filter): every particle moves by second-order (constant-velocity) dynamics with
random-walk noise, is weighted by the colour likelihood
exp(-lambda d^2) with d^2 = 1 - rho(q, p) (rho the Bhattacharyya coefficient of the
target's colour model q and the particle box's p), the estimate is the
weighted mean, and the particles are resampled (systematic resampling). Seeded: the same
seed gives the same tracks. Life cycle and colour model: ``occbench.trackers.comparators.appearance``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occbench.trackers.common.checks import at_least, coerce, parameter_group, refuse_moved
from occbench.trackers.comparators.appearance import (
    ColourTarget,
    ColourTrackerBase,
    Loss,
    Restart,
    colour_model,
)
from occbench.trackers.records import Detections, Track


def systematic_resample(weight: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Indices of N particles drawn by systematic resampling from normalised ``weight`` (N,):
    one uniform offset, then N evenly spaced points on the cumulative weights."""
    n = len(weight)
    u = (rng.random() + np.arange(n)) / n
    return np.minimum(np.searchsorted(np.cumsum(weight), u), n - 1)


@dataclass(frozen=True)
class ParticleSampling:
    """A target's particle set and its random walk.

    Args:
        particles: N, particles per target.
        position_noise: random-walk standard deviation of the centre (and, for the colour
            particle filter, of the velocity), in box sizes (per frame).
        scale_noise: random-walk standard deviation of the log scale (0 = a fixed size, as
            mean shift keeps: colour alone favours boxes shrunk inside the person).
        seed: seed of the random walk and the resampling (restarted by ``reset``).
    """

    particles: int = 100
    position_noise: float = 0.1
    scale_noise: float = 0.0
    seed: int = 0

    def __post_init__(self) -> None:
        at_least("sampling", 1, particles=self.particles)
        at_least("sampling", 0, position_noise=self.position_noise, scale_noise=self.scale_noise)
        coerce(self, {"particles": int, "position_noise": float, "scale_noise": float,
                      "seed": int})


class ParticleTrackerBase(ColourTrackerBase):
    """A colour comparator with one seeded particle set per target (``_sets``, id -> (N, d)),
    dropped when its target ends; subclasses implement ``_follow``.

    Args:
        sampling: the particle sets and their random walk (``ParticleSampling``).
        birth_iou, loss, restart, max_targets: life cycle (``ColourTrackerBase``).
    """

    def __init__(self, sampling: ParticleSampling, birth_iou: float, loss: Loss | None,
                 restart: Restart | None, max_targets: int | None) -> None:
        self.sampling = parameter_group("sampling", sampling, ParticleSampling)
        super().__init__(birth_iou, loss, restart, max_targets)

    def reset(self) -> None:
        super().reset()
        self._rng = np.random.default_rng(self.sampling.seed)
        self._sets: dict[int, np.ndarray] = {}

    def _estimate(self, target: ColourTarget, s: np.ndarray, weight: np.ndarray,
                  scale: int) -> None:
        """The posterior mean of particles ``s`` (N, d) under normalised ``weight`` becomes
        ``target.box`` (column 0-1 the centre, column ``scale`` the log scale against the
        current box); then systematic resampling, scales made relative to the new box."""
        mean = weight @ s  # the posterior mean
        w, h = target.box[2:]
        sc = np.exp(mean[scale])
        target.box = np.array([mean[0] - w * sc / 2, mean[1] - h * sc / 2, w * sc, h * sc])
        s = s[systematic_resample(weight, self._rng)]
        s[:, scale] -= mean[scale]  # scales relative to the new box
        self._sets[target.id] = s

    def update(self, frame: np.ndarray | None, detections: Detections,
               foreground: np.ndarray | None = None) -> list[Track]:
        tracks = super().update(frame, detections, foreground)
        live = {t.id for t in self._targets}
        self._sets = {k: v for k, v in self._sets.items() if k in live}
        return tracks

    update.__doc__ = ColourTrackerBase.update.__doc__


class ColourParticleFilter(ParticleTrackerBase):
    """Bootstrap particle filter with a colour likelihood, one particle set per target.

    Args:
        sampling: N particles per target, their random walk over centre, velocity and log
            scale, and its seed (``ParticleSampling``; None: its defaults).
        likelihood_lambda: lambda of exp(-lambda (1 - rho)).
        birth_iou, loss, restart, max_targets: life cycle (``ColourTrackerBase``); the
            evidence ``loss`` judges is rho at the posterior-mean box.
        A key of the flat arguments before the groups is refused with a TypeError naming
        its group.
    """

    def __init__(self, sampling: ParticleSampling | None = None,
                 likelihood_lambda: float = 20.0, birth_iou: float = 0.3,
                 loss: Loss | None = None, restart: Restart | None = None,
                 max_targets: int | None = None, **moved: object) -> None:
        refuse_moved("tracker", moved, {"sampling": ParticleSampling})
        at_least("", 0, likelihood_lambda=likelihood_lambda)
        self.likelihood_lambda = likelihood_lambda
        super().__init__(parameter_group("sampling", sampling, ParticleSampling), birth_iou,
                         loss, restart, max_targets)

    def _follow(self, target: ColourTarget, bins: np.ndarray) -> float:
        x, y, w, h = target.box
        s = self._sets.get(target.id)
        walk = self.sampling
        if s is None:  # (N, 5): centre x, y, velocity x, y, log scale against the current box
            s = np.tile([x + w / 2, y + h / 2, 0.0, 0.0, 0.0], (walk.particles, 1))
        e = self._rng.normal(0.0, 1.0, s.shape) * [walk.position_noise * w,
                                                   walk.position_noise * h,
                                                   walk.position_noise * w,
                                                   walk.position_noise * h, walk.scale_noise]
        s = s + e
        s[:, :2] += s[:, 2:4]  # second-order dynamics: x_t = x_{t-1} + v_t + e, v_t = v_{t-1} + e
        scale = np.exp(s[:, 4])
        boxes = np.column_stack([s[:, 0] - w * scale / 2, s[:, 1] - h * scale / 2,
                                 w * scale, h * scale])
        rho = np.array([np.sqrt(target.q * colour_model(bins, b)).sum() for b in boxes])
        weight = np.exp(-self.likelihood_lambda * (1.0 - rho))  # p(z|x) = exp(-lambda d^2)
        self._estimate(target, s, weight / weight.sum(), scale=4)
        return float(np.sqrt(target.q * colour_model(bins, target.box)).sum())
