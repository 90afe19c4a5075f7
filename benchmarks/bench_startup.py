"""Start-up of occbench: how long before a run's (or a sweep job's) first frame.

Each figure is the median of ``--runs`` fresh processes: wall time with its ratio to
``python -c pass`` (the interpreter's own start, timed in the same loop), and the process's
CPU time, which the other work on a shared machine disturbs less. Targets (issue 23):
``occbench --version`` and a one-job run's start-up before its first frame at most 1 s on a
warm machine (numba's cache filled by an earlier run).

- ``python -c pass``: the reference.
- ``occbench --version``: the console script, wall time.
- import: ``import occbench.commands.run, occbench.pipeline.experiment`` in a fresh process.
- build: in one fresh process, after the imports above: compose the config of ``tracker=T``
  and build the tracker (its own imports included), then its warm-up (numba kernels loaded
  from the cache) - for reta and pbm.
- first frame: ``occbench tracker=T progress=false`` from the start of the process to the
  frame loop (``run_sequence`` entered: config, checks, trackers built and warmed up; the
  data's own warm-up, e.g. a detector's background, is what the loop does first and is
  left out), on the synthetic ``crossing`` scene, split into (wall, the same process):
  interpreter + imports (to the Hydra app's start: ``occbench.commands.cli.main`` called),
  Hydra compose (both of Hydra's compositions: the mode's, ``Hydra.get_mode``, then the
  run's), build (the run's plan: checks, config.yaml, trackers built with their imports,
  detection source, sequences loaded) and warm-up (``plan.prepare_trackers``); what is left
  (the run's own trackers built, the ground truth written) is the total's remainder.
- first frame, default suite: the same for ``occbench tracker=reta`` on the default dataset
  (the eight synthetic scenes).
- first frame, served: the one-job run handed by the console script's fast path
  (``occbench.__main__.main``, ``OCCBENCH_SERVER=on``) to a warm server (``occbench.server``,
  started once by the bench in a temporary folder with the real preload; its children apply
  the same stage timers), from the client's start to the served child's frame loop.
- sweep job: a 4-job sweep (``hydra.launcher.n_jobs=1``, one job at a time) on the default
  launcher, warm (forked from the preloaded fork server) and cold (``preload=false``):
  the median time from a job's last log line to the next job's frame loop (its log line
  "N sequence(s) x ...").

``--vs CHECKOUT`` times another checkout's code the same way, round by round in turn with this
one (e.g. ``git worktree add /tmp/before <commit>`` for a before/after on the same machine at
the same time), and prints its figures beside these with the CPU ratio.

Usage: ``python benchmarks/bench_startup.py [--runs 5] [--tracker reta] [--no-sweep]
[--no-served] [--vs CHECKOUT]``.
"""

from __future__ import annotations

import argparse
import atexit
import functools
import itertools
import json
import math
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib
from collections.abc import Callable
from datetime import datetime
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ["dataset.scenarios=[crossing]", "dataset.length=20", "progress=false"]

# a one-job run stopped where its frame loop starts: prints each stage's [wall, CPU] seconds
FIRST_FRAME = """
import json, os, sys, time
T0 = float(os.environ["BENCH_T0"])
import occbench.pipeline.experiment as experiment
import occbench.pipeline.plan as plan
from hydra._internal.hydra import Hydra
from occbench.commands.cli import main
def now():
    return time.time() - T0, time.process_time()
spent, ended = {"interpreter + imports": now(), "Hydra compose": (0.0, 0.0)}, {}
def timed(fn, key):
    def wrapper(*args, **kwargs):
        t = now()
        try:
            return fn(*args, **kwargs)
        finally:
            ended[key] = now()
            spent[key] = tuple(s + e - b for s, b, e in zip(spent.get(key, (0, 0)), t, ended[key]))
    return wrapper
Hydra.compose_config = timed(Hydra.compose_config, "Hydra compose")
plan.prepare_trackers = timed(plan.prepare_trackers, "warm-up")
def stop(*args, **kwargs):
    total = now()
    out = {k: spent[k] for k in ("interpreter + imports", "Hydra compose")}
    out["build"] = [w - s - c for w, s, c in zip(ended["warm-up"], spent["warm-up"],
                                                  ended["Hydra compose"])]
    out["warm-up"] = spent["warm-up"]
    out["rest"] = [t - sum(v[i] for v in out.values()) for i, t in enumerate(total)]
    out["total"] = total
    print(json.dumps(out), flush=True)
    os._exit(0)
experiment.run_sequence = stop
main(sys.argv[1:])
"""

BUILD = """
import json, sys, time
def now():
    return time.perf_counter(), time.process_time()
def since(t):
    return [b - a for a, b in zip(t, now())]
t = now()
import occbench.commands.run, occbench.pipeline.experiment
out = {"import": since(t)}
from occbench.config.build import build_tracker, compose_config
from occbench.pipeline.warmup import warm_up
for name in sys.argv[1:]:
    t = now()
    tracker = build_tracker(name, compose_config([f"tracker={name}"]).tracker, "tracker")
    out[f"build {name}"] = since(t)
    t = now()
    warm_up(tracker)
    out[f"warm-up {name}"] = since(t)
print(json.dumps(out))
"""


# the bench's own server: the real preload; each child times its stages as FIRST_FRAME does
SERVED_SERVER = """
import sys
from occbench.commands.server import preload
from occbench.server.serve import Server
def run(args):
    sys.argv = ["occbench", *args]
    exec(compile(FIRST_FRAME, "first_frame", "exec"), {"__name__": "first_frame"})
    return 0
FIRST_FRAME = sys.argv[2]
sys.exit(Server(sys.argv[1], run, preload).serve())
"""
# the console script's fast path, in a ``python -c`` process as the server is (same sys.path)
CLIENT = "import sys; from occbench.__main__ import main; sys.argv[0] = 'occbench'; main()"


def _child_cpu() -> float:
    use = resource.getrusage(resource.RUSAGE_CHILDREN)
    return use.ru_utime + use.ru_stime


# ``sitecustomize`` of the processes ``tree_env`` starts: the import packages of the checkout
# named in $BENCH_PACKAGES are imported from it, before the editable install's own finder
# (PYTHONPATH=CHECKOUT alone does not do it: ``occbench`` is the folder harness/, so
# PYTHONPATH found nothing and the install mapped every import to the installed checkout)
SHIM = """
import os, sys
from _frozen_importlib_external import spec_from_file_location  # loaded already: no import cost
_PACKAGES = dict(line.split("=", 1) for line in os.environ.get("BENCH_PACKAGES", "").splitlines())
class _Checkout:
    @classmethod
    def find_spec(cls, fullname, path=None, target=None):
        folder = _PACKAGES.get(fullname)
        if folder is None:
            return None
        return spec_from_file_location(fullname, os.path.join(folder, "__init__.py"),
                                       submodule_search_locations=[folder])
sys.meta_path.insert(0, _Checkout)
"""


@functools.cache
def shim_dir() -> Path:
    """A folder holding ``SHIM`` as ``sitecustomize.py``, removed when this process ends."""
    folder = Path(tempfile.mkdtemp(prefix="bench_startup_shim."))
    (folder / "sitecustomize.py").write_text(SHIM)
    atexit.register(shutil.rmtree, folder, True)
    return folder


# where each import package of a checkout is, and a module whose file says it was imported
IMPORTED = ("import json, occbench, occbench.trackers, hydra_plugins.occbench_launcher as h; "
            "print(json.dumps([m.__file__ for m in (occbench, occbench.trackers, h)]))")


def packages(root: Path) -> dict[str, str]:
    """Import package -> its folder in ``root``, from ``root``'s pyproject.toml (package-dir;
    a namespace folder, hydra_plugins/, gives each of its packages)."""
    dirs = tomllib.loads((root / "pyproject.toml").read_text())["tool"]["setuptools"]["package-dir"]
    out = {}
    for name, folder in dirs.items():
        path = root / folder
        if (path / "__init__.py").exists():
            out[name] = str(path)
        else:
            out |= {f"{name}.{p.parent.name}": str(p.parent) for p in path.glob("*/__init__.py")}
    return out


def tree_env(root: Path) -> dict[str, str]:
    """The environment of a process running the code of the checkout ``root`` (``SHIM``),
    cold (no warm server: ``ServedRuns`` sets its own)."""
    path = [str(shim_dir()), *filter(None, [os.environ.get("PYTHONPATH")])]
    mapped = "\n".join(f"{name}={folder}" for name, folder in packages(root).items())
    return {**os.environ, "OMP_NUM_THREADS": "1", "OCCBENCH_SERVER": "off",
            "BENCH_PACKAGES": mapped, "PYTHONPATH": os.pathsep.join(path)}


def imported_from(root: Path) -> list[Path]:
    """The files of ``occbench``, ``occbench.trackers`` and the launcher plugin as a process of
    ``tree_env(root)`` imports them; raises ``SystemExit`` naming any outside ``root``."""
    files = [Path(f) for f in json.loads(run([sys.executable, "-c", IMPORTED], root)[1])]
    outside = [f for f in files if not f.resolve().is_relative_to(root.resolve())]
    if outside:
        raise SystemExit(f"occbench: the processes timed for {root} import "
                         f"{', '.join(map(str, outside))}: not that checkout's code")
    return files


def run(cmd: list[str], root: Path = ROOT,
        env: dict[str, str] | None = None) -> tuple[list[float], str]:
    """[wall, CPU] seconds of the command (a fresh process in ``root``) and its stdout."""
    t, c = time.perf_counter(), _child_cpu()
    proc = subprocess.run(cmd, check=True, cwd=root, env=env or tree_env(root),
                          capture_output=True, text=True, timeout=600)
    return [time.perf_counter() - t, _child_cpu() - c], proc.stdout


def first_frame(tracker: str, out: Path, scene: list[str] = SCENE,
                root: Path = ROOT) -> dict[str, list[float]]:
    """[wall, CPU] seconds from the process's start to the frame loop of
    ``occbench tracker=T *scene``, by stage (``FIRST_FRAME``), ``total`` among them."""
    env = {**tree_env(root), "BENCH_T0": repr(time.time())}
    _, stdout = run([sys.executable, "-c", FIRST_FRAME, f"tracker={tracker}", *scene,
                     f"hydra.run.dir={out}"], root, env)
    return json.loads(stdout.strip().splitlines()[-1])


class ServedRuns:
    """A warm server of the code of ``root`` in ``folder`` (``SERVED_SERVER``), for
    ``first_frame``'s served figure; ``close()`` stops it."""

    def __init__(self, root: Path, folder: Path) -> None:
        self.root = root
        self.env = {**tree_env(root), "XDG_RUNTIME_DIR": str(folder), "OCCBENCH_SERVER": "on"}
        code = ("from occbench.server.client import identity, socket_path; "
                "print(socket_path(identity()))")
        self.path = Path(run([sys.executable, "-c", code], root, self.env)[1].strip())
        self.proc = subprocess.Popen([sys.executable, "-c", SERVED_SERVER, str(self.path),
                                      FIRST_FRAME],
                                     cwd=root, env=self.env, stdout=subprocess.DEVNULL,
                                     stderr=subprocess.PIPE, text=True)
        end = time.monotonic() + 600
        while not self.path.exists():
            if self.proc.poll() is not None or time.monotonic() > end:
                raise RuntimeError(f"the bench's server did not start: {self.proc.stderr.read()}")
            time.sleep(0.2)

    def first_frame(self, tracker: str, out: Path) -> dict[str, list[float]]:
        """As ``first_frame``, served: wall from the client's start; CPU of the client and
        of the served child (its own process_time, from its fork)."""
        env = {**self.env, "BENCH_T0": repr(time.time())}
        cmd = [sys.executable, "-c", CLIENT, f"tracker={tracker}", *SCENE,
               f"hydra.run.dir={out}"]
        wall, stdout = run(cmd, self.root, env)
        stages = json.loads(stdout.strip().splitlines()[-1])
        stages["total"] = [stages["total"][0], stages["total"][1] + wall[1]]
        return stages

    def close(self) -> None:
        self.proc.terminate()
        self.proc.wait(timeout=60)


def _stamp(line: str) -> float:
    return datetime.strptime(line[1:24], "%Y-%m-%d %H:%M:%S,%f").timestamp()


def job_gaps(sweep_dir: Path, *extra: str) -> list[float]:
    """Seconds from each job's last log line to the next job's frame loop."""
    subprocess.run([sys.executable, "-m", "occbench", "-m", "tracker=reta", "seed=0,1,2,3",
                    *SCENE, "hydra.launcher.n_jobs=1", f"hydra.sweep.dir={sweep_dir}", *extra],
                   check=True, cwd=ROOT, env=tree_env(ROOT), capture_output=True, timeout=1800)
    logs = [(sweep_dir / str(j) / "occbench.log").read_text().splitlines() for j in range(4)]
    gaps = []
    for before, after in itertools.pairwise(logs):
        loop = next(ln for ln in after if "sequence(s) x" in ln)
        gaps.append(_stamp(loop) - _stamp(before[-1]))
    return gaps


def one_round(root: Path, trackers: list[str], tmp: Path,
              add: Callable[[str, list[float]], None], served: ServedRuns | None = None) -> None:
    """Every per-process figure once, for the code of ``root`` (``served``: its server)."""
    add("python -c pass", run([sys.executable, "-c", "pass"], root)[0])
    add("occbench --version", run([sys.executable, "-m", "occbench", "--version"], root)[0])
    for key, value in json.loads(run([sys.executable, "-c", BUILD, *trackers], root)[1]).items():
        add(key, value)
    for name in trackers:
        stages = first_frame(name, tmp / name, root=root)
        add(f"first frame, one-job run, {name}", stages.pop("total"))
        for stage, value in stages.items():
            add(f"  {name}: {stage}", value)
    add(f"first frame, default suite, {trackers[0]}",
        first_frame(trackers[0], tmp / "suite", ["progress=false"], root)["total"])
    for name in trackers if served is not None else ():
        stages = served.first_frame(name, tmp / f"served-{name}")
        add(f"first frame, served, {name}", stages.pop("total"))
        for stage, value in stages.items():
            add(f"  served {name}: {stage}", value)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=5, help="processes per figure (median)")
    parser.add_argument("--tracker", action="append", help="trackers (default reta and pbm)")
    parser.add_argument("--no-sweep", action="store_true", help="skip the sweep-job figure")
    parser.add_argument("--no-served", action="store_true",
                        help="skip the served first frame (a warm server of this checkout)")
    parser.add_argument("--vs", type=Path, metavar="CHECKOUT",
                        help="also time another checkout's code (e.g. a worktree of main before "
                             "a change), round by round in turn with this one; CPU ratios")
    args = parser.parse_args(argv)
    trackers = args.tracker or ["reta", "pbm"]
    roots = [ROOT, *([args.vs.resolve()] if args.vs else [])]
    print(f"load average {os.getloadavg()[0]:.2f} / {os.cpu_count()} cores; median of "
          f"{args.runs} runs; {' vs '.join(map(str, roots))}", flush=True)
    for root in roots:  # which code each is; numba's cache filled, files in the page cache
        print(f"{root} imports " + ", ".join(map(str, imported_from(root))), flush=True)
        run([sys.executable, "-c", BUILD, *trackers], root)
    times: list[dict[str, list[list[float]]]] = [{} for _ in roots]
    with tempfile.TemporaryDirectory(prefix="obb", dir="/tmp") as tmp:
        served = None if args.no_served else ServedRuns(ROOT, Path(tmp) / "server")
        try:
            for i in range(args.runs):
                for r, root in enumerate(roots):
                    one_round(root, trackers, Path(tmp) / f"{r}-{i}",
                              lambda key, value, r=r: times[r].setdefault(key, []).append(value),
                              served if r == 0 else None)
        finally:
            if served is not None:
                served.close()
        if not args.no_sweep:
            for key, folder, extra in (
                    ("sweep job start, warm (default)", "warm", ()),
                    ("sweep job start, cold (preload=false)", "cold",
                     ("hydra.launcher.preload=false",))):
                times[0][key] = [[gap, math.nan] for gap in job_gaps(Path(tmp) / folder, *extra)]
    _print(times)
    return 0


def _print(times: list[dict[str, list[list[float]]]]) -> None:
    ref = statistics.median(v[0] for v in times[0]["python -c pass"])
    width = max(map(len, times[0]))
    other = " | vs: wall s   CPU s  CPU vs/this" if len(times) > 1 else ""
    print(f"{'':<{width}}  wall s  x python   CPU s  (medians){other}")
    for key, values in times[0].items():
        wall, cpu = (statistics.median(v[i] for v in values) for i in (0, 1))
        line = f"{key:<{width}}  {wall:6.3f}  {wall / ref:8.1f}  {cpu:6.3f}"
        if len(times) > 1 and key in times[1]:
            w2, c2 = (statistics.median(v[i] for v in times[1][key]) for i in (0, 1))
            line += f"           |     {w2:6.3f}  {c2:6.3f}  {c2 / cpu:8.2f}"
        print(line)


if __name__ == "__main__":
    raise SystemExit(main())
