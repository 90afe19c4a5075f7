"""HOTA(alpha): HOTA, DetA and AssA of each tracker against the localisation threshold alpha.

Luiten et al. (IJCV 2021) Fig. 6 style: one colour per tracker, HOTA solid, DetA dashed,
AssA dotted, over the 19 alphas 0.05..0.95 of the COMBINED rows of ``hota_alpha.csv``.
"""

from __future__ import annotations

import logging
from pathlib import Path

import pandas as pd

from harness.report.figures import save_figure
from harness.report.tables import COMBINED

log = logging.getLogger(__name__)

STYLES = {"HOTA": "-", "DetA": "--", "AssA": ":"}


def hota_alpha_plot(table: pd.DataFrame, path: str | Path, title: str | None = None) -> Path | None:
    """Draw the COMBINED rows of ``table`` (``tracker``, ``sequence``, ``alpha``, HOTA, DetA,
    AssA: ``hota_alpha.csv``) into ``path`` (PNG); None when there is no COMBINED row."""
    rows = table[table["sequence"] == COMBINED]
    if rows.empty:
        log.info("no COMBINED rows: %s not written", path)
        return None
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    fig, ax = plt.subplots(figsize=(6.4, 4.0), dpi=120)
    trackers = list(dict.fromkeys(rows["tracker"]))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, t in enumerate(trackers):
        r = rows[rows["tracker"] == t].sort_values("alpha")
        colour = colours[i % len(colours)]
        for metric, style in STYLES.items():
            ax.plot(r["alpha"], r[metric], style, color=colour, linewidth=1.4)
        mean = float(r["HOTA"].mean())
        ax.plot([], [], "-", color=colour, label=f"{t} (HOTA {mean:.3f})")
    first = ax.legend(fontsize=8, loc="lower left", frameon=False, title="tracker",
                      title_fontsize=8)
    ax.add_artist(first)
    ax.legend([Line2D([], [], color="grey", linestyle=s) for s in STYLES.values()],
              list(STYLES), fontsize=8, loc="lower right", frameon=False, title="metric",
              title_fontsize=8)
    ax.set_xlim(0.0, 1.0)
    ax.set_ylim(0.0, 1.02)
    ax.set_xlabel("alpha (localisation threshold, IoU)")
    ax.set_ylabel("score (COMBINED)")
    ax.set_title(f"HOTA(alpha): {title}" if title else "HOTA(alpha)", fontsize=9)
    ax.grid(alpha=0.3)
    return save_figure(fig, path)
