"""The three hypotheses about a missing person (Reta Alg. 1, 3.3.3) and their pruning.

* 'velocity' (hypothesis 1, case 1): the person keeps velocity and direction.
* 'occluder' (hypothesis 2, case 2): at the first total occlusion, the person acquires the
  velocity and direction of the occluder.
* 'still' (hypothesis 3, case 3): at the first total occlusion, the person stays where it
  was last seen.

States are (8,) Kalman vectors (xc, yc, w, h, vx, vy, vw, vh), boxes (N, 4) xywh pixels.
"""

from __future__ import annotations

import numpy as np

VELOCITY = "velocity"
OCCLUDER = "occluder"
STILL = "still"
KINDS = (VELOCITY, OCCLUDER, STILL)
# preference among equally plausible hypotheses (reported.LeastContradicted, FirstHypothesis)
PRIORITY = {VELOCITY: 0, OCCLUDER: 1, STILL: 2}


def set_motion(x: np.ndarray, kinds: list[str], occluder_velocity: np.ndarray) -> np.ndarray:
    """Motion of each hypothesis before the Kalman prediction (3.3.3 motion cases).

    Args:
        x: (N, 8) states of the previous nodes.
        kinds: N kinds: 'visible' and 'velocity' keep their velocity (case 1), 'occluder'
            takes the occluder's (case 2), 'still' is set to rest (case 3). Hypotheses keep
            their size (size rates zeroed): the shape comes from the prediction.
        occluder_velocity: (N, 2) occluder (vx, vy) per row (used by 'occluder' rows).
    Returns:
        (N, 8) states with velocities set.
    """
    x = x.copy()
    for i, kind in enumerate(kinds):
        if kind == STILL:
            x[i, 4:] = 0.0
        elif kind == OCCLUDER:
            x[i, 4:6] = occluder_velocity[i]
            x[i, 6:] = 0.0
        elif kind == VELOCITY:
            x[i, 6:] = 0.0
    return x


def spawn(x_parent: np.ndarray, occluder_velocity: np.ndarray) -> dict[str, np.ndarray]:
    """Hypotheses 2 and 3 at the first total occlusion (Alg. 1, FirstOcclusion).

    Args:
        x_parent: (8,) state of the last node before the occlusion (the parent node).
        occluder_velocity: (2,) occluder (vx, vy).
    Returns:
        {'occluder': (8,) state moved one step with the occluder's velocity,
         'still': (8,) state at the parent's position with zero velocity}.
    """
    follow = x_parent.copy()
    follow[4:6] = occluder_velocity
    follow[6:] = 0.0
    follow[:4] += follow[4:]
    still = x_parent.copy()
    still[4:] = 0.0
    return {OCCLUDER: follow, STILL: still}


def outside_image(boxes: np.ndarray, width: int, height: int) -> np.ndarray:
    """(N,) bool: the centre of each xywh box lies outside the image (the person left: our
    reading of 3.3's "objects getting out of the scene", ``reading:image_exit``)."""
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    c = b[:, :2] + b[:, 2:] / 2
    return (c[:, 0] < 0) | (c[:, 0] >= width) | (c[:, 1] < 0) | (c[:, 1] >= height)
