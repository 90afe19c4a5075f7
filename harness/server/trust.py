"""Whether a warm server still holds the code a cold run would load: never a stale result.

``Fingerprint()`` is taken when the server starts, before it imports anything of the
project: size, mtime and inode of every ``.py`` and ``.yaml`` file of the project's code
(``harness/``, ``trackers/``, ``conf/`` and every folder of the ``hydra_plugins`` namespace,
installed plugins too), of each preloaded library's ``__init__.py`` (an upgrade rewrites it)
and of the interpreter (the libraries' versions are recorded beside them, for ``occbench
server status``). ``changed()``, asked on every request (about 10 ms), takes it again and
names the first difference: a file added, removed or rewritten (a library upgraded). A
file modified within ``RACY_NS`` of the first fingerprint could be rewritten again within
the file system's timestamp granularity without its stat changing (git's "racily clean"
entries), so its content hash is kept and compared as well.
"""

from __future__ import annotations

import hashlib
import importlib.metadata
import importlib.util
import os
import sys
import time

# the libraries a served run has preloaded (import names)
LIBRARIES = ("numpy", "scipy", "cv2", "numba", "llvmlite", "hydra", "omegaconf", "pandas",
             "matplotlib")
SUFFIXES = (".py", ".yaml")
RACY_NS = 3_000_000_000


def code_folders() -> list[str]:
    """The project's code as a cold process of this ``sys.path`` would find it."""
    out = []
    for name in ("occbench", "occbench.trackers", "hydra_plugins"):
        spec = importlib.util.find_spec(name)
        out.extend(spec.submodule_search_locations or [] if spec else [])
    harness = importlib.util.find_spec("occbench")
    if harness and harness.origin:  # the checkout's, not a strict editable install's link tree
        out.append(os.path.join(os.path.dirname(os.path.dirname(os.path.realpath(
            harness.origin))), "conf"))
    return [p for p in dict.fromkeys(out) if os.path.isdir(p)]


def watched_files(folders: list[str] | None = None) -> list[str]:
    """Every file whose change makes a server stale (``folders``: the code's, by default
    ``code_folders()``)."""
    files = [os.path.realpath(sys.executable)]
    for top in code_folders() if folders is None else folders:
        for here, dirs, names in os.walk(top):
            dirs[:] = sorted(d for d in dirs if d != "__pycache__")
            files.extend(os.path.join(here, n) for n in sorted(names) if n.endswith(SUFFIXES))
    for name in LIBRARIES:
        spec = importlib.util.find_spec(name)
        if spec is not None and spec.origin:
            files.append(spec.origin)
    return list(dict.fromkeys(files))  # once each: a strict editable install nests the folders


def versions() -> dict[str, str]:
    """``LIBRARIES``' installed versions by import name (a metadata search: at start only)."""
    dists = importlib.metadata.packages_distributions()
    out = {}
    for name in LIBRARIES:
        try:
            out[name] = importlib.metadata.version(dists[name][0])
        except (KeyError, importlib.metadata.PackageNotFoundError):
            out[name] = "absent"
    return out


def _stat(path: str) -> tuple[int, int, int] | None:
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_size, st.st_mtime_ns, st.st_ino


def _digest(path: str) -> str | None:
    try:
        with open(path, "rb") as fh:
            return hashlib.blake2b(fh.read(), digest_size=16).hexdigest()
    except OSError:
        return None


class Fingerprint:
    """The state of the code at the server's start; ``changed()`` compares it with now.
    ``folders``: the code's folders (default ``code_folders()``)."""

    def __init__(self, folders: list[str] | None = None) -> None:
        self.folders = folders
        self.taken = time.time_ns()
        self.stats = {p: _stat(p) for p in watched_files(folders)}
        self.versions = versions()
        self.racy = {p: _digest(p) for p, s in self.stats.items()
                     if s is not None and s[1] >= self.taken - RACY_NS}

    def changed(self) -> str | None:
        """What differs from the start (one line), or None."""
        now = watched_files(self.folders)
        if now != list(self.stats):
            added = sorted(set(now) - set(self.stats))
            removed = sorted(set(self.stats) - set(now))
            return f"files added {added[:3]} / removed {removed[:3]}"
        for path, before in self.stats.items():
            if _stat(path) != before:
                return f"{path} changed"
        for path, before in self.racy.items():
            if _digest(path) != before:
                return f"{path} changed (same size and time stamp)"
        return None
