"""The ``${occbench.choose:key,{key: value, ...},default}`` resolver: a value picked by a key.

Its use is a config group's choice that follows another group's choice, e.g. the detector of
a paper table that follows the tracker (``conf/experiment/reta_table2.yaml``)::

    - override /detector: "${occbench.choose:${tracker},{reta_paper: active_basis},silhouette}"

Hydra resolves a defaults-list override after every group's choice is known, so ``${tracker}``
is the final tracker choice (the command line's or the experiment's); a detector chosen on the
command line still wins. Registered by ``occbench.config.register_resolvers()``.
"""

from __future__ import annotations

from typing import Any

from omegaconf import OmegaConf

RESOLVER = "occbench.choose"


def choose(key: Any, table: Any, default: Any) -> Any:
    """``table[key]`` when the key is in the table, else ``default``."""
    if not hasattr(table, "get"):
        raise ValueError(f"{RESOLVER}: the table must be a mapping, got {table!r}")
    return table.get(str(key), default)


def register() -> None:
    """Register ``${occbench.choose:...}`` with OmegaConf (idempotent)."""
    if not OmegaConf.has_resolver(RESOLVER):
        OmegaConf.register_new_resolver(RESOLVER, choose)
