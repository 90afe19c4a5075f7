"""The two Kalman filters of PBM section 3, KF1 for the gate and KF2 for the size, for all
targets at once (one row per target).

Both are 2-D constant-velocity filters (state = two values and their rates, measurement =
the two values), written out element by element in small compiled loops over the rows:
the tracker runs two per target per frame, and one step for all targets costs less than
filterpy's (or any) per-target call.

KF1 (eq. 7): Z1 = (xc, yc), X1 = (xc, yc, xc', yc'). Its velocity estimate only sets the
gate's size; the gate is centred on the target's last validated position (zero-order
prediction): "the direction of human movement is unpredictable while speed magnitude is
approximately constant". After a miss the gate doubles and then keeps growing until the
target is found again or dropped (``Gate``).

KF2 (eq. 8): Z2 = (h, w), X2 = (h, w, h', w'): the predicted size used by the occlusion
test (PBM 3.1) and as the centre of the head-anchored size search (eqs. 9-10).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from occbench.trackers.layered import kernel_cache  # noqa: F401 (before any kernel: one stamp for all)

# ----------------------------------------------------------------------------- PBM 3, eqs. 7-8, plain numpy


def kf1_z(dof: np.ndarray) -> np.ndarray:
    """Eq. 7, KF1: Z1 = (xc, yc) of (..., 6) DOF; its state is X1 = (xc, yc, xc', yc')."""
    return np.asarray(dof)[..., [2, 3]]                                      # eq. 7


def kf2_z(dof: np.ndarray) -> np.ndarray:
    """Eq. 8, KF2: Z2 = (h, w) of (..., 6) DOF; its state is X2 = (h, w, h', w')."""
    return np.asarray(dof)[..., [5, 4]]                                      # eq. 8


_F = np.block([[np.eye(2), np.eye(2)], [np.zeros((2, 2)), np.eye(2)]])


_H = np.hstack([np.eye(2), np.zeros((2, 2))])


def cv_predicted(x: np.ndarray, P: np.ndarray, q_p: float, q_v: float
               ) -> tuple[np.ndarray, np.ndarray]:
    """Predict step of KF1 (eq. 7) and KF2 (eq. 8), constant velocity, unit time step:
    x (4,) = (a, b, a', b'), P (4, 4), Q = diag(q_p, q_p, q_v, q_v) (variances)."""
    Q = np.diag([q_p, q_p, q_v, q_v])
    x = _F @ x                                                               # x = F x
    P = _F @ P @ _F.T + Q                                                    # P = F P F' + Q
    return x, P


def cv_updated(x: np.ndarray, P: np.ndarray, z: np.ndarray, r: float
              ) -> tuple[np.ndarray, np.ndarray]:
    """Update step of KF1 (eq. 7, z = Z1) and KF2 (eq. 8, z = Z2): measurement z (2,),
    R = r I (variance)."""
    y = z - _H @ x                                                           # y = z - H x
    S = _H @ P @ _H.T + r * np.eye(2)                                        # S = H P H' + R
    K = P @ _H.T @ np.linalg.inv(S)                                          # K = P H' S^-1
    x = x + K @ y                                                            # x = x + K y
    P = (np.eye(4) - K @ _H) @ P                                             # P = (I - K H) P
    return x, P


# ----------------------------------------------------------------------------- PBM 3, eqs. 7-8 and the gate, compiled


@numba.njit(cache=True)
def cv_predict_inplace(x: np.ndarray, p: np.ndarray, qp: np.ndarray, qv: np.ndarray) -> None:
    """Predict step of KF1 (eq. 7) and KF2 (eq. 8) (``cv_predicted``: x = F x,
    P = F P F' + Q) of every row, in place: x (T, 4) = (a, b, a', b'); P kept per axis i
    as its 2 x 2 block p[:, i] = (A, B, C, D) = (P[a, a], P[a, a'], P[a', a], P[a', a'])
    (diagonal P0, Q and R never couple the axes); qp, qv (T,) the noise variances."""
    for n in range(x.shape[0]):
        for i in range(2):
            x[n, i] = x[n, i] + x[n, i + 2]                                  # x = F x
            A, B, C, D = p[n, i, 0], p[n, i, 1], p[n, i, 2], p[n, i, 3]
            p[n, i, 0] = A + B + C + D + qp[n]                               # P = F P F' + Q
            p[n, i, 1] = B + D
            p[n, i, 2] = C + D
            p[n, i, 3] = D + qv[n]


@numba.njit(cache=True)
def cv_update_inplace(x: np.ndarray, p: np.ndarray, r: np.ndarray, rows: np.ndarray,
                      z: np.ndarray) -> None:
    """Update step of KF1 (eq. 7, z = (xc, yc)) and KF2 (eq. 8, z = (h, w))
    (``cv_updated``) of the filters at ``rows`` with measurements z (M, 2), in
    place (layout as ``cv_predict_inplace``; r (T,) the measurement variance)."""
    for q in range(rows.shape[0]):
        n = rows[q]
        for i in range(2):
            s = p[n, i, 0] + r[n]                                            # S = H P H' + R
            y = z[q, i] - x[n, i]                                            # y = z - H x
            A, B, C, D = p[n, i, 0], p[n, i, 1], p[n, i, 2], p[n, i, 3]
            kp, kv = A / s, C / s                                            # K = P H' S^-1
            x[n, i] += kp * y                                                # x = x + K y
            x[n, i + 2] += kv * y
            p[n, i, 0], p[n, i, 1] = A - kp * A, B - kp * B                  # P = (I - K H) P
            p[n, i, 2], p[n, i, 3] = C - kv * A, D - kv * B


@numba.njit(cache=True)
def gate_boxes(centres: np.ndarray, rates: np.ndarray, size_wh: np.ndarray, misses: np.ndarray,
               rule: tuple, out: np.ndarray) -> None:
    """The gate (PBM 3, Fig. 5; ``dynamics.Gate``) of every row into out (T, 4) xywh:
    centred on ``centres`` (zero-order prediction), half-sizes h = speed_factor |v| +
    min_fraction size (|v| KF1's speed, eq. 7), after m > 0 misses h miss_factor
    growth^(m - 1), capped at max_fraction max(size, 1). ``rule``: (speed_factor,
    min_fraction, miss_factor, growth, max_fraction)."""
    speed_factor, min_fraction, miss_factor, growth, max_fraction = rule
    for n in range(size_wh.shape[0]):
        sp = speed_factor * math.hypot(rates[n, 0], rates[n, 1])
        for i in range(2):
            h = sp + min_fraction * size_wh[n, i]
            if misses[n] > 0:
                h = h * miss_factor * growth ** (misses[n] - 1.0)
            h = min(h, max_fraction * max(size_wh[n, i], 1.0))
            out[n, i] = centres[n, i] - h
            out[n, 2 + i] = 2 * h


@numba.njit(cache=True)
def targets_predict(kf1: tuple, kf2: tuple) -> None:
    """KF1 (eq. 7) and KF2 (eq. 8) predict (``cv_predict_inplace``) of every target; KF2's
    rates are zeroed first where a step would take h or w below 2 pixels. ``kf1``, ``kf2``:
    (x, p, qp, qv) of ``ConstantVelocity2D``."""
    x2 = kf2[0]
    for n in range(x2.shape[0]):
        if x2[n, 0] + x2[n, 2] < 2 or x2[n, 1] + x2[n, 3] < 2:
            x2[n, 2] = 0.0
            x2[n, 3] = 0.0
    cv_predict_inplace(kf1[0], kf1[1], kf1[2], kf1[3])
    cv_predict_inplace(kf2[0], kf2[1], kf2[2], kf2[3])




class ConstantVelocity2D:
    """Kalman filters x = (a, b, a', b'), z = (a, b), unit time step, one row per filter.

    Noise is given as standard deviations scaled per filter by ``scale`` (the person
    height / 10) so one setting serves near and far people: Q = diag(q_p^2, q_p^2, q_v^2,
    q_v^2) scale^2, R = r^2 scale^2 I.

    The equations are the textbook ones (F = [[I, I], [0, I]], H = [I, 0]):
    predict x = F x, P = F P F' + Q; update y = z - H x, S = H P H' + R, K = P H' S^-1,
    x += K y, P = (I - K H) P. With diagonal P0, Q and R the two axes never couple, so P
    is kept as one 2 x 2 block per axis, ``p[:, axis] = (P[a, a], P[a, a'], P[a', a],
    P[a', a'])``, and the arithmetic is written out element-wise, in place
    (``cv_predict_inplace``, ``cv_update_inplace``); they equal the matrix form of
    ``cv_predicted`` / ``cv_updated`` (eqs. 7-8, above) to rounding
    (tests/trackers/layered/test_equations.py; tests/trackers/layered/test_dynamics.py checks
    agreement with filterpy's KalmanFilter).

    Args:
        position_noise, velocity_noise, measurement_noise: q_p, q_v, r.
        initial_velocity_std: prior standard deviation of the rates (times scale).
    """

    def __init__(self, position_noise: float, velocity_noise: float, measurement_noise: float,
                 initial_velocity_std: float = 1.0) -> None:
        self.noise = (float(position_noise), float(velocity_noise), float(measurement_noise),
                      float(initial_velocity_std))
        self.x = np.zeros((0, 4))
        self.p = np.zeros((0, 2, 4))
        self.qp = np.zeros(0)
        self.qv = np.zeros(0)
        self.r = np.zeros(0)
        # state and measurement at each filter's last observation (``observed``; read by
        # ``reupdate.ReUpdate``, OC-SORT's re-update after a gap)
        self.seen_x = np.zeros((0, 4))
        self.seen_p = np.zeros((0, 2, 4))
        self.seen_z = np.zeros((0, 2))

    def __len__(self) -> int:
        return len(self.x)

    def add(self, z: np.ndarray, scale: float) -> None:
        """Append a filter at the first measurement z (2,), noise scaled by ``scale``."""
        self.extend(np.asarray(z, dtype=np.float64)[None], [scale])

    def extend(self, z: np.ndarray, scale) -> None:
        """Append K filters at their first measurements z (K, 2), noise scaled by ``scale``
        (K,) (``add`` of each, in order, with one copy of the arrays)."""
        qp, qv, r, v0 = self.noise
        x, p, q = [], [], []
        for (a, b), sc in zip(np.asarray(z, dtype=np.float64).tolist(), scale, strict=True):
            s2 = max(float(sc), 1e-3) ** 2
            pp, pv = r**2 * s2, v0**2 * s2
            x.append([a, b, 0.0, 0.0])
            p.append([[pp, 0.0, 0.0, pv], [pp, 0.0, 0.0, pv]])
            q.append([qp**2 * s2, qv**2 * s2, r**2 * s2])
        x, p, q = np.array(x).reshape(-1, 4), np.array(p).reshape(-1, 2, 4), np.array(q).reshape(-1, 3)
        cat = np.concatenate  # one new array each, the old rows first
        self.x, self.p = cat((self.x, x)), cat((self.p, p))
        self.qp, self.qv, self.r = cat((self.qp, q[:, 0])), cat((self.qv, q[:, 1])), cat((self.r, q[:, 2]))
        self.seen_x, self.seen_p, self.seen_z = cat((self.seen_x, x)), cat((self.seen_p, p)), cat((self.seen_z, x[:, :2]))

    def take(self, rows) -> None:
        """Keep only the filters at ``rows`` (in that order)."""
        rows = np.asarray(rows, dtype=np.intp)
        self.x, self.p = self.x[rows], self.p[rows]
        self.qp, self.qv, self.r = self.qp[rows], self.qv[rows], self.r[rows]
        self.seen_x, self.seen_p = self.seen_x[rows], self.seen_p[rows]
        self.seen_z = self.seen_z[rows]

    def observed(self, rows: np.ndarray, z: np.ndarray) -> None:
        """Remember the state (x, P) of the filters at ``rows``, just updated with their
        measurements z (M, 2), as their last observation's."""
        self.seen_x[rows], self.seen_p[rows], self.seen_z[rows] = self.x[rows], self.p[rows], z

    def state(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """(4,) state and (4, 4) covariance of filter ``i`` (copies)."""
        P = np.zeros((4, 4))
        for axis, (A, B, C, D) in enumerate(self.p[i]):
            P[axis, axis], P[axis, axis + 2], P[axis + 2, axis], P[axis + 2, axis + 2] = A, B, C, D
        return self.x[i].copy(), P

    def predict(self) -> None:
        """x = F x; P = F P F' + Q, for every filter."""
        cv_predict_inplace(self.x, self.p, self.qp, self.qv)

    def update(self, rows: np.ndarray, z: np.ndarray) -> None:
        """y = z - H x; S = H P H' + R; K = P H' S^-1; x += K y; P = (I - K H) P, for the
        filters at ``rows`` (unique) with measurements z (M, 2)."""
        cv_update_inplace(self.x, self.p, self.r, np.asarray(rows, dtype=np.int64),
                       np.asarray(z, dtype=np.float64))


@dataclass(frozen=True)
class Gate:
    """The gate rectangle of PBM 3 (eq. 7, Fig. 5).

    The gate is centred on the last validated centroid; its half-sizes are
    ``speed_factor * |v| + min_fraction * (w, h)`` with |v| the KF1 speed magnitude, times
    ``miss_factor`` after one miss and a further ``growth`` per extra miss, capped at
    ``max_fraction * (w, h)``. A candidate is inside when its centre lies in the gate.
    """

    speed_factor: float
    min_fraction: float
    miss_factor: float
    growth: float
    max_fraction: float

    def half_sizes(self, rates: np.ndarray, size_wh: np.ndarray, misses: np.ndarray) -> np.ndarray:
        """(T, 2) gate half-width and half-height of targets with KF1 rates (T, 2), size
        (w, h) (T, 2) and ``misses`` (T,) frames unfound."""
        size_wh = np.asarray(size_wh, dtype=np.float64).reshape(-1, 2)
        return 0.5 * self.boxes(np.zeros((len(size_wh), 2)), rates, size_wh, misses)[:, 2:]

    def boxes(self, centres: np.ndarray, rates: np.ndarray, size_wh: np.ndarray,
              misses: np.ndarray) -> np.ndarray:
        """(T, 4) xywh gates centred on ``centres`` (T, 2): (centre - half, 2 half)."""
        out = np.empty((len(size_wh), 4))
        gate_boxes(np.asarray(centres, dtype=np.float64),
                            np.asarray(rates, dtype=np.float64),
                            np.asarray(size_wh, dtype=np.float64), np.asarray(misses, dtype=np.int64),
                            (float(self.speed_factor), float(self.min_fraction),
                             float(self.miss_factor), float(self.growth), float(self.max_fraction)),
                            out)
        return out
