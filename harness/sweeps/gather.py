"""Sweeps: gathering a multirun's job folders into one table, ``sweep.csv``/``.md`` and plots.

A Hydra multirun (``occbench -m tracker=baseline tracker.max_age=1,3 seed=0,1,2``) writes one
job directory per parameter combination under ``hydra.sweep.dir`` (``<sweep>/<job
number>/``), each with the run's ``metrics.csv``, Hydra's ``.hydra/overrides.yaml`` and the
job's ``status.json`` (``occbench.sweeps.resume``: each job is skipped when truly done, its
failure recorded, its outputs fingerprinted).

* ``gather(sweep_dir)`` reads the jobs of the sweep that last used the folder
  (``occbench.sweeps.jobs.members``; folders left by an earlier sweep are listed as ignored)
  into one frame: one row per job and sequence (the per-sequence and COMBINED rows of each
  ``metrics.csv``) with the job number, every overridden value as a column, ``status`` and
  ``error`` (a failed job is one row with its error and no metrics). A job whose status says
  done but whose outputs are missing, cut short or changed since (a ``metrics.csv`` truncated
  at a line end included) is ``damaged``, named file by file. Rows are ordered by job number,
  tracker and sequence as the run wrote them, so the table does not depend on the launcher.
* ``write_sweep(sweep_dir)`` writes ``sweep.csv``, ``sweep.md`` (``occbench.sweeps.tables``),
  ``plots/`` (``occbench.sweeps.plots``) and ``report.html`` (``occbench.report.html``).

The Hydra callback ``occbench.sweeps.callbacks.GatherSweep`` calls ``write_sweep`` at the end
of a multirun; ``occbench sweep <sweep_dir>`` does the same by hand and exits 1 when any job
is not done (failed, damaged, missing).
"""

from __future__ import annotations

import argparse
import csv
import io
import logging
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pandas as pd
from omegaconf import OmegaConf

from occbench.errors import REFUSED, refusal
from occbench.io.write import write_atomic
from occbench.progress import log_to_stderr
from occbench.sweeps.jobs import (  # noqa: F401 - re-exported: occbench.sweeps.gather's names
    DAMAGED,
    DONE,
    FAILED,
    STATUS_FILE,
    SweepError,
    job_dirs,
    members,
    parse_override,
    read_overrides,
    read_status,
    sweep_metas,
)
from occbench.sweeps.page import write_sweep_report
from occbench.sweeps.plots import plot_sweep
from occbench.sweeps.resume import (  # noqa: F401 - re-exported
    changed_inputs,
    damage,
    finished,
    guarded,
    write_status,
)
from occbench.sweeps.tables import (  # noqa: F401 - re-exported
    COMBINED,
    DEFAULT_METRICS,
    aggregate,
    column,
    interval,
    is_replicate,
    parameters,
    plot_axes,
    setting_table,
    summary_text,
    sweep_markdown,
    swept,
    tick,
)
from occbench.sweeps.tune import is_optuna, plot_study

log = logging.getLogger(__name__)


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
    unclosed = _without_combined(frame)
    if unclosed:
        return pd.DataFrame(), (f"{path}: truncated (no COMBINED row for "
                                f"{', '.join(unclosed)}: the file ends before the run's end)")
    return frame, ""


def _without_combined(frame: pd.DataFrame) -> list[str]:
    """Trackers of a metrics table without their COMBINED row (the run writes one for every
    tracker it scored, so a table cut at a line end usually lacks the last one's)."""
    names = frame["tracker"].astype(str)
    closed = set(names[frame["sequence"].astype(str) == COMBINED])
    return [t for t in dict.fromkeys(names) if t not in closed]


def _job_state(d: Path, status: dict[str, Any] | None) -> tuple[str, str, pd.DataFrame]:
    """A job folder's state (done, failed, damaged, incomplete, missing...), its error and its
    metrics rows (a failed job keeps whatever it scored before failing)."""
    state = (status or {}).get("status", "")
    error = (status or {}).get("error") or ""
    metrics_path = d / "metrics.csv"
    if not state:
        state = DONE if metrics_path.is_file() else "missing"
        if state == "missing":
            error = "no status.json and no metrics.csv: the job did not run or finish"
    damaged = damage(d, status) if state == DONE and status else []
    if damaged:
        state, error = DAMAGED, "; ".join(damaged)
    frame, broken = (read_metrics(metrics_path) if metrics_path.is_file()
                     else (pd.DataFrame(), ""))
    if broken:
        log.warning("%s", broken)
        if state == DONE:
            state, error = DAMAGED, broken
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
    return state, error, frame


def _params(d: Path, status: dict[str, Any] | None) -> dict[str, str]:
    params = dict(parse_override(o) for o in read_overrides(d))
    if status and status.get("overrides"):
        params = dict(parse_override(o) for o in status["overrides"]) | params
    return params


def gather(sweep_dir: str | Path) -> pd.DataFrame:
    """One frame of every job of a sweep (see the module docstring).

    Columns: ``job``, the overridden keys (in order of first appearance), ``status``,
    ``error``, then the columns of ``metrics.csv`` (``tracker``, ``sequence``, metrics).
    ``frame.attrs["ignored"]``: ``(job, overrides, why)`` of the job folders left out.
    """
    parts: list[pd.DataFrame] = []
    keys: list[str] = []
    dirs, left = members(sweep_dir)
    for d in dirs:
        status = read_status(d)
        params = _params(d, status)
        keys += [column(k) for k in params if column(k) not in keys]
        state, error, frame = _job_state(d, status)
        head = {"job": d.name, **{column(k): v for k, v in params.items()}, "status": state,
                "error": error}
        for col, value in reversed(list(head.items())):
            frame.insert(0, col, [value] * len(frame))
        parts.append(frame)
    out = _concat(parts, keys)
    out.attrs["ignored"] = [(d.name, " ".join(f"{k}={v}" for k, v in _params(
        d, read_status(d)).items()), why) for d, why in left]
    if left:
        log.warning("%s: %d job folder(s) not of the latest sweep ignored: %s", sweep_dir,
                    len(left), ", ".join(d.name for d, _ in left))
    return out


def _concat(parts: list[pd.DataFrame], keys: list[str]) -> pd.DataFrame:
    if not parts:
        return pd.DataFrame(columns=["job", "status", "error"])
    out = pd.concat(parts, ignore_index=True)
    for col in out.columns:  # counts stay whole numbers beside a failed job's empty row
        kinds = {p[col].dtype.kind for p in parts if col in p.columns and p[col].notna().any()}
        if kinds == {"i"} and out[col].dtype.kind == "f":
            out[col] = out[col].astype("Int64")
    lead = ["job", *keys, "status", "error"]
    return out[lead + [c for c in out.columns if c not in lead]]


def write_sweep(sweep_dir: str | Path, metrics: Sequence[str] = DEFAULT_METRICS,
                plots: bool = True) -> pd.DataFrame:
    """Gather a sweep and write ``sweep.csv``, ``sweep.md`` and ``plots/`` into it."""
    sweep_dir = Path(sweep_dir)

    frame = gather(sweep_dir)
    write_atomic(sweep_dir / "sweep.csv",
                 frame.to_csv(index=False, float_format="%.6f", lineterminator="\n"))
    write_atomic(sweep_dir / "sweep.md", sweep_markdown(frame, metrics, sweep_dir.name))
    shown = sweep_metas(sweep_dir, frame)  # the trackers' labels, colours and roles
    if plots:
        for old in [*(sweep_dir / "plots").glob("sweep_*.png"),
                    *(sweep_dir / "plots").glob("heatmap_*.png")]:
            old.unlink()  # drawn for an earlier sweep's parameters, perhaps not swept now
        try:
            plot_sweep(frame, sweep_dir / "plots", metrics, shown)
        except Exception:  # a plot is not worth losing the table for
            log.exception("sweep plots failed")
    try:  # the sweep's page (occbench.report.html); the tables above stand without it
        write_sweep_report(sweep_dir, frame, metrics, shown)
    except Exception:
        log.exception("report.html of the sweep failed")
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
    log_to_stderr()

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
        print(refusal(err), file=sys.stderr)
        return REFUSED
    if optuna and not args.no_plots:
        try:
            plot_study(args.sweep_dir, config,
                       metric=str(OmegaConf.select(config, "objective.metric") or "objective"))
        except Exception:
            log.exception("optuna plots of %s failed", args.sweep_dir)
    if len(frame):
        print(summary_text(frame, args.metrics, str(args.sweep_dir)), end="")
    print(args.sweep_dir / "sweep.md")
    bad = not_done(frame)
    if bad:
        print(f"occbench: {failed_summary(frame, args.sweep_dir)}", file=sys.stderr)
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
