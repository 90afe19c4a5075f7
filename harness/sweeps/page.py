"""``report.html`` of a sweep folder (the run page's parts, ``occbench.report.html``): each
swept parameter against each metric (mean and 95% interval over seeds), the best settings,
the paired difference of the best two, the jobs, the sweep's plots and the command. Every
interval is ``aggregate``'s, the one of sweep.md and the sweep's PNGs; every tracker is in
its colour (``occbench.config.meta``).

The best settings are ranked on the COMBINED ``objective`` metric of one tracker (the
sweep's ``objective``: by default IDF1 of the first of ours). The best two are compared on
the same frames: their jobs are paired by their other values (the seeds), each job's
sequences are strata of the block bootstrap (``occbench.metrics.paired``).
"""

from __future__ import annotations

import logging
import shlex
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import pandas as pd
import yaml

from occbench.config.meta import TrackerMeta, first_of_ours
from occbench.metrics.paired import Bootstrap, PairedDifference
from occbench.report.html import charts
from occbench.report.html.page import Page, esc, table_html
from occbench.report.html.run import read_frame_counts
from occbench.report.paired import NOT_DISTINGUISHABLE, cell
from occbench.report.tables import direction
from occbench.sweeps.jobs import sweep_metas
from occbench.sweeps.tables import (BOUNDS, COMBINED, DONE, aggregate, parameters, plot_axes,
                                    setting_table, swept)
from occbench.sweeps.tables import cells as interval_cells

log = logging.getLogger(__name__)


def objective_of(sweep_dir: Path, frame: pd.DataFrame,
                 looks: Mapping[str, TrackerMeta]) -> tuple[str, str]:
    """(tracker, metric) the sweep optimises: its jobs' ``objective`` (config.yaml); with no
    tracker named there, the first of ours (``first_of_ours``: never the baseline when one of
    ours ran)."""
    tracker, metric = None, "IDF1"
    for job in sorted(sweep_dir.glob("*/config.yaml")):
        obj = (yaml.safe_load(job.read_text()) or {}).get("objective") or {}
        tracker, metric = obj.get("tracker"), obj.get("metric") or "IDF1"
        break
    if tracker is None and "tracker" in frame.columns and frame["tracker"].notna().any():
        tracker = first_of_ours(dict.fromkeys(frame["tracker"].dropna().astype(str)), looks)
    return str(tracker), str(metric)


def best_settings(frame: pd.DataFrame, tracker: str, metric: str) -> pd.DataFrame:
    """``aggregate`` of the swept settings of ``tracker``, best ``metric`` first."""
    by = [p for p in swept(frame) if p != "tracker_choice" and not p.endswith("seed")]
    agg = aggregate(frame, by, [metric])
    if agg.empty or metric not in agg:
        return agg
    agg = agg[agg["tracker"] == tracker] if "tracker" in agg else agg
    return agg.sort_values(metric, ascending=direction(metric) < 0, kind="stable")


def best_table(best: pd.DataFrame, metric: str, rows: int = 10) -> pd.DataFrame:
    """The first ``rows`` of ``best_settings`` as shown: ``metric`` as ``mean [low, high]``."""
    top = best.head(rows).reset_index(drop=True)
    top[metric] = interval_cells(top, metric)
    return top.drop(columns=[f"{metric}{b}" for b in BOUNDS])


def paired_best(sweep_dir: Path, frame: pd.DataFrame, best: pd.DataFrame,
                tracker: str) -> list[PairedDifference]:
    """The best setting minus the second best, on the frames of jobs paired by seed."""
    if len(best) < 2:
        return []
    params = [p for p in swept(frame) if p in best.columns]
    rest = [p for p in parameters(frame) if p not in params]
    jobs = frame[(frame["status"] == DONE) & (frame["sequence"] == COMBINED)
                 & (frame["tracker"] == tracker)]
    sides: list[dict[str, Any]] = [{}, {}]
    names = []
    for side, (_, setting) in zip(sides, best.head(2).iterrows()):
        names.append(", ".join(f"{p}={setting[p]}" for p in params))
        mine = jobs[(jobs[params].astype(str) == setting[params].astype(str)).all(axis=1)]
        for job in mine.itertuples():
            key = "/".join(str(getattr(job, p, "")) for p in rest)
            counts = read_frame_counts(sweep_dir / str(job.job)).get(tracker, {})
            side.update({f"{key}/{s}": c for s, c in counts.items()})
    try:
        return Bootstrap().compare(sides[0], sides[1], (f"best ({names[0]})",
                                                        f"second ({names[1]})"))
    except ValueError as err:  # no replicate in common
        log.warning("paired comparison of the best two settings: %s", err)
        return []


def write_sweep_report(sweep_dir: str | Path, frame: pd.DataFrame, metrics: Sequence[str],
                       looks: Mapping[str, TrackerMeta] | None = None) -> Path:
    """Write ``<sweep_dir>/report.html`` from the gathered ``frame`` (``gather``); ``looks``:
    tracker -> label, colour and role (default: ``sweep_metas``)."""
    sweep_dir = Path(sweep_dir)
    looks = sweep_metas(sweep_dir, frame) if looks is None else looks
    page = Page(f"occbench sweep {sweep_dir.name}")
    jobs = frame.drop_duplicates("job") if "job" in frame else frame
    page.text(f"Sweep folder: {sweep_dir.resolve()}; {len(jobs)} jobs.")
    shown = [m for m in metrics if m in frame.columns]
    tracker, objective = objective_of(sweep_dir, frame, looks)
    best = best_settings(frame, tracker, objective)
    page.section("best", "Best settings")
    if not best.empty:
        page.text(f"Ranked on the COMBINED {objective} of {tracker} (the sweep's objective), "
                  "mean [95% bootstrap interval] over seeds (n jobs each), as in sweep.md "
                  "and the plots.")
        page.add(table_html(best_table(best, objective)))
    diffs = paired_best(sweep_dir, frame, best, tracker)
    if diffs:
        page.add("<h3>Best minus second best, paired</h3>")
        page.text(f"{Bootstrap().describe()}; the jobs' sequences (paired by seed) are the "
                  f"strata. (n.d.): {NOT_DISTINGUISHABLE}.")
        page.add(table_html(pd.DataFrame([{"A": d.a, "B": d.b, "metric": d.metric,
                                           "A - B [95%]": cell(d)} for d in diffs])))
        short = [replace(d, a="best", b="second") for d in diffs]
        page.chart(charts.paired_forest(short))
    page.section("parameters", "Each parameter against each metric")
    for p in plot_axes(frame):
        agg = aggregate(frame, [p], shown)
        for m in shown:
            if not agg.empty and m in agg:
                page.chart(charts.metric_lines(agg, p, m, looks))
    page.section("settings", "Settings")
    page.add(table_html(setting_table(frame, shown)))
    page.section("jobs", "Jobs")
    cols = [c for c in ["job", *[c for c in frame.columns if c not in ("job",)]]
            if c in frame.columns and (c in ("job", "status", "tracker", "sequence", "error")
                                       or c in shown or c in plot_axes(frame)
                                       or c.endswith("seed"))]
    rows = frame[frame["sequence"].isin(["COMBINED"]) | frame["sequence"].isna()] \
        if "sequence" in frame else frame
    page.add(table_html(rows[cols]))
    pngs = sorted((sweep_dir / "plots").glob("*.png"))
    if pngs:
        page.section("plots", "Plots")
        for path in pngs:
            page.image(path, f"plots/{path.name}")
    page.section("command", "Command")
    page.pre(_command(sweep_dir))
    page.add(f'<p class="note">Each job\'s own page: <code>{esc(sweep_dir.name)}/&lt;job&gt;/'
             'report.html</code>.</p>')
    return page.write(sweep_dir / "report.html")


def _command(sweep_dir: Path) -> str:
    """The multirun's command line (Hydra's ``multirun.yaml``), else a hint."""
    path = sweep_dir / "multirun.yaml"
    if not path.is_file():
        return "occbench -m ... (multirun.yaml not found)"
    h = (yaml.safe_load(path.read_text()) or {}).get("hydra") or {}
    over = h.get("overrides") or {}
    cwd = (h.get("runtime") or {}).get("cwd")
    words = ["occbench", "-m", *(over.get("task") or []),
             *[o for o in over.get("hydra") or [] if o.startswith("hydra.sweep.dir")]]
    line = " ".join(shlex.quote(str(w)) for w in words)
    return f"cd {shlex.quote(str(cwd))} && {line}" if cwd else line
