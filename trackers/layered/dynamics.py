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

    The equations are the textbook ones (F = [[I, I], [0, I]], H = [I, 0]):
    predict x = F x, P = F P F' + Q; update y = z - H x, S = H P H' + R, K = P H' S^-1,
    x += K y, P = (I - K H) P. With diagonal P0, Q and R the two axes never couple, so P
    is kept as one 2 x 2 block per axis, (P[a, a], P[a, a'], P[a', a], P[a', a']), and
    the arithmetic is written out on Python floats (a tracker runs two filters per target
    per frame: numpy's per-call overhead dominated the 4 x 4 products). Every sum is
    grouped as the 4 x 4 matrix products group it (their other terms are exact zeros),
    so ``x`` and ``P`` equal the matrix form bit for bit (tests/test_pbm.py checks this,
    and agreement with filterpy's KalmanFilter).

    Args:
        z: (2,) first measurement. scale: pixels per unit noise (e.g. height / 10).
        position_noise, velocity_noise, measurement_noise: q_p, q_v, r.
        initial_velocity_std: prior standard deviation of the rates (times scale).
    """

    def __init__(self, z: np.ndarray, scale: float, position_noise: float,
                 velocity_noise: float, measurement_noise: float,
                 initial_velocity_std: float = 1.0) -> None:
        s2 = max(scale, 1e-3) ** 2
        self._x = [float(z[0]), float(z[1]), 0.0, 0.0]
        pp, pv = measurement_noise**2 * s2, initial_velocity_std**2 * s2
        self._p = [[pp, 0.0, 0.0, pv], [pp, 0.0, 0.0, pv]]  # per axis: A, B, C, D
        self._qp, self._qv = position_noise**2 * s2, velocity_noise**2 * s2
        self._r = measurement_noise**2 * s2

    @property
    def x(self) -> np.ndarray:
        """(4,) state (a, b, a', b') (a copy)."""
        return np.array(self._x)

    @property
    def P(self) -> np.ndarray:
        """(4, 4) state covariance (a copy)."""
        P = np.zeros((4, 4))
        for i, (A, B, C, D) in enumerate(self._p):
            P[i, i], P[i, i + 2], P[i + 2, i], P[i + 2, i + 2] = A, B, C, D
        return P

    def zero_rates(self) -> None:
        """Set a' = b' = 0 (the covariance is kept)."""
        self._x[2] = self._x[3] = 0.0

    def predict(self) -> np.ndarray:
        """x = F x; P = F P F' + Q. Returns the predicted (a, b)."""
        x = self._x
        x[0], x[1] = x[0] + x[2], x[1] + x[3]
        for blk in self._p:
            A, B, C, D = blk
            blk[0] = (A + C) + (B + D) + self._qp
            blk[1] = B + D
            blk[2] = C + D
            blk[3] = D + self._qv
        return np.array(x[:2])

    def update(self, z: np.ndarray) -> None:
        """y = z - H x; S = H P H' + R; K = P H' S^-1; x += K y; P = (I - K H) P."""
        x, (p0, p1) = self._x, self._p
        y0, y1 = float(z[0]) - x[0], float(z[1]) - x[1]
        s0, s1 = p0[0] + self._r, p1[0] + self._r
        det = s0 * s1
        for blk, inv, y, i in ((p0, s1 / det, y0, 0), (p1, s0 / det, y1, 1)):
            A, B, C, D = blk
            kp, kv = A * inv, C * inv
            x[i] += kp * y
            x[i + 2] += kv * y
            blk[0], blk[1], blk[2], blk[3] = A - kp * A, B - kp * B, C - kv * A, D - kv * B

    @property
    def rate(self) -> np.ndarray:
        return np.array(self._x[2:])


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
        return float(np.hypot(self.kf._x[2], self.kf._x[3]))

    def half_size(self, size_wh: np.ndarray, misses: int) -> np.ndarray:
        """(2,) gate half-width and half-height for a target of size (w, h)."""
        return np.array(self._half(float(size_wh[0]), float(size_wh[1]), misses))

    def _half(self, w: float, h: float, misses: int) -> tuple[float, float]:
        sp = self.speed_factor * self.speed
        hx, hy = sp + self.min_fraction * w, sp + self.min_fraction * h
        if misses > 0:
            g = self.growth ** (misses - 1)
            hx, hy = hx * self.miss_factor * g, hy * self.miss_factor * g
        return (min(hx, self.max_fraction * max(w, 1.0)), min(hy, self.max_fraction * max(h, 1.0)))

    def gate(self, size_wh: np.ndarray, misses: int) -> np.ndarray:
        """(4,) xywh gate rectangle."""
        hx, hy = self._half(float(size_wh[0]), float(size_wh[1]), misses)
        return np.array([self.centre[0] - hx, self.centre[1] - hy, 2 * hx, 2 * hy])


class SizeFilter:
    """KF2 (eq. 8): h, w and their rates; ``predicted`` is the (w, h) for this frame."""

    def __init__(self, w: float, h: float, position_noise: float, velocity_noise: float,
                 measurement_noise: float) -> None:
        self.kf = ConstantVelocity2D(np.array([h, w]), h / 10.0, position_noise,
                                     velocity_noise, measurement_noise, initial_velocity_std=0.1)

    def predict(self) -> np.ndarray:
        """Predicted (w, h), floored at 2 pixels (rates are zeroed if they would shrink it)."""
        x = self.kf._x
        if x[0] + x[2] < 2 or x[1] + x[3] < 2:
            self.kf.zero_rates()
        self.kf.predict()
        return self.predicted

    def correct(self, w: float, h: float) -> None:
        self.kf.update((h, w))

    @property
    def predicted(self) -> np.ndarray:
        h, w = self.kf._x[:2]
        return np.array([max(w, 2.0), max(h, 2.0)])
