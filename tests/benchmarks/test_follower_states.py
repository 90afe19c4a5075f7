"""benchmarks/follower_states.py on hand-made MOT rows: where a follower's box is per frame."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from follower_states import states


def test_each_frame_of_a_person_gets_one_state():
    # persons 1 (x 100) and 2 (x 300), frames 1-5; follower 1 starts on person 1, then sits
    # inside it off-size, then on person 2, then on the background, then reports nothing;
    # its restart (id 7, follower 1) comes back on person 1 at frame 5
    gt = np.array([(f, g, x, 50, 40, 100, 1, -1, -1, -1) for f in range(1, 6)
                   for g, x in ((1, 100), (2, 300))], dtype=float)
    tracks = np.array([(1, 1, 100, 50, 40, 100), (2, 1, 110, 80, 20, 40), (3, 1, 300, 50, 40, 100),
                       (4, 1, 500, 50, 40, 100), (5, 7, 101, 50, 40, 100)], dtype=float)
    counts, ratios = states(gt, tracks, {1: 1, 7: 1})
    assert dict(counts) == {"on": 2, "inside, IoU < 0.5": 1, "on another": 1, "off": 1}
    assert len(ratios) == 3 and ratios[1] == (0.5, 0.4)
    counts, _ = states(gt, tracks[:4], {1: 1})
    assert counts["none"] == 1
