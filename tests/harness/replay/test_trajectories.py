"""Trajectory plots (harness/replay/trajectories.py)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from report_scenes import Walk, mot

from occbench.replay.trajectories import most_occluded_person, person_paths, plot_person


def test_trajectory_plot_follows_the_matched_ids(tmp_path):
    seq = Walk()
    assert most_occluded_person(seq.gt) == 2
    t = seq.gt.table
    # tracker A follows person 2 as id 7 then id 8 after the occlusion; B never finds it
    p2 = t.ids == 2
    rows_a = [(f, 7 if f < 6 else 8, *b) for f, b in zip(t.frames[p2], t.boxes[p2])]
    res = {"A": mot(rows_a), "B": mot([(1, 1, 0, 0, 5, 5)])}
    paths = person_paths(t, res, 2)
    assert sorted(paths["A"]) == [7, 8] and paths["B"] == {}
    assert len(paths["A"][7]) == 5 and paths["A"][8][0, 0] == 6
    path = plot_person(seq.gt, res, 2, tmp_path / "traj.png")
    assert cv2.imread(str(path)) is not None
    with pytest.raises(ValueError, match="no ground-truth person"):
        person_paths(t, res, 9)


def test_a_path_is_not_drawn_across_missed_frames():
    from occbench.replay.trajectories import gaps_broken

    frames = np.array([1, 2, 5, 6])
    out = gaps_broken(frames, np.array([[0.0], [1.0], [4.0], [5.0]]))
    assert out.shape == (5, 1) and np.isnan(out[2, 0])
    assert np.array_equal(out[[0, 1, 3, 4], 0], [0.0, 1.0, 4.0, 5.0])
    assert gaps_broken(np.array([1, 2, 3]), np.ones((3, 2))).shape == (3, 2)  # no gap
