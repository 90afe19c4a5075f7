"""``occbench run`` (plain ``occbench``, ``python -m occbench``): the Hydra app.

Runs the selected trackers (default: every built tracker, ``conf/tracker/all.yaml``) on the
selected dataset (default: the synthetic suite) with the selected detection source, writes
the run directory (``results/<date>/<time>/``: metrics.csv, summary.md, tracks/, plots/,
config.yaml) and prints the COMBINED comparison table. Examples::

    python -m occbench tracker=baseline
    python -m occbench dataset=synthetic dataset.scenarios=[stop_behind] dataset.seed=3
    python -m occbench detector=noisy_gt detector.miss_rate=0.3
    python -m occbench dataset=mot dataset.root=datasets/trajectories/TUD-Campus dataset.image_size=[640,480] detector=noisy_gt tracker=baseline
    python -m occbench +external.sort=path/to/results   # score another tracker's files too

The job returns the objective for sweepers: the COMBINED ``objective.metric`` of
``objective.tracker`` (default IDF1 of the first of our trackers that ran, else the first).

Ctrl-C and SIGTERM (``occbench.errors.Terminated``, raised by ``occbench.commands.cli.run``'s
handler) stop the run: it marks its metrics and summary interrupted and writes errors.txt on the way
out (``occbench.pipeline.experiment``), then one line on stderr names the run folder and the
exit status is 130 (SIGINT) or 143 (SIGTERM), with no traceback.
"""

from __future__ import annotations

import contextlib
import logging
import sys
from pathlib import Path
from typing import NoReturn

import hydra
from hydra.core.hydra_config import HydraConfig
from hydra.errors import CompactHydraException
from hydra.types import RunMode
from omegaconf import DictConfig
from tqdm.contrib.logging import logging_redirect_tqdm

from occbench.errors import EXIT_SIGINT, EXIT_SIGTERM, RunError, Terminated
from occbench.pipeline.experiment import run_experiment
from occbench.progress import bars_wanted, progress_factory
from occbench.report.tracks import tracks_text
from occbench.sweeps.fingerprint import inputs

log = logging.getLogger("occbench")

# Columns of the table printed at the end (all columns are in summary.md and metrics.csv).
PRINTED = ("HOTA", "DetA", "AssA", "IDF1", "MOTA", "MOTP", "Recall", "Precision", "MT", "ML",
           "FP", "FN", "IDs", "Frag", "ReID")


class AppError(CompactHydraException):
    """A run that failed with a clear message: Hydra prints it (no traceback), exit code 1."""


# An absolute path: relative config paths resolve against the calling *module* when the app
# is started as the console script `occbench` (pkg://conf, not a package), and fail there.
CONF_DIR = str(Path(__file__).resolve().parents[2] / "conf")


@hydra.main(version_base="1.3", config_path=CONF_DIR, config_name="config")
def app(cfg: DictConfig) -> float:
    """The Hydra task: run the experiment, print the table, return the objective.

    In a multirun each job goes through ``occbench.sweeps.gather.guarded``: a job already done with
    the same overrides and the same inputs (config, code, data: ``occbench.sweeps.fingerprint``) is
    skipped, a failing job is recorded in its ``status.json`` (and
    gathered into sweep.csv) while the other jobs go on.
    """
    hc = HydraConfig.get()
    if hc.mode == RunMode.MULTIRUN:
        from occbench.sweeps.gather import guarded  # start-up: pandas, tables (~0.25 s CPU)

        return guarded(hc.runtime.output_dir, list(hc.overrides.task), lambda: run_app(cfg),
                       inputs=lambda: inputs(cfg))
    return run_app(cfg)


def run_app(cfg: DictConfig) -> float:
    """One run: the experiment, the printed table, the objective (raises AppError on failure)."""
    hc = HydraConfig.get()
    out_dir = Path(hc.runtime.output_dir)
    choice = hc.runtime.choices.get("tracker")
    objective = cfg.get("objective") or {}
    multirun = hc.mode == RunMode.MULTIRUN
    progress = progress_factory(bool(cfg.get("progress", True)), multirun)
    bars = bars_wanted(bool(cfg.get("progress", True)), multirun)  # else log lines, or nothing
    try:
        with logging_redirect_tqdm() if bars else contextlib.nullcontext():
            result = run_experiment(cfg, out_dir, tracker_name=choice, progress=progress)
        value = result.objective(objective.get("tracker"), objective.get("metric") or "IDF1")
    except RunError as err:
        raise AppError(f"occbench: {err}") from None
    except (KeyboardInterrupt, Terminated) as err:
        _stopped(err, out_dir)
    if multirun:  # one line per job; the sweep's summary is printed when the multirun ends
        from occbench.report.tables import number  # start-up: pandas, ~0.25 s CPU

        log.info("job %s [%s]: %s %s = %s", hc.job.num, " ".join(hc.overrides.task),
                 result.objective_tracker(objective.get("tracker")),
                 objective.get("metric") or "IDF1", number(value))
    else:
        from occbench.report.tables import comparison, to_text  # start-up: pandas, ~0.25 s CPU

        if not result.metrics.empty:
            from occbench.report.paired import paired_footer  # start-up: ~6 ms CPU

            print(f"{result.title} (COMBINED)")
            print(to_text(comparison(result.metrics, PRINTED)), end="")
            print(paired_footer(result.paired), end="")
        if result.tracks is not None:
            print(f"{result.title}: tracks counted, not scored (no ground truth)")
            print(tracks_text(result.tracks), end="")
        print(f"results: {out_dir}")
    if result.failures:
        raise AppError(  # each failure was logged once when it happened
            f"occbench: {len(result.failures)} part(s) of the run failed (the rest is written; "
            f"each is logged above, with its traceback in {out_dir / 'errors.txt'})")
    return value


def _stopped(err: BaseException, out_dir: Path) -> NoReturn:
    """One line for a run stopped by Ctrl-C or SIGTERM, then exit 130 or 143."""
    how, status = (("terminated (SIGTERM)", EXIT_SIGTERM) if isinstance(err, Terminated)
                   else ("interrupted (Ctrl-C)", EXIT_SIGINT))
    said = ("summary.md and report.html say" if (out_dir / "report.html").is_file()
            else "summary.md says")
    kept = (f"what was scored before is in {out_dir} ({said} interrupted, errors.txt where)"
            if (out_dir / "summary.md").is_file() else f"nothing was scored ({out_dir})")
    print(f"occbench: {how}: {kept}", file=sys.stderr)
    raise SystemExit(status)

