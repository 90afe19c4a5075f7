"""The default launcher's warm start: jobs forked from a fork server that has imported the
harness and warmed the trackers up give the same results as jobs that do it themselves,
and skip the warm-up. (Killed jobs, a killed launcher: tests/harness/test_faults.py.)"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TINY = ["dataset.scenarios=[crossing]", "dataset.length=12", "dataset.width=160",
        "dataset.height=120", "progress=false"]


def _sweep(sweep_dir: Path, *extra: str) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-m", "occbench", "-m", "tracker=reta", "seed=0,1,2", *TINY,
           f"hydra.sweep.dir={sweep_dir}", "hydra.verbose=[occbench.pipeline.warmup]", *extra]
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    proc = subprocess.run(cmd, check=False, cwd=ROOT, capture_output=True, text=True, env=env,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc


def _job_logs(sweep_dir: Path) -> list[str]:
    return [(sweep_dir / str(j) / "occbench.log").read_text() for j in range(3)]


def test_warm_jobs_skip_the_warm_up_and_give_the_same_results(tmp_path):
    warm = _sweep(tmp_path / "warm")
    assert "jobs are forked from a warm process" in warm.stderr
    assert "trackers reta warmed up once" in warm.stderr
    assert not any("warmed up" in log for log in _job_logs(tmp_path / "warm"))
    cold = _sweep(tmp_path / "cold", "hydra.launcher.preload=false")
    assert "warm process" not in cold.stderr
    assert all("warmed up reta" in log for log in _job_logs(tmp_path / "cold"))
    assert ((tmp_path / "warm" / "sweep.csv").read_text()
            == (tmp_path / "cold" / "sweep.csv").read_text())
    for j in range(3):
        for name in ("metrics.csv", "tracks/reta/crossing.txt"):
            assert ((tmp_path / "warm" / str(j) / name).read_bytes()
                    == (tmp_path / "cold" / str(j) / name).read_bytes())


def test_a_job_waiting_on_the_fork_server_says_so(monkeypatch):
    """issue 39: a sweep's first job waits while the fork server warms the trackers up (100 s
    of compiling after an install, pbm) and nothing was logged meanwhile: the launcher says
    so every WAIT_LINE seconds while a job's start waits."""
    import logging
    import threading

    from hydra_plugins.occbench_launcher import launcher as launcher_module

    lines: list[str] = []
    heard = threading.Event()

    class Ear(logging.Handler):
        def emit(self, record):
            lines.append(record.getMessage())
            if "still warming up" in record.getMessage():
                heard.set()

    class Waiting:  # a job's process whose start waits on a fork server still warming up
        def start(self):
            heard.wait(30)

    class Conn:
        def close(self):
            pass

    class Context:
        def Pipe(self, duplex):  # noqa: N802 - multiprocessing's name
            return Conn(), Conn()

        def Process(self, **_):  # noqa: N802
            return Waiting()

        def get_start_method(self):
            return "forkserver"

    monkeypatch.setattr(launcher_module, "WAIT_LINE", 0.05)
    logger = logging.getLogger(launcher_module.__name__)
    monkeypatch.setattr(logger, "level", logging.INFO)
    ear = Ear()
    logger.addHandler(ear)
    try:
        launcher = launcher_module.ProcessLauncher(n_jobs=1)
        launcher._preloaded = ["pbm"]
        launcher._start_job(Context(), 0, [], (b"", b""))
    finally:
        logger.removeHandler(ear)
    assert heard.is_set(), lines
    assert "the jobs wait for the fork server to import and warm up pbm" in lines[0]
