"""summary.md's column legend (harness/report/legend.py): every column a run can write is
explained, each once, and only the columns shown."""

from __future__ import annotations

import pandas as pd

from occbench.metrics import COLUMNS
from occbench.metrics.occlusion import EXTRA_COLUMNS
from occbench.pipeline.summary import summary_markdown
from occbench.report.legend import column_legend, meaning


def test_every_metric_column_is_explained():
    unknown = [c for c in [*COLUMNS, *EXTRA_COLUMNS] if not meaning(c)]
    assert unknown == []
    assert meaning("no_such_column") is None
    assert column_legend(["tracker", "made_up"])[-2] == "- `made_up`: (not described here)"


def test_summary_explains_each_shown_column_once():
    rows = []
    for tracker, idf1 in (("a", 0.5), ("b", 0.7)):
        for seq in ("s1", "COMBINED"):
            rows.append({"tracker": tracker, "sequence": seq, "IDF1": idf1, "MOTA": 0.4,
                         "IDs": 3, "Song_MT%": 50.0, "PBM_IDs/frame": 1.0, "ReID": 0.5})
    text = summary_markdown(pd.DataFrame(rows), [], columns=["IDF1", "MOTA", "IDs"])
    legend = text[text.index("## Columns"):]
    for column in ("IDF1", "MOTA", "IDs", "Song_MT%", "PBM_IDs/frame", "ReID"):
        assert legend.count(f"- `{column}`:") == 1
    assert "`HOTA`" not in legend  # not in any table shown
