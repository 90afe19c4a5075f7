"""HOTA(alpha): HOTA, DetA and AssA of each tracker against the localisation threshold alpha.

Luiten et al. (IJCV 2021) Fig. 6 style, one panel per metric (HOTA, DetA, AssA), one colour
and marker per tracker, over the 19 alphas 0.05..0.95 of the COMBINED rows of
``hota_alpha.csv``.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import pandas as pd

from occbench.config.meta import TrackerMeta, metas
from occbench.report.figures import save_figure
from occbench.report.tables import COMBINED

log = logging.getLogger(__name__)

METRICS = ("HOTA", "DetA", "AssA")
MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")


def hota_alpha_plot(table: pd.DataFrame, path: str | Path, title: str | None = None,
                    shown: Mapping[str, TrackerMeta] | None = None) -> Path | None:
    """Draw the COMBINED rows of ``table`` (``tracker``, ``sequence``, ``alpha``, HOTA, DetA,
    AssA: ``hota_alpha.csv``) into ``path`` (PNG): one panel per metric, one colour (``shown``:
    tracker -> its label and colour, ``occbench.config.meta``) and marker per tracker, one
    legend; None when there is no COMBINED row."""
    rows = table[table["sequence"] == COMBINED]
    if rows.empty:
        log.info("no COMBINED rows: %s not written", path)
        return None

    matplotlib.use("Agg", force=False)

    fig, axes = plt.subplots(1, len(METRICS), figsize=(4.0 * len(METRICS), 3.8), dpi=110,
                             sharey=True, squeeze=False)
    trackers = list(dict.fromkeys(rows["tracker"]))
    shown = metas(trackers, known=shown)
    for ax, metric in zip(axes[0], METRICS):
        for i, t in enumerate(trackers):
            r = rows[rows["tracker"] == t].sort_values("alpha")
            ax.plot(r["alpha"], r[metric], "-", marker=MARKERS[i % len(MARKERS)], markevery=3,
                    ms=4, color=shown[t].colour, linewidth=1.4,
                    label=f"{shown[t].label} (mean {float(r[metric].mean()):.3f})")
        ax.set_xlim(0.0, 1.0)
        ax.set_ylim(0.0, 1.02)
        ax.set_xlabel("alpha (localisation threshold, IoU)")
        ax.set_title(f"{metric}(alpha)", fontsize=11)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="lower left", frameon=False)
    axes[0][0].set_ylabel("score (COMBINED)")
    fig.suptitle(f"HOTA, DetA, AssA against alpha: {title}" if title
                 else "HOTA, DetA, AssA against alpha", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path)
