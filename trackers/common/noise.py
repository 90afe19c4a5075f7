"""The Kalman noises of the constant-velocity box filter estimated from the measurements.

``constant_velocity_box_filter`` scales its noises by the box height h: Q = diag((sigma_p
h/10)^2 x4, (sigma_v h/10)^2 x4), R = (sigma_z h/10)^2 I. Which sigmas fit depends on the
detector (exact boxes want a small R, a silhouette detector a larger one) and on how people
move, so constants chosen on one kind of detections do not transfer.

``KalmanNoiseML`` estimates (sigma_p, sigma_v, sigma_z) by maximum likelihood over a grid,
online: a bank of filters per track, one per candidate triple (multiple-model adaptive
estimation, Magill 1965; the innovation likelihood is Mehra 1970's and Schweppe 1965's), each
run on the track's own measurements, and each candidate's innovation log-likelihood summed
over every track and step,

    log L(theta) = -1/2 sum_t [y_t' S_t^-1 y_t + log det(2 pi S_t)],  y_t = z_t - H x_t|t-1,
    S_t = H P_t|t-1 H' + R,

a sum over matched steps: the sufficient statistic of the grid is one number per candidate,
and each step costs one filter step per candidate. The four coordinates (xc, yc, w, h) are
independent two-state filters with one shared covariance, so a step is a few scalar
operations per candidate (compiled: ``_bank_steps``; ``tests/test_noise.py`` checks it against
filterpy's ``KalmanFilter.log_likelihood``). Measurements are divided by the track's first
height / 10, as the filter scales its noises. A track's first two measurements initialise it
(x = z, v = 0, P0 = diag(sigma_z^2, initial_velocity_variance)); its innovations count from
the third on, where P0 no longer matters.

The configured sigmas are one more candidate and stay in use until the grid's best beats
them by a likelihood-ratio test at ``significance`` (Wilks: 2 (log L_best - log L_prior) >
chi^2_3 quantile): with few measurements the prior stands, with many the data decide.
Boxes are (N, 4) float64 xywh pixels.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from scipy.stats import chi2

#: sigma levels of the grid (per 10 px of height): 1/81 .. 3, a factor 3 apart
LEVELS = (1 / 81, 1 / 27, 1 / 9, 1 / 3, 1.0, 3.0)


@numba.njit(cache=True)
def _bank_steps(slots: np.ndarray, ks: np.ndarray, n: np.ndarray, Z: np.ndarray,
                X: np.ndarray, U: np.ndarray, Pm: np.ndarray, qp: np.ndarray, qv: np.ndarray,
                r: np.ndarray, ivv: float, ll: np.ndarray) -> None:  # pragma: no cover (compiled)
    """One measurement z = Z[i] (4,) of each track ``slots[i]``, through every candidate
    filter g: a first measurement (n[i] == 0) initialises x = z, v = 0, P0 = diag(r, ivv);
    a later one predicts ``ks[i]`` frames, adds the innovation log-likelihood to ``ll[g]``
    from the track's third measurement on (n[i] >= 2), and corrects.
    X, U: (S, G, 4) positions and velocities; Pm: (S, G, 3) = (p11, p12, p22), the two-state
    covariance every coordinate shares; qp, qv, r: (G,) variances."""
    log2pi = math.log(2.0 * math.pi)
    for i in range(slots.shape[0]):
        s, k = slots[i], ks[i]
        for g in range(qp.shape[0]):
            if n[i] == 0:
                for j in range(4):
                    X[s, g, j] = Z[i, j]
                    U[s, g, j] = 0.0
                Pm[s, g, 0], Pm[s, g, 1], Pm[s, g, 2] = r[g], 0.0, ivv
                continue
            p11, p12, p22 = Pm[s, g, 0], Pm[s, g, 1], Pm[s, g, 2]
            for _ in range(k):  # P = F P F' + Q, F = [[1, 1], [0, 1]] per coordinate
                p11 = p11 + 2.0 * p12 + p22 + qp[g]
                p12 = p12 + p22
                p22 = p22 + qv[g]
            S = p11 + r[g]  # S = H P H' + R
            k1, k2 = p11 / S, p12 / S  # K = P H' S^-1
            quad = 0.0
            for j in range(4):
                x = X[s, g, j] + k * U[s, g, j]  # x = F^k x
                y = Z[i, j] - x  # y = z - H x
                quad += y * y
                X[s, g, j] = x + k1 * y  # x = x + K y
                U[s, g, j] += k2 * y
            if n[i] >= 2:  # log L += -1/2 (y' S^-1 y + log det(2 pi S))
                ll[g] -= 0.5 * (quad / S + 4.0 * (log2pi + math.log(S)))
            Pm[s, g, 0] = (1.0 - k1) * p11  # P = (I - K H) P
            Pm[s, g, 1] = (1.0 - k1) * p12
            Pm[s, g, 2] = p22 - k2 * p12


class KalmanNoiseML:
    """Maximum-likelihood (sigma_p, sigma_v, sigma_z) of the height-scaled constant-velocity
    box filter over a grid, from the measurements of each track (module docstring).

    Args:
        prior: the configured (sigma_p, sigma_v, sigma_z), in use until the data beat them.
        initial_velocity_variance: P0's velocity variance per (10 px)^2 (the filter's).
        levels: sigma values of the grid, each of the three sigmas takes each level.
        significance: level of the likelihood-ratio test against the prior, in (0, 1).
    """

    def __init__(self, prior: tuple[float, float, float],
                 initial_velocity_variance: float = 100.0,
                 levels: tuple[float, ...] = LEVELS, significance: float = 0.99) -> None:
        prior = tuple(float(v) for v in prior)
        if len(prior) != 3 or min(prior) <= 0:
            raise ValueError(f"prior: expected three sigmas > 0, got {prior!r}")
        if not levels or min(levels) <= 0:
            raise ValueError(f"levels: expected sigmas > 0, got {levels!r}")
        if not 0.0 < significance < 1.0:
            raise ValueError(f"significance: must lie in (0, 1), got {significance!r}")
        if initial_velocity_variance <= 0:
            raise ValueError("initial_velocity_variance: must be > 0, got "
                             f"{initial_velocity_variance!r}")
        lv = np.asarray(levels, dtype=np.float64)
        sp, sv, sz = (a.ravel() for a in np.meshgrid(lv, lv, lv, indexing="ij"))
        #: (G, 3) candidate sigmas; the last row is the prior
        self.candidates = np.vstack([np.stack([sp, sv, sz], axis=1), [prior]])
        self._qp, self._qv, self._r = (np.ascontiguousarray(self.candidates[:, c] ** 2)
                                       for c in range(3))
        self.prior = prior
        self.ivv = float(initial_velocity_variance)
        self.threshold = float(chi2.ppf(significance, 3)) / 2.0  # on log L_best - log L_prior
        self.reset()

    def reset(self) -> None:
        """Forget every track and the summed likelihoods (a new sequence)."""
        g = len(self.candidates)
        self._slots: dict[int, int] = {}
        self._free: list[int] = []
        self._X = np.zeros((0, g, 4))
        self._U = np.zeros((0, g, 4))
        self._P = np.zeros((0, g, 3))
        self._last = np.zeros(0, dtype=np.int64)
        self._n = np.zeros(0, dtype=np.int64)
        self._scale = np.zeros(0)
        self.loglik = np.zeros(g)  # (G,) summed innovation log-likelihood per candidate
        self.innovations = 0  # measurements whose innovations were counted

    def _slot(self, key: int) -> int:
        s = self._slots.get(key)
        if s is not None:
            return s
        if not self._free:
            old = len(self._n)
            grow = max(8, old)
            self._X = np.concatenate([self._X, np.zeros((grow, *self._X.shape[1:]))])
            self._U = np.concatenate([self._U, np.zeros((grow, *self._U.shape[1:]))])
            self._P = np.concatenate([self._P, np.zeros((grow, *self._P.shape[1:]))])
            self._last = np.concatenate([self._last, np.zeros(grow, dtype=np.int64)])
            self._n = np.concatenate([self._n, np.zeros(grow, dtype=np.int64)])
            self._scale = np.concatenate([self._scale, np.zeros(grow)])
            self._free = list(range(old + grow - 1, old - 1, -1))
        s = self._free.pop()
        self._n[s] = 0
        self._slots[key] = s
        return s

    def measure(self, frame: int, keys: list[int], boxes: np.ndarray) -> None:
        """Run every candidate filter of each track ``keys[i]`` on its measured box
        ``boxes[i]`` (N, 4) xywh at ``frame`` (frames increase per track)."""
        if not len(keys):
            return
        boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
        slots = np.array([self._slot(key) for key in keys], dtype=np.int64)
        n = self._n[slots]
        first = n == 0
        self._scale[slots[first]] = np.maximum(boxes[first, 3], 1.0) / 10.0
        ks = frame - self._last[slots]
        if (ks[~first] < 1).any():
            bad = int((~first & (ks < 1)).nonzero()[0][0])
            raise ValueError(f"measure: frame {frame} of track {keys[bad]} is not after its "
                             f"last ({self._last[slots[bad]]})")
        Z = np.concatenate([boxes[:, :2] + boxes[:, 2:] / 2, boxes[:, 2:]], axis=1)
        Z /= self._scale[slots][:, None]  # z in units of the track's first height / 10
        _bank_steps(slots, ks, n, Z, self._X, self._U, self._P, self._qp, self._qv, self._r,
                    self.ivv, self.loglik)
        self.innovations += int((n >= 2).sum())
        self._n[slots] = n + 1
        self._last[slots] = frame

    def forget(self, alive: set[int]) -> None:
        """Free the banks of tracks no longer in ``alive`` (their likelihoods stay summed)."""
        for key in [k for k in self._slots if k not in alive]:
            self._free.append(self._slots.pop(key))

    def estimate(self) -> tuple[float, float, float]:
        """(sigma_p, sigma_v, sigma_z): the grid's maximum-likelihood candidate once it beats
        the prior by the likelihood-ratio test, else the prior."""
        best = int(np.argmax(self.loglik[:-1]))
        if self.loglik[best] - self.loglik[-1] > self.threshold:
            return tuple(float(v) for v in self.candidates[best])
        return self.prior


class ConfiguredNoise:
    """The noises as configured (every paper): nothing is estimated."""

    def reset(self) -> None:
        pass

    def measured(self, frame: int, keys: list[int], boxes: np.ndarray) -> None:
        """Nothing changes: returns None."""

    def forget(self, alive: set[int]) -> None:
        pass


class EstimatedNoise:
    """``noise_estimate``: the noises a ``KalmanNoiseML`` finds in the found people's
    measurements, per sequence (``reset``), starting from the configured ones.

    Args:
        prior: the configured (sigma_p, sigma_v, sigma_z).
        initial_velocity_variance: P0's velocity variance per (10 px)^2.
    """

    def __init__(self, prior: tuple[float, float, float],
                 initial_velocity_variance: float = 100.0) -> None:
        self.ml = KalmanNoiseML(prior, initial_velocity_variance)
        self.current = self.ml.prior

    def reset(self) -> None:
        self.ml.reset()
        self.current = self.ml.prior

    def measured(self, frame: int, keys: list[int],
                 boxes: np.ndarray) -> tuple[float, float, float] | None:
        """Add the measured boxes (N, 4) xywh of tracks ``keys`` at ``frame``; the new
        (sigma_p, sigma_v, sigma_z) when the estimate changed, else None."""
        self.ml.measure(frame, keys, boxes)
        est = self.ml.estimate()
        if est == self.current:
            return None
        self.current = est
        return est

    def forget(self, alive: set[int]) -> None:
        self.ml.forget(alive)
