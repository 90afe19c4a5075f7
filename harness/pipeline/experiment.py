"""Run trackers on sequences and score them: plain functions, usable without Hydra.

Per sequence the data flow is: frame k -> detection source (once per frame) -> every
tracker (the same detections and foreground, each tracker its own copy) -> reported tracks
-> ``tracks/<tracker>/<sequence>.txt`` -> metrics against the ground truth. Frames are
visited once, in order, and every tracker advances on the same frame before the next one is
read: the detections are computed once per sequence, identical for every tracker, and no
more than one frame is held in memory.

``run_tracker`` runs one tracker on one sequence; ``run_sequence`` runs several side by
side; ``run_experiment`` runs a whole composed config (dataset x detector x trackers, plus
external result folders) and writes the run directory (``harness.pipeline.writer.RunWriter``; the
Markdown summary is ``harness.pipeline.summary``).

A failing tracker (an exception in ``update``) or a failing sequence (an unreadable frame,
a failing detector) is recorded in ``errors.txt`` and the run goes on; everything written
before the failure stays on disk.
"""

from __future__ import annotations

import logging
import math
import time
import traceback
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import pandas as pd

from harness.datasets.base import Sequence
from harness.io.mot import (
    MotTable,
    format_mot,
    read_mot,
    read_mot_text,
    write_atomic,
)
from harness.metrics import COLUMNS, SequenceScore, score_sequence
from harness.pipeline.build import (  # noqa: F401 - re-exported: harness.pipeline.experiment's public names
    _cfg_get,
    _check_located,
    _container,
    _hydra_choice,
    _locate_target,
    _missing_library,
    build_source,
    build_tracker,
    check_node,
    load_sequences,
    tracker_configs,
)
from harness.pipeline.loop import (  # noqa: F401 - re-exported: harness.pipeline.experiment's public names
    FOREGROUND_MODES,
    ForegroundProvider,
    LoopFrame,
    Progress,
    ProgressFactory,
    RunError,
    Tracker,
    TrackerOutput,
    _copy,
    _copy_detections,
    _no_progress,
    _NoProgress,
    _Rows,
    clean_detections,
    frames,
    start_trackers,
)
from harness.pipeline.summary import (  # noqa: F401 - re-exported: harness.pipeline.experiment's public names
    COMBINED,
    _hota_alpha_frame,
    _metrics_frame,
    _with_extras,
    mark_complete,
    run_status,
    summary_markdown,
    summary_rows,
)
from harness.pipeline.writer import Failure, RunWriter
from harness.report.bars import DEFAULT_METRICS, metric_bars
from harness.report.graph import GraphExport
from harness.report.hota_alpha import hota_alpha_plot
from harness.report.tables import comparison, to_latex
from harness.sources.base import DetectionSource

log = logging.getLogger(__name__)

def run_sequence(
    trackers: Mapping[str, Tracker],
    sequence: Sequence,
    source: DetectionSource,
    foreground: str = "auto",
    background: Mapping[str, Any] | None = None,
    progress: ProgressFactory | None = None,
    on_update: Callable[[str, int, Tracker], None] | None = None,
) -> dict[str, TrackerOutput]:
    """Run several trackers side by side on one sequence.

    Every frame is read once and detected once; each tracker gets its own copy of the frame,
    the detections and the foreground, so no tracker can disturb another's input.

    Args:
        trackers: name -> freshly built tracker.
        sequence: the sequence; its ``frame_numbers()`` (1..length, or a window's
            first..last) are visited in order, and tracks carry those numbers.
        source: detection source; ``start(sequence)`` is called here.
        foreground: foreground mode (see ``ForegroundProvider``).
        background: keyword arguments of the background model for ``foreground="mog2"``.
        progress: progress-bar factory ``(total=, desc=)``; None shows nothing.
        on_update: called as ``on_update(name, k, tracker)`` after each successful update
            of frame k, outside the timed section (e.g. ``GraphExport.record``).
    Returns:
        name -> ``TrackerOutput``. A tracker raising an exception is stopped there (its
        ``error`` set, the exception logged) while the others go on.
    Raises:
        Whatever reading a frame, the detection source or the foreground raise: the sequence
        cannot go on for any tracker.
    """
    name = sequence.info.name
    loop = frames(sequence, source, foreground, background)
    start_trackers(trackers, sequence)
    rows = {t: _Rows() for t in trackers}
    out = {t: TrackerOutput(MotTable.empty()) for t in trackers}
    active = dict(trackers)
    dropped_dets = 0
    bar = (progress or _no_progress)(total=sequence.info.length, desc=name)
    try:
        for step in loop if active else ():
            k, frame, dets, fg = step.index, step.image, step.detections, step.foreground
            dropped_dets += step.dropped
            shared = len(active) == 1
            for t, tracker in list(active.items()):
                args = (frame, dets, fg) if shared else (_copy(frame), _copy_detections(dets),
                                                         _copy(fg))
                t0 = time.perf_counter()
                try:
                    tracks = tracker.update(*args)
                except Exception as err:  # noqa: BLE001 - one tracker's failure must not stop the others
                    out[t].error = f"frame {k}: {type(err).__name__}: {err}"
                    out[t].trace = traceback.format_exc()
                    # the caller reports it (run_experiment: errors.txt and one log line)
                    log.debug("%s on %s failed at frame %d: %s: %s", t, name, k,
                              type(err).__name__, err)
                    del active[t]
                    continue
                out[t].seconds += time.perf_counter() - t0
                out[t].frames += 1
                rows[t].add(k, tracks)
                if on_update is not None:
                    on_update(t, k, tracker)
            bar.update(1)
            if not active:  # read no further frame
                break
    finally:
        bar.close()
    if dropped_dets:
        log.warning("%s: %d detections with a NaN/infinite box or score or no area dropped",
                    name, dropped_dets)
    for t in trackers:
        out[t].table = rows[t].table()
        out[t].dropped = rows[t].dropped
        if rows[t].dropped:
            log.warning("%s on %s: %d reported boxes not finite or without area dropped",
                        t, name, rows[t].dropped)
    return out


def run_tracker(tracker: Tracker, sequence: Sequence, source: DetectionSource,
                foreground: str = "auto") -> MotTable:
    """Run one tracker on one sequence; the reported tracks (0-based xywh) as a MotTable.

    Raises:
        RuntimeError: the tracker raised (the original exception is chained).
    """
    out = run_sequence({"tracker": tracker}, sequence, source, foreground)["tracker"]
    if out.error is not None:
        raise RuntimeError(f"tracker failed on {sequence.info.name}: {out.error}")
    return out.table


# --------------------------------------------------------------------------- scoring


def score(gt: Any, result: MotTable, iou_threshold: float = 0.5) -> SequenceScore:
    """``harness.metrics.score_sequence`` of ``result`` against a sequence's GroundTruth."""
    return score_sequence(gt.table, result, iou_threshold=iou_threshold)


# --------------------------------------------------------------------------- experiment


@dataclass
class ExperimentResult:
    """The outcome of ``run_experiment``.

    Attributes:
        metrics: the rows of ``metrics.csv`` (``tracker``, ``sequence`` + metric columns).
        failures: everything that failed (also in ``errors.txt``).
        timings: per tracker and sequence: frames, seconds, frames/s (``timings.csv``).
        out_dir: the run directory.
        trackers: names of the trackers run, in order (then the external names).
    """

    metrics: pd.DataFrame
    failures: list[Failure]
    timings: pd.DataFrame
    out_dir: Path
    trackers: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.failures

    def objective(self, tracker: str | None = None, metric: str = "IDF1") -> float:
        """COMBINED ``metric`` of ``tracker`` (default: the first tracker)."""
        tracker = tracker or (self.trackers[0] if self.trackers else None)
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


def prepare_trackers(configs: Mapping[str, Any], sequences: Iterable[Sequence]) -> None:
    """Before anything is timed (``harness.pipeline.warmup``): reject a tracker that needs frames when
    a sequence has none, then warm every tracker class up once per process."""
    from harness.pipeline.warmup import needs_pixels, warm_up_once

    frameless = [s.info.name for s in sequences if not s.has_pixels]
    if frameless:
        for name, node in configs.items():
            why = needs_pixels(build_tracker(name, node))
            if why is not None:
                raise RunError(
                    f"tracker {name!r} needs frame pixels ({why}), but {len(frameless)} "
                    f"sequence(s) have none (ground truth and detections only: "
                    f"{', '.join(frameless[:5])}{', ...' if len(frameless) > 5 else ''}); "
                    "run it on a dataset with frames, or choose a tracker that reads boxes "
                    "only (tracker=baseline)")
    warm_up_once({n: (lambda n=n, node=node: build_tracker(n, node))
                  for n, node in configs.items()}, log.info)


def external_folders(node: Any, taken: Iterable[str]) -> dict[str, Path]:
    """``external: {name: folder}`` checked: folders exist, names do not clash."""
    out: dict[str, Path] = {}
    taken = set(taken)
    for name, folder in dict(_container(node) or {}).items():
        if name in taken:
            raise RunError(f"external.{name}: the name is already a tracker of this run")
        if name == COMBINED or "/" in str(name):
            raise RunError(f"external.{name}: not a valid tracker name")
        path = Path(str(folder)).expanduser()
        if not path.is_dir():
            raise RunError(f"external.{name}: result folder not found: {path}")
        out[str(name)] = path
    return out


def read_external(name: str, folder: Path, sequence: str,
                  last_frame: int | None = None) -> MotTable:
    """The external tracker's result for ``sequence``; empty (with a warning) when missing.

    Raises:
        MotFormatError: a malformed row, or a row beyond ``last_frame`` (file and line named).
    """
    path = folder / f"{sequence}.txt"
    if not path.is_file():
        log.warning("external %s: no result file %s: scored as an empty result", name, path)
        return MotTable.empty(str(path))
    return read_mot(path, kind="result", last_frame=last_frame)


def _last_frame(seq: Sequence) -> int:
    """The last frame number of the whole sequence (a ``FrameWindow``'s original's)."""
    return getattr(seq, "inner", seq).frame_numbers()[-1]


def _in_window(table: MotTable, seq: Sequence) -> MotTable:
    """``table``'s rows on the frames of ``seq`` (a window scores only its own frames)."""
    frames = seq.frame_numbers()
    keep = (table.frames >= frames.start) & (table.frames < frames.stop)
    return table if keep.all() else table.rows(keep)


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
    from omegaconf import OmegaConf

    if out_dir is None:
        from hydra.core.hydra_config import HydraConfig

        if not HydraConfig.initialized():
            raise RunError("run_experiment needs out_dir outside a Hydra app")
        out_dir = HydraConfig.get().runtime.output_dir
    check_config(cfg)
    writer = RunWriter(out_dir)
    if OmegaConf.is_config(cfg):
        try:
            writer.text("config.yaml", OmegaConf.to_yaml(cfg, resolve=True))
        except OSError as err:
            raise RunError(str(err)) from None
    foreground = str(_cfg_get(cfg, "foreground", "auto"))
    if foreground not in FOREGROUND_MODES:
        raise RunError(f"foreground must be one of {FOREGROUND_MODES}, got {foreground!r}")
    background = _container(_cfg_get(cfg, "background", {}))
    evaluation = _cfg_get(cfg, "evaluation", {})
    iou_threshold = float(_cfg_get(evaluation, "iou_threshold", 0.5))
    table_columns = list(_container(_cfg_get(evaluation, "table", [])) or []) or None
    plot_metrics = list(_container(_cfg_get(evaluation, "plot", DEFAULT_METRICS)))
    try:  # per-frame tracking graphs beside the tracks (config key ``graph``)
        graphs = GraphExport.from_config(_container(_cfg_get(cfg, "graph", {})),
                                         writer.out_dir / "tracks")
    except ValueError as err:
        raise RunError(str(err)) from None

    protocol_node = _cfg_get(cfg, "protocol", {})
    protocol = str(_cfg_get(protocol_node, "name", "multi"))
    if protocol not in ("multi", "single_target"):
        raise RunError(f"protocol.name must be multi or single_target, got {protocol!r}")
    targets = _container(_cfg_get(protocol_node, "targets", None))

    # check everything that can be checked before the first frame
    tracker_node = _cfg_get(cfg, "tracker")
    configs = tracker_configs(tracker_node, tracker_name)
    group = "_target_" not in tracker_node
    keys = {n: f"tracker.{n}" if group else "tracker" for n in configs}
    for name, node in list(configs.items()):
        try:
            build_tracker(name, node, keys[name])
        except RunError as err:
            # in a group (tracker=everyone) an outside tracker whose optional library is
            # not installed is left out; selected alone, it stops the run
            if not (group and _missing_library(err)):
                raise
            log.warning("tracker %s left out: %s", name, err.__cause__)
            del configs[name]
    if not configs:
        raise RunError("no tracker of the selected group can be built (see the warnings)")
    externals = external_folders(_cfg_get(cfg, "external", {}), configs)
    build_source(_cfg_get(cfg, "detector"))
    sequences = load_sequences(_cfg_get(cfg, "dataset"))
    prepare_trackers(configs, sequences)
    names = [*configs, *externals]
    wanted = _cfg_get(_cfg_get(cfg, "objective", {}), "tracker")
    if wanted is not None and str(wanted) not in names:
        raise RunError(f"objective.tracker={wanted}: not a tracker of this run ({names})")
    title = _title(cfg, sequences)
    log.info("%d sequence(s) x %d tracker(s) %s, foreground=%s", len(sequences), len(names),
             names, foreground)

    scores: dict[str, dict[str, Any]] = {n: {} for n in names}
    # paper-table and occlusion metrics (harness.metrics.paper / .occlusion), merged below
    extras: dict[str, dict[str, Any]] = {n: {} for n in names}
    hidden_below = float(_cfg_get(evaluation, "hidden_below", 0.05))
    from harness.metrics.occlusion import extra_score
    failures: list[Failure] = []
    timings: list[dict[str, Any]] = []
    metrics = pd.DataFrame()

    def fail(tracker: str, sequence: str, stage: str, err: BaseException | str,
             trace: str = "") -> None:
        msg = err if isinstance(err, str) else f"{type(err).__name__}: {err}"
        f = Failure(tracker, sequence, stage, msg, trace)
        failures.append(f)
        writer.failure(f)
        log.error("%s failed (tracker=%s, sequence=%s): %s", stage, tracker, sequence, msg)

    expected = sum(1 for s in sequences if s.gt is not None)  # sequences that can be scored

    def publish(state: str) -> pd.DataFrame:
        """Write metrics.csv (with its ``complete`` column) and summary.md for ``state``:
        ``running``, ``finished`` or ``interrupted``."""
        frame = _with_extras(_metrics_frame(scores), extras)
        frame = mark_complete(frame, expected, state == "finished")
        done = len({s for p in scores.values() for s in p})
        status = run_status(state, done, len(sequences), failures)
        if frame.empty:
            frame = pd.DataFrame(columns=["tracker", "sequence", *COLUMNS, "complete"])
        writer.metrics(frame)
        writer.text("summary.md", summary_markdown(frame, failures, table_columns, title, status))
        return frame

    overall = (progress or _no_progress)(total=len(sequences), desc="sequences", unit="seq")
    tracked: list[str] = []  # sequences with gt and track files: gt/seqmap.txt
    sname = ""
    try:
        for seq in sequences:
            sname = seq.info.name
            try:
                writer.ground_truth(seq)
                source = build_source(_cfg_get(cfg, "detector"))
                if protocol == "single_target":
                    from harness.pipeline.protocols import run_single_target

                    builders = {n: partial(build_tracker, n, node, keys[n])
                                for n, node in configs.items()}
                    outputs = run_single_target(builders, seq, source, foreground, background,
                                                progress, targets)
                else:
                    trackers = {n: build_tracker(n, node, keys[n]) for n, node in configs.items()}
                    outputs = run_sequence(trackers, seq, source, foreground, background,
                                           progress, on_update=graphs.hook())
                graphs.write(sname)
            except Exception as err:  # noqa: BLE001 - the sequence fails, the next goes on
                fail("*", sname, "sequence", err, traceback.format_exc())
                overall.update(1)
                continue
            if seq.gt is not None and outputs:
                tracked.append(sname)
                try:
                    writer.seqmap(tracked)
                except OSError as err:
                    fail("*", sname, "write", err)
            for n, out in outputs.items():
                path = writer.track_path(n, sname)
                text = format_mot(out.table.frames, out.table.ids, out.table.boxes,
                                  out.table.conf)
                try:
                    write_atomic(path, text)
                except OSError as err:  # scored all the same, from the bytes meant for it
                    fail(n, sname, "write", err)
                timings.append({"tracker": n, "sequence": sname, "frames": out.frames,
                                "seconds": round(out.seconds, 4),
                                "fps": round(out.fps, 2) if math.isfinite(out.fps) else ""})
                if out.error is not None:
                    fail(n, sname, "tracker", out.error, out.trace or "")
                    continue
                log.info("%s on %s: %d frames, %.1f frames/s", n, sname, out.frames, out.fps)
                if seq.gt is None:
                    log.warning("%s has no ground truth: %s not scored", sname, n)
                    continue
                try:
                    result_table = read_mot_text(text, path, kind="result",
                                                 last_frame=_last_frame(seq))
                    scores[n][sname] = score(seq.gt, result_table, iou_threshold)
                    extras[n][sname] = extra_score(seq.gt, result_table, iou_threshold,
                                                   hidden_below)
                except Exception as err:  # noqa: BLE001 - recorded, the run goes on
                    fail(n, sname, "score", err, traceback.format_exc())
            for n, folder in externals.items():
                if seq.gt is None:
                    continue
                try:
                    result_table = _in_window(read_external(n, folder, sname, _last_frame(seq)),
                                              seq)
                    scores[n][sname] = score(seq.gt, result_table, iou_threshold)
                    extras[n][sname] = extra_score(seq.gt, result_table, iou_threshold,
                                                   hidden_below)
                except Exception as err:  # noqa: BLE001 - recorded, the run goes on
                    fail(n, sname, "external", err, traceback.format_exc())
            overall.update(1)
            try:
                writer.timings(timings)
                metrics = publish("running")
            except Exception as err:  # noqa: BLE001 - recorded, the run goes on
                fail("*", sname, "metrics", err, traceback.format_exc())
    except BaseException as err:  # Ctrl-C, SIGTERM: say so in errors.txt, metrics, summary
        if isinstance(err, Exception):
            raise
        fail("*", sname or "*", "interrupted",
             f"{type(err).__name__}: the run was stopped during sequence {sname!r}; "
             "metrics.csv and summary.md cover only the sequences before it")
        try:
            publish("interrupted")
        except Exception:  # noqa: BLE001 - already stopping; errors.txt says why
            log.exception("could not mark %s as interrupted", writer.out_dir)
        raise
    finally:
        overall.close()
    try:
        metrics = publish("finished")
    except Exception as err:  # noqa: BLE001 - recorded (disk full...), the run ends failed
        fail("*", "*", "metrics", err, traceback.format_exc())
    if metrics.empty:
        log.warning("no sequence was scored: metrics.csv has no rows")
    try:
        if not metrics.empty:
            writer.text("summary.tex", to_latex(comparison(metrics, table_columns),
                                                caption=f"occbench: {title} (COMBINED)"))
    except Exception as err:  # noqa: BLE001 - recorded
        fail("*", "*", "summary", err, traceback.format_exc())
    try:
        metric_bars(metrics, writer.out_dir / "plots" / "metrics.png", plot_metrics, title)
    except Exception as err:  # noqa: BLE001 - a plot is not worth losing the run for
        fail("*", "*", "plot", err, traceback.format_exc())
    try:  # HOTA and its sub-metrics at each alpha, and plots/hota_alpha.png
        alpha = _hota_alpha_frame(scores)
        if not alpha.empty:
            writer.text("hota_alpha.csv", alpha.to_csv(index=False, float_format="%.6f",
                                                       lineterminator="\n"))
            hota_alpha_plot(alpha, writer.out_dir / "plots" / "hota_alpha.png", title)
    except Exception as err:  # noqa: BLE001 - recorded, the run's other outputs stand
        fail("*", "*", "hota_alpha", err, traceback.format_exc())
    return ExperimentResult(metrics, failures, pd.DataFrame(timings), writer.out_dir, names)


def check_config(cfg: Any) -> None:
    """Type- and range-check the app's own keys (``harness.pipeline.config_check.check_app``) before
    anything is built or written; RunError naming the key."""
    from harness.errors import ConfigError
    from harness.pipeline.config_check import APP_SCHEMA, check_app

    plain: dict[str, Any] = {}
    for top in dict.fromkeys(k.split(".")[0] for k in APP_SCHEMA):
        try:
            present = top in cfg
        except TypeError:
            present = hasattr(cfg, top)
        if present:
            plain[top] = _container(cfg[top] if hasattr(cfg, "__getitem__") else getattr(cfg, top))
    try:
        check_app(plain)
    except ConfigError as err:
        raise RunError(str(err)) from None


def _title(cfg: Any, sequences: list[Sequence]) -> str:
    def target(key: str) -> str:
        choice = _hydra_choice(key)
        if choice is not None:
            return choice
        node = _cfg_get(cfg, key, {})
        return str(_cfg_get(node, "_target_", "?")).rsplit(".", 1)[-1]

    return (f"dataset {target('dataset')} ({len(sequences)} sequences), "
            f"detector {target('detector')}")
