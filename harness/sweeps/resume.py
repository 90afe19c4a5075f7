"""Resuming a sweep: each job's ``status.json``, and skipping only what is truly done.

``guarded(job_dir, overrides, run)``, called by the app around one job of a multirun: a job
already done is skipped and its stored objective returned; a job that raises is recorded as
``failed`` with its error and returns NaN, so the launcher goes on with the other jobs.

A job counts as done only when all of these hold:

* its ``status.json`` says ``done`` with exactly the same overrides;
* the fingerprints of its inputs are the same (config, code, data:
  ``occbench.sweeps.fingerprint``);
* every output file it wrote is still there, whole and unchanged
  (``occbench.sweeps.outputs``: sizes and digests recorded when it finished).
"""

from __future__ import annotations

import json
import logging
import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from occbench.errors import verbose
from occbench.io.write import write_atomic
from occbench.sweeps import outputs
from occbench.sweeps.jobs import DONE, FAILED, STATUS_FILE, read_status, sweep_id

log = logging.getLogger(__name__)


def write_status(job_dir: str | Path, status: str, overrides: Sequence[str],
                 objective: float | None = None, error: str | None = None,
                 inputs: Mapping[str, str] | None = None,
                 files: Mapping[str, Any] | None = None) -> Path:
    """Write ``status.json`` (atomically): status, overrides, objective, error, the
    fingerprint of the job's inputs (``inputs``: config, code, data), the outputs of a done
    job (``files``: ``occbench.sweeps.outputs.record``) and the id of the sweep that ran it
    (``sweep.json`` of the parent folder: ``occbench.sweeps.jobs.members``)."""
    path = Path(job_dir) / STATUS_FILE
    obj = None if objective is None or not math.isfinite(objective) else float(objective)
    body = {"status": status, "overrides": list(overrides), "objective": obj, "error": error,
            "inputs": dict(inputs) if inputs else None,
            "outputs": dict(files) if files is not None else None,
            "sweep": sweep_id(Path(job_dir).parent)}
    return write_atomic(path, json.dumps(body, indent=1) + "\n")


def damage(job_dir: str | Path, status: Mapping[str, Any]) -> list[str]:
    """Why a job whose status says done cannot be trusted: its recorded outputs missing or
    changed (``occbench.sweeps.outputs.check``); [] for a status without a record (written
    before records existed: then only ``metrics.csv`` is checked, when gathered)."""
    recorded = status.get("outputs")
    if not isinstance(recorded, dict):
        return []
    return outputs.check(job_dir, recorded)


def finished(job_dir: str | Path, overrides: Sequence[str],
             inputs: Mapping[str, str] | None = None) -> dict[str, Any] | None:
    """The status of a job already done with exactly these overrides, whole outputs and,
    when ``inputs`` is given, the same input fingerprint, else None."""
    status = read_status(job_dir)
    if not (status and status.get("status") == DONE
            and list(status.get("overrides") or []) == list(overrides)):
        return None
    if inputs is not None:
        changed = changed_inputs(status.get("inputs"), inputs)
        if changed:
            log.info("%s: inputs changed since it was done (%s): recomputed", job_dir,
                     ", ".join(changed))
            return None
    damaged = damage(job_dir, status)
    if damaged:
        log.warning("%s: outputs damaged since it was done (%s): recomputed", job_dir,
                    "; ".join(damaged))
        return None
    return status


def changed_inputs(old: Mapping[str, str] | None, new: Mapping[str, str]) -> list[str]:
    """Names of the fingerprint parts that differ (all when none was recorded, or when
    either could not be computed)."""
    if not old:
        return ["no fingerprint recorded"]
    if "error" in old or "error" in new:
        return ["fingerprint not computed: " + str(new.get("error") or old.get("error"))]
    return [k for k in new if old.get(k) != new[k]]


def guarded(job_dir: str | Path, overrides: Sequence[str], run: Callable[[], float],
            inputs: Callable[[], Mapping[str, str]] | None = None) -> float:
    """Run one sweep job: skip it when already done, record its failure instead of raising.

    Args:
        job_dir: the job's output directory.
        overrides: the job's task overrides (``HydraConfig.get().overrides.task``).
        run: the job; returns the objective.
        inputs: gives the fingerprint of the job's inputs (config, code version, data
            files: ``occbench.sweeps.fingerprint.inputs``); a job done with other inputs is run
            again, and so is one whose inputs cannot be fingerprinted.
    Returns:
        The objective; the stored one for a skipped job; NaN for a failed job.
    """
    fingerprint = None
    try:
        fingerprint = dict(inputs()) if inputs is not None else None
    except Exception as err:  # noqa: BLE001 - the job then always runs
        log.warning("%s: cannot fingerprint the inputs (%s): the job is run", job_dir, err)
        fingerprint = {"error": str(err)}
    done = finished(job_dir, overrides, fingerprint)
    if done is not None:
        log.info("%s: already done with the same overrides: skipped", job_dir)
        value = done.get("objective")
        # claimed by this sweep (sweep.json's id), as if it had run again
        write_status(job_dir, DONE, overrides, value, done.get("error"), done.get("inputs"),
                     done.get("outputs"))
        return float("nan") if value is None else float(value)
    write_status(job_dir, "running", overrides, inputs=fingerprint)
    try:
        value = float(run())
    except Exception as err:  # one job's failure must not stop the sweep
        msg = _cause(err)
        # one line per job (an input mistake fails every job alike); the traceback with -v
        log.error("%s: job failed: %s", job_dir, msg, exc_info=verbose())
        write_status(job_dir, FAILED, overrides, error=msg, inputs=fingerprint)
        return float("nan")
    write_status(job_dir, DONE, overrides, objective=value, inputs=fingerprint,
                 files=outputs.record(job_dir))
    return value


def _cause(err: BaseException) -> str:
    """A failed job's cause in one line: the app's own refusal as it says it (its
    ``occbench: `` prefix dropped: the sweep's line has one), anything else with its type."""
    text = str(err).strip()
    if text.startswith("occbench: "):  # AppError: already the one line of a refused input
        return text.removeprefix("occbench: ")
    return f"{type(err).__name__}: {text}".strip()
