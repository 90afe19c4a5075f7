"""Sweep plots: each metric against each swept parameter (mean ± 95% interval over seeds,
one line per tracker) and, when two or more parameters are swept, a heatmap of each pair."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from harness.sweeps.tables import aggregate, plot_axes, tick

MAX_HEATMAP_VALUES = 12  # a parameter with more distinct values gets no heatmap


def plot_sweep(frame: pd.DataFrame, out_dir: str | Path, metrics: Sequence[str]) -> list[Path]:
    """Metric-vs-parameter line plots (mean ± 95% over seeds) and pairwise heatmaps."""
    import matplotlib

    matplotlib.use("Agg")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    params = plot_axes(frame)
    shown = [m for m in metrics if m in frame.columns]
    written: list[Path] = []
    if "sequence" not in frame.columns:
        return written
    for p in params:
        agg = aggregate(frame, [p], shown)
        if not agg.empty:
            written.append(_line_plot(agg, p, shown, out_dir / f"sweep_{_safe(p)}.png"))
    jobs = frame.drop_duplicates("job")
    # a heatmap needs two parameter axes (never a tracker or seed) of 2..12 values each
    grid_params = [p for p in params if 2 <= jobs[p].nunique() <= MAX_HEATMAP_VALUES]
    for i, a in enumerate(grid_params):  # continuous searches (Optuna) draw no heatmaps
        for b in grid_params[i + 1:]:
            agg = aggregate(frame, [a, b], shown)
            if agg.empty:
                continue
            for m in shown[:2]:
                path = out_dir / f"heatmap_{_safe(m)}_{_safe(a)}_{_safe(b)}.png"
                written.append(_heatmap(agg, a, b, m, path))
    return written


def _line_plot(agg: pd.DataFrame, p: str, shown: Sequence[str], path: Path) -> Path:
    """Each metric of ``shown`` against parameter ``p`` (``aggregate``'s rows), one line per
    tracker, into ``path``."""
    import matplotlib.pyplot as plt

    numeric = pd.to_numeric(agg[p], errors="coerce").notna().all()
    labels = list(dict.fromkeys(agg[p].astype(str)))
    fig, axes = plt.subplots(1, len(shown), figsize=(3.6 * len(shown), 3.2), squeeze=False)
    for ax, m in zip(axes[0], shown):
        for tracker, g in agg.groupby("tracker", sort=False) if "tracker" in agg else [("", agg)]:
            x = (pd.to_numeric(g[p]).to_numpy() if numeric
                 else np.array([labels.index(str(v)) for v in g[p]]))
            ax.errorbar(x, g[m], yerr=g[f"{m}_ci95"], marker="o", capsize=3, label=tracker)
        if not numeric:
            ax.set_xticks(range(len(labels)), [tick(v) for v in labels], rotation=30)
        elif len(labels) <= MAX_HEATMAP_VALUES:  # a grid: ticks at its values
            values = sorted({float(v) for v in labels})
            ax.set_xticks(values, [tick(v) for v in values])
        ax.set_xlabel(p)
        ax.set_title(m)
        ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=8)
    n = int(agg["n"].max())
    fig.suptitle(f"COMBINED metrics against {p} (mean ± 95% interval, up to {n} jobs each)",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def _heatmap(agg: pd.DataFrame, a: str, b: str, m: str, path: Path) -> Path:
    """Metric ``m`` over parameters ``a`` (rows) and ``b`` (columns), mean over the rest, one
    panel per tracker, into ``path``."""
    import matplotlib.pyplot as plt

    trackers = list(dict.fromkeys(agg["tracker"])) if "tracker" in agg else [None]
    fig, axes = plt.subplots(1, len(trackers), figsize=(4 * len(trackers), 3.4), squeeze=False)
    for ax, t in zip(axes[0], trackers):
        g = (agg if t is None else agg[agg["tracker"] == t]).copy()
        for col in (a, b):  # numeric values in numeric order (10 after 9)
            num = pd.to_numeric(g[col], errors="coerce")
            if num.notna().all():
                g[col] = num
        grid = g.pivot_table(index=a, columns=b, values=m, aggfunc="mean", sort=True)
        im = ax.imshow(grid.to_numpy(dtype=float), cmap="viridis", aspect="auto")
        ax.set_xticks(range(grid.shape[1]), [tick(v) for v in grid.columns])
        ax.set_yticks(range(grid.shape[0]), [tick(v) for v in grid.index])
        ax.set_xlabel(b)
        ax.set_ylabel(a)
        ax.set_title(f"{t or ''} {m} (mean over the rest)".strip(), fontsize=9)
        for (r, c), v in np.ndenumerate(grid.to_numpy(dtype=float)):
            if np.isfinite(v):
                ax.text(c, r, f"{v:.3g}", ha="center", va="center", fontsize=7, color="w")
        fig.colorbar(im, ax=ax)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def _safe(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in name)
