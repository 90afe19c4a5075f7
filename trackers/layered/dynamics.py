"""The two Kalman filters of PBM section 3: KF1 for the gate, KF2 for the size.

Both are 2-D constant-velocity filters (state = two values and their rates, measurement =
the two values) written out in plain numpy: the tracker runs two per target per frame and
filterpy's generality costs more than the arithmetic.

KF1 (eq. 7): Z1 = (xc, yc), X1 = (xc, yc, xc', yc'). Its velocity estimate only sets the
gate's size; the gate is centred on the target's last validated position (zero-order
prediction): "the direction of human movement is unpredictable while speed magnitude is
approximately constant". After a miss the gate doubles and then keeps growing until the
target is found again or dropped.

KF2 (eq. 8): Z2 = (h, w), X2 = (h, w, h', w'): the predicted size used by the occlusion
test (PBM 3.1) and as the centre of the head-anchored size search (eqs. 9-10).
"""

from __future__ import annotations

import numpy as np

_F = np.array([[1.0, 0, 1, 0], [0, 1, 0, 1], [0, 0, 1, 0], [0, 0, 0, 1]])
_H = np.eye(2, 4)


class ConstantVelocity2D:
    """Kalman filter x = (a, b, a', b'), z = (a, b), unit time step.

    Noise is given as standard deviations scaled by ``scale`` (the person height) so one
    setting serves near and far people: Q = diag(q_p^2, q_p^2, q_v^2, q_v^2) scale^2,
    R = r^2 scale^2 I.

    Args:
        z: (2,) first measurement. scale: pixels per unit noise (e.g. height / 10).
        position_noise, velocity_noise, measurement_noise: q_p, q_v, r.
        initial_velocity_std: prior standard deviation of the rates (times scale).
    """

    def __init__(self, z: np.ndarray, scale: float, position_noise: float,
                 velocity_noise: float, measurement_noise: float,
                 initial_velocity_std: float = 1.0) -> None:
        s2 = max(scale, 1e-3) ** 2
        self.x = np.array([z[0], z[1], 0.0, 0.0], dtype=np.float64)
        self.P = np.diag([measurement_noise**2] * 2 + [initial_velocity_std**2] * 2) * s2
        self.Q = np.diag([position_noise**2] * 2 + [velocity_noise**2] * 2) * s2
        self.R = np.eye(2) * measurement_noise**2 * s2

    def predict(self) -> np.ndarray:
        """x = F x; P = F P F' + Q. Returns the predicted (a, b)."""
        self.x = _F @ self.x
        self.P = _F @ self.P @ _F.T + self.Q
        return self.x[:2]

    def update(self, z: np.ndarray) -> None:
        """y = z - H x; S = H P H' + R; K = P H' S^-1; x += K y; P = (I - K H) P."""
        y = np.asarray(z, dtype=np.float64) - self.x[:2]
        S = self.P[:2, :2] + self.R
        det = S[0, 0] * S[1, 1] - S[0, 1] * S[1, 0]
        S_inv = np.array([[S[1, 1], -S[0, 1]], [-S[1, 0], S[0, 0]]]) / det
        K = self.P[:, :2] @ S_inv
        self.x = self.x + K @ y
        self.P = self.P - K @ self.P[:2, :]

    @property
    def rate(self) -> np.ndarray:
        return self.x[2:]


class GateFilter:
    """KF1 and the gate rectangle (PBM 3, eq. 7, Fig. 5).

    The gate is centred on the last validated centroid; its half-sizes are
    ``speed_factor * |v| + min_fraction * (w, h)`` with |v| the KF1 speed magnitude, times
    ``miss_factor`` after one miss and a further ``growth`` per extra miss, capped at
    ``max_fraction * (w, h)``. A candidate is inside when its centre lies in the gate.
    """

    def __init__(self, centre: np.ndarray, height: float, position_noise: float,
                 velocity_noise: float, measurement_noise: float, speed_factor: float,
                 min_fraction: float, miss_factor: float, growth: float, max_fraction: float) -> None:
        self.kf = ConstantVelocity2D(centre, height / 10.0, position_noise, velocity_noise,
                                     measurement_noise)
        self.centre = np.asarray(centre, dtype=np.float64).copy()
        self.speed_factor = speed_factor
        self.min_fraction = min_fraction
        self.miss_factor = miss_factor
        self.growth = growth
        self.max_fraction = max_fraction

    def predict(self) -> None:
        self.kf.predict()

    def correct(self, centre: np.ndarray) -> None:
        self.kf.update(centre)
        self.centre = np.asarray(centre, dtype=np.float64).copy()

    @property
    def speed(self) -> float:
        return float(np.hypot(*self.kf.rate))

    def half_size(self, size_wh: np.ndarray, misses: int) -> np.ndarray:
        """(2,) gate half-width and half-height for a target of size (w, h)."""
        wh = np.asarray(size_wh, dtype=np.float64)
        half = self.speed_factor * self.speed + self.min_fraction * wh
        if misses > 0:
            half = half * self.miss_factor * self.growth ** (misses - 1)
        return np.minimum(half, self.max_fraction * np.maximum(wh, 1.0))

    def gate(self, size_wh: np.ndarray, misses: int) -> np.ndarray:
        """(4,) xywh gate rectangle."""
        half = self.half_size(size_wh, misses)
        return np.array([*(self.centre - half), *(2 * half)])


class SizeFilter:
    """KF2 (eq. 8): h, w and their rates; ``predicted`` is the (w, h) for this frame."""

    def __init__(self, w: float, h: float, position_noise: float, velocity_noise: float,
                 measurement_noise: float) -> None:
        self.kf = ConstantVelocity2D(np.array([h, w]), h / 10.0, position_noise,
                                     velocity_noise, measurement_noise, initial_velocity_std=0.1)

    def predict(self) -> np.ndarray:
        """Predicted (w, h), floored at 2 pixels (rates are zeroed if they would shrink it)."""
        if self.kf.x[0] + self.kf.x[2] < 2 or self.kf.x[1] + self.kf.x[3] < 2:
            self.kf.x[2:] = 0.0
        self.kf.predict()
        return self.predicted

    def correct(self, w: float, h: float) -> None:
        self.kf.update(np.array([h, w]))

    @property
    def predicted(self) -> np.ndarray:
        h, w = self.kf.x[:2]
        return np.array([max(w, 2.0), max(h, 2.0)])
