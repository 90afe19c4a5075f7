"""``ProcessLauncher``: every sweep job in its own process, at most ``n_jobs`` at a time.

Why not joblib's loky pool: when one of its workers dies (the kernel's out-of-memory killer,
a segfault in a compiled kernel), joblib aborts the whole ``Parallel`` call
(``TerminatedWorkerError``): the other in-flight jobs are lost, later jobs never run and
the sweep is not gathered. Here a job whose process dies is recorded as failed in its
``status.json`` ("process died: killed by SIGKILL"), returns NaN to the sweeper, and the
sweep goes on; the sweep then exits with status 1 (``occbench.sweeps.callbacks.GatherSweep``).

Each job process asks the kernel to end it when the launcher ends
(``PR_SET_PDEATHSIG``, Linux) and also watches its parent, so killing the launcher ends
its jobs instead of leaving them running. A fresh process per job also means no state
leaks from one job into the next (as with Ray's ``max_calls=1``). Processes are started
with ``forkserver`` where available, else ``spawn``.

Jobs start warm (``preload: true``, the default): before the first job, the fork server
(one process, started once per launcher process and kept for every batch of an Optuna
study) imports what a job imports and warms the first job's trackers up
(``occbench.pipeline.warmup.preload``, through ``_preload``, which the server imports); each
job is then forked from it with the imports, the loaded compiled kernels and the warm-up
already done, so it goes straight to its data. The fork server never runs a job itself,
and what a job changes dies with its process.

Hydra's state travels to the job in two parts: ``Singleton.set_state`` re-runs Hydra's
plugin scan, which re-executes every plugin module already imported (this package's
``config`` too, making a new ``ProcessLauncherConf`` class); so the state is restored first
and the job's configs are unpickled after it, against the classes the job's own pickling
of its ``JobReturn`` will find.
"""

from __future__ import annotations

import json
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


PRELOAD_ENV = "OCCBENCH_PRELOAD"  # the fork server's preload spec (JSON), read by _preload
WAIT_LINE = 15.0  # seconds a job's start waits on the fork server before a line says so


class ProcessLauncher(Launcher):
    def __init__(self, n_jobs: int = 2, preload: bool = True) -> None:
        self.n_jobs = int(n_jobs) if int(n_jobs) > 0 else (os.cpu_count() or 1)
        self.preload = bool(preload)
        self._server_started = False
        self._preloaded: list[str] = []  # the trackers the fork server warms up
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
        if job_overrides and not self._server_started:
            self._start_server(ctx, job_overrides[0])
        # Hydra's state first, the configs after it: see the module docstring
        payload = (cloudpickle.dumps(Singleton.get_state()),
                   cloudpickle.dumps((self.hydra_context, self.config, self.task_function)))
        results: list[JobReturn | None] = [None] * len(job_overrides)
        pending = list(enumerate(job_overrides))
        running: dict[int, tuple[Any, Any]] = {}
        try:
            while pending or running:
                while pending and len(running) < self.n_jobs:
                    i, overrides = pending.pop(0)
                    running[i] = self._start_job(ctx, initial_job_idx + i, overrides, payload)
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

    def _start_job(self, ctx: Any, idx: int, overrides: Sequence[str],
                   payload: tuple[bytes, bytes]) -> tuple[Any, Any]:
        """Start job ``idx``'s process; (process, the pipe its JobReturn comes back on).
        A fork server that died (e.g. a tracker's warm-up crashed it) is started again,
        plain, once: the jobs then import and warm up by themselves."""
        for attempt in (0, 1):
            recv, send = ctx.Pipe(duplex=False)
            proc = ctx.Process(target=_child, name=f"occbench-job-{idx}",
                               args=(send, os.getpid(), idx, list(overrides), payload))
            try:
                with self._waiting():  # the first job waits while the fork server warms up
                    proc.start()
            except (EOFError, OSError) as err:
                recv.close()
                send.close()
                if attempt or ctx.get_start_method() != "forkserver":
                    raise
                log.warning("the warm fork server died (%s: %s): jobs start from a plain "
                            "one", type(err).__name__, err or "no answer")
                ctx.set_forkserver_preload(["__main__"])
                continue
            send.close()
            return proc, recv
        raise AssertionError("unreachable")

    def _waiting(self) -> Any:
        """Within: a log line after ``WAIT_LINE`` seconds, then one every ``WAIT_LINE``
        seconds (a sweep's first job waits silently on the fork server's warm-up, which
        compiles the kernels on the first run after an install: minutes without a line)."""
        from occbench.pipeline.warmup import heartbeat

        return heartbeat(log.info, "the jobs wait for the fork server to import and warm up "
                         f"{', '.join(self._preloaded) or 'their modules'} (the first run after "
                         "an install compiles the kernels: half a minute to a few minutes)",
                         WAIT_LINE, WAIT_LINE)

    def _start_server(self, ctx: Any, overrides: Sequence[str]) -> None:
        """Start the fork server, warm (``preload``) or plain, before the first job."""
        self._server_started = True
        if ctx.get_start_method() != "forkserver":
            return
        if not self.preload:
            ctx.set_forkserver_preload(["__main__"])
            return
        spec = self._preload_spec(overrides)
        self._preloaded = list(spec["trackers"])
        ctx.set_forkserver_preload(["__main__", "hydra_plugins.occbench_launcher._preload"])
        saved = os.environ.get(PRELOAD_ENV)
        os.environ[PRELOAD_ENV] = json.dumps(spec, default=str)
        try:
            from multiprocessing import forkserver

            forkserver.ensure_running()  # the server reads the spec from its environment
        finally:
            if saved is None:
                os.environ.pop(PRELOAD_ENV, None)
            else:
                os.environ[PRELOAD_ENV] = saved
        log.info("jobs are forked from a warm process (imports done, trackers %s warmed up "
                 "once; hydra.launcher.preload=false switches it off)",
                 ", ".join(spec["trackers"]) or "none")

    def _preload_spec(self, overrides: Sequence[str]) -> dict[str, Any]:
        """What the fork server imports and warms up: the ``_target_`` modules and the
        trackers (resolved configs) of the job with ``overrides``, this project's only."""
        spec: dict[str, Any] = {"modules": [], "trackers": {}}
        try:
            from occbench.pipeline.warmup import preload_spec

            cfg = self.hydra_context.config_loader.load_sweep_config(self.config, list(overrides))
            choice = OmegaConf.select(cfg, "hydra.runtime.choices.tracker", default=None)
            with open_dict(cfg):
                del cfg["hydra"]
            spec = preload_spec(cfg, choice)
        except Exception as err:  # noqa: BLE001 - the jobs then import and warm up themselves
            log.warning("the fork server is not warmed up (%s: %s): each job warms itself up",
                        type(err).__name__, err)
        return spec

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
            from occbench.sweeps.gather import read_status, write_status

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


def _child(conn: Any, parent: int, idx: int, overrides: list[str],
           payload: tuple[bytes, bytes]) -> None:
    """One job in its own process: Hydra's run_job, its JobReturn sent back on ``conn``.
    ``payload``: the Singleton state, then (hydra_context, config, task_function), each
    cloudpickled; unpickled in that order (module docstring)."""
    import pickle

    _die_with_parent(parent)
    # SIGTERM (the launcher ended or stopped us) as Ctrl-C: the run marks itself interrupted
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    setup_globals()
    Singleton.set_state(pickle.loads(payload[0]))
    hydra_context, config, task_function = pickle.loads(payload[1])
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
        log.warning("job #%d: its result cannot be sent back whole (%s: %s): sending its "
                    "status and value only", idx, type(err).__name__, err)
        conn.send(_bare(ret, overrides, idx))
    conn.close()


def _bare(ret: JobReturn, overrides: list[str], idx: int) -> JobReturn:
    """``ret`` without its configs: status, working dir and the return value where that
    pickles (a failed job's exception as its text)."""
    import pickle

    bare = JobReturn(overrides=overrides, working_dir=ret.working_dir, task_name=ret.task_name)
    bare.status = ret.status
    value = ret._return_value
    try:
        pickle.dumps(value)
    except Exception as err:  # noqa: BLE001 - said in place of the value
        value = (RuntimeError(f"job #{idx}: {value!r}") if ret.status == JobStatus.FAILED
                 else RuntimeError(f"job #{idx}: its return value does not pickle: {err}"))
        if ret.status != JobStatus.FAILED:
            bare.status = JobStatus.FAILED
    bare._return_value = value
    return bare
