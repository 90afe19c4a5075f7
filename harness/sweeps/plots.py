"""Sweep plots: each metric against each swept parameter (mean over jobs with a 95% bootstrap
percentile interval, which stays inside each metric's range; one line per tracker, one panel
per metric in a grid, one legend) and, when two or more parameters are swept, a heatmap of
each pair."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from occbench.config.meta import TrackerMeta, metas
from occbench.metrics import COMBINED
from occbench.sweeps.jobs import DONE
from occbench.sweeps.tables import aggregate, plot_axes, tick

MAX_HEATMAP_VALUES = 12  # a parameter with more distinct values gets no heatmap


def plot_sweep(frame: pd.DataFrame, out_dir: str | Path, metrics: Sequence[str],
               looks: Mapping[str, TrackerMeta] | None = None) -> list[Path]:
    """Metric-vs-parameter line plots (mean, 95% bootstrap interval) and pairwise heatmaps;
    ``looks``: tracker -> its label and colour (``occbench.config.meta``; default: the
    shipped configs' by name)."""
    matplotlib.use("Agg")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    params = plot_axes(frame)
    trackers = frame["tracker"].dropna().astype(str) if "tracker" in frame else []
    looks = metas(dict.fromkeys(trackers), known=looks)
    shown = [m for m in metrics if m in frame.columns]
    written: list[Path] = []
    if "sequence" not in frame.columns:
        return written
    for p in params:
        agg = aggregate(frame, [p], shown)
        if not agg.empty:
            written.append(_line_plot(frame, p, shown, out_dir / f"sweep_{_safe(p)}.png", looks))
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


def _line_plot(frame: pd.DataFrame, p: str, shown: Sequence[str], path: Path,
               looks: Mapping[str, TrackerMeta]) -> Path:
    """Each metric of ``shown`` against parameter ``p``, one line per tracker (``aggregate``:
    the mean over the finished jobs' COMBINED rows and its 95% bootstrap interval), one panel
    per metric in a grid and one legend, into ``path``."""
    rows = frame[(frame["status"] == DONE) & (frame["sequence"] == COMBINED)]
    numeric = pd.to_numeric(rows[p], errors="coerce").notna().all()
    labels = list(dict.fromkeys(rows[p].astype(str)))
    ncols = min(3, len(shown))
    nrows = -(-len(shown) // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(4.2 * ncols, 3.4 * nrows), squeeze=False)
    agg = aggregate(frame, [p], shown)  # the page's and sweep.md's numbers, intervals included
    trackers = list(dict.fromkeys(rows["tracker"])) if "tracker" in rows else [""]
    n_max = int(agg["n"].max())
    for ax, m in zip(axes.flat, shown):
        for tracker in trackers:
            g = agg[agg["tracker"] == tracker] if tracker != "" else agg
            x = [float(v) if numeric else labels.index(str(v)) for v in g[p]]
            points = sorted(zip(x, g[m], g[f"{m}_low"], g[f"{m}_high"]))
            x, mean, low, high = (np.array(c, dtype=float) for c in zip(*points))
            yerr = np.clip([mean - low, high - mean], 0.0, None)  # float round-off only
            look = looks.get(str(tracker))
            ax.errorbar(x, mean, yerr=yerr, marker="o", capsize=3,
                        label=look.label if look else None,
                        color=look.colour if look else None)
        if not numeric:
            ax.set_xticks(range(len(labels)), [tick(v) for v in labels], rotation=30)
        elif len(labels) <= MAX_HEATMAP_VALUES:  # a grid: ticks at its values
            values = sorted({float(v) for v in labels})
            ax.set_xticks(values, [tick(v) for v in values])
        ax.set_xlabel(p)
        ax.set_title(m, fontsize=11)
        ax.grid(alpha=0.3)
    spare = list(axes.flat)[len(shown):]
    for ax in spare:
        ax.axis("off")
    handles, names = axes.flat[0].get_legend_handles_labels()
    if handles:  # in a spare cell of the grid, else in the first panel
        (spare[0] if spare else axes.flat[0]).legend(
            handles, names, loc="center" if spare else "best", fontsize=9, title="tracker",
            frameon=not spare)
    fig.suptitle(f"COMBINED metrics against {p}: mean over up to {n_max} jobs, 95% bootstrap "
                 "percentile interval", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def _heatmap(agg: pd.DataFrame, a: str, b: str, m: str, path: Path) -> Path:
    """Metric ``m`` over parameters ``a`` (rows) and ``b`` (columns), mean over the rest, one
    panel per tracker, into ``path``."""
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
