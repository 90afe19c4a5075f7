"""``ProcessLauncher``: every sweep job in its own process, at most ``n_jobs`` at a time.

Why not joblib's loky pool: when one of its workers dies (the kernel's out-of-memory killer,
a segfault in a compiled kernel), joblib aborts the whole ``Parallel`` call
(``TerminatedWorkerError``): the other in-flight jobs are lost, later jobs never run and
the sweep is not gathered. Here a job whose process dies is recorded as failed in its
``status.json`` ("process died: killed by SIGKILL"), returns NaN to the sweeper, and the
sweep goes on; the sweep then exits with status 1 (``harness.sweeps.callbacks.GatherSweep``).

Each job process asks the kernel to end it when the launcher ends
(``PR_SET_PDEATHSIG``, Linux) and also watches its parent, so killing the launcher ends
its jobs instead of leaving them running. A fresh process per job also means no state
leaks from one job into the next (as with Ray's ``max_calls=1``). Processes are started
with ``forkserver`` where available (a clean single-threaded parent), else ``spawn``.
"""

from __future__ import annotations

import logging
import math
import multiprocessing as mp
import os
import signal
import threading
import time
from collections.abc import Sequence
from multiprocessing.connection import wait
from pathlib import Path
from typing import Any

from hydra.core.hydra_config import HydraConfig
from hydra.core.singleton import Singleton
from hydra.core.utils import (
    JobReturn,
    JobStatus,
    configure_log,
    filter_overrides,
    run_job,
    setup_globals,
)
from hydra.plugins.launcher import Launcher
from hydra.types import HydraContext, TaskFunction
from omegaconf import DictConfig, OmegaConf, open_dict

log = logging.getLogger(__name__)


class ProcessLauncher(Launcher):
    def __init__(self, n_jobs: int = 2) -> None:
        self.n_jobs = int(n_jobs) if int(n_jobs) > 0 else (os.cpu_count() or 1)
        self.config: DictConfig | None = None
        self.task_function: TaskFunction | None = None
        self.hydra_context: HydraContext | None = None

    def setup(self, *, hydra_context: HydraContext, task_function: TaskFunction,
              config: DictConfig) -> None:
        self.config = config
        self.task_function = task_function
        self.hydra_context = hydra_context

    def launch(self, job_overrides: Sequence[Sequence[str]],
               initial_job_idx: int) -> Sequence[JobReturn]:
        setup_globals()
        assert self.config is not None and self.hydra_context is not None
        configure_log(self.config.hydra.hydra_logging, self.config.hydra.verbose)
        sweep_dir = Path(str(self.config.hydra.sweep.dir))
        sweep_dir.mkdir(parents=True, exist_ok=True)
        log.info("ProcessLauncher(n_jobs=%d) is launching %d jobs, sweep output dir: %s",
                 self.n_jobs, len(job_overrides), sweep_dir)
        for i, overrides in enumerate(job_overrides):
            log.info("\t#%d : %s", initial_job_idx + i, " ".join(filter_overrides(overrides)))
        import cloudpickle  # the task function is a closure of hydra.main

        ctx = _context()
        payload = cloudpickle.dumps((self.hydra_context, self.config, self.task_function,
                                     Singleton.get_state()))
        results: list[JobReturn | None] = [None] * len(job_overrides)
        pending = list(enumerate(job_overrides))
        running: dict[int, tuple[Any, Any]] = {}
        try:
            while pending or running:
                while pending and len(running) < self.n_jobs:
                    i, overrides = pending.pop(0)
                    recv, send = ctx.Pipe(duplex=False)
                    proc = ctx.Process(
                        target=_child, name=f"occbench-job-{initial_job_idx + i}",
                        args=(send, os.getpid(), initial_job_idx + i, list(overrides), payload))
                    proc.start()
                    send.close()
                    running[i] = (proc, recv)
                wait([p.sentinel for p, _ in running.values()]
                     + [c for _, c in running.values()], timeout=1.0)
                for i, (proc, conn) in list(running.items()):
                    got = _receive(conn)
                    if got is not None:
                        results[i] = got
                    if proc.is_alive():
                        continue
                    proc.join()
                    if results[i] is None:
                        results[i] = _receive(conn)
                    conn.close()
                    del running[i]
                    if results[i] is None:
                        results[i] = self._died(initial_job_idx + i, job_overrides[i],
                                                proc.exitcode)
        finally:
            for proc, _ in running.values():  # interrupted: end the jobs still running
                proc.terminate()
            for proc, _ in running.values():
                proc.join(timeout=10)
                if proc.is_alive():
                    proc.kill()
        return [r for r in results if r is not None]

    def _died(self, idx: int, overrides: Sequence[str], exitcode: int | None) -> JobReturn:
        """The JobReturn of a job whose process ended without one; its status.json says so."""
        how = (f"killed by {signal.Signals(-exitcode).name}" if exitcode and exitcode < 0
               else f"exit status {exitcode}")
        msg = (f"the job's process died ({how}; e.g. out of memory) before it finished: "
               "the sweep went on without it")
        job_dir = None
        try:
            cfg = self.hydra_context.config_loader.load_sweep_config(self.config, list(overrides))
            with open_dict(cfg):
                cfg.hydra.job.id = f"{cfg.hydra.job.name}_{idx}"
                cfg.hydra.job.num = idx
            job_dir = Path(str(OmegaConf.select(cfg, "hydra.sweep.dir"))) / str(
                OmegaConf.select(cfg, "hydra.sweep.subdir"))
            from harness.sweeps.gather import read_status, write_status

            old = read_status(job_dir) or {}
            write_status(job_dir, "failed", list(overrides), error=msg,
                         inputs=old.get("inputs"))
        except Exception as err:  # noqa: BLE001 - the failure is logged all the same
            log.error("job #%d: cannot record its failure in status.json: %s", idx, err)
        log.error("job #%d (%s) failed: %s", idx, " ".join(filter_overrides(overrides)), msg)
        ret = JobReturn(overrides=list(overrides), working_dir=str(job_dir or ""))
        ret.status = JobStatus.COMPLETED
        ret._return_value = math.nan
        return ret


def _context() -> Any:
    methods = mp.get_all_start_methods()
    return mp.get_context("forkserver" if "forkserver" in methods else "spawn")


def _receive(conn: Any) -> JobReturn | None:
    try:
        if conn.poll():
            return conn.recv()
    except (EOFError, OSError):
        pass
    return None


def _die_with_parent(parent: int) -> None:
    """End this process when the launcher ends: PR_SET_PDEATHSIG where the kernel has it
    (the forkserver, our parent, exits when the launcher does), and a watcher thread."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass

    def watch() -> None:
        while True:
            try:
                os.kill(parent, 0)
            except ProcessLookupError:
                os.kill(os.getpid(), signal.SIGTERM)
                return
            time.sleep(1.0)

    threading.Thread(target=watch, daemon=True, name="occbench-parent-watch").start()


def _child(conn: Any, parent: int, idx: int, overrides: list[str], payload: bytes) -> None:
    """One job in its own process: Hydra's run_job, its JobReturn sent back on ``conn``.
    ``payload``: (hydra_context, config, task_function, Singleton state), cloudpickled."""
    import pickle

    _die_with_parent(parent)
    hydra_context, config, task_function, state = pickle.loads(payload)
    # SIGTERM (the launcher ended or stopped us) as Ctrl-C: the run marks itself interrupted
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    setup_globals()
    Singleton.set_state(state)
    sweep_config = hydra_context.config_loader.load_sweep_config(config, overrides)
    with open_dict(sweep_config):
        sweep_config.hydra.job.id = f"{sweep_config.hydra.job.name}_{idx}"
        sweep_config.hydra.job.num = idx
    HydraConfig.instance().set_config(sweep_config)
    ret = run_job(hydra_context=hydra_context, config=sweep_config, task_function=task_function,
                  job_dir_key="hydra.sweep.dir", job_subdir_key="hydra.sweep.subdir")
    try:
        conn.send(ret)
    except Exception as err:  # noqa: BLE001 - e.g. an unpicklable return value
        fallback = JobReturn(overrides=overrides, working_dir=ret.working_dir)
        fallback.status = ret.status
        fallback._return_value = (RuntimeError(f"job #{idx}: {err}")
                                  if ret.status == JobStatus.FAILED else math.nan)
        conn.send(fallback)
    conn.close()
