"""A run's plan: everything checked and built from the config before the first frame.

``plan_run`` type-checks the app's keys, opens the run directory (``RunWriter``; the
resolved ``config.yaml`` first), reads the evaluation settings, builds every tracker once
(an outside tracker whose optional library is missing is left out of a group), checks the
external result folders, the detector and the dataset, and warms the trackers up
(``occbench.pipeline.warmup``), so that a bad config fails before anything is timed.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from omegaconf import OmegaConf

from occbench.datasets.base import Sequence
from occbench.errors import ConfigError, RunError
from occbench.metrics import COMBINED
from occbench.config.meta import TrackerMeta, metas
from occbench.config.paths import absolute_paths
from occbench.config.build import (
    build_source,
    build_tracker,
    cfg_get,
    container,
    hydra_choice,
    load_sequences,
    missing_library,
    tracker_configs,
)
from occbench.config.check import APP_SCHEMA, check_app
from occbench.pipeline.loop import FOREGROUND_MODES, ProgressFactory
from occbench.pipeline.warmup import warm_up_once
from occbench.pipeline.writer import RunWriter
from occbench.report.bars import DEFAULT_METRICS
from occbench.report.graph import GraphExport
from occbench.trackers.protocol import Tracker, needs_frames

log = logging.getLogger(__name__)


@dataclass
class RunPlan:
    """What ``run_experiment`` runs, checked.

    Attributes:
        writer: the run directory's writer.
        foreground, background: the foreground mode and the background model's keywords.
        iou_threshold, hidden_below: the evaluation's IoU threshold and the visible share
            below which a person counts as hidden (``occbench.metrics.occlusion``).
        table_columns, plot_metrics: the summary's columns (None = all) and plotted metrics.
        graphs: the per-frame tracking-graph export (config key ``graph``).
        protocol, targets: ``multi`` or ``single_target``, and the followed ground-truth ids.
        configs, keys: tracker name -> its config node, and the config key naming it.
        detector: the detection source's config node (a fresh source per sequence).
        externals: external tracker name -> its result folder.
        sequences: the sequences, in order.
        names: the trackers' names, then the external ones.
        title: the run's title for the summary and plots.
        report: write the run's pages and pictures (config key ``report``): report.html,
            plots/ and the paired differences (with the per-frame counts they read); false
            = the scores only, for large sweeps (``occbench.pipeline.record``).
    """

    writer: RunWriter
    foreground: str
    background: Any
    iou_threshold: float
    hidden_below: float
    table_columns: list[str] | None
    plot_metrics: list[str]
    graphs: GraphExport
    protocol: str
    targets: Any
    configs: dict[str, Any]
    keys: dict[str, str]
    detector: Any
    externals: dict[str, Path]
    sequences: list[Sequence]
    names: list[str]
    title: str
    report: bool = True

    @property
    def metas(self) -> dict[str, TrackerMeta]:
        """Name -> how the views show each tracker (its config's ``meta:`` block)."""
        return metas(self.names, self.configs)

    def build(self, name: str) -> Tracker:
        """A freshly built tracker ``name``."""
        return build_tracker(name, self.configs[name], self.keys[name])


def plan_run(cfg: Any, out_dir: str | Path, tracker_name: str | None = None,
             progress: ProgressFactory | None = None) -> RunPlan:
    """Check and build everything of ``cfg`` that can be before the first frame (the
    trackers' warm-up with a ``progress`` bar).

    Raises:
        RunError: the run cannot start (no such dataset, tracker not built, bad config).
    """
    check_config(cfg)
    writer = RunWriter(out_dir)
    if OmegaConf.is_config(cfg):
        absolute_paths(cfg_get(cfg, "dataset"))  # resolved once: config.yaml works from anywhere
        try:
            writer.text("config.yaml", OmegaConf.to_yaml(cfg, resolve=True))
        except OSError as err:
            raise RunError(str(err)) from None
    foreground = str(cfg_get(cfg, "foreground", "auto"))
    if foreground not in FOREGROUND_MODES:
        raise RunError(f"foreground must be one of {FOREGROUND_MODES}, got {foreground!r}")
    evaluation = cfg_get(cfg, "evaluation", {})
    try:  # per-frame tracking graphs beside the tracks (config key ``graph``)
        graphs = GraphExport.from_config(container(cfg_get(cfg, "graph", {})),
                                         writer.out_dir / "tracks")
    except ValueError as err:
        raise RunError(str(err)) from None
    protocol_node = cfg_get(cfg, "protocol", {})
    protocol = str(cfg_get(protocol_node, "name", "multi"))
    if protocol not in ("multi", "single_target"):
        raise RunError(f"protocol.name must be multi or single_target, got {protocol!r}")
    configs, keys = buildable_trackers(cfg_get(cfg, "tracker"), tracker_name)
    externals = external_folders(cfg_get(cfg, "external", {}), configs)
    source = build_source(cfg_get(cfg, "detector"), cache=False)
    sequences = load_sequences(cfg_get(cfg, "dataset"))
    detector = detector_label(source, hydra_choice("detector"))
    if getattr(source, "needs_pixels", False):
        frameless = [s.info.name for s in sequences if not s.has_pixels]
        if frameless:
            raise RunError(
                f"detector {detector} reads frames, but {', '.join(frameless)} has none: choose "
                "detector=noisy_gt (ground truth + noise) or detector=public (det/det.txt)")
    prepare_trackers(configs, sequences, progress)
    names = [*configs, *externals]
    wanted = cfg_get(cfg_get(cfg, "objective", {}), "tracker")
    if wanted is not None and str(wanted) not in names:
        raise RunError(f"objective.tracker={wanted}: not a tracker of this run ({names})")
    log.info("%d sequence(s) x %d tracker(s) %s, detector %s, foreground=%s", len(sequences),
             len(names), names, detector, foreground)
    return RunPlan(
        writer, foreground, container(cfg_get(cfg, "background", {})),
        float(cfg_get(evaluation, "iou_threshold", 0.5)),
        float(cfg_get(evaluation, "hidden_below", 0.05)),
        list(container(cfg_get(evaluation, "table", [])) or []) or None,
        list(container(cfg_get(evaluation, "plot", DEFAULT_METRICS))), graphs, protocol,
        container(cfg_get(protocol_node, "targets", None)), configs, keys,
        cfg_get(cfg, "detector"), externals, sequences, names,
        _title(cfg, sequences, detector), bool(cfg_get(cfg, "report", True)))


def buildable_trackers(node: Any, name: str | None) -> tuple[dict[str, Any], dict[str, str]]:
    """The tracker configs of ``node`` that build (each built once here), and the config key
    of each; in a group (tracker=everyone) an outside tracker whose optional library is not
    installed is left out with a warning, selected alone it stops the run.

    Raises:
        RunError: a tracker does not build, or no tracker of the group does.
    """
    configs = tracker_configs(node, name)
    group = "_target_" not in node
    keys = {n: f"tracker.{n}" if group else "tracker" for n in configs}
    missing: dict[str, Any] = {}
    for n, tracker_node in list(configs.items()):
        try:
            build_tracker(n, tracker_node, keys[n])
        except RunError as err:
            missing[n] = missing_library(err) if group else None
            if missing[n] is None:
                raise
            del configs[n]
    if missing:
        log.warning("%s", left_out_line(missing))
    if not configs:
        raise RunError("no tracker of the selected group can be built (see the warning)")
    return configs, keys


def left_out_line(missing: Mapping[str, Any]) -> str:
    """One line for the trackers of a group left out for a missing outside library
    (``{tracker: MissingLibrary}``): which trackers, which libraries, the install commands."""
    libraries = sorted({err.module for err in missing.values()})
    commands = " ; ".join(dict.fromkeys(err.command for err in missing.values() if err.command))
    return (f"{len(missing)} outside tracker(s) left out, their libraries "
            f"({', '.join(libraries)}) not installed: {', '.join(missing)}; to run them: "
            f"{commands}")


def check_config(cfg: Any) -> None:
    """Type- and range-check the app's own keys (``occbench.config.check.check_app``)
    before anything is built or written; RunError naming the key."""
    plain: dict[str, Any] = {}
    for top in dict.fromkeys(k.split(".")[0] for k in APP_SCHEMA):
        try:
            present = top in cfg
        except TypeError:
            present = hasattr(cfg, top)
        if present:
            plain[top] = container(cfg[top] if hasattr(cfg, "__getitem__") else getattr(cfg, top))
    try:
        check_app(plain)
    except ConfigError as err:
        raise RunError(str(err)) from None


def prepare_trackers(configs: Mapping[str, Any], sequences: Iterable[Sequence],
                     progress: ProgressFactory | None = None) -> None:
    """Before anything is timed (``occbench.pipeline.warmup``): reject a tracker that needs
    frames when a sequence has none, then warm every tracker class up once per process
    (a ``progress`` bar over the warm-up's passes)."""
    frameless = [s.info.name for s in sequences if not s.has_pixels]
    if frameless:
        for name, node in configs.items():
            tracker = build_tracker(name, node)
            try:
                declared = needs_frames(tracker)
            except TypeError as err:
                raise RunError(f"tracker {name!r}: {err}") from None
            if declared:
                raise RunError(
                    f"tracker {name!r} needs frame pixels ({type(tracker).__name__}.needs_frames), "
                    f"but {len(frameless)} "
                    f"sequence(s) have none (ground truth and detections only: "
                    f"{', '.join(frameless[:5])}{', ...' if len(frameless) > 5 else ''}); "
                    "run it on a dataset with frames, or choose a tracker that reads boxes "
                    "only (tracker=baseline)")
    warm_up_once({n: (lambda n=n, node=node: build_tracker(n, node))
                  for n, node in configs.items()}, log.info, progress)


def external_folders(node: Any, taken: Iterable[str]) -> dict[str, Path]:
    """``external: {name: folder}`` checked: folders exist, names do not clash."""
    out: dict[str, Path] = {}
    taken = set(taken)
    for name, folder in dict(container(node) or {}).items():
        if name in taken:
            raise RunError(f"external.{name}: the name is already a tracker of this run")
        if name == COMBINED or "/" in str(name):
            raise RunError(f"external.{name}: not a valid tracker name")
        path = Path(str(folder)).expanduser()
        if not path.is_dir():
            raise RunError(f"external.{name}: result folder not found: {path}")
        out[str(name)] = path
    return out


def detector_label(source: Any, choice: str | None) -> str:
    """The detection source as results name it: its ``label`` (``ground truth + noise``,
    ``silhouette front end``...) after the config choice that selected it, e.g.
    ``noisy_gt (ground truth + noise)``; a dataset's default (``default_<dataset>``) by its
    label alone."""
    label = getattr(source, "label", None) or type(source).__name__
    if choice is None or choice.startswith("default_") or str(label).startswith(choice):
        return str(label)
    return f"{choice} ({label})"


def _title(cfg: Any, sequences: list[Sequence], detector: str) -> str:
    dataset = hydra_choice("dataset")
    if dataset is None:
        node = cfg_get(cfg, "dataset", {})
        dataset = str(cfg_get(node, "_target_", "?")).rsplit(".", 1)[-1]
    n = len(sequences)
    return f"dataset {dataset} ({n} sequence{'' if n == 1 else 's'}), detector {detector}"
