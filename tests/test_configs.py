"""Every config in conf/ composes, and every ``_target_`` in it instantiates.

In the style of lightning-hydra-template's config tests. Configs are found by walking
conf/, so a new config is tested without editing this file. Mandatory keys (``???``) are
filled with small fixtures written to a temporary folder. A config whose ``_target_``
module is not importable yet (a part still being built) is skipped with its name; any other
failure fails.
"""

from __future__ import annotations

import importlib
from pathlib import Path

import cv2
import numpy as np
import pytest
from hydra import compose, initialize_config_dir
from hydra.errors import MissingConfigException
from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf

from occbench.config.meta import ROLES, declared, without_meta
from occbench.datasets.base import Sequence
from occbench.pipeline.warmup import config_targets
from occbench.progress import LOG_FORMAT

ROOT = Path(__file__).resolve().parents[1]
CONF = ROOT / "conf"
GROUPS = ("dataset", "detector", "tracker", "evaluation", "experiment")


def _configs(group: str) -> list[str]:
    return sorted(p.stem for p in (CONF / group).glob("*.yaml"))


def _primaries() -> list[str]:
    return sorted(p.stem for p in CONF.glob("*.yaml"))


@pytest.fixture(scope="module")
def fixtures(tmp_path_factory) -> dict[str, Path]:
    """A tiny MOT sequence folder with frames, and a tiny video with its gt file."""
    tmp = tmp_path_factory.mktemp("configs")
    seq = tmp / "mot" / "tiny"
    (seq / "gt").mkdir(parents=True)
    (seq / "det").mkdir()
    (seq / "img1").mkdir()
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=tiny\nimDir=img1\nframeRate=25\n"
                                     "seqLength=3\nimWidth=64\nimHeight=48\nimExt=.jpg\n")
    rows = "".join(f"{k},1,{10 + k},5,12,30,1,1,1\n" for k in (1, 2, 3))
    (seq / "gt" / "gt.txt").write_text(rows)
    (seq / "det" / "det.txt").write_text(rows.replace(",1,", ",-1,", 1))
    img = np.full((48, 64, 3), 100, np.uint8)
    for k in (1, 2, 3):
        cv2.imwrite(str(seq / "img1" / f"{k:06d}.jpg"), img)
    video = tmp / "clip.avi"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 25, (64, 48))
    for _ in range(3):
        writer.write(img)
    writer.release()
    gt = tmp / "clip_gt.txt"
    gt.write_text(rows)
    return {"mot": tmp / "mot", "video": video, "video_gt": gt}


def _fill(group: str, name: str, fx: dict[str, Path]) -> list[str]:
    """Overrides that fill the mandatory (???) keys of a config with fixtures."""
    if group == "dataset" and name == "mot":
        return [f"dataset.root={fx['mot']}"]
    if group == "dataset" and name == "video":
        return [f"dataset.path={fx['video']}", f"dataset.gt={fx['video_gt']}"]
    return []


def _compose(primary: str, overrides: list[str], hydra: bool = False) -> DictConfig:
    with initialize_config_dir(config_dir=str(CONF), version_base="1.3"):
        return compose(primary, overrides=overrides, return_hydra_config=hydra)


def _missing_module(target: str) -> str | None:
    """The module of ``target`` when it cannot be found (a part not built yet), else None."""
    parts = target.split(".")
    for i in range(len(parts) - 1, 0, -1):
        name = ".".join(parts[:i])
        try:
            importlib.import_module(name)
        except ModuleNotFoundError as err:
            if err.name and (name + ".").startswith(err.name + "."):
                continue
            raise
        return None if hasattr(importlib.import_module(name), parts[i]) else name
    return target


def _targets(node) -> list[str]:
    """Every ``_target_`` in a config node, nested ones included."""
    if OmegaConf.is_config(node):
        node = OmegaConf.to_container(node, resolve=False)
    return config_targets(node)


def _skip_unbuilt(node) -> None:
    for target in _targets(node):
        missing = _missing_module(target)
        if missing is not None:
            pytest.skip(f"{target}: module {missing} is not built yet")


@pytest.mark.parametrize("primary", _primaries())
def test_primary_config_composes(primary):
    cfg = _compose(primary, [])
    assert isinstance(cfg, DictConfig)
    OmegaConf.to_container(cfg, resolve=True)  # every interpolation resolves


def test_default_app_config():
    cfg = _compose("config", [], hydra=True)
    # unresolved: resolving it creates the folder (occbench.config.rundir)
    assert OmegaConf.to_container(cfg.hydra.run)["dir"].startswith(
        "${occbench.unique_dir:results/")
    assert cfg.foreground == "auto" and cfg.objective.metric == "IDF1"
    assert "_target_" in cfg.dataset and "_target_" in cfg.detector
    assert "_target_" not in cfg.tracker and "baseline" in cfg.tracker
    for name in cfg.tracker:  # every listed tracker is built
        assert _missing_module(str(cfg.tracker[name]["_target_"])) is None, name
    tracker_targets = {n: OmegaConf.load(CONF / "tracker" / f"{n}.yaml").get("_target_")
                       for n in set(_configs("tracker")) - {"all"}}
    # lists (everyone), the outside adapters (an extra), our ByteTrack (run beside them, in
    # everyone) and PBM's single-target comparators (pbm_comparison) are not in all
    built = {n for n, target in tracker_targets.items()
             if target is not None
             and not str(target).startswith(("occbench.trackers.outside.", "occbench.trackers.bytetrack.",
                                             "occbench.trackers.comparators."))
             and _missing_module(str(target)) is None}
    assert built <= set(cfg.tracker), "conf/tracker/all.yaml must list every built tracker"


@pytest.mark.parametrize("name", _configs("dataset"))
def test_dataset_config_instantiates(name, fixtures):
    cfg = _compose("config", [f"dataset={name}", *_fill("dataset", name, fixtures)])
    _skip_unbuilt(cfg.dataset)
    seqs = instantiate(cfg.dataset, _convert_="all")
    seqs = [seqs] if isinstance(seqs, Sequence) else list(seqs)
    assert seqs and all(isinstance(s, Sequence) and s.info.length > 0 for s in seqs)


@pytest.mark.parametrize("name", _configs("detector"))
def test_detector_config_instantiates(name):
    cfg = _compose("config", [f"detector={name}", "dataset=mot", "dataset.root=unused"])
    _skip_unbuilt(cfg.detector)
    source = instantiate(cfg.detector, _convert_="all")
    assert callable(getattr(source, "start", None)) and callable(getattr(source, "detect", None))


def _instantiate_or_skip_extra(node, key: str):
    """``instantiate(node)``; an outside tracker whose library (an extra) is not installed
    skips the test with the install hint. A tracker's ``meta:`` block is for the views: it is
    checked and stripped, as ``build_tracker`` does."""
    declared(node, key)
    node = without_meta(node)
    if not str(node.get("_target_", "")).startswith("occbench.trackers.outside."):
        return instantiate(node, _convert_="all")
    try:
        return instantiate(node, _convert_="all")
    except Exception as err:
        if isinstance(err.__cause__ or err, ImportError):
            pytest.skip(f"{key}: {err.__cause__ or err}")
        raise


@pytest.mark.parametrize("name", _configs("tracker"))
def test_tracker_config_instantiates(name):
    cfg = _compose("config", [f"tracker={name}", "dataset=mot", "dataset.root=unused"])
    nodes = {name: cfg.tracker} if "_target_" in cfg.tracker else dict(cfg.tracker)
    assert nodes
    for key, node in nodes.items():
        _skip_unbuilt(node)
        tracker = _instantiate_or_skip_extra(node, key)
        assert callable(tracker.update) and callable(tracker.reset), key
        tracker.reset()


@pytest.mark.parametrize("name", _configs("tracker"))
def test_every_tracker_config_declares_how_the_views_show_it(name):
    """A config that builds one tracker (``_target_`` once composed) declares its own
    ``meta:`` block (label, colour, role; a paper mode or a tuned variant its own, never its
    parent's); a config listing trackers (all, everyone...) declares none."""
    cfg = _compose("config", [f"tracker={name}", "dataset=mot", "dataset.root=unused"])
    own = OmegaConf.load(CONF / "tracker" / f"{name}.yaml")
    if "_target_" not in cfg.tracker:
        assert "meta" not in own, f"{name}: a list of trackers has no meta of its own"
        return
    assert "meta" in own, f"conf/tracker/{name}.yaml: no meta: block (occbench.config.meta)"
    meta = declared(own, name)
    assert {"label", "colour", "role"} <= set(own.meta) and meta.role in ROLES
    assert declared(cfg.tracker, name) == meta  # composed: its own block, not its parent's


def test_tracker_colours_and_labels_are_distinct():
    from occbench.config.meta import shipped

    found = {n: shipped(n) for n in _configs("tracker")}
    found = {n: m for n, m in found.items() if m is not None}
    assert len({m.colour.lower() for m in found.values()}) == len(found)
    assert len({m.label for m in found.values()}) == len(found)


@pytest.mark.parametrize("name", _configs("evaluation"))
def test_evaluation_config(name):
    cfg = _compose("config", [f"evaluation={name}", "dataset=mot", "dataset.root=unused"])
    assert 0 < cfg.evaluation.iou_threshold <= 1
    from occbench.metrics import COLUMNS

    for key in ("table", "plot"):
        unknown = set(cfg.evaluation.get(key) or []) - set(COLUMNS)
        assert not unknown, f"evaluation.{key} names unknown metric columns {unknown}"


@pytest.mark.parametrize("name", _configs("experiment"))
def test_experiment_config_instantiates(name, fixtures):
    try:
        cfg = _compose("config", [f"+experiment={name}"])
    except MissingConfigException as err:  # e.g. tune_*: Optuna sweeper (extra `tune`) absent
        if not str(err.missing_cfg_file).startswith("hydra/"):
            raise
        pytest.skip(f"experiment {name} needs {err.missing_cfg_file}: plugin not installed")
    for group in ("tracker", "detector"):
        node = cfg[group]
        nodes = [node] if "_target_" in node else list(node.values())
        for sub in nodes:
            _skip_unbuilt(sub)
            _instantiate_or_skip_extra(sub, f"{name}: {group}")


@pytest.mark.parametrize("primary", _primaries())
def test_hydra_logs_in_the_one_form_of_every_command(primary):
    """A run's lines (job_logging) and a sweep's own (hydra_logging, Hydra's default
    '[time][HYDRA] message') are in ``LOG_FORMAT``, as the argparse commands' are."""
    cfg = _compose(primary, [], hydra=True)
    for node in (cfg.hydra.job_logging, cfg.hydra.hydra_logging):
        assert node.handlers.console.formatter == "simple"
        assert node.formatters.simple.format == LOG_FORMAT


@pytest.mark.parametrize("group,name", [
    (f"hydra/{g.name}", p.stem) for g in sorted((CONF / "hydra").glob("*")) if g.is_dir()
    for p in sorted(g.glob("*.yaml"))
])
def test_hydra_plugin_config_composes(group, name):
    # a plugin config extends the plugin's own config: without the plugin it cannot compose
    _skip_unbuilt(OmegaConf.load(CONF / group / f"{name}.yaml"))
    try:
        cfg = _compose("config", [f"{group}={name}", "dataset=mot", "dataset.root=unused"],
                       hydra=True)
    except MissingConfigException as err:
        if not str(err.missing_cfg_file).startswith(group):
            raise
        pytest.skip(f"{group}/{name} extends {err.missing_cfg_file}: its plugin is not installed")
    node = OmegaConf.select(cfg, group.replace("/", "."))
    assert node is not None and "_target_" in node
    _skip_unbuilt(node)  # launcher/sweeper plugins are optional extras
    if "submitit" not in str(node["_target_"]):  # submitit needs a cluster to build
        assert _missing_module(str(node["_target_"])) is None


@pytest.mark.parametrize("name", _configs("experiment"))
def test_sweep_parameters_name_existing_keys(name):
    """Every key an experiment sweeps or tunes (``hydra.sweeper.params``) is a key of the
    config it composes, e.g. ``tracker.matching.match_threshold`` (a renamed tracker key
    would otherwise be added as a new, ignored key)."""
    try:
        cfg = _compose("config", [f"+experiment={name}"], hydra=True)
    except MissingConfigException as err:
        if not str(err.missing_cfg_file).startswith("hydra/"):
            raise
        pytest.skip(f"experiment {name} needs {err.missing_cfg_file}: plugin not installed")
    params = OmegaConf.select(cfg, "hydra.sweeper.params") or {}
    for key in params:
        if key.startswith(("+", "~")) or "=" in key:
            continue
        assert OmegaConf.select(cfg, key, default="<absent>") != "<absent>", f"{name}: {key}"
