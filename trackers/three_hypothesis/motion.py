"""Motion model M = [x, P] (Reta 3.2): constant-velocity Kalman filter, batched.

Each node carries its own state x (8,) = (xc, yc, w, h, vx, vy, vw, vh) and covariance
P (8, 8). The matrices F, H, Q, R come from
``occbench.trackers.common.kalman.constant_velocity_model`` (one set-up for the project); the
predict and correct steps below are filterpy's equations applied to all nodes of a frame
at once (``tests/trackers/three_hypothesis/test_tracker.py`` checks them against
``filterpy.kalman.KalmanFilter``).

Two states, picked by ``Adaptations.filter_size``: ``BoxState`` filters the whole box (ours);
``CentreState`` is the paper's M (3.2, "position and velocity"): a 4-D filter over
(xc, yc, vx, vy) with z = (xc, yc), the size carried as the shape's. Both keep the 8-slot
layout above, so hypotheses, the graph and the reports read one kind of state.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from occbench.trackers.common.checks import require
from occbench.trackers.common.kalman import constant_velocity_model


@dataclass(frozen=True)
class MotionModel:
    """Noise set-up of M shared by all people of one tracker (standard deviations, scaled by
    the person's height / 10 as in ``constant_velocity_model``).

    Args:
        position_noise: Kalman Q, position and size process noise std per 10 px of height.
        velocity_noise: Kalman Q, velocity process noise std per 10 px of height.
        measurement_noise: Kalman R, measurement noise std per 10 px of height.
        initial_velocity_variance: Kalman P0, initial velocity variance per (10 px)^2.
    """

    position_noise: float = 1.0
    velocity_noise: float = 0.1
    measurement_noise: float = 1.0
    initial_velocity_variance: float = 100.0

    def __post_init__(self) -> None:
        for name in ("position_noise", "velocity_noise", "measurement_noise",
                     "initial_velocity_variance"):
            value = getattr(self, name)
            require(f"motion.{name}", value > 0, "must be > 0", value)

    def init(self, box: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """First state of a person from its (4,) xywh box: x (8,), P (8, 8), F, H, Q, R."""
        m = constant_velocity_model(
            box,
            position_noise=self.position_noise,
            velocity_noise=self.velocity_noise,
            measurement_noise=self.measurement_noise,
            initial_velocity_variance=self.initial_velocity_variance,
        )
        return m.x[:, 0].copy(), m.P, m.F, m.H, m.Q, m.R


def predict(x: np.ndarray, P: np.ndarray, F: np.ndarray, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Kalman prediction of N box states at once (``BoxState``): a size rate that would
    shrink a size through zero is dropped first (as the baseline does).

    Args:
        x: (N, 8) states; P: (N, 8, 8); F: (8, 8); Q: (N, 8, 8).
    Returns:
        x = F x, P = F P F' + Q  (filterpy ``KalmanFilter.predict``).
    """
    x = x.copy()
    shrink = (x[:, 2] + x[:, 6] <= 1) | (x[:, 3] + x[:, 7] <= 1)
    x[shrink, 6:] = 0.0
    return _predict(x, P, F, Q)


def _predict(x: np.ndarray, P: np.ndarray, F: np.ndarray, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """x = F x, P = F P F' + Q for (N, n) states, (N, n, n) P and Q, (n, n) F."""
    x = x @ F.T  # x = F x
    P = F @ P @ F.T + Q  # P = F P F' + Q
    return x, P


def correct(
    x: np.ndarray, P: np.ndarray, z: np.ndarray, H: np.ndarray, R: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Kalman correction of N states with N measurements (filterpy ``KalmanFilter.update``).

    Args:
        x: (N, 8); P: (N, 8, 8); z: (N, 4) measurements (xc, yc, w, h); H: (4, 8); R: (N, 4, 4).
    Returns:
        corrected x, P with the Joseph form P = (I - K H) P (I - K H)' + K R K'.
    """
    y = z - x @ H.T  # y = z - H x
    PHt = P @ H.T
    S = H @ PHt + R  # S = H P H' + R
    K = PHt @ np.linalg.inv(S)  # K = P H' S^-1
    x = x + np.einsum("nij,nj->ni", K, y)  # x = x + K y
    IKH = np.eye(P.shape[1])[None] - K @ H
    P = IKH @ P @ IKH.transpose(0, 2, 1) + K @ R @ K.transpose(0, 2, 1)
    return x, P


def state_boxes(x: np.ndarray) -> np.ndarray:
    """(N, 8) states -> (N, 4) xywh boxes (sizes floored at 1 pixel)."""
    x = np.asarray(x, dtype=np.float64).reshape(-1, 8)
    wh = np.maximum(x[:, 2:4], 1.0)
    return np.concatenate([x[:, :2] - wh / 2, wh], axis=1)


def box_measurements(boxes: np.ndarray) -> np.ndarray:
    """(N, 4) xywh -> (N, 4) measurements z = (xc, yc, w, h)."""
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    return np.concatenate([b[:, :2] + b[:, 2:] / 2, b[:, 2:]], axis=1)


@dataclass(frozen=True)
class BoxState:
    """``filter_size``: M over the whole box, x = (xc, yc, w, h, vx, vy, vw, vh) and
    z = (xc, yc, w, h): the size and its rate are filtered with the centre."""

    model: MotionModel

    def init(self, box: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """x (8,), P (8, 8), Q (8, 8), R (4, 4) of a person first measured at (4,) xywh box."""
        x, P, _, _, Q, R = self.model.init(box)
        return x, P, Q, R

    def predict(self, x: np.ndarray, P: np.ndarray, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(N, 8) x, (N, 8, 8) P and Q -> predicted x, P."""
        return predict(x, P, _F8, Q)

    def correct(self, x: np.ndarray, P: np.ndarray, z: np.ndarray,
                R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(N, 8) x, (N, 8, 8) P, (N, 4) z = (xc, yc, w, h), (N, 4, 4) R -> corrected x, P."""
        return correct(x, P, z, _H8, R)


@dataclass(frozen=True)
class CentreState:
    """3.2 as written: M's state is the centre's position and velocity, x = (xc, yc, vx, vy)
    in slots (0, 1, 4, 5) of the 8-slot layout, measured by z = (xc, yc); slots (2, 3) carry
    the size of the shape S, taken from the measurement (3.2) and kept by the prediction
    area (3.3.3), slots (6, 7) and every entry of P outside the 4-D block stay 0. Q and R
    are the centre's terms of ``MotionModel``'s."""

    model: MotionModel

    def init(self, box: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """x (8,), P (8, 8) and Q (8, 8) zero outside the 4-D block, R (4, 4)."""
        x, P8, _, _, Q8, R = self.model.init(box)
        P, Q = np.zeros((8, 8)), np.zeros((8, 8))
        P[_M4] = P8[_M4]
        Q[_M4] = Q8[_M4]
        return x, P, Q, R

    def predict(self, x: np.ndarray, P: np.ndarray, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(N, 8) x, (N, 8, 8) P and Q -> predicted x, P; the size is kept."""
        x4, P4 = _predict(x[:, _C4], P[:, _C4][:, :, _C4], _F4, Q[:, _C4][:, :, _C4])
        return _put(x, P, x4, P4)

    def correct(self, x: np.ndarray, P: np.ndarray, z: np.ndarray,
                R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(N, 8) x, (N, 8, 8) P, (N, 4) z = (xc, yc, w, h), (N, 4, 4) R -> corrected x, P:
        the centre by the 4-D filter, the size replaced by the measured one (3.2)."""
        x4, P4 = correct(x[:, _C4], P[:, _C4][:, :, _C4], z[:, :2], _H4, R[:, :2, :2])
        x, P = _put(x, P, x4, P4)
        x[:, 2:4] = z[:, 2:4]
        return x, P


@dataclass(frozen=True)
class PredictedBehind:
    """3.3.3 as written: M of a matched person being occluded is not updated from its
    measurement ("given that the person is not being occluded"); it evolves by case 1,
    keeping its velocity and direction: the prediction."""

    def update(self, corrected: tuple[np.ndarray, np.ndarray], predicted: tuple[np.ndarray, np.ndarray],
               behind: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(x, P) per matched row: ``corrected`` and ``predicted`` ((K, 8), (K, 8, 8)),
        ``behind`` (K,) bool rows behind others, which keep the prediction."""
        (Xc, Pc), (Xp, Pp) = corrected, predicted
        if not behind.any():
            return Xc, Pc
        return (np.where(behind[:, None], Xp, Xc), np.where(behind[:, None, None], Pp, Pc))


@dataclass(frozen=True)
class CorrectedBehind:
    """``correct_behind``: M of a matched person behind others is corrected by its
    (possibly partial) measurement, as anyone's."""

    def update(self, corrected: tuple[np.ndarray, np.ndarray], predicted: tuple[np.ndarray, np.ndarray],
               behind: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return corrected


_F8, _H8 = constant_velocity_model(np.array([0.0, 0.0, 10.0, 10.0]))[2:4]  # F, H (box)
_C4 = np.array([0, 1, 4, 5])  # (xc, yc, vx, vy) in the 8-slot layout
_M4 = np.ix_(_C4, _C4)
_F4 = _F8[_M4]  # [[I, I], [0, I]] over (position, velocity)
_H4 = np.eye(2, 4)  # z = (xc, yc)


def _put(x: np.ndarray, P: np.ndarray, x4: np.ndarray,
         P4: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Copies of (N, 8) x and (N, 8, 8) P with the 4-D block replaced by x4 (N, 4), P4."""
    x, P = x.copy(), P.copy()
    x[:, _C4] = x4
    P[:, _C4[:, None], _C4[None, :]] = P4
    return x, P
