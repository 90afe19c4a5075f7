"""A sweep folder's job folders: their status (``status.json``) and overrides
(``.hydra/overrides.yaml``), read by ``harness.sweeps.gather`` (tables, plots) and ``harness.sweeps.tune``
(an Optuna study of a finished sweep).
"""

from __future__ import annotations

import json
import logging
from pathlib import Path
from typing import Any

import yaml

log = logging.getLogger(__name__)

STATUS_FILE = "status.json"
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
