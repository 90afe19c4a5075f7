"""A run's record: the tracks, timings, scores and failures written as results arrive.

``RunRecord`` takes each sequence's ``TrackerOutput``s (and the external result folders),
writes the track files, scores them from the bytes written, appends every failure to
``errors.txt`` and republishes ``metrics.csv`` and ``summary.md`` after every sequence, so
that a later failure or an interruption loses nothing; ``finish`` writes the end-of-run
tables and plots. A failing piece is recorded (``Failure``) and the run goes on.
"""

from __future__ import annotations

import logging
import math
import traceback
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

from occbench.datasets.base import Sequence
from occbench.errors import signals_held
from occbench.io.mot import MotTable, read_mot, read_mot_text
from occbench.io.write import format_mot, write_atomic
from occbench.metrics import SequenceScore, score_sequence
from occbench.metrics.occlusion import extra_score
from occbench.metrics.timeline import frame_counts
from occbench.pipeline.bank import TrackerOutput
from occbench.pipeline.plan import RunPlan
from occbench.pipeline.summary import (
    empty_metrics,
    hota_alpha_frame,
    mark_complete,
    metrics_frame,
    run_status,
    summary_markdown,
    with_extras,
)
from occbench.pipeline.writer import Failure
from occbench.report.tracks import track_rows, track_stats

if TYPE_CHECKING:  # pandas and the report room are imported after the first frames
    import pandas as pd

log = logging.getLogger(__name__)


def score(gt: Any, result: MotTable, iou_threshold: float = 0.5) -> SequenceScore:
    """``occbench.metrics.score_sequence`` of ``result`` against a sequence's GroundTruth."""
    return score_sequence(gt.table, result, iou_threshold=iou_threshold)


def pages() -> ModuleType:
    """``occbench.report.publish``, the report room's door: imported when the first
    sequence's summary is written, not before the first frames."""
    with signals_held():  # a Ctrl-C in the middle would break the interrupted run's summary
        # start-up: the report room's pandas, matplotlib and altair (~1 s CPU)
        from occbench.report import publish

    return publish


class RunRecord:
    """Everything a run has recorded so far, and the files that show it.

    Attributes:
        scores, extras: tracker -> sequence -> ``SequenceScore`` / paper-table and
            occlusion metrics (``occbench.metrics.occlusion.extra_score``).
        failures: every ``Failure`` (also in ``errors.txt``).
        timings: per tracker and sequence: frames, seconds, frames/s (``timings.csv``).
        metrics: the last published ``metrics.csv`` rows.
    """

    def __init__(self, plan: RunPlan) -> None:
        self.plan = plan
        self.writer = plan.writer
        self.scores: dict[str, dict[str, Any]] = {n: {} for n in plan.names}
        self.extras: dict[str, dict[str, Any]] = {n: {} for n in plan.names}
        self.failures: list[Failure] = []
        self.timings: list[dict[str, Any]] = []
        self.metrics: pd.DataFrame | None = None  # pandas is imported after the first frames
        self.frames: dict[str, dict[str, Any]] = {n: {} for n in plan.names}  # FrameCounts
        self.paired: list[Any] = []  # PairedDifference of every pair of trackers
        self.tracked: list[str] = []  # sequences with gt and track files: gt/seqmap.txt
        self.expected = sum(1 for s in plan.sequences if s.gt is not None)  # can be scored
        #: per tracker and sequence without ground truth: occbench.report.tracks.track_stats
        self.unscored: dict[str, dict[str, Any]] = {}

    def fail(self, tracker: str, sequence: str, stage: str, err: BaseException | str,
             trace: str = "") -> None:
        """Record a failed piece of the run (``errors.txt`` and one log line)."""
        msg = err if isinstance(err, str) else f"{type(err).__name__}: {err}"
        f = Failure(tracker, sequence, stage, msg, trace)
        self.failures.append(f)
        self.writer.failure(f)
        if stage == "interrupted":  # not a failure of the run's: the user stopped it
            log.warning("%s", msg)
        else:
            log.error("%s failed (tracker=%s, sequence=%s): %s", stage, tracker, sequence, msg)

    def current(self, state: str) -> pd.DataFrame:
        """The rows of every sequence scored so far, with the ``complete`` column for
        ``state`` (``running``, ``finished`` or ``interrupted``), whatever could be written."""
        frame = with_extras(metrics_frame(self.scores), self.extras)
        frame = mark_complete(frame, self.expected, state == "finished")
        return empty_metrics() if frame.empty else frame

    def publish(self, state: str, sname: str = "*") -> pd.DataFrame:
        """Write metrics.csv and summary.md for ``state``; a write that fails is recorded
        (the other is still tried) and the rows are returned all the same."""
        frame = self.current(state)
        done = len({s for p in self.scores.values() for s in p})
        try:
            self.writer.metrics(frame)
        except OSError as err:
            self.fail("*", sname, "metrics", err)
        status = run_status(state, done, len(self.plan.sequences), self.failures)
        try:  # the paired differences (summary.md's section, the printed footer) once the
            # run has ended: 1000 resamples per pair are not redone after every sequence
            done = state != "running" and self.plan.report  # report: false skips them
            self.paired = pages().paired_differences(self.frames) if done else []
        except Exception as err:  # noqa: BLE001 - recorded, the summary is written without
            self.paired = []
            self.fail("*", sname, "paired", err, traceback.format_exc())
        try:
            self.writer.text("summary.md", summary_markdown(
                frame, self.failures, self.plan.table_columns, self.plan.title, status,
                pages().paired_section(self.paired), self.track_rows()))
        except OSError as err:
            self.fail("*", sname, "summary", err)
        return frame

    def track_rows(self) -> pd.DataFrame | None:
        """Tracks counted on the sequences without ground truth (None: every sequence has)."""
        if not self.unscored:
            return None
        return track_rows(self.unscored, self.timings)

    def sequence(self, seq: Sequence, outputs: dict[str, TrackerOutput]) -> None:
        """Write, time and score every tracker's output on ``seq``, then the externals'."""
        sname = seq.info.name
        if seq.gt is not None and outputs:
            self.tracked.append(sname)
            try:
                self.writer.seqmap(self.tracked)
            except OSError as err:
                self.fail("*", sname, "write", err)
        for n, out in outputs.items():
            self._tracker(n, seq, out)
        for n, folder in self.plan.externals.items():
            if seq.gt is None:
                continue
            try:
                table = _in_window(read_external(n, folder, sname, _last_frame(seq),
                                                 (seq.info.width, seq.info.height)), seq)
                self._score(n, seq, table)
            except Exception as err:  # noqa: BLE001 - recorded, the run goes on
                self.fail(n, sname, "external", err, traceback.format_exc())

    def _tracker(self, n: str, seq: Sequence, out: TrackerOutput) -> None:
        sname = seq.info.name
        path = self.writer.track_path(n, sname)
        text = format_mot(out.table.frames, out.table.ids, out.table.boxes, out.table.conf)
        try:
            write_atomic(path, text)
            if out.followers is not None:
                self.writer.followers(n, sname, out.followers)
        except OSError as err:  # scored all the same, from the bytes meant for it
            self.fail(n, sname, "write", err)
        self.timings.append({"tracker": n, "sequence": sname, "frames": out.frames,
                             "seconds": round(out.seconds, 4),
                             "fps": round(out.fps, 2) if math.isfinite(out.fps) else ""})
        if out.error is not None:
            self.fail(n, sname, "tracker", out.error, out.trace or "")
            return
        log.info("%s on %s: %d frames, %.1f frames/s", n, sname, out.frames, out.fps)
        if seq.gt is None:
            log.info("%s has no ground truth: %s's tracks counted, not scored", sname, n)
            self.unscored.setdefault(n, {})[sname] = track_stats(out.table.ids)
            return
        try:
            self._score(n, seq, read_mot_text(text, path, kind="result",
                                              last_frame=_last_frame(seq)), out.followers)
        except Exception as err:  # noqa: BLE001 - recorded, the run goes on
            self.fail(n, sname, "score", err, traceback.format_exc())

    def _score(self, n: str, seq: Sequence, table: MotTable,
               followers: dict[int, int] | None = None) -> None:
        plan, sname = self.plan, seq.info.name
        self.scores[n][sname] = score(seq.gt, table, plan.iou_threshold)
        self.extras[n][sname] = extra_score(seq.gt, table, plan.iou_threshold,
                                            plan.hidden_below, followers)
        if not plan.report:  # the per-frame counts serve only the page and the paired bootstrap
            return
        try:  # the report's timeline, and the paired differences' counts
            self.frames[n][sname] = frame_counts(seq.gt.table, table, plan.iou_threshold)
        except Exception as err:  # noqa: BLE001 - recorded, the scores stand
            self.fail(n, sname, "timeline", err, traceback.format_exc())

    def sequence_done(self, sname: str) -> None:
        """After each sequence: timings.csv, and metrics.csv and summary.md as running."""
        try:
            self.writer.timings(self.timings)
        except OSError as err:  # recorded, the run goes on
            self.fail("*", sname, "timings", err)
        try:
            self.metrics = self.publish("running", sname)
        except Exception as err:  # noqa: BLE001 - recorded, the run goes on
            self.fail("*", sname, "metrics", err, traceback.format_exc())

    def interrupted(self, sname: str, err: BaseException) -> None:
        """Ctrl-C, SIGTERM during ``sname``: say so in errors.txt, metrics and summary."""
        self.fail("*", sname or "*", "interrupted",
                  f"{type(err).__name__}: the run was stopped during sequence {sname!r}; "
                  "metrics.csv and summary.md cover only the sequences before it")
        try:
            self.publish("interrupted", sname or "*")
        except Exception:
            log.exception("could not mark %s as interrupted", self.writer.out_dir)
            return
        self.page("interrupted", sname or "*")  # a second Ctrl-C stops it: the rest stands

    def finish(self) -> None:
        """summary.tex, the plots and hota_alpha.csv, then the final metrics.csv and
        summary.md (so that summary.md counts every failure the run reports), then
        report.html (summary.md written again if the page fails): one call to the report
        room (``occbench.report.publish.end_of_run``); a failing page is recorded and the
        others are still written. ``metrics`` keeps every scored sequence whatever could be
        written (disk full...). With ``report: false`` the plots and report.html are not
        made (nor the paired differences: ``publish``)."""
        plan = self.plan
        self.metrics = self.current("finished")
        door = pages()
        door.end_of_run(self._folder(), door.RunPages(
            self.metrics, lambda: hota_alpha_frame(self.scores), self.frames, lambda: self.paired,
            lambda: self.publish("finished"), plan.title, plan.table_columns,
            plan.plot_metrics, plan.metas, plan.report))

    def page(self, state: str = "finished", sname: str = "*") -> None:
        """report.html, last: it shows every output above (``report: false``: none). A
        failure is recorded and summary.md (of ``state``) written again to count it."""
        if self.plan.report:
            pages().run_page(self._folder(), self.frames, self.plan.title, self.paired,
                             lambda: self.publish(state, sname))

    def _folder(self) -> Any:
        """The run folder as the report room writes into it (``occbench.report.publish``)."""
        return pages().Folder(self.writer.out_dir, self.writer.text, self.writer.path,
                              lambda stage, err, trace: self.fail("*", "*", stage, err, trace))


def read_external(name: str, folder: Path, sequence: str, last_frame: int | None = None,
                  image: tuple[int, int] | None = None) -> MotTable:
    """The external tracker's result for ``sequence``; empty (with a warning) when missing.

    Raises:
        MotFormatError: a malformed row, a row beyond ``last_frame`` or a box more than 100
            (width, height) frames ``image`` wide or tall (file and line named).
    """
    path = folder / f"{sequence}.txt"
    if not path.is_file():
        log.warning("external %s: no result file %s: scored as an empty result", name, path)
        return MotTable.empty(str(path))
    return read_mot(path, kind="result", last_frame=last_frame, image=image)


def _last_frame(seq: Sequence) -> int:
    """The last frame number of the whole sequence (a ``FrameWindow``'s original's)."""
    return getattr(seq, "inner", seq).frame_numbers()[-1]


def _in_window(table: MotTable, seq: Sequence) -> MotTable:
    """``table``'s rows on the frames of ``seq`` (a window scores only its own frames)."""
    frames = seq.frame_numbers()
    keep = (table.frames >= frames.start) & (table.frames < frames.stop)
    return table if keep.all() else table.rows(keep)
