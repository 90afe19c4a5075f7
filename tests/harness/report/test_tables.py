"""Comparison tables (harness/report/tables.py): best values by each metric's direction,
COMBINED rows."""

from __future__ import annotations

import numpy as np
import pandas as pd

from occbench.metrics import COLUMNS
from occbench.metrics.occlusion import EXTRA_COLUMNS
from occbench.report.tables import best_mask, comparison, to_latex, to_markdown, to_text


def test_best_values_are_marked_by_direction():
    df = pd.DataFrame({"IDF1": [0.5, 0.7, 0.6], "FP": [10, 3, 4], "IDs": [2, 2, 3],
                       "PT": [1, 5, 5], "MOTA": [np.nan, -0.2, np.nan], "ML": [0, 0, 0]},
                      index=pd.Index(["a", "b", "c"], name="tracker"))
    best = best_mask(df)
    assert list(best["IDF1"]) == [False, True, False]
    assert list(best["FP"]) == [False, True, False]  # lower is better
    assert list(best["IDs"]) == [True, True, False]  # a tie for best marks both
    assert list(best["PT"]) == [False, False, False]  # neither better nor worse
    assert list(best["MOTA"]) == [False, False, False]  # one finite value: nothing to compare
    assert list(best["ML"]) == [False, False, False]  # every value ties: none is best
    md = to_markdown(df)
    assert "| b | **0.700** | **3** | **2** | 5 | -0.200 | 0 |" in md
    tex = to_latex(df.rename(index={"b": "my_tracker"}))
    assert r"my\_tracker & \textbf{0.700} & \textbf{3}" in tex
    assert "0.700*" in to_text(df)


def test_comparison_picks_combined_rows():
    m = pd.DataFrame({"tracker": ["a", "a", "b", "b"],
                      "sequence": ["s", "COMBINED", "s", "COMBINED"],
                      "IDF1": [0.1, 0.2, 0.3, 0.4], "FP": [1, 2, 3, 4]})
    c = comparison(m, ["FP", "IDF1", "absent"])
    assert list(c.index) == ["a", "b"] and list(c.columns) == ["FP", "IDF1"]
    assert list(c["IDF1"]) == [0.2, 0.4]


def test_every_metric_column_has_a_deliberate_direction():
    from occbench.report.tables import direction

    lower = {"FP", "FN", "IDs", "Frag", "ML", "Song_ML%", "Song_IDS", "PBM_Missed",
             "PBM_IDs/frame", "PBM_dx%", "IDs_v0-25", "ReID_frames"}
    neutral = {"GT", "PT", "Song_GT", "PBM_GT", "ReID_n"}
    higher = {"IDF1", "HOTA", "MOTA", "MOTP", "Recall", "MT", "Song_MT%", "PBM_MT",
              "Recall_v0-25", "IDP_v0-25", "ReID"}
    for names, d in ((lower, -1), (neutral, 0), (higher, 1)):
        for c in names:
            assert c in [*COLUMNS, *EXTRA_COLUMNS], c
            assert direction(c) == d, c
