"""Fingerprints of a job's inputs, so that a resumed sweep recomputes what changed.

``inputs(cfg)`` gives three hex digests, stored in each sweep job's ``status.json``
(``harness.sweeps.gather.guarded``); a job done before is skipped only when all three are the same:

* ``config``: the job's whole composed config, interpolations resolved (so a changed
  default in ``conf/`` counts, not only the command line's overrides);
* ``code``: the package version and the bytes of every ``.py`` file of ``harness`` and
  ``trackers`` and every ``.yaml`` under ``conf/``;
* ``data``: every file under each existing path named in ``cfg.dataset`` (and
  ``cfg.external``): its relative path and size, and its bytes when under ``HASH_BYTES``,
  else its modification time (large videos are not read whole).
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterable, Iterator
from functools import lru_cache
from pathlib import Path
from typing import Any

HASH_BYTES = 8 << 20  # files up to this size are hashed by content
ROOT = Path(__file__).resolve().parents[2]


def inputs(cfg: Any) -> dict[str, str]:
    """``{"config": ..., "code": ..., "data": ...}`` hex digests of a composed config."""
    from omegaconf import OmegaConf

    plain = OmegaConf.to_container(cfg, resolve=True) if OmegaConf.is_config(cfg) else cfg
    text = OmegaConf.to_yaml(OmegaConf.create(plain), sort_keys=True)
    paths = list(_paths(plain.get("dataset"))) + list(_paths(plain.get("external")))
    return {"config": _digest([text.encode()]), "code": code_version(),
            "data": data_fingerprint(paths)}


@lru_cache(maxsize=1)
def code_version() -> str:
    """Digest of the package version and the source files (computed once per process)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        ver = version("occbench")
    except PackageNotFoundError:
        ver = "unknown"
    files = sorted(p for d in ("harness", "trackers") for p in (ROOT / d).rglob("*.py"))
    files += sorted((ROOT / "conf").rglob("*.yaml"))
    h = hashlib.sha256(ver.encode())
    for p in files:
        h.update(str(p.relative_to(ROOT)).encode() + b"\0")
        h.update(p.read_bytes())
    return h.hexdigest()[:16]


def data_fingerprint(paths: Iterable[Path]) -> str:
    """Digest of every file under ``paths`` (see the module docstring)."""
    h = hashlib.sha256()
    for root in sorted({Path(p).resolve() for p in paths}):
        for f in _files(root):
            st = f.stat()
            h.update(f"{f}\0{st.st_size}\0".encode())
            if st.st_size <= HASH_BYTES:
                h.update(f.read_bytes())
            else:
                h.update(str(st.st_mtime_ns).encode())
    return h.hexdigest()[:16]


def _files(root: Path) -> Iterator[Path]:
    if root.is_file():
        yield root
        return
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames.sort()
        for name in sorted(filenames):
            yield Path(dirpath) / name


def _paths(node: Any) -> Iterator[Path]:
    """Existing files and folders named by the string values of a config node."""
    if isinstance(node, dict):
        for key, value in node.items():
            if key != "_target_":
                yield from _paths(value)
    elif isinstance(node, list | tuple):
        for value in node:
            yield from _paths(value)
    elif isinstance(node, str) and node and ("/" in node or "." in node):
        p = Path(node).expanduser()
        if p.exists():
            r = p.resolve()
            if r in (Path.cwd(), *Path.cwd().parents, ROOT, *ROOT.parents):
                return  # "." or a parent: not a data path
            yield p


def _digest(chunks: Iterable[bytes]) -> str:
    h = hashlib.sha256()
    for c in chunks:
        h.update(c)
    return h.hexdigest()[:16]
