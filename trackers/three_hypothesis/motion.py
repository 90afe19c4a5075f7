"""Motion model M = [x, P] (Reta 3.2): constant-velocity Kalman filter, batched.

Each node carries its own state x (8,) = (xc, yc, w, h, vx, vy, vw, vh) and covariance
P (8, 8). The matrices F, H, Q, R come from
``trackers.common.kalman.constant_velocity_model`` (one set-up for the project); the
predict and correct steps below are filterpy's equations applied to all nodes of a frame
at once (``tests/trackers/three_hypothesis/test_tracker.py`` checks them against
``filterpy.kalman.KalmanFilter``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trackers.common.checks import require
from trackers.common.kalman import constant_velocity_model


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
    """Kalman prediction of N states at once.

    Args:
        x: (N, 8) states; P: (N, 8, 8); F: (8, 8); Q: (N, 8, 8).
    Returns:
        x = F x, P = F P F' + Q  (filterpy ``KalmanFilter.predict``).
    """
    x = x.copy()
    # never let a size shrink through zero (as the baseline does)
    shrink = (x[:, 2] + x[:, 6] <= 1) | (x[:, 3] + x[:, 7] <= 1)
    x[shrink, 6:] = 0.0
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
