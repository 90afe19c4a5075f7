"""Each tracker's metadata: how the views show it, declared in its own config.

Every tracker config (``conf/tracker/<name>.yaml``) holds a ``meta:`` block::

    meta:                 # how plots, reports, sweep pages and versus.md show this tracker
      label: reta         # display name (legends)
      colour: "#ff7f0e"   # its colour in every plot and chart
      role: ours          # ours | paper (a paper tracker in paper mode) | baseline | outside
      style: ellipses     # how a replay draws its tracks: auto | boxes | ellipses | parts

``build_tracker`` strips the block (``without_meta``) before instantiating: a tracker never
sees it. A view looks a tracker's metadata up by name (``metas``): in the run's own config
first, then in the shipped ``conf/tracker/<name>.yaml``, else it is an outside tracker (an
``external`` result folder) with a colour no other tracker of the view has.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import yaml
from omegaconf import OmegaConf, open_dict

from occbench.errors import ConfigError

CONF_TRACKERS = Path(__file__).resolve().parents[2] / "conf" / "tracker"
KEY = "meta"
ROLES = ("ours", "paper", "baseline", "outside")
STYLES = ("auto", "boxes", "ellipses", "parts")
FIELDS = ("label", "colour", "role", "style")
#: colours of trackers without metadata (external result folders), the first free one each
SPARE = ("#7f7f7f", "#bcbd22", "#17becf", "#8c564b", "#e377c2", "#9467bd", "#d62728",
         "#393b79", "#637939", "#8c6d31", "#843c39", "#7b4173")
_HEX = re.compile(r"#[0-9a-fA-F]{6}")


@dataclass(frozen=True)
class TrackerMeta:
    """How the views show one tracker (the config's ``meta:`` block)."""

    label: str
    colour: str
    role: str
    style: str = "auto"

    @classmethod
    def of(cls, block: Mapping[str, Any], where: str) -> TrackerMeta:
        """The metadata of a ``meta:`` block; ConfigError naming ``<where>.<key>``."""
        unknown = sorted(set(block) - set(FIELDS))
        if unknown:
            raise ConfigError(f"{where}.{unknown[0]}: not a metadata key (keys: {', '.join(FIELDS)})")
        missing = [k for k in FIELDS[:3] if block.get(k) in (None, "")]
        if missing:
            raise ConfigError(f"{where}.{missing[0]}: missing (a tracker's meta gives "
                              f"{', '.join(FIELDS[:3])})")
        meta = cls(str(block["label"]), str(block["colour"]), str(block["role"]),
                   str(block.get("style") or "auto"))
        if not _HEX.fullmatch(meta.colour):
            raise ConfigError(f"{where}.colour: a colour is #rrggbb, got {meta.colour!r}")
        if meta.role not in ROLES:
            raise ConfigError(f"{where}.role: one of {', '.join(ROLES)}, got {meta.role!r}")
        if meta.style not in STYLES:
            raise ConfigError(f"{where}.style: one of {', '.join(STYLES)}, got {meta.style!r}")
        return meta


def declared(node: Any, where: str) -> TrackerMeta | None:
    """The metadata a tracker config node (or plain dict) declares, else None."""
    block = node.get(KEY) if hasattr(node, "get") else None
    if block is None:
        return None
    return TrackerMeta.of(dict(block), f"{where}.{KEY}")


def without_meta(node: Any) -> Any:
    """``node`` without its ``meta:`` block (a copy; ``node`` itself when it has none)."""
    if not hasattr(node, "keys") or KEY not in node:
        return node

    if OmegaConf.is_config(node):
        out = node.copy()
        with open_dict(out):
            out.pop(KEY)
        return out
    return {k: v for k, v in node.items() if k != KEY}


@cache
def shipped(name: str) -> TrackerMeta | None:
    """The metadata of the shipped ``conf/tracker/<name>.yaml``, None when there is none."""
    path = CONF_TRACKERS / f"{name}.yaml"
    if not path.is_file():
        return None
    return declared(yaml.safe_load(path.read_text()) or {}, f"conf/tracker/{name}.yaml")


def metas(names: Iterable[str], nodes: Mapping[str, Any] | None = None,
          known: Mapping[str, TrackerMeta] | None = None) -> dict[str, TrackerMeta]:
    """Name -> metadata of each tracker of a view: ``known[name]``, else the run's config node
    ``nodes[name]``'s, else the shipped config's, else an outside tracker labelled by its
    name with the first ``SPARE`` colour no other tracker of ``names`` has."""
    names = list(dict.fromkeys(str(n) for n in names))
    nodes, known = nodes or {}, known or {}
    out: dict[str, TrackerMeta | None] = {}
    for n in names:
        if n in known:
            out[n] = known[n]
            continue
        out[n] = declared(nodes[n], f"tracker.{n}") if n in nodes else None
        out[n] = out[n] or shipped(n)
    taken = {m.colour.lower() for m in out.values() if m is not None}
    free = [c for c in SPARE if c not in taken] or list(SPARE)
    k = 0
    for n in names:
        if out[n] is None:
            out[n] = TrackerMeta(n, free[k % len(free)], "outside")
            k += 1
    return {n: m for n, m in out.items() if m is not None}


def config_nodes(cfg: Mapping[str, Any] | Any, names: Iterable[str]) -> dict[str, Any]:
    """Name -> tracker config node of a run whose (saved) config is ``cfg``: a tracker
    group's nodes by name, or one tracker's node for the one of ``names`` that is not
    external."""
    tracker = (cfg.get("tracker") if hasattr(cfg, "get") else None) or {}
    if "_target_" in tracker:
        external = set((cfg.get("external") or {}) if hasattr(cfg, "get") else {})
        own = [n for n in names if n not in external]
        return {own[0]: tracker} if len(own) == 1 else {}
    return {str(k): v for k, v in tracker.items() if hasattr(v, "get")}


def run_nodes(run_dir: str | Path, names: Iterable[str]) -> dict[str, Any]:
    """``config_nodes`` of a finished run folder's ``config.yaml``; none when the file is
    missing or unreadable (the shipped metadata then: a view never fails for want of
    colours)."""
    try:
        cfg = yaml.safe_load((Path(run_dir) / "config.yaml").read_text()) or {}
    except (OSError, yaml.YAMLError):
        cfg = {}
    return config_nodes(cfg if isinstance(cfg, dict) else {}, list(names))


def first_of_ours(names: Iterable[str], found: Mapping[str, TrackerMeta]) -> str | None:
    """The tracker a view ranks on when none is named: the first of ours, else the first
    in paper mode, else the first that is not the baseline, else the first; None for none."""
    names = list(names)
    for roles in (("ours",), ("paper",), ("outside",), ROLES):
        for n in names:
            if n in found and found[n].role in roles:
                return n
    return names[0] if names else None
