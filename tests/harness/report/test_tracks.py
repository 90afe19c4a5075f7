"""occbench.report.tracks: a run without ground truth counts its tracks, their lengths and
frames/s; summary.md shows them instead of "No sequence was scored"."""

from __future__ import annotations

import numpy as np
import pandas as pd

from occbench.pipeline.summary import summary_markdown
from occbench.report.tracks import track_rows, track_stats, tracks_text


def test_track_stats_by_hand():
    ids = np.array([1, 1, 1, 2, 3, 3, 1, 2])  # lengths 4, 2, 2
    st = track_stats(ids)
    assert st == {"tracks": 3, "boxes": 8, "len_min": 2, "len_median": 2.0,
                  "len_p90": 3.6, "len_max": 4}
    assert track_stats(np.array([], dtype=int))["tracks"] == 0


def test_summary_without_ground_truth_counts_the_tracks():
    rows = track_rows({"baseline": {"clip": track_stats(np.array([1, 1, 2]))}},
                      [{"tracker": "baseline", "sequence": "clip", "fps": 123.4}])
    assert rows.iloc[0].to_dict() == {"tracker": "baseline", "sequence": "clip", "tracks": 2,
                                      "boxes": 3, "len_min": 1, "len_median": 1.5,
                                      "len_p90": 1.9, "len_max": 2, "fps": 123.4}
    empty = pd.DataFrame(columns=["tracker", "sequence", "HOTA", "complete"])
    text = summary_markdown(empty, [], title="dataset video (1 sequence)", tracks=rows)
    assert "No sequence was scored" not in text
    assert "| baseline | clip | 2 | 3 | 1 | 1.5 | 1.9 | 2 | 123.4 |" in text
    assert "len_p90" in text and "90th percentile" in text  # every column explained
    assert "No sequence was scored" in summary_markdown(empty, [])
    assert "baseline" in tracks_text(rows)
