"""Run trackers on sequences and score them: plain functions, usable without Hydra.

Per sequence the data flow is: frame k -> detection source (once per frame) -> every
tracker (the same detections and foreground, each tracker its own copy:
``occbench.pipeline.bank.TrackerBank``) -> reported tracks -> ``tracks/<tracker>/<sequence>.txt``
-> metrics against the ground truth.

``run_experiment`` runs a whole composed config (dataset x detector x trackers, plus
external result folders) in three steps: the plan (``occbench.pipeline.plan``: everything
checked and built before the first frame), the bank (``track_sequence``: the frame loop
into the trackers, ``occbench.pipeline.loop.run_sequence`` or the single-target protocol)
and the record (``occbench.pipeline.record.RunRecord``: the run directory written as results
arrive; the Markdown summary is ``occbench.pipeline.summary``).

A failing tracker (an exception in ``update``) or a failing sequence (an unreadable frame,
a failing detector) is recorded in ``errors.txt`` and the run goes on; everything written
before the failure stays on disk.
"""

from __future__ import annotations

import math
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from hydra.core.hydra_config import HydraConfig

from occbench.datasets.base import Sequence
from occbench.errors import RunError
from occbench.metrics import COMBINED
from occbench.pipeline.bank import TrackerOutput
from occbench.config.build import build_source
from occbench.config.meta import first_of_ours, metas, run_nodes
from occbench.pipeline.loop import ProgressFactory, no_progress, run_sequence
from occbench.pipeline.plan import RunPlan, plan_run
from occbench.pipeline.record import RunRecord
from occbench.pipeline.writer import Failure

if TYPE_CHECKING:
    import pandas as pd


@dataclass
class ExperimentResult:
    """The outcome of ``run_experiment``.

    Attributes:
        metrics: the rows of ``metrics.csv`` (``tracker``, ``sequence`` + metric columns).
        failures: everything that failed (also in ``errors.txt``).
        timings: per tracker and sequence: frames, seconds, frames/s (``timings.csv``).
        out_dir: the run directory.
        trackers: names of the trackers run, in order (then the external names).
        paired: ``occbench.metrics.paired.PairedDifference`` of every pair of trackers.
        title: what was run: dataset, sequences, detector (as summary.md opens).
        tracks: tracks counted per tracker on the sequences without ground truth (None when
            every sequence has it): ``occbench.report.tracks.track_rows``.
    """

    metrics: pd.DataFrame
    failures: list[Failure]
    timings: pd.DataFrame
    out_dir: Path
    trackers: list[str] = field(default_factory=list)
    paired: list[Any] = field(default_factory=list)
    title: str = ""
    tracks: pd.DataFrame | None = None

    @property
    def ok(self) -> bool:
        return not self.failures

    def objective_tracker(self, tracker: str | None = None) -> str | None:
        """``tracker``, else the first of ours that ran (``occbench.config.meta.first_of_ours``,
        the rule of the sweep page's best settings: never the baseline beside one of ours)."""
        if tracker:
            return tracker
        return first_of_ours(self.trackers, metas(self.trackers,
                                                  run_nodes(self.out_dir, self.trackers)))

    def objective(self, tracker: str | None = None, metric: str = "IDF1") -> float:
        """COMBINED ``metric`` of ``tracker`` (default: ``objective_tracker``)."""
        tracker = self.objective_tracker(tracker)
        if tracker not in self.trackers:
            raise RunError(f"objective.tracker {tracker!r} is not in this run: {self.trackers}")
        if metric not in self.metrics.columns or metric in ("tracker", "sequence"):
            cols = [c for c in self.metrics.columns if c not in ("tracker", "sequence")]
            raise RunError(f"objective.metric {metric!r} is not a metric column: {cols}")
        rows = self.metrics[(self.metrics["tracker"] == tracker)
                            & (self.metrics["sequence"] == COMBINED)]
        if rows.empty:
            return math.nan
        return float(rows[metric].iloc[0])


def run_experiment(
    cfg: Any,
    out_dir: str | Path | None = None,
    tracker_name: str | None = None,
    progress: ProgressFactory | None = None,
) -> ExperimentResult:
    """Run every tracker (and external result folder) of ``cfg`` on every sequence.

    Args:
        cfg: the composed config (``conf/config.yaml``): ``dataset``, ``detector``,
            ``tracker``, ``evaluation``, ``external``, ``foreground``, ``background``.
        out_dir: the run directory (see ``RunWriter`` for its layout); None = the output
            directory of the running Hydra app.
        tracker_name: the name of a single selected tracker config (Hydra's choice).
        progress: progress-bar factory; None shows nothing.
    Returns:
        ``ExperimentResult``; failures are recorded there and in ``errors.txt``.
    Raises:
        RunError: the run cannot start (no such dataset, tracker not built, bad config).
    """
    plan = plan_run(cfg, _out_dir(out_dir), tracker_name, progress)
    record = RunRecord(plan)
    plan.writer.reserve()  # room for metrics, summary and errors.txt on a full disk
    overall = (progress or no_progress)(total=len(plan.sequences), desc="sequences", unit="seq")
    sname = ""
    try:
        for seq in plan.sequences:
            sname = seq.info.name
            try:
                outputs = track_sequence(plan, seq, progress)
            except Exception as err:  # noqa: BLE001 - the sequence fails, the next goes on
                record.fail("*", sname, "sequence", err, traceback.format_exc())
                overall.update(1)
                continue
            record.sequence(seq, outputs)
            overall.update(1)
            record.sequence_done(sname)
    except BaseException as err:  # Ctrl-C, SIGTERM: say so in errors.txt, metrics, summary
        if isinstance(err, Exception):
            plan.writer.close()
            raise
        record.interrupted(sname, err)
        plan.writer.close()
        raise
    finally:
        overall.close()
    writing = (progress or no_progress)(total=0, desc="scoring and writing the outputs", unit="")
    try:  # a step of its own: the page and the bootstrap of a large run take a while
        record.finish()
    finally:
        writing.close()
    plan.writer.close()
    import pandas as pd  # start-up: pandas, ~0.25 s CPU

    return ExperimentResult(record.metrics, record.failures, pd.DataFrame(record.timings),
                            plan.writer.out_dir, plan.names, record.paired, plan.title,
                            record.track_rows())


def track_sequence(plan: RunPlan, seq: Sequence,
                   progress: ProgressFactory | None = None) -> dict[str, TrackerOutput]:
    """The ground truth written, then every tracker of ``plan`` run on ``seq`` (fresh
    trackers and detection source) by the plan's protocol; the tracking graphs written.

    Raises:
        Whatever fails for the whole sequence (an unreadable frame, a failing detector).
    """
    plan.writer.ground_truth(seq)
    source = build_source(plan.detector)
    if plan.protocol == "single_target":
        # start-up: occbench.pipeline.protocols (~3 ms CPU), for protocol=single_target
        from occbench.pipeline.protocols import run_single_target

        builders = {n: (lambda n=n: plan.build(n)) for n in plan.configs}
        outputs = run_single_target(builders, seq, source, plan.foreground, plan.background,
                                    progress, plan.targets)
    else:
        trackers = {n: plan.build(n) for n in plan.configs}
        outputs = run_sequence(trackers, seq, source, plan.foreground, plan.background,
                               progress, on_update=plan.graphs.hook())
    plan.graphs.write(seq.info.name)
    return outputs


def _out_dir(out_dir: str | Path | None) -> str | Path:
    """``out_dir``, or the output directory of the running Hydra app."""
    if out_dir is not None:
        return out_dir

    if not HydraConfig.initialized():
        raise RunError("run_experiment needs out_dir outside a Hydra app")
    return HydraConfig.get().runtime.output_dir
