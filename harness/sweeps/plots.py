"""Sweep plots: each metric against each swept parameter (mean over jobs with a 95% bootstrap
percentile interval, which stays inside each metric's range; one line per tracker, one panel
per metric in a grid, one legend) and, when two or more parameters are swept, a heatmap of
each pair; and the generalisation table's figure (``plot_generalisation``: ours and their
paper modes against the best outside tracker of every set, tuning sets then untouched)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.patches import Patch

from occbench.config.meta import TrackerMeta, metas
from occbench.metrics import COMBINED
from occbench.report.figures import save_figure
from occbench.sweeps.jobs import DONE
from occbench.sweeps.tables import aggregate, plot_axes, tick

MAX_HEATMAP_VALUES = 12  # a parameter with more distinct values gets no heatmap
#: the generalisation figure's trackers drawn beside the best outside one, in bar order
GENERALISATION_SHOWN = ("reta", "reta_paper", "pbm", "pbm_paper")
GENERALISATION_METRICS = ("IDF1", "HOTA")
_SLOT = 0.16  # bar height in set rows (five bars and a gap per set)


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


def plot_generalisation(table: pd.DataFrame, path: str | Path, sets: Sequence[str] = (),
                        shown: Sequence[str] = GENERALISATION_SHOWN,
                        metrics: Sequence[str] = GENERALISATION_METRICS,
                        title: str | None = None) -> Path | None:
    """The generalisation table (long: set, role, tracker, metrics, optional failures) as
    horizontal bars into ``path`` (PNG): one panel per metric, one row per set (``sets``' order,
    sets it does not name after them; tuning sets (T) above untouched (U)), in each row the
    trackers of ``shown`` present in the table and the best outside tracker of the set
    (``occbench.sweeps.versus.best_outside``, per metric), named at its bar and hatched.
    Colours and labels from each tracker's ``meta:``. A missing score is written "no score" in
    its bar's place (never a zero bar); "(!)" marks a score whose set recorded a failure.

    Returns the written path, or None when no tracker to draw is in the table.
    Raises ValueError naming a missing column."""
    from occbench.sweeps.versus import best_outside  # start-up: hydra and the pipeline

    needed = ["set", "role", "tracker", *metrics]
    absent = [c for c in needed if c not in table.columns]
    if absent:
        raise ValueError(f"generalisation table: no column {absent[0]!r} (the figure needs "
                         f"{', '.join(needed)}; columns: {', '.join(map(str, table.columns))})")
    ours = [t for t in shown if (table["tracker"] == t).any()]
    bests = best_outside(table, metrics)
    if not ours and not bests:
        return None
    rows = _set_rows(table, sets)
    looks = metas([*ours, *(r["tracker"] for b in bests.values() for r in b.values())])
    matplotlib.use("Agg", force=False)
    height = 1.2 + 0.72 * len(rows)
    fig = plt.figure(figsize=(7.0 * len(metrics), height), dpi=100)
    grid = fig.add_gridspec(2, len(metrics), height_ratios=[0.9, height - 0.9])
    for i, m in enumerate(metrics):
        ax = fig.add_subplot(grid[1, i])
        _generalisation_panel(ax, table, rows, ours, bests, m, looks)
        if i:
            ax.set_yticklabels([])
    top = fig.add_subplot(grid[0, :])
    top.axis("off")
    handles = [Patch(color=looks[t].colour, label=looks[t].label) for t in ours]
    handles.append(Patch(facecolor="white", edgecolor="black", hatch="///",
                         label="best outside tracker of the set (its colour, named at its bar)"))
    top.legend(handles=handles, loc="center", ncol=len(handles), fontsize=9, frameon=False)
    top.set_title(title or "Generalisation table: COMBINED scores per set, ours and their paper "
                  "modes against the best outside tracker of the set", fontsize=11)
    return save_figure(fig, path)


def _set_rows(table: pd.DataFrame, sets: Sequence[str]) -> list[tuple[str, str, float]]:
    """(set, T or U, y) of each set of ``table``: tuning sets first, each group in ``sets``'
    order then the table's; a gap of half a row between the groups."""
    order = {n: i for i, n in enumerate(sets)}
    names = sorted(dict.fromkeys(table["set"].astype(str)), key=lambda n: order.get(n, len(order)))
    first = table.drop_duplicates("set")
    role = dict(zip(first["set"].astype(str), first["role"]))
    tuning = [n for n in names if role[n] == "tuning"]
    untouched = [n for n in names if role[n] != "tuning"]
    return ([(n, "T", float(i)) for i, n in enumerate(tuning)]
            + [(n, "U", len(tuning) + 0.5 + i) for i, n in enumerate(untouched)])


def _generalisation_panel(ax: Any, table: pd.DataFrame, rows: Sequence[tuple[str, str, float]],
                          ours: Sequence[str], bests: Mapping[str, Mapping[str, pd.Series]],
                          m: str, looks: Mapping[str, TrackerMeta]) -> None:
    """One metric's panel of ``plot_generalisation``."""
    n = len(ours) + 1
    for name, _, y in rows:
        s = table[table["set"].astype(str) == name]
        bars = [(t, s[s["tracker"] == t]) for t in ours]
        best = bests.get(name, {}).get(m)
        bars.append((None if best is None else str(best["tracker"]),
                     None if best is None else best.to_frame().T))
        for k, (t, r) in enumerate(bars):
            yk = y + (k - (n - 1) / 2) * _SLOT
            v = float("nan") if r is None or r.empty else float(r[m].iloc[0])
            if not np.isfinite(v):
                what = "no outside tracker" if t is None else f"{looks[t].label}: no score"
                ax.text(0.01, yk, what, va="center", fontsize=6.5, color="#b00000")
                continue
            outside = k == n - 1
            ax.barh(yk, v, _SLOT * 0.92, color=looks[t].colour, hatch="///" if outside else None,
                    edgecolor="black" if outside else "none", linewidth=0.4)
            failed = "failures" in r and bool(pd.to_numeric(r["failures"], errors="coerce")
                                              .fillna(0).iloc[0])
            text = f"{v:.3f}{' (!)' if failed else ''}" + (f" {looks[t].label}" if outside else "")
            ax.text(v + 0.008, yk, text, va="center", fontsize=6.5)
    ax.set_yticks([y for *_, y in rows], [f"{n} ({g})" for n, g, _ in rows], fontsize=8.5)
    ax.set_ylim(max([y for *_, y in rows], default=0.0) + 0.5, -0.5)
    split = [y for _, g, y in rows if g == "U"]
    if split and split[0] > 0:
        ax.axhline(split[0] - 0.5, color="black", linewidth=0.8, linestyle="--")
    ax.set_xlim(min(0.0, float(pd.to_numeric(table[m], errors="coerce").min())), 1.42)
    ax.set_xticks(np.linspace(0.0, 1.0, 6))
    ax.grid(axis="x", alpha=0.3)
    ax.set_xlabel(f"{m} (COMBINED; mean over the set's seeds)")
    ax.set_title(f"{m}: tuning sets (T) above the dashed line, untouched (U) below", fontsize=9)
