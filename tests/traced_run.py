"""Which functions of ``trackers/`` a tracker calls on a short synthetic scene.

Run as a script, ``python tests/traced_run.py TRACKER [TRACKER ...]`` (a name of
``conf/tracker/``), with ``NUMBA_DISABLE_JIT=1`` so that the compiled kernels run as the
Python functions they are written as and every call is seen. Under a ``sys.setprofile``
hook it builds each tracker from its config as a run does and tracks the synthetic
``crossing`` scene (two people, the far one totally hidden, 30 frames, 320 x 240) through
``occbench.pipeline.experiment.run_tracker`` with the default run's detector; it prints one
JSON object {tracker: [[path, qualname], ...]}, paths relative to ``trackers/``. ``calls``
runs it in a subprocess.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def calls(*names: str) -> dict[str, set[tuple[str, str]]]:
    """{tracker name: {(path relative to trackers/, qualname)}} of every function called."""
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1",
           "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    out = subprocess.run([sys.executable, str(Path(__file__)), *names], env=env, cwd=ROOT,
                         capture_output=True, text=True, timeout=600, check=False)
    if out.returncode:
        raise RuntimeError(f"traced_run.py {' '.join(names)} failed:\n{out.stderr[-3000:]}")
    return {k: {tuple(c) for c in v} for k, v in json.loads(out.stdout.splitlines()[-1]).items()}


def _trace(name: str) -> list[tuple[str, str]]:
    from occbench.datasets.synthetic import load_suite
    from occbench.config.build import build_source, build_tracker, compose_config
    from occbench.pipeline.loop import run_tracker

    cfg = compose_config([f"tracker={name}"])  # the default run's detector and foreground
    source = build_source(cfg.detector)
    (sequence,) = load_suite(["crossing"], length=30, width=320, height=240)
    import occbench.trackers

    # where the trackers' code is loaded from: the checkout, or a strict editable install's
    # link tree (build/__editable__.*/occbench/trackers), whose paths the frames carry
    root = os.path.dirname(occbench.trackers.__file__) + os.sep
    seen: set[tuple[str, str]] = set()

    def hook(frame, event, arg):
        if event == "call" and frame.f_code.co_filename.startswith(root):
            seen.add((frame.f_code.co_filename[len(root):], frame.f_code.co_qualname))

    threading.setprofile(hook)
    sys.setprofile(hook)
    try:  # building the tracker from its config included
        run_tracker(build_tracker(name, cfg.tracker), sequence, source)
    finally:
        sys.setprofile(None)
        threading.setprofile(None)
    return sorted(seen)


if __name__ == "__main__":
    if os.environ.get("NUMBA_DISABLE_JIT") != "1":
        raise SystemExit("traced_run.py: set NUMBA_DISABLE_JIT=1 (compiled calls are not seen)")
    print(json.dumps({name: _trace(name) for name in sys.argv[1:]}))
