"""Hydra callbacks of the app (registered under ``hydra.callbacks`` in ``conf/config.yaml``).

``GatherSweep``: at the end of a multirun, gather every job's ``metrics.csv`` into
``sweep.csv``, ``sweep.md`` and ``plots/`` in the sweep directory (``occbench.sweeps.gather``; an
Optuna study's plots are Optuna's own, ``occbench.sweeps.tune``) and print the sweep's summary. It runs
in the launching process, whatever the launcher (basic, joblib, Ray, SLURM via submitit), so
the job directories must be on a file system it can read.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from hydra.experimental.callback import Callback
from omegaconf import DictConfig, OmegaConf

from occbench.sweeps.jobs import begin_sweep
from occbench.sweeps.tune import is_optuna, plot_study

log = logging.getLogger(__name__)


class GatherSweep(Callback):
    """Write the sweep table and plots when a multirun ends.

    Args:
        metrics: metric columns shown in sweep.md and plotted (COMBINED rows); None =
            ``occbench.sweeps.gather.DEFAULT_METRICS``.
        plots: draw the metric-vs-parameter plots and heatmaps.

    Hydra builds its callbacks at every start, a single run's too: the gathering code (and
    its pandas) is imported when a multirun ends, not here (start-up time).
    """

    def __init__(self, metrics: Sequence[str] | None = None, plots: bool = True) -> None:
        self.metrics = None if metrics is None else list(metrics)
        self.plots = bool(plots)

    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        """Mark the sweep folder as this multirun's (``sweep.json``), so that the job folders
        an earlier sweep left in it are never gathered as this one's."""
        sweep_dir = Path(str(config.hydra.sweep.dir))
        try:
            begin_sweep(sweep_dir, list(config.hydra.overrides.task))
        except OSError as err:
            _exit_failed(f"occbench: cannot use the sweep folder {sweep_dir}: {err}")

    def on_multirun_end(self, config: DictConfig, **kwargs: Any) -> None:
        # start-up: the gathering's pandas, tables and pages (~0.3 s CPU), when a multirun ends
        from occbench.sweeps.gather import (
            DEFAULT_METRICS,
            failed_summary,
            not_done,
            summary_text,
            write_sweep,
        )

        metrics = list(DEFAULT_METRICS) if self.metrics is None else self.metrics
        sweep_dir = Path(str(config.hydra.sweep.dir))
        if not sweep_dir.is_dir():
            log.warning("sweep directory %s does not exist: nothing gathered", sweep_dir)
            return

        optuna = is_optuna(config)
        try:  # an Optuna study is drawn with Optuna's own views, not as parameter lines
            frame = write_sweep(sweep_dir, metrics, self.plots and not optuna)
        except Exception as err:
            log.exception("gathering the sweep in %s failed", sweep_dir)
            _exit_failed(f"occbench: gathering the sweep in {sweep_dir} failed: "
                         f"{type(err).__name__}: {err}")
            return
        if self.plots and optuna:
            try:
                metric = OmegaConf.select(config, "objective.metric", default=None) or "objective"
                plot_study(sweep_dir, config, metric=str(metric))
            except Exception:  # a plot is not worth losing the table for
                log.exception("optuna plots of %s failed", sweep_dir)
        if len(frame):  # the sweep's summary on stdout (jobs print no tables of their own)
            print(summary_text(frame, metrics, str(sweep_dir)), end="")
        print(f"sweep: {sweep_dir / 'sweep.md'}")
        if not_done(frame):
            _exit_failed(f"occbench: {failed_summary(frame, sweep_dir)}")


def _exit_failed(message: str) -> None:
    """End the multirun with exit status 1 after ``message`` on stderr. Hydra turns an
    exception in a callback into a warning (exit 0), so this exits instead: a sweep in
    which any job failed must not look like a success."""
    print(message, file=sys.stderr)
    raise SystemExit(1)


class PaperTable(Callback):
    """At the end of a job whose config has a ``paper_table`` node (``+experiment=...``),
    write ``paper_table.md`` / ``.csv`` into the job's output directory and, in a single
    run, print the table on stdout (a result; where it was written is a log line on
    stderr). ``occbench.report.paper_tables`` documents the node."""

    def on_job_end(self, config: DictConfig, job_return: Any, **kwargs: Any) -> None:
        # start-up: occbench.report.paper_tables (pandas, ~0.25 s CPU), after the job
        from occbench.report.paper_tables import write_paper_table

        spec = config.get("paper_table")
        if not spec:
            return
        out_dir = Path(str(config.hydra.runtime.output_dir))
        try:
            path = write_paper_table(out_dir, OmegaConf.to_container(spec, resolve=True))
        except Exception:  # the job's own results stay valid without the table
            log.exception("paper table for %s failed", out_dir)
            return
        log.info("paper table written to %s", path)
        if str(config.hydra.mode) != "RunMode.MULTIRUN":  # the sweep prints its own table
            print(path.read_text(), end="", flush=True)
