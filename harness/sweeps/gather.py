"""Sweeps: per-job status and done-markers, gathering a multirun into one table, sweep plots.

A Hydra multirun (``python -m harness -m tracker=baseline tracker.max_age=1,3 seed=0,1,2``)
writes one job directory per parameter combination under ``hydra.sweep.dir``
(``<sweep>/<job number>/``), each with the run's ``metrics.csv`` and Hydra's
``.hydra/overrides.yaml``. Three things make a sweep robust and repeatable:

* ``guarded(job_dir, overrides, run)``, called by the app around one job: a job already
  finished with the same overrides (its ``status.json`` says ``done``) is skipped and its
  stored objective returned; a job that raises is recorded as ``failed`` with its error and
  returns NaN, so the launcher goes on with the other jobs.
* ``gather(sweep_dir)`` reads every job directory into one frame: one row per job and
  sequence (the per-sequence and COMBINED rows of each ``metrics.csv``) with the job number,
  every overridden value as a column, ``status`` and ``error`` (a failed job is one row with
  its error and no metrics). Rows are ordered by job number, tracker and sequence as the run
  wrote them, so the table does not depend on the launcher or on the number of workers.
* ``write_sweep(sweep_dir)`` writes ``sweep.csv``, ``sweep.md`` and ``plots/``: for each
  metric and each swept parameter the COMBINED value against the parameter, one line per
  tracker, mean and 95% t-interval over the jobs sharing the value (the seeds, and the other
  parameters' values when several are swept); and, when two or more parameters are swept,
  a heatmap of each pair (mean over the rest). Keys named ``seed`` (``seed``,
  ``dataset.seed``, any group) are replicates, never a parameter axis: they give the mean
  and interval. The tracker choice is no axis either: each tracker is its own line.
* ``summary_text(frame)`` is the sweep's summary printed at the end of a multirun: the
  COMBINED mean and interval per parameter setting, then each job's overrides and status.

The Hydra callback ``harness.sweeps.callbacks.GatherSweep`` calls ``write_sweep`` at the end of a
multirun; ``python -m harness.sweeps.gather <sweep_dir>`` does the same by hand.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import sys
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from harness.sweeps.jobs import (  # noqa: F401 - re-exported: harness.sweeps.gather's names
    DAMAGED,
    DONE,
    FAILED,
    STATUS_FILE,
    SweepError,
    job_dirs,
    parse_override,
    read_overrides,
    read_status,
)

log = logging.getLogger(__name__)

COMBINED = "COMBINED"
SEED = "seed"
DEFAULT_METRICS = ("HOTA", "IDF1", "MOTA", "IDs", "ReID")
MAX_HEATMAP_VALUES = 12  # a parameter with more distinct values gets no heatmap


# --------------------------------------------------------------------------- job status


def write_status(job_dir: str | Path, status: str, overrides: Sequence[str],
                 objective: float | None = None, error: str | None = None,
                 inputs: Mapping[str, str] | None = None) -> Path:
    """Write ``status.json`` (atomically): status, overrides, objective, error, and the
    fingerprint of the job's inputs (``inputs``: config, code, data)."""
    from harness.io.mot import write_atomic

    path = Path(job_dir) / STATUS_FILE
    obj = None if objective is None or not math.isfinite(objective) else float(objective)
    body = {"status": status, "overrides": list(overrides), "objective": obj, "error": error,
            "inputs": dict(inputs) if inputs else None}
    return write_atomic(path, json.dumps(body, indent=1) + "\n")


def finished(job_dir: str | Path, overrides: Sequence[str],
             inputs: Mapping[str, str] | None = None) -> dict[str, Any] | None:
    """The status of a job already done with exactly these overrides and, when ``inputs``
    is given, the same input fingerprint (``harness.sweeps.fingerprint``), else None."""
    status = read_status(job_dir)
    if not (status and status.get("status") == DONE
            and list(status.get("overrides") or []) == list(overrides)):
        return None
    if inputs is not None:
        changed = changed_inputs(status.get("inputs"), inputs)
        if changed:
            log.info("%s: inputs changed since it was done (%s): recomputed", job_dir,
                     ", ".join(changed))
            return None
    return status


def changed_inputs(old: Mapping[str, str] | None, new: Mapping[str, str]) -> list[str]:
    """Names of the fingerprint parts that differ (all when none was recorded)."""
    if not old:
        return ["no fingerprint recorded"]
    return [k for k in new if old.get(k) != new[k]]


def guarded(job_dir: str | Path, overrides: Sequence[str], run: Callable[[], float],
            inputs: Callable[[], Mapping[str, str]] | None = None) -> float:
    """Run one sweep job: skip it when already done, record its failure instead of raising.

    Args:
        job_dir: the job's output directory.
        overrides: the job's task overrides (``HydraConfig.get().overrides.task``).
        run: the job; returns the objective.
        inputs: gives the fingerprint of the job's inputs (config, code version, data
            files: ``harness.sweeps.fingerprint.inputs``); a job done with other inputs is run
            again.
    Returns:
        The objective; the stored one for a skipped job; NaN for a failed job.
    """
    fingerprint = None
    try:
        fingerprint = dict(inputs()) if inputs is not None else None
    except Exception as err:  # noqa: BLE001 - the job then always runs
        log.warning("%s: cannot fingerprint the inputs (%s): the job is run", job_dir, err)
        fingerprint = {"error": str(err)}
    done = finished(job_dir, overrides, fingerprint)
    if done is not None:
        log.info("%s: already done with the same overrides: skipped", job_dir)
        value = done.get("objective")
        return float("nan") if value is None else float(value)
    write_status(job_dir, "running", overrides, inputs=fingerprint)
    try:
        value = float(run())
    except Exception as err:  # one job's failure must not stop the sweep
        msg = f"{type(err).__name__}: {err}".strip()
        log.exception("%s: job failed: %s", job_dir, msg)
        write_status(job_dir, FAILED, overrides, error=msg, inputs=fingerprint)
        return float("nan")
    write_status(job_dir, DONE, overrides, objective=value, inputs=fingerprint)
    return value


# --------------------------------------------------------------------------- gathering


def read_metrics(path: Path) -> tuple[pd.DataFrame, str]:
    """A job's ``metrics.csv`` and "" when it is whole, else an empty frame and why not (the
    message names the file): empty, truncated (a row with fewer fields than the header or
    no final newline: the job was stopped while writing), or not a CSV table."""
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as err:
        return pd.DataFrame(), f"{path}: unreadable ({err})"
    if not text.strip():
        return pd.DataFrame(), f"{path}: empty file (the job did not finish writing it)"
    if not text.endswith("\n"):
        return pd.DataFrame(), f"{path}: truncated (no final newline)"
    import csv
    import io

    rows = list(csv.reader(io.StringIO(text)))
    width = len(rows[0])
    for i, row in enumerate(rows[1:], 2):
        if row and len(row) != width:
            return pd.DataFrame(), (f"{path}:{i}: truncated or malformed row ({len(row)} "
                                    f"fields, the header has {width})")
    try:
        frame = pd.read_csv(io.StringIO(text))
    except (ValueError, pd.errors.ParserError) as err:
        return pd.DataFrame(), f"{path}: not a CSV table ({err})"
    missing = [c for c in ("tracker", "sequence") if c not in frame.columns]
    if missing:
        return pd.DataFrame(), f"{path}: not a metrics table (no column {', '.join(missing)})"
    return frame, ""


# metrics.csv columns that an override key (a config-group choice) may share a name with
_RESERVED = frozenset({"job", "status", "error", "tracker", "sequence"})


def _column(key: str) -> str:
    """Column name of an override key: ``tracker`` (the group choice) becomes ``tracker_choice``
    so that it does not clash with the ``tracker`` column of metrics.csv."""
    return f"{key}_choice" if key in _RESERVED else key


def _key(column: str) -> str:
    """The override key of a gathered column (``tracker_choice`` -> ``tracker``)."""
    base = column.removesuffix("_choice")
    return base if column.endswith("_choice") and base in _RESERVED else column


def gather(sweep_dir: str | Path) -> pd.DataFrame:
    """One frame of every job of a sweep (see the module docstring).

    Columns: ``job``, the overridden keys (in order of first appearance), ``status``,
    ``error``, then the columns of ``metrics.csv`` (``tracker``, ``sequence``, metrics).
    """
    parts: list[pd.DataFrame] = []
    keys: list[str] = []
    for d in job_dirs(sweep_dir):
        overrides = read_overrides(d)
        status = read_status(d)
        params = dict(parse_override(o) for o in overrides)
        if status and status.get("overrides"):
            params = dict(parse_override(o) for o in status["overrides"]) | params
        keys += [_column(k) for k in params if _column(k) not in keys]
        state = (status or {}).get("status", "")
        error = (status or {}).get("error") or ""
        metrics_path = d / "metrics.csv"
        if not state:
            state = DONE if metrics_path.is_file() else "missing"
            if state == "missing":
                error = "no status.json and no metrics.csv: the job did not run or finish"
        # a failed job keeps whatever it scored before failing
        frame, damage = (read_metrics(metrics_path) if metrics_path.is_file()
                         else (pd.DataFrame(), ""))
        if damage:
            log.warning("%s", damage)
            if state == DONE:
                state, error = DAMAGED, damage
        if state == DONE and "complete" in frame.columns:
            whole = frame["complete"].astype(str).str.lower().isin(["true", "1"])
            if not whole.all():
                state = "incomplete"
                error = error or f"{metrics_path}: the run did not complete (complete=false)"
        if frame.empty:
            frame = pd.DataFrame([{}])
            if state == DONE:
                error = error or f"{metrics_path}: no rows (nothing scored)"
        if (d / "errors.txt").is_file() and state == DONE and not error:
            lines = (d / "errors.txt").read_text(errors="replace").splitlines()
            error = lines[0] if lines else ""
        head = {"job": d.name, **{_column(k): v for k, v in params.items()}, "status": state,
                "error": error}
        for col, value in reversed(list(head.items())):
            frame.insert(0, col, [value] * len(frame))
        parts.append(frame)
    if not parts:
        return pd.DataFrame(columns=["job", "status", "error"])
    out = pd.concat(parts, ignore_index=True)
    for col in out.columns:  # counts stay whole numbers beside a failed job's empty row
        kinds = {p[col].dtype.kind for p in parts if col in p.columns and p[col].notna().any()}
        if kinds == {"i"} and out[col].dtype.kind == "f":
            out[col] = out[col].astype("Int64")
    lead = ["job", *keys, "status", "error"]
    return out[lead + [c for c in out.columns if c not in lead]]


def is_replicate(key: str) -> bool:
    """A key named ``seed`` in any group (``seed``, ``dataset.seed``): a replicate."""
    return key.rsplit(".", 1)[-1] == SEED


def plot_axes(frame: pd.DataFrame) -> list[str]:
    """Swept parameters that are plot axes: not replicates (seeds) and not the tracker
    choice (every tracker is its own line already)."""
    return [p for p in swept(frame) if not is_replicate(p) and p != _column("tracker")]


def _tick(value: Any) -> str:
    """A parameter value as a tick label: numbers to 4 significant digits."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        return str(value)
    if not math.isfinite(v):
        return str(value)
    return f"{v:.4g}"


def parameters(frame: pd.DataFrame) -> list[str]:
    """The override columns of a gathered frame (between ``job`` and ``status``)."""
    cols = list(frame.columns)
    if "job" not in cols or "status" not in cols:
        return []
    return cols[cols.index("job") + 1:cols.index("status")]


def swept(frame: pd.DataFrame) -> list[str]:
    """Override columns that take more than one value across the jobs."""
    jobs = frame.drop_duplicates("job")
    return [c for c in parameters(frame) if jobs[c].astype(str).nunique() > 1]


def interval95(values: np.ndarray) -> tuple[float, float, int]:
    """Mean, half-width of the 95% t-interval, and number of finite values."""
    from scipy import stats

    v = np.asarray(values, dtype=np.float64)
    v = v[np.isfinite(v)]
    n = len(v)
    if n == 0:
        return float("nan"), float("nan"), 0
    if n == 1:
        return float(v[0]), 0.0, 1
    half = stats.t.ppf(0.975, n - 1) * v.std(ddof=1) / math.sqrt(n)
    return float(v.mean()), float(half), n


def aggregate(frame: pd.DataFrame, by: Sequence[str], metrics: Sequence[str]) -> pd.DataFrame:
    """COMBINED rows of finished jobs grouped by ``by`` (+ tracker): mean, 95% half-width
    and count of each metric (columns ``<m>``, ``<m>_ci95``, ``n``)."""
    if "sequence" not in frame.columns:
        return pd.DataFrame()
    rows = frame[(frame["status"] == DONE) & (frame["sequence"] == COMBINED)]
    group = [*by, "tracker"] if "tracker" in rows.columns else list(by)
    out = []
    for keys, g in rows.groupby(group, sort=False, dropna=False):
        keys = keys if isinstance(keys, tuple) else (keys,)
        rec: dict[str, Any] = dict(zip(group, keys))
        for m in metrics:
            if m not in g.columns:
                continue
            mean, half, _ = interval95(pd.to_numeric(g[m], errors="coerce").to_numpy())
            rec[m], rec[f"{m}_ci95"] = mean, half
        rec["n"] = len(g)
        out.append(rec)
    result = pd.DataFrame(out)
    if not result.empty and by:
        result = _sort_values(result, [*by])
    return result


def _sort_values(frame: pd.DataFrame, cols: list[str]) -> pd.DataFrame:
    """Stable sort by parameter columns, numbers numerically, others as text."""
    def key(s: pd.Series) -> pd.Series:
        num = pd.to_numeric(s, errors="coerce")
        return num if num.notna().all() else s.astype(str)

    return frame.sort_values(cols, key=key, kind="stable").reset_index(drop=True)


# --------------------------------------------------------------------------- writing


def _fmt(v: Any) -> str:
    if v is None or v is pd.NA:
        return "-"
    if isinstance(v, float):
        if math.isnan(v):
            return "-"
        return f"{v:.4g}"
    return str(v).replace("|", "\\|").replace("\n", " ")


def markdown_table(frame: pd.DataFrame) -> str:
    if frame.empty:
        return "(no rows)\n"
    cols = list(frame.columns)
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for rec in frame.itertuples(index=False):
        lines.append("| " + " | ".join(_fmt(v) for v in rec) + " |")
    return "\n".join(lines) + "\n"


def sweep_markdown(frame: pd.DataFrame, metrics: Sequence[str], title: str = "") -> str:
    params = swept(frame)
    shown = [m for m in metrics if m in frame.columns]
    lines = [f"# Sweep {title}".rstrip(), ""]
    jobs = frame.drop_duplicates("job")
    n_failed = int((jobs["status"] != DONE).sum())
    done = len(jobs) - n_failed
    lines += [f"{len(jobs)} jobs, {done} done, {n_failed} failed or missing; swept: "
              + (", ".join(params) or "nothing") + ".", ""]
    table = setting_table(frame, shown)
    if not table.empty:
        seeds = [p for p in params if is_replicate(p)]
        over = f" over {', '.join(seeds)}" if seeds else ""
        lines += [f"## COMBINED, mean ± 95% interval{over}", "", markdown_table(table), ""]
    per_job = frame
    if "sequence" in frame.columns:
        per_job = frame[(frame["sequence"] == COMBINED) | frame["sequence"].isna()]
    cols = ["job", *params, "status", *(["tracker"] if "tracker" in frame.columns else []),
            *shown]
    per_job = per_job[cols].copy()
    for c in params:
        per_job[c] = per_job[c].map(_tick)
    lines += ["## Jobs (COMBINED rows)", "", markdown_table(per_job)]
    failed = jobs[jobs["status"] != DONE]
    if not failed.empty:
        lines += ["## Failed jobs", ""]
        lines += [f"- job {r.job}: {r.status}: {r.error}" for r in failed.itertuples()]
        lines.append("")
    return "\n".join(lines)


def setting_table(frame: pd.DataFrame, metrics: Sequence[str]) -> pd.DataFrame:
    """COMBINED ``metric`` as ``mean ± half-width`` per setting of the swept non-replicate
    parameters and tracker (``n``: the jobs averaged, the seeds)."""
    shown = [m for m in metrics if m in frame.columns]
    if "sequence" not in frame.columns or not shown:
        return pd.DataFrame()
    by = [p for p in swept(frame) if not is_replicate(p)
          and not (p == _column("tracker") and "tracker" in frame.columns)]
    agg = aggregate(frame, by, shown)
    if agg.empty:
        return agg
    table = agg[[c for c in agg.columns if not c.endswith("_ci95")]].copy()
    for c in by:  # Optuna's values carry 17 digits
        table[c] = table[c].map(_tick)
    for m in shown:
        if m in agg.columns:
            table[m] = [f"{a:.4g} ± {b:.2g}" if np.isfinite(a) and b > 0 else _fmt(a)
                        for a, b in zip(agg[m], agg[f"{m}_ci95"])]
    return table


def summary_text(frame: pd.DataFrame, metrics: Sequence[str] = DEFAULT_METRICS,
                 title: str = "") -> str:
    """The sweep's summary for the terminal: settings (mean ± 95% over seeds), then one line
    per job with its overrides and its status."""
    jobs = frame.drop_duplicates("job")
    n_bad = int((jobs["status"] != DONE).sum())
    params = swept(frame)
    lines = [f"sweep {title}: {len(jobs)} jobs, {len(jobs) - n_bad} done, {n_bad} failed or "
             f"missing; swept: {', '.join(params) or 'nothing'}".replace("sweep :", "sweep:")]
    table = setting_table(frame, metrics)
    if not table.empty:
        seeds = [p for p in params if is_replicate(p)]
        lines += ["", "COMBINED, mean ± 95% interval" + (f" over {', '.join(seeds)}" if seeds
                                                           else "")]
        with pd.option_context("display.width", 200, "display.max_columns", 50,
                               "display.max_colwidth", 40):
            lines.append(table.to_string(index=False))
    common = [k for k in parameters(frame) if k not in params]
    first = jobs.iloc[0] if len(jobs) else {}
    shared = " ".join(f"{_key(k)}={first[k]}" for k in common if not pd.isna(first[k]))
    lines += ["", "jobs" + (f" (all with {shared})" if shared else "") + ":"]
    for row in jobs.to_dict("records"):
        over = " ".join(f"{_key(k)}={_tick(row[k])}" for k in params
                        if not pd.isna(row.get(k)) and str(row[k]) != "")
        error = f": {row['error']}" if row["status"] != DONE and row.get("error") else ""
        lines.append(f"  {row['job']:>3}  {over}  [{row['status']}{error}]")
    return "\n".join(lines) + "\n"


def plot_sweep(frame: pd.DataFrame, out_dir: str | Path, metrics: Sequence[str]) -> list[Path]:
    """Metric-vs-parameter line plots (mean ± 95% over seeds) and pairwise heatmaps."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    params = plot_axes(frame)
    shown = [m for m in metrics if m in frame.columns]
    written: list[Path] = []
    if "sequence" not in frame.columns:
        return written
    for p in params:
        agg = aggregate(frame, [p], shown)
        if agg.empty:
            continue
        numeric = pd.to_numeric(agg[p], errors="coerce").notna().all()
        labels = list(dict.fromkeys(agg[p].astype(str)))
        fig, axes = plt.subplots(1, len(shown), figsize=(3.6 * len(shown), 3.2), squeeze=False)
        for ax, m in zip(axes[0], shown):
            for tracker, g in agg.groupby("tracker", sort=False) if "tracker" in agg else [("", agg)]:
                x = (pd.to_numeric(g[p]).to_numpy() if numeric
                     else np.array([labels.index(str(v)) for v in g[p]]))
                ax.errorbar(x, g[m], yerr=g[f"{m}_ci95"], marker="o", capsize=3, label=tracker)
            if not numeric:
                ax.set_xticks(range(len(labels)), [_tick(v) for v in labels], rotation=30)
            elif len(labels) <= MAX_HEATMAP_VALUES:  # a grid: ticks at its values
                values = sorted({float(v) for v in labels})
                ax.set_xticks(values, [_tick(v) for v in values])
            ax.set_xlabel(p)
            ax.set_title(m)
            ax.grid(alpha=0.3)
        axes[0][0].legend(fontsize=8)
        n = int(agg["n"].max())
        fig.suptitle(f"COMBINED metrics against {p} (mean ± 95% interval, up to {n} jobs each)",
                     fontsize=9)
        fig.tight_layout()
        path = out_dir / f"sweep_{_safe(p)}.png"
        fig.savefig(path, dpi=90)
        plt.close(fig)
        written.append(path)
    jobs = frame.drop_duplicates("job")
    # a heatmap needs two parameter axes (never a tracker or seed) of 2..12 values each
    grid_params = [p for p in params if 2 <= jobs[p].nunique() <= MAX_HEATMAP_VALUES]
    for i, a in enumerate(grid_params):  # continuous searches (Optuna) draw no heatmaps
        for b in grid_params[i + 1:]:
            agg = aggregate(frame, [a, b], shown)
            if agg.empty:
                continue
            trackers = list(dict.fromkeys(agg["tracker"])) if "tracker" in agg else [None]
            for m in shown[:2]:
                fig, axes = plt.subplots(1, len(trackers), figsize=(4 * len(trackers), 3.4),
                                         squeeze=False)
                for ax, t in zip(axes[0], trackers):
                    g = (agg if t is None else agg[agg["tracker"] == t]).copy()
                    for col in (a, b):  # numeric values in numeric order (10 after 9)
                        num = pd.to_numeric(g[col], errors="coerce")
                        if num.notna().all():
                            g[col] = num
                    grid = g.pivot_table(index=a, columns=b, values=m, aggfunc="mean",
                                         sort=True)
                    im = ax.imshow(grid.to_numpy(dtype=float), cmap="viridis", aspect="auto")
                    ax.set_xticks(range(grid.shape[1]), [_tick(v) for v in grid.columns])
                    ax.set_yticks(range(grid.shape[0]), [_tick(v) for v in grid.index])
                    ax.set_xlabel(b)
                    ax.set_ylabel(a)
                    ax.set_title(f"{t or ''} {m} (mean over the rest)".strip(), fontsize=9)
                    for (r, c), v in np.ndenumerate(grid.to_numpy(dtype=float)):
                        if np.isfinite(v):
                            ax.text(c, r, f"{v:.3g}", ha="center", va="center", fontsize=7,
                                    color="w")
                    fig.colorbar(im, ax=ax)
                fig.tight_layout()
                path = out_dir / f"heatmap_{_safe(m)}_{_safe(a)}_{_safe(b)}.png"
                fig.savefig(path, dpi=90)
                plt.close(fig)
                written.append(path)
    return written


def _safe(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in name)


def write_sweep(sweep_dir: str | Path, metrics: Sequence[str] = DEFAULT_METRICS,
                plots: bool = True) -> pd.DataFrame:
    """Gather a sweep and write ``sweep.csv``, ``sweep.md`` and ``plots/`` into it."""
    sweep_dir = Path(sweep_dir)
    from harness.io.mot import write_atomic

    frame = gather(sweep_dir)
    write_atomic(sweep_dir / "sweep.csv",
                 frame.to_csv(index=False, float_format="%.6f", lineterminator="\n"))
    write_atomic(sweep_dir / "sweep.md", sweep_markdown(frame, metrics, sweep_dir.name))
    if plots:
        try:
            plot_sweep(frame, sweep_dir / "plots", metrics)
        except Exception:  # a plot is not worth losing the table for
            log.exception("sweep plots failed")
    n_bad = int((frame.drop_duplicates("job")["status"] != DONE).sum()) if len(frame) else 0
    log.info("gathered %d jobs into %s (%d not done)", frame["job"].nunique(),
             sweep_dir / "sweep.csv", n_bad)
    return frame


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="occbench sweep",
                                description="Gather a Hydra multirun into sweep.csv/.md/plots.")
    p.add_argument("sweep_dir", type=Path)
    p.add_argument("--metrics", nargs="+", default=list(DEFAULT_METRICS))
    p.add_argument("--no-plots", action="store_true")
    args = p.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    from omegaconf import OmegaConf

    from harness.sweeps.tune import is_optuna

    config = None  # Hydra's copy of a job's config (with hydra.sweeper): an Optuna study?
    found = sorted(args.sweep_dir.glob("*/.hydra/hydra.yaml"))
    first = found[0].parent if found else args.sweep_dir
    if (first / "hydra.yaml").is_file() and (first / "config.yaml").is_file():
        try:
            config = OmegaConf.merge(OmegaConf.load(first / "config.yaml"),
                                     OmegaConf.load(first / "hydra.yaml"))
        except Exception:  # noqa: BLE001 - a damaged job folder: gathered as such below
            config = None

    optuna = config is not None and is_optuna(config)
    try:
        frame = write_sweep(args.sweep_dir, args.metrics, not args.no_plots and not optuna)
    except (OSError, ValueError, TypeError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    if optuna and not args.no_plots:
        from harness.sweeps.tune import plot_study

        try:
            plot_study(args.sweep_dir, config,
                       metric=str(OmegaConf.select(config, "objective.metric") or "objective"))
        except Exception:  # noqa: BLE001 - a plot is not worth losing the table for
            log.exception("optuna plots of %s failed", args.sweep_dir)
    if len(frame):
        print(summary_text(frame, args.metrics, str(args.sweep_dir)), end="")
    print(args.sweep_dir / "sweep.md")
    bad = not_done(frame)
    if bad:
        print(f"error: {failed_summary(frame, args.sweep_dir)}", file=sys.stderr)
        return 1
    return 0


def not_done(frame: pd.DataFrame) -> list[str]:
    """Job numbers of a gathered sweep that are not done (failed, damaged, missing...)."""
    if frame.empty:
        return []
    jobs = frame.drop_duplicates("job")
    return [str(j) for j in jobs.loc[jobs["status"] != DONE, "job"]]


def failed_summary(frame: pd.DataFrame, sweep_dir: str | Path) -> str:
    """One paragraph: how many jobs are not done, and the first few with their error."""
    jobs = frame.drop_duplicates("job")
    bad = jobs[jobs["status"] != DONE]
    lines = [f"{len(bad)} of {len(jobs)} sweep jobs not done (see {Path(sweep_dir) / 'sweep.md'}):"]
    lines += [f"  job {r.job}: {r.status}: {r.error}" for r in bad.head(5).itertuples()]
    if len(bad) > 5:
        lines.append(f"  ... and {len(bad) - 5} more")
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
