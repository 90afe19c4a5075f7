"""Config composition and building: the one place where Hydra configs become objects.

``compose_config`` composes ``conf/`` (or loads a finished run's ``config.yaml``);
``tracker_configs`` names the tracker configs of ``cfg.tracker``; ``build_tracker``,
``build_source`` and ``load_sequences`` instantiate them, type-checked against the target's
signature (``occbench.config.check``), with a ``RunError`` naming the key when they
cannot be.
"""

from __future__ import annotations

import importlib
from collections.abc import Sequence as Seq
from pathlib import Path
from typing import Any

from hydra import compose, initialize_config_dir
from hydra.core.hydra_config import HydraConfig
from hydra.utils import instantiate
from omegaconf import DictConfig, ListConfig, OmegaConf

from occbench.config import register
from occbench.config.check import check_target
from occbench.config.meta import declared, without_meta
from occbench.datasets.base import Sequence
from occbench.errors import ConfigError, RunError
from occbench.sources.base import DetectionSource
from occbench.sources.cache import cached
from occbench.trackers.protocol import Tracker

CONF_DIR = Path(__file__).resolve().parents[2] / "conf"


def compose_config(overrides: Seq[str], run_dir: Path | None = None,
                   config_name: str = "config") -> Any:
    """The app's config (``conf/<config_name>.yaml``) composed with ``overrides``, or, with
    ``run_dir``, a finished run's saved ``config.yaml`` with ``overrides`` merged in."""
    if run_dir is not None:
        path = Path(run_dir) / "config.yaml"
        if not path.is_file():
            raise FileNotFoundError(f"{path} not found (a run directory of python -m occbench)")
        cfg = OmegaConf.load(path)
        return OmegaConf.merge(cfg, OmegaConf.from_dotlist(list(overrides)))

    register()
    with initialize_config_dir(str(CONF_DIR), version_base="1.3"):
        return compose(config_name, overrides=list(overrides))


def tracker_choice(overrides: Seq[str]) -> str | None:
    """The ``tracker=<name>`` choice among command-line overrides (names a single tracker)."""
    for o in overrides:
        key, _, value = o.partition("=")
        if key.lstrip("+") == "tracker" and value:
            return value
    return None


def cfg_get(cfg: Any, key: str, default: Any = None) -> Any:
    """``cfg[key]`` of a config node, dict or object; ``default`` when missing or None."""
    try:
        value = cfg.get(key, default)
    except AttributeError:
        value = getattr(cfg, key, default)
    return default if value is None else value


def container(node: Any) -> Any:
    """A config node as plain Python (resolved); any other value as it is."""
    if isinstance(node, DictConfig | ListConfig):
        return OmegaConf.to_container(node, resolve=True)
    return node


def _locate_target(target: str) -> Any:
    """The object named by the dotted path ``target``; ImportError naming what is missing."""
    parts = target.split(".")
    first_error: ImportError | None = None
    for i in range(len(parts) - 1, 0, -1):  # the longest importable module prefix
        module_name = ".".join(parts[:i])
        try:
            obj = importlib.import_module(module_name)
        except ModuleNotFoundError as err:
            if err.name and (module_name + ".").startswith(err.name + "."):
                first_error = first_error or err  # this prefix is not a module: try shorter
                continue
            raise  # the module exists but one of its own imports is missing
        try:
            for attr in parts[i:]:
                obj = getattr(obj, attr)
        except AttributeError as err:
            raise first_error or ImportError(f"{target}: {err}") from err
        return obj
    raise first_error or ImportError(f"{target!r} is not a dotted path to an object")


def hydra_choice(group: str) -> str | None:
    """The config choice of ``group`` in a running Hydra app, else None."""
    if not HydraConfig.initialized():
        return None
    choice = HydraConfig.get().runtime.choices.get(group)
    return None if choice is None else str(choice)


def tracker_configs(node: Any, name: str | None = None) -> dict[str, Any]:
    """Tracker configs by name from ``cfg.tracker``.

    ``cfg.tracker`` is either one config with ``_target_`` (``tracker=baseline``; its name
    is ``name``, by default the config choice of a running Hydra app, else the class name)
    or a dict of such configs keyed by name
    (``tracker=all``).
    """
    if node is None or len(node) == 0:
        raise RunError("no tracker selected: set tracker=<name> or tracker=all")
    if "_target_" in node:
        if name is None:
            name = hydra_choice("tracker")
        if name is None or name == "all":
            name = str(node["_target_"]).rsplit(".", 1)[-1]
        return {str(name): node}
    out = {}
    for key, sub in node.items():
        if not hasattr(sub, "keys") or "_target_" not in sub:
            raise RunError(f"tracker.{key}: a tracker config needs a _target_ key, got {sub!r}")
        out[str(key)] = sub
    return out


def missing_library(err: BaseException):
    """The outside tracker's missing optional library behind ``err``
    (``occbench.trackers.outside.MissingLibrary``, found along its causes), else None."""
    # start-up: occbench.trackers.outside's wrappers (~7 ms CPU), wanted when a build fails
    from occbench.trackers.outside import MissingLibrary

    seen = set()
    while err is not None and id(err) not in seen:
        if isinstance(err, MissingLibrary):
            return err
        seen.add(id(err))
        err = err.__cause__ or err.__context__
    return None


def check_node(node: Any, key: str, target: Any) -> None:
    """Type-check a ``_target_`` config against ``target``'s signature
    (``occbench.config.check.check_target``); RunError naming ``key.<argument>``."""
    try:
        check_target(dict(container(node)), key, target)
    except ConfigError as err:
        raise RunError(str(err)) from None


def build_tracker(name: str, node: Any, key: str | None = None) -> Tracker:
    """Instantiate one tracker config; RunError with a clear message when it cannot be.

    ``key`` is the config path of ``node`` for messages (default ``tracker.<name>``); its
    ``meta:`` block (``occbench.config.meta``, for the views) is checked, never passed on."""
    key = key or f"tracker.{name}"
    try:
        declared(node, key)
    except ConfigError as err:
        raise RunError(str(err)) from None
    node = without_meta(node)
    target = str(node["_target_"])
    try:
        cls = _locate_target(target)
    except Exception as err:
        raise RunError(
            f"tracker {name!r}: its code {target} is not built or cannot be imported "
            f"({type(err).__name__}: {err}). conf/tracker/all.yaml lists the built trackers."
        ) from err
    check_node(node, key, cls)
    return _instantiate(node, f"tracker {name!r}")


def _instantiate(node: Any, label: str) -> Any:
    """``instantiate(node)``; a RunError ``<label> (<target>): <error>`` when it fails."""
    try:
        return instantiate(node, _convert_="all")
    except Exception as err:
        cause = err.__cause__ or err
        raise RunError(f"{label} ({node['_target_']}): {type(cause).__name__}: {cause}") from err


def _check_located(node: Any, key: str) -> None:
    """``check_node`` when ``node``'s target imports (else instantiate reports it)."""
    try:
        target = _locate_target(str(node["_target_"]))
    except Exception:  # noqa: BLE001 - instantiate gives the full message
        return
    check_node(node, key, target)


def load_sequences(node: Any) -> list[Sequence]:
    """Instantiate the dataset config: a list of Sequence, RunError when it cannot be."""
    if node is None or "_target_" not in node:
        raise RunError("dataset: no dataset selected (dataset=<name> with a _target_)")
    _check_located(node, "dataset")
    seqs = _instantiate(node, "dataset")
    if isinstance(seqs, Sequence):
        seqs = [seqs]
    seqs = list(seqs)
    if not seqs:
        raise RunError(f"dataset ({node['_target_']}) has no sequences")
    for s in seqs:
        if not isinstance(s, Sequence):
            raise RunError(f"dataset ({node['_target_']}) yielded {type(s).__name__}, "
                           "not a occbench.datasets.base.Sequence")
    names = [s.info.name for s in seqs]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise RunError(f"dataset: sequence names repeat: {dup}")
    return seqs


def build_source(node: Any, cache: bool = True) -> DetectionSource:
    """Instantiate the detector config; with ``cache``, a front-end source reads and fills
    the front-end cache (``occbench.sources.cache``: ``OCCBENCH_CACHE``)."""
    if node is None or "_target_" not in node:
        raise RunError("detector: no detection source selected (detector=<name>)")
    _check_located(node, "detector")
    source = _instantiate(node, "detector")
    if not cache:
        return source

    return cached(source, container(node))


def dataset_sequences(overrides: list[str]) -> list[Sequence]:
    """The sequences of ``dataset=...`` (and its keys) given as Hydra overrides."""
    cfg = compose_config(overrides)
    return list(instantiate(cfg.dataset))
