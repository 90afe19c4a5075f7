"""Grouped bar chart of the COMBINED metrics: one group per metric, one bar per tracker."""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from occbench.config.meta import TrackerMeta, metas
from occbench.report.figures import save_figure

if TYPE_CHECKING:
    import pandas as pd

log = logging.getLogger(__name__)

DEFAULT_METRICS = ("HOTA", "DetA", "AssA", "IDF1", "MOTA")


def metric_bars(metrics: pd.DataFrame, path: str | Path,
                names: Sequence[str] = DEFAULT_METRICS, title: str | None = None,
                shown: Mapping[str, TrackerMeta] | None = None) -> Path | None:
    """Draw the COMBINED rows of ``metrics`` as grouped bars into ``path`` (PNG).

    Args:
        metrics: frame with ``tracker``, ``sequence`` and metric columns (``metrics.csv``).
        names: metrics to draw, in order; names absent from ``metrics`` are left out.
        shown: tracker -> its label and colour (``occbench.config.meta``; default: the
            shipped configs' by name).
    Returns:
        The written path, or None when there is nothing to draw (no COMBINED row or none of
        ``names`` present).
    """
    from occbench.report.tables import COMBINED  # start-up: pandas, ~0.25 s CPU

    rows = metrics[metrics["sequence"] == COMBINED]
    names = [m for m in names if m in rows.columns]
    if rows.empty or not names:
        log.info("no COMBINED rows or metrics to plot: %s not written", path)
        return None
    import matplotlib  # start-up: matplotlib, ~0.08 s CPU

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt  # start-up: matplotlib.pyplot, ~0.4 s CPU
    trackers = list(dict.fromkeys(rows["tracker"]))
    shown = metas(trackers, known=shown)
    values = np.array([[float(rows.loc[rows["tracker"] == t, m].iloc[0]) for m in names]
                       for t in trackers])
    width = 0.8 / len(trackers)
    x = np.arange(len(names))
    size = (min(12.0, max(4.0, 1.0 + len(names) * (0.5 + 0.35 * len(trackers)))), 3.6)
    fig, ax = plt.subplots(figsize=size, dpi=120)
    for i, t in enumerate(trackers):
        pos = x - 0.4 + width * (i + 0.5)
        bars = ax.bar(pos, np.nan_to_num(values[i]), width, label=shown[t].label,
                      color=shown[t].colour)
        for b, v in zip(bars, values[i]):
            if np.isfinite(v):
                ax.annotate(f"{v:.2f}", (b.get_x() + b.get_width() / 2, b.get_height()),
                            ha="center", va="bottom", fontsize=7)
    ax.set_xticks(x, names)
    top = np.nanmax(values) if np.isfinite(values).any() else 1.0
    ax.set_ylim(min(0.0, np.nanmin(np.nan_to_num(values))) * 1.1, max(1.0, top) * 1.12)
    ax.axhline(0.0, color="black", linewidth=0.6)
    ax.set_ylabel("score (COMBINED)")
    if title:
        ax.set_title(title, fontsize=9)
    ax.legend(fontsize=8, ncol=min(len(trackers), 4), loc="upper right", frameon=False)
    return save_figure(fig, path)
