"""A sweep folder's job folders: their status (``status.json``) and overrides
(``.hydra/overrides.yaml``), read by ``occbench.sweeps.gather`` (tables, plots) and
``occbench.sweeps.tune`` (an Optuna study of a finished sweep).

A sweep folder may be reused by a later multirun with other settings: ``begin_sweep`` (called
when a multirun starts) writes ``sweep.json`` with a new id, every ``status.json`` written
afterwards in the folder's jobs carries that id (``occbench.sweeps.resume.write_status``), and
``members`` tells the jobs of the latest sweep from the folders an earlier one left behind.
"""

from __future__ import annotations

import json
import logging
import uuid
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import yaml

from occbench.config.meta import metas, run_nodes
from occbench.io.write import write_atomic

log = logging.getLogger(__name__)

STATUS_FILE = "status.json"
SWEEP_FILE = "sweep.json"  # in the sweep folder: the id of the multirun that last used it
DONE, FAILED, DAMAGED = "done", "failed", "damaged"


class SweepError(ValueError):
    """A folder that is not a sweep, or a sweep that cannot be gathered; names the path."""


def read_overrides(job_dir: str | Path) -> list[str]:
    """The job's task overrides (``.hydra/overrides.yaml``), [] when there are none."""
    path = Path(job_dir) / ".hydra" / "overrides.yaml"
    if not path.is_file():
        return []
    value = yaml.safe_load(path.read_text()) or []
    if not isinstance(value, list):
        raise TypeError(f"{path}: expected a list of overrides, got {type(value).__name__}")
    return [str(v) for v in value]


def read_status(job_dir: str | Path) -> dict[str, Any] | None:
    """The job's ``status.json`` as a dict, None when absent; an unreadable or malformed one
    gives ``{"status": "damaged", "error": <message naming the file>}`` (never done)."""
    path = Path(job_dir) / STATUS_FILE
    if not path.is_file():
        return None
    try:
        body = json.loads(path.read_text())
        if not isinstance(body, dict) or not isinstance(body.get("status"), str):
            raise ValueError("not an object with a 'status' string")
        return body
    except (OSError, UnicodeDecodeError, ValueError) as err:
        msg = f"{path}: unreadable status ({err}): the job counts as not done"
        log.warning("%s", msg)
        return {"status": DAMAGED, "error": msg}


def parse_override(text: str) -> tuple[str, str]:
    """``key=value`` (``+key``/``++key``/``~key`` prefixes dropped) -> (key, value as written).

    Values stay text, so sweep.csv shows them as the command line gave them; plots read
    numbers out of them where every value is one."""
    key, _, value = text.partition("=")
    return key.lstrip("+~"), value


def job_dirs(sweep_dir: str | Path) -> list[Path]:
    """Job directories of a sweep (those with ``.hydra/`` or a status), by job number."""
    root = Path(sweep_dir)
    if not root.is_dir():
        raise FileNotFoundError(f"sweep directory not found: {root}")
    dirs = [d for d in root.iterdir()
            if d.is_dir() and ((d / ".hydra").is_dir() or (d / STATUS_FILE).is_file())]
    if not dirs:
        raise SweepError(f"not a sweep folder: {root} holds no job folders (sub-folders with "
                         f".hydra/ or {STATUS_FILE}, as a multirun writes them)")

    def key(d: Path) -> tuple[int, int | str]:
        return (0, int(d.name)) if d.name.isdigit() else (1, d.name)

    return sorted(dirs, key=key)


def begin_sweep(sweep_dir: str | Path, overrides: Sequence[str]) -> str:
    """Mark ``sweep_dir`` as used by a new multirun (``sweep.json``: a fresh id and the
    multirun's overrides); returns the id."""
    ident = uuid.uuid4().hex[:16]
    body = {"id": ident, "overrides": [str(o) for o in overrides]}
    write_atomic(Path(sweep_dir) / SWEEP_FILE, json.dumps(body, indent=1) + "\n")
    return ident


def sweep_id(sweep_dir: str | Path) -> str | None:
    """The id of the multirun that last used ``sweep_dir`` (``sweep.json``), None when the
    folder has none (a sweep made before sweep.json existed) or it is unreadable."""
    path = Path(sweep_dir) / SWEEP_FILE
    try:
        body = json.loads(path.read_text())
    except FileNotFoundError:
        return None
    except (OSError, UnicodeDecodeError, ValueError) as err:
        log.warning("%s: unreadable (%s): every job folder is gathered", path, err)
        return None
    ident = body.get("id") if isinstance(body, dict) else None
    return ident if isinstance(ident, str) else None


def members(sweep_dir: str | Path) -> tuple[list[Path], list[tuple[Path, str]]]:
    """The job folders of the sweep that last used ``sweep_dir``, and the others with why
    they are left out (a job of an earlier sweep, or one without a status). Without
    ``sweep.json`` every job folder is a member."""
    dirs = job_dirs(sweep_dir)
    current = sweep_id(sweep_dir)
    if current is None:
        return dirs, []
    kept: list[Path] = []
    left: list[tuple[Path, str]] = []
    for d in dirs:
        status = read_status(d)
        if status is None:
            left.append((d, f"no {STATUS_FILE}: never started by this sweep"))
        elif status.get("sweep") != current and status.get("status") != DAMAGED:
            left.append((d, "left by an earlier sweep in this folder"))
        else:
            kept.append(d)
    return kept, left


def sweep_metas(sweep_dir: str | Path, frame: Any) -> dict[str, Any]:
    """Tracker -> how the views show it (``occbench.config.meta``) for every tracker of a
    gathered sweep ``frame``: the ``meta:`` block of the first job's config that runs it."""
    if "tracker" not in getattr(frame, "columns", ()):
        return {}
    nodes: dict[str, Any] = {}
    for job, rows in frame.dropna(subset=["tracker"]).groupby("job", sort=False):
        names = [n for n in dict.fromkeys(rows["tracker"].astype(str)) if n not in nodes]
        if names:
            found = run_nodes(Path(sweep_dir) / str(job), names)
            nodes.update({n: v for n, v in found.items() if n in names})
    return metas(dict.fromkeys(frame["tracker"].dropna().astype(str)), nodes)
