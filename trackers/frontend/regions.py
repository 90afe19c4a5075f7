"""Foreground regions grouped into person boxes: merging near fragments, k-means splits
(``fallback.RegionDetector``). Plain numpy and OpenCV."""

from __future__ import annotations

import cv2
import numpy as np


def merge_near(stats: np.ndarray, keep: list[int], gap: float) -> list[list[int]]:
    """Components (indices into ``stats``) grouped when their boxes lie within ``gap``
    pixels of each other (transitively)."""
    parent = {i: i for i in keep}

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    box = {i: stats[i, :4].astype(np.float64) for i in keep}
    for a_i, a in enumerate(keep):
        for b in keep[a_i + 1:]:
            xa, ya, wa, ha = box[a]
            xb, yb, wb, hb = box[b]
            dx = max(xb - (xa + wa), xa - (xb + wb), 0.0)
            dy = max(yb - (ya + ha), ya - (yb + hb), 0.0)
            if max(dx, dy) <= gap:
                parent[root(a)] = root(b)
    groups: dict[int, list[int]] = {}
    for i in keep:
        groups.setdefault(root(i), []).append(i)
    return list(groups.values())


def split_kmeans(mask: np.ndarray, parts: int, seed: int) -> list[np.ndarray]:
    """``mask`` as ``parts`` masks by k-means on its pixel coordinates (one when parts = 1)."""
    if parts <= 1:
        return [mask]
    rows, cols = np.nonzero(mask)
    pts = np.column_stack([cols, rows]).astype(np.float32)
    cv2.setRNGSeed(seed)
    crit = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 20, 0.5)
    _, assign, _ = cv2.kmeans(pts, parts, None, crit, 1, cv2.KMEANS_PP_CENTERS)
    out = []
    for k in range(parts):
        sel = assign.ravel() == k
        if sel.any():
            m = np.zeros_like(mask)
            m[rows[sel], cols[sel]] = True
            out.append(m)
    return out
