"""Start-up of occbench: how long before a run's (or a sweep job's) first frame.

Each figure is the median of ``--runs`` fresh processes, printed with its ratio to
``python -c pass`` (the interpreter's own start, timed in the same loop). Targets (issue 23):
``occbench --version`` and a one-job run's start-up before its first frame at most 1 s on a
warm machine (numba's cache filled by an earlier run).

- ``python -c pass``: the reference.
- ``occbench --version``: the console script, wall time.
- import: ``import harness.commands.run, harness.pipeline.experiment`` in a fresh process.
- build: in one fresh process, after the imports above: compose the config of ``tracker=T``
  and build the tracker (its own imports included), then its warm-up (numba kernels loaded
  from the cache) - for reta and pbm.
- first frame: ``occbench tracker=T progress=false`` from the start of the process to the
  frame loop (``run_sequence`` entered: config, checks, trackers built and warmed up; the
  data's own warm-up, e.g. a detector's background, is what the loop does first and is
  left out), on the synthetic ``crossing`` scene.
- sweep job: a 4-job sweep (``hydra.launcher.n_jobs=1``, one job at a time) on the default
  launcher, warm (forked from the preloaded fork server) and cold (``preload=false``):
  the median time from a job's last log line to the next job's frame loop (its log line
  "N sequence(s) x ...").

Usage: ``python benchmarks/bench_startup.py [--runs 5] [--tracker reta] [--no-sweep]``.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import datetime
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ENV = {**os.environ, "OMP_NUM_THREADS": "1",
       "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
SCENE = ["dataset.scenarios=[crossing]", "dataset.length=20", "progress=false"]

# a one-job run stopped where its frame loop starts: prints the seconds since T0 (wall)
FIRST_FRAME = """
import os, sys, time
import harness.pipeline.experiment as experiment
def stop(*args, **kwargs):
    print(time.time() - float(os.environ["BENCH_T0"]), flush=True)
    os._exit(0)
experiment.run_sequence = stop
from harness.commands.cli import main
main(sys.argv[1:])
"""

BUILD = """
import json, sys, time
t = time.perf_counter()
import harness.commands.run, harness.pipeline.experiment
t_import = time.perf_counter() - t
from harness.pipeline.build import build_tracker, compose_config
from harness.pipeline.warmup import warm_up
out = {"import": t_import}
for name in sys.argv[1:]:
    t = time.perf_counter()
    tracker = build_tracker(name, compose_config([f"tracker={name}"]).tracker, "tracker")
    out[f"build {name}"] = time.perf_counter() - t
    t = time.perf_counter()
    warm_up(tracker)
    out[f"warm-up {name}"] = time.perf_counter() - t
print(json.dumps(out))
"""


def wall(cmd: list[str]) -> float:
    t = time.perf_counter()
    subprocess.run(cmd, check=True, cwd=ROOT, env=ENV, capture_output=True, timeout=600)
    return time.perf_counter() - t


def first_frame(tracker: str, out: Path) -> float:
    env = {**ENV, "BENCH_T0": repr(time.time())}
    proc = subprocess.run([sys.executable, "-c", FIRST_FRAME, f"tracker={tracker}", *SCENE,
                           f"hydra.run.dir={out}"], check=True, cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=600)
    return float(proc.stdout.strip().splitlines()[-1])


def _stamp(line: str) -> float:
    return datetime.strptime(line[1:24], "%Y-%m-%d %H:%M:%S,%f").timestamp()


def job_gaps(sweep_dir: Path, *extra: str) -> list[float]:
    """Seconds from each job's last log line to the next job's frame loop."""
    subprocess.run([sys.executable, "-m", "harness", "-m", "tracker=reta", "seed=0,1,2,3",
                    *SCENE, "hydra.launcher.n_jobs=1", f"hydra.sweep.dir={sweep_dir}", *extra],
                   check=True, cwd=ROOT, env=ENV, capture_output=True, timeout=1800)
    logs = [(sweep_dir / str(j) / "occbench.log").read_text().splitlines() for j in range(4)]
    gaps = []
    for before, after in itertools.pairwise(logs):
        loop = next(ln for ln in after if "sequence(s) x" in ln)
        gaps.append(_stamp(loop) - _stamp(before[-1]))
    return gaps


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=5, help="processes per figure (median)")
    parser.add_argument("--tracker", action="append", help="trackers (default reta and pbm)")
    parser.add_argument("--no-sweep", action="store_true", help="skip the sweep-job figure")
    args = parser.parse_args(argv)
    trackers = args.tracker or ["reta", "pbm"]
    occbench = [sys.executable, "-m", "harness"]
    print(f"load average {os.getloadavg()[0]:.2f} / {os.cpu_count()} cores; median of "
          f"{args.runs} runs", flush=True)
    wall([sys.executable, "-c", BUILD, *trackers])  # numba's cache filled, files in the page cache
    times: dict[str, list[float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.runs):
            times.setdefault("python -c pass", []).append(wall([sys.executable, "-c", "pass"]))
            times.setdefault("occbench --version", []).append(wall([*occbench, "--version"]))
            for key, value in json.loads(subprocess.run(
                    [sys.executable, "-c", BUILD, *trackers], check=True, cwd=ROOT, env=ENV,
                    capture_output=True, text=True, timeout=600).stdout).items():
                times.setdefault(key, []).append(value)
            for name in trackers:
                times.setdefault(f"first frame, one-job run, {name}", []).append(
                    first_frame(name, Path(tmp) / f"{name}-{i}"))
        if not args.no_sweep:
            times["sweep job start, warm (default)"] = job_gaps(Path(tmp) / "warm")
            times["sweep job start, cold (preload=false)"] = job_gaps(
                Path(tmp) / "cold", "hydra.launcher.preload=false")
    ref = statistics.median(times["python -c pass"])
    width = max(map(len, times))
    print(f"{'':<{width}}  median s  x python")
    for key, values in times.items():
        med = statistics.median(values)
        print(f"{key:<{width}}  {med:8.3f}  {med / ref:8.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
