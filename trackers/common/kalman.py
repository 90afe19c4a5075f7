"""Kalman filter set-ups shared by the trackers: the constant-velocity box model as plain
arrays (``constant_velocity_model``) and as a filterpy ``KalmanFilter``
(``constant_velocity_box_filter``; filterpy, which imports scipy.stats, is imported there,
on the first filter built, not with this module)."""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

if TYPE_CHECKING:
    from filterpy.kalman import KalmanFilter


class BoxModel(NamedTuple):
    """First state and matrices of a constant-velocity box filter: x (8, 1), P (8, 8),
    F (8, 8), H (4, 8), Q (8, 8), R (4, 4)."""

    x: np.ndarray
    P: np.ndarray
    F: np.ndarray
    H: np.ndarray
    Q: np.ndarray
    R: np.ndarray


def constant_velocity_model(
    box: np.ndarray,
    dt: float = 1.0,
    position_noise: float = 1.0,
    velocity_noise: float = 0.1,
    measurement_noise: float = 1.0,
    initial_velocity_variance: float = 100.0,
) -> BoxModel:
    """Constant-velocity model over the box centre and size.

    State x = (xc, yc, w, h, vx, vy, vw, vh); measurement z = (xc, yc, w, h). Noise
    standard deviations are scaled by the box height so one setting fits near and far
    people: Q = diag((sigma_p h)^2, .., (sigma_v h)^2, ..), R = (sigma_z h)^2 I.

    Args:
        box: (4,) xywh first measurement.
    """
    x, y, w, h = (float(v) for v in box)
    F = np.eye(8)
    F[:4, 4:] = dt * np.eye(4)  # x' = F x
    H = np.eye(4, 8)  # z = H x
    scale = max(h, 1.0) / 10.0
    Q = np.diag([position_noise**2] * 4 + [velocity_noise**2] * 4) * scale**2
    R = np.eye(4) * (measurement_noise * scale) ** 2
    P = np.diag([measurement_noise**2] * 4 + [initial_velocity_variance] * 4) * scale**2
    x0 = np.array([x + w / 2, y + h / 2, w, h, 0, 0, 0, 0], dtype=np.float64).reshape(8, 1)
    return BoxModel(x0, P, F, H, Q, R)


def constant_velocity_box_filter(box: np.ndarray, **noise: float) -> KalmanFilter:
    """filterpy ``KalmanFilter`` of ``constant_velocity_model(box, **noise)``."""
    # start-up: filterpy (it imports scipy.stats), ~0.4 s CPU; reta's first frame needs none
    from filterpy.kalman import KalmanFilter

    model = constant_velocity_model(box, **noise)
    kf = KalmanFilter(dim_x=8, dim_z=4)
    kf.F, kf.H, kf.Q, kf.R, kf.P, kf.x = model.F, model.H, model.Q, model.R, model.P, model.x
    return kf


def state_box(kf: KalmanFilter) -> np.ndarray:
    """(4,) xywh box of a constant-velocity box filter's state (sizes floored at 1 pixel)."""
    xc, yc, w, h = kf.x[:4, 0]
    w, h = max(w, 1.0), max(h, 1.0)
    return np.array([xc - w / 2, yc - h / 2, w, h])


def box_measurement(box: np.ndarray) -> np.ndarray:
    """(4,) xywh -> (4, 1) measurement z = (xc, yc, w, h)."""
    x, y, w, h = (float(v) for v in box)
    return np.array([[x + w / 2], [y + h / 2], [w], [h]])
