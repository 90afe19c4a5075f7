"""What a finished sweep job wrote, recorded so that a damaged job never counts as done.

When a job finishes, ``record(job_dir)`` lists every file of its run folder with its size
and a SHA-256 digest; ``status.json`` keeps that list (``outputs``). ``check(job_dir,
recorded)`` compares the folder with it: a file missing, cut short (a ``metrics.csv``
truncated at a line end still parses) or changed makes the job damaged, named file by file.
Hydra's own files (``.hydra/``, the log), ``status.json`` and the run lock are not outputs.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Mapping
from pathlib import Path

from occbench.sweeps.jobs import STATUS_FILE

SKIPPED_DIRS = (".hydra",)


def _is_output(rel: str) -> bool:
    name = rel.rsplit("/", 1)[-1]
    return not (rel == STATUS_FILE or name.endswith(".log") or name.startswith(".occbench")
                or rel.split("/", 1)[0] in SKIPPED_DIRS)


def _files(job_dir: Path) -> list[str]:
    out = []
    for dirpath, dirnames, filenames in os.walk(job_dir):
        dirnames.sort()
        for name in sorted(filenames):
            rel = (Path(dirpath) / name).relative_to(job_dir).as_posix()
            if _is_output(rel):
                out.append(rel)
    return out


def _digest(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()[:16]


def record(job_dir: str | Path) -> dict[str, list[int | str]]:
    """``{relative path: [size, sha256 prefix]}`` of every output file of ``job_dir``."""
    root = Path(job_dir)
    return {rel: [(root / rel).stat().st_size, _digest(root / rel)] for rel in _files(root)}


def check(job_dir: str | Path, recorded: Mapping[str, list[int | str]]) -> list[str]:
    """Why the outputs of ``job_dir`` are not those ``recorded`` when the job finished, one
    message per damaged file naming it (empty when they are whole)."""
    root = Path(job_dir)
    problems = []
    for rel, (size, digest) in recorded.items():
        path = root / rel
        try:
            now = path.stat().st_size
        except FileNotFoundError:
            problems.append(f"{path}: missing (written when the job finished)")
            continue
        except OSError as err:
            problems.append(f"{path}: unreadable ({err.strerror or err})")
            continue
        if now != size:
            what = "cut short" if now < int(size) else "grown"
            problems.append(f"{path}: {what} since the job finished ({now} of {size} bytes)")
        elif _digest(path) != digest:
            problems.append(f"{path}: changed since the job finished (same size, other bytes)")
    return problems
