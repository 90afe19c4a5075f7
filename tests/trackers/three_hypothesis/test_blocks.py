"""Reta's association solved block by block (a frame beyond ``spatial.DENSE_LIMIT``) gives
the whole frame's tracks: the same ids, states and boxes on a crowded scene, with the
limit forced down so that every frame splits into many blocks."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.config.build import build_tracker, compose_config
from occbench.trackers.common import spatial
from occbench.trackers.records import Detections


def _tracks(name: str, overrides: tuple = (), frames: int = 12, n: int = 60) -> list:
    tracker = build_tracker(name, compose_config([f"tracker={name}", *overrides]).tracker)
    tracker.reset()
    rng = np.random.default_rng(0)
    xy = rng.uniform([0, 0], [620, 440], (n, 2))
    v = rng.normal(0, 3, (n, 2))
    image = rng.integers(0, 255, (480, 640, 3), dtype=np.uint8)
    out = []
    for t in range(frames):
        seen = rng.random(n) > 0.2  # missed detections: hypotheses, stage 2, new tracks
        jump = (rng.random(n) < 0.2)[:, None] * rng.choice([-40.0, 40.0], (n, 2))  # stage 2
        boxes = np.column_stack([xy + v * t + jump, np.full((n, 2), [16.0, 36.0])])[seen]
        tracks = tracker.update(image, Detections(boxes, np.ones(len(boxes))), None)
        out.append([(k.id, k.state, k.box.tobytes()) for k in tracks])
    return out


OURS = tuple(f"tracker.adaptations.{k}" for k in (  # the rules that read pairs across people
    "shape_gate=0.7", "contact_region=true", "split_parts=true", "merged_appearance=true",
    "merged_motion=true", "split_appearance=true"))


@pytest.mark.parametrize("name, overrides, n", [
    ("reta", (), 60), ("reta_paper", (), 60), ("reta", OURS, 150)])  # 150: parts barred
def test_block_by_block_gives_the_whole_frames_tracks(name, overrides, n, monkeypatch):
    whole = _tracks(name, overrides, n=n)
    monkeypatch.setattr(spatial.blocks, "__defaults__", (4,))  # every frame in blocks
    assert _tracks(name, overrides, n=n) == whole
    assert sum(len(o) for o in whole) > 500


def test_the_sparse_delta_holds_the_arrays_scipys_coo_pass_builds():
    from scipy.sparse import csr_array

    from occbench.trackers.three_hypothesis.steps_occlusion import _csr

    rng = np.random.default_rng(4)
    for n, m in [(0, 3), (3, 0), (1, 1), (7, 5), (30, 12)]:
        pairs = np.unique(rng.integers(0, [max(n, 1), max(m, 1)], (rng.integers(0, 40), 2)),
                          axis=0).reshape(-1, 2)[: (0 if n * m == 0 else None)]
        values = rng.random(len(pairs))
        values[::4] = 0.0  # explicit zeros stay stored
        ours = _csr(values, pairs[:, 0], pairs[:, 1], (n, m))
        theirs = csr_array((values, (pairs[:, 0], pairs[:, 1])), shape=(n, m))
        for name in ("indptr", "indices", "data"):
            assert getattr(ours, name).tolist() == getattr(theirs, name).tolist(), name
            assert getattr(ours, name).dtype == getattr(theirs, name).dtype, name
        assert ours.shape == theirs.shape
