"""The silhouette detector's person template ``T``: a mean person mask (values in [0, 1]),
learnt by ``occbench fit silhouette`` from exact person masks (``fit_template``), shipped as
``trackers/frontend/data/silhouette.npy`` (``load_template``), or drawn (``analytic_template``).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import cv2
import numpy as np

TEMPLATE_HEIGHT = 64  # rows of the stored template
HEAD_FRACTION = 1 / 7  # head height / person height (PBM 2.1)


def analytic_template(height: int = TEMPLATE_HEIGHT, width_ratio: float = 0.42) -> np.ndarray:
    """A drawn mean-person mask: head 1/7 of height, torso with arms, two legs, blurred.

    Returns (height, round(width_ratio * height)) float32 in [0, 1].
    """
    w = round(width_ratio * height)
    img = np.zeros((height * 4, w * 4), dtype=np.float32)
    H, W = img.shape
    hh = H / 7
    cx = W / 2
    cv2.ellipse(img, (int(cx), int(hh / 2)), (int(0.33 * hh), int(hh / 2)), 0, 0, 360, 1.0, -1)
    cv2.rectangle(img, (int(cx - 0.12 * H / 2.4), int(hh * 0.9)), (int(cx + 0.12 * H / 2.4), int(hh * 1.3)),
                  1.0, -1)  # neck
    torso = np.array([[cx - 0.4 * W, hh * 1.25], [cx + 0.4 * W, hh * 1.25],
                      [cx + 0.45 * W, hh * 4.0], [cx - 0.45 * W, hh * 4.0]], dtype=np.int32)
    cv2.fillPoly(img, [torso], 1.0)
    for side in (-1, 1):
        leg = np.array([[cx + side * 0.02 * W, hh * 3.6], [cx + side * 0.4 * W, hh * 3.6],
                        [cx + side * 0.36 * W, H], [cx + side * 0.06 * W, H]], dtype=np.int32)
        cv2.fillPoly(img, [leg], 1.0)
    img = cv2.GaussianBlur(img, (0, 0), sigmaX=W * 0.06)
    return np.clip(cv2.resize(img, (w, height), interpolation=cv2.INTER_AREA), 0.0, 1.0)


def fit_template(masks: list[np.ndarray], height: int = TEMPLATE_HEIGHT) -> np.ndarray:
    """Mean of person masks, each cropped to its box and resized to a common size.

    Args:
        masks: list of (h_i, w_i) bool/0-1 masks of single people, each cropped to the
            person's box.
        height: rows of the template; its width is height x the median box aspect ratio.
    Returns:
        (height, width) float32 in [0, 1].
    """
    masks = [np.asarray(m, dtype=np.float32) for m in masks if m.size and m.any()]
    if not masks:
        raise ValueError("fit_template: no non-empty masks")
    aspect = float(np.median([m.shape[1] / m.shape[0] for m in masks]))
    width = max(round(aspect * height), 3)
    acc = np.zeros((height, width), dtype=np.float64)
    for m in masks:
        acc += cv2.resize(m, (width, height), interpolation=cv2.INTER_AREA)
    return np.clip(acc / len(masks), 0.0, 1.0).astype(np.float32)


def load_template(path: str | Path | None = None) -> np.ndarray:
    """Load a template ``.npy``; None loads the shipped ``trackers/frontend/data/silhouette.npy``."""
    if path is None:
        path = resources.files("occbench.trackers.frontend") / "data" / "silhouette.npy"
    path = Path(str(path))
    if not path.is_file():
        raise FileNotFoundError(f"silhouette template not found: {path}")
    t = np.load(path, allow_pickle=False).astype(np.float32)
    if t.ndim != 2 or t.min() < 0 or t.max() > 1:
        raise ValueError(f"{path}: a template must be a 2-D array in [0, 1], got {t.shape}")
    return t

