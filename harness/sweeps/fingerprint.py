"""Fingerprints of a job's inputs, so that a resumed sweep recomputes what changed.

``inputs(cfg)`` gives three hex digests, stored in each sweep job's ``status.json``
(``occbench.sweeps.gather.guarded``); a job done before is skipped only when all three are the same:

* ``config``: the job's whole composed config, interpolations resolved (so a changed
  default in ``conf/`` counts, not only the command line's overrides);
* ``code``: the package version and the bytes of every ``.py`` file of ``harness`` and
  ``trackers`` and every ``.yaml`` under ``conf/``;
* ``data``: every file under each path named in ``cfg.dataset``, ``cfg.detector`` and
  ``cfg.external``, resolved to an absolute path (a relative one against the working
  folder, as the loaders read it): its path and size, and its bytes when under
  ``HASH_BYTES``, else its modification time (large videos are not read whole).

A path is the value of a path key (``PATH_KEYS``: ``root``, ``path``, ``gt``, ``*_path``,
every value under ``external``...) whatever it looks like (``dataset.root=rs2``), or any
other string with a "/" or "." naming an existing file or folder. A path key naming nothing
that exists, or a data path holding no file, raises ``FingerprintError``: the job then runs
(``occbench.sweeps.resume.guarded``), it is never skipped on a fingerprint of nothing. A
dataset without files (synthetic) is fingerprinted by its config alone; its data digest says
so, it is never the digest of no bytes.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterable, Iterator
from functools import lru_cache
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

from omegaconf import OmegaConf

HASH_BYTES = 8 << 20  # files up to this size are hashed by content
ROOT = Path(__file__).resolve().parents[2]
# config keys whose string values are data paths (besides every ``*_path``/``*_dir``/``*_file``)
PATH_KEYS = frozenset({"root", "path", "gt", "det", "xml", "video", "images",
                       "model", "weights", "mixtures", "template", "file", "folder", "dir"})
DATA_NODES = ("dataset", "detector", "external")


class FingerprintError(ValueError):
    """A data path that cannot be fingerprinted; names the key and the path."""


def inputs(cfg: Any) -> dict[str, str]:
    """``{"config": ..., "code": ..., "data": ...}`` hex digests of a composed config."""
    plain = OmegaConf.to_container(cfg, resolve=True) if OmegaConf.is_config(cfg) else cfg
    text = OmegaConf.to_yaml(OmegaConf.create(plain), sort_keys=True)
    paths = [p for node in DATA_NODES
             for p in _paths(plain.get(node), node, path_key=node == "external")]
    return {"config": _digest([text.encode()]), "code": code_version(),
            "data": data_fingerprint(paths)}


@lru_cache(maxsize=1)
def code_version() -> str:
    """Digest of the package version and the source files (computed once per process)."""
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
    """Digest of every file under ``paths`` (see the module docstring).

    Raises:
        FingerprintError: a path holds no file.
    """
    h = hashlib.sha256(b"data files:")  # no paths: "data files:", never the empty digest
    for root in sorted({Path(p).resolve() for p in paths}):
        h.update(f"{root}\0".encode())
        files = list(_files(root))
        if not files:
            raise FingerprintError(f"{root}: no data file in it to fingerprint")
        for f in files:
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


def _paths(node: Any, key: str = "", path_key: bool = False) -> Iterator[Path]:
    """Absolute data paths named by the string values of a config node (``key``: its dotted
    name, for messages; ``path_key``: its values are paths whatever they look like)."""
    if isinstance(node, dict):
        for k, value in node.items():
            if k != "_target_":
                yield from _paths(value, f"{key}.{k}", path_key or _is_path_key(str(k)))
    elif isinstance(node, list | tuple):
        for i, value in enumerate(node):
            yield from _paths(value, f"{key}[{i}]", path_key)
    elif isinstance(node, str) and node:
        p = Path(node).expanduser()
        if path_key:
            if not p.exists():
                raise FingerprintError(f"{key}={node}: no such file or folder "
                                       f"({p.absolute()})")
            yield p.resolve()
        elif ("/" in node or "." in node) and p.exists():
            r = p.resolve()
            if r in (Path.cwd(), *Path.cwd().parents, ROOT, *ROOT.parents):
                return  # "." or a parent: not a data path
            yield r


def _is_path_key(name: str) -> bool:
    return name in PATH_KEYS or name.endswith(("_path", "_dir", "_file", "_root"))


def _digest(chunks: Iterable[bytes]) -> str:
    h = hashlib.sha256()
    for c in chunks:
        h.update(c)
    return h.hexdigest()[:16]
