"""A large frame's association in independent blocks (``frame_blocks``) equals the one
dense association of the whole frame: the same tracks, frame by frame, on a crowd (with and
without the foreground mask, with the adaptations that read across pairs switched on)."""

from __future__ import annotations

import pytest

from occbench.config.build import build_tracker, compose_config
from occbench.datasets.synthetic import load_scenario
from occbench.sources.annotations import NoisyGroundTruth
from occbench.trackers.common import spatial
from occbench.trackers.layered import tracker as pbm

ACROSS = ["tracker.adaptations.lone_shrink=0.3", "tracker.adaptations.contested_template=1.2",
          "tracker.adaptations.rival_match=0.8",
          "tracker.adaptations.rival_claims=true"]  # rules reading more than one pair


def _crowd(frames: int = 10, people: int = 16) -> list[tuple]:
    seq = load_scenario("crowd", seed=3, length=frames, people=people, width=640, height=480)
    src = NoisyGroundTruth(miss_rate=0.2, jitter=0.05, seed=3)
    src.start(seq)
    return [(seq.frame(k), src.detect(k, seq.frame(k))[0], seq.foreground(k) != 0)
            for k in range(1, frames + 1)]


def _tracks(data, with_fg: bool) -> list[list[tuple]]:
    tracker = build_tracker("pbm", compose_config(["tracker=pbm", *ACROSS]).tracker)
    return [[(t.id, t.state, t.box.tobytes(), t.score) for t in
             tracker.update(image, dets, fg if with_fg else None)] for image, dets, fg in data]


@pytest.mark.parametrize("with_fg", [True, False])
def test_blocks_give_the_tracks_of_one_dense_association(monkeypatch, with_fg):
    data = _crowd()
    dense = _tracks(data, with_fg)
    split = []
    monkeypatch.setattr(pbm, "blocks", lambda n, m, pairs: split.append(
        parts := spatial.blocks(n, m, pairs, limit=16)) or parts)
    assert _tracks(data, with_fg) == dense
    assert max(len(p) for p in split) > 1  # the frames were split
    assert sum(len(f) for f in dense) > 100
