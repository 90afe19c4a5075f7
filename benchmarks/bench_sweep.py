"""Sweep benchmark: a 6-job tracker sweep against one job, each from an empty front-end cache.

Runs, as a user would from the shell (``python -m occbench``, the ``occbench`` command):

* one job: ``occbench tracker=reta dataset=caviar detector=silhouette``;
* a multirun of the same over ``tracker.association.mu_g=60,90,120,150,180,240`` (the
  default launcher, ``conf/hydra/launcher/parallel.yaml``);

each with its own empty ``OCCBENCH_CACHE`` folder (a temporary one), so the sweep's jobs
compute the front end once between them and the single job computes it once too. It prints
the wall times (median of ``--repeats`` rounds, single job and sweep alternating), their
ratio (the target of issue 23: at most 2), the machine's load, and checks that the
mu_g=120 job's ``metrics.csv`` equals the single job's byte for byte (the exit status is 1
when it does not).

Usage: ``python benchmarks/bench_sweep.py [--repeats N] [--checkout DIR] [--keep DIR]``;
``--checkout`` runs another source tree (its ``harness``, ``trackers``, ``hydra_plugins``
first on PYTHONPATH), e.g. to measure main before a change.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MU_G = (60, 90, 120, 150, 180, 240)
BASE = ("tracker=reta", "dataset=caviar", "detector=silhouette", "progress=false")
CHECKED = 120  # the sweep job whose metrics.csv must equal the single job's


def load() -> str:
    """The 1, 5 and 15 minute load averages."""
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def run(args: list[str], cache: Path, checkout: Path) -> float:
    """Wall seconds of ``python -m occbench ARGS`` with ``OCCBENCH_CACHE=cache``, cold (a
    warm server, ``occbench.server``, would start the job from its preloaded process)."""
    env = dict(os.environ, OCCBENCH_CACHE=str(cache), OCCBENCH_SERVER="off",
               PYTHONPATH=os.pathsep.join([str(checkout), os.environ.get("PYTHONPATH", "")]))
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "occbench", *args], env=env, cwd=checkout, check=False,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    seconds = time.perf_counter() - t0
    if done.returncode != 0:
        raise SystemExit(f"bench_sweep: `occbench {' '.join(args)}` failed "
                         f"(exit {done.returncode}):\n{done.stdout[-3000:]}")
    return seconds


def job_of(sweep: Path, value: int) -> Path:
    """The job folder of ``sweep`` whose overrides set mu_g to ``value``."""
    wanted = f"tracker.association.mu_g={value}"
    for overrides in sorted(sweep.glob("*/.hydra/overrides.yaml")):
        if wanted in overrides.read_text():
            return overrides.parent.parent
    raise SystemExit(f"bench_sweep: no job of {sweep} has {wanted}")


def one_round(work: Path, checkout: Path) -> tuple[float, float, bool]:
    """(single job seconds, sweep seconds, metrics.csv equal) of one round in ``work``."""
    single_dir, sweep_dir = work / "single", work / "sweep"
    single = run([*BASE, f"hydra.run.dir={single_dir}"], work / "cache_single", checkout)
    values = ",".join(map(str, MU_G))
    sweep = run(["-m", *BASE, f"tracker.association.mu_g={values}",
                 f"hydra.sweep.dir={sweep_dir}"], work / "cache_sweep", checkout)
    a = (single_dir / "metrics.csv").read_bytes()
    b = (job_of(sweep_dir, CHECKED) / "metrics.csv").read_bytes()
    return single, sweep, a == b


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=1, help="rounds (median reported)")
    parser.add_argument("--checkout", type=Path, default=ROOT,
                        help="source tree to run (default: this one)")
    parser.add_argument("--keep", type=Path, default=None,
                        help="keep the run folders and caches here (default: a temp folder)")
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error(f"--repeats must be >= 1, got {args.repeats}")
    checkout = args.checkout.resolve()
    print(f"checkout {checkout}; load before: {load()}", flush=True)
    singles, sweeps, equal = [], [], True
    with tempfile.TemporaryDirectory(prefix="bench_sweep_") as tmp:
        for r in range(args.repeats):
            work = (args.keep or Path(tmp)) / f"round{r}"
            work.mkdir(parents=True, exist_ok=False)
            single, sweep, same = one_round(work, checkout)
            singles.append(single)
            sweeps.append(sweep)
            equal &= same
            print(f"round {r + 1}: one job {single:.1f} s, {len(MU_G)}-job sweep {sweep:.1f} s, "
                  f"ratio {sweep / single:.2f}; mu_g={CHECKED} metrics.csv "
                  f"{'equal' if same else 'DIFFERS'}", flush=True)
    s, w = statistics.median(singles), statistics.median(sweeps)
    print(f"median of {args.repeats}: one job {s:.1f} s, sweep {w:.1f} s, ratio {w / s:.2f} "
          f"(target <= 2); load after: {load()}")
    print(f"mu_g={CHECKED} job's metrics.csv {'equals' if equal else 'DIFFERS from'} "
          "the single job's")
    return 0 if equal else 1


if __name__ == "__main__":
    sys.exit(main())
