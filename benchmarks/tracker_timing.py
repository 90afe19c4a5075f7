"""Timing helpers shared by ``bench_reta.py`` and ``bench_pbm.py``: per-stage CPU time of a
tracker's steps, a reference workload timed in the same process, and a digest of the
reported rows (``--check``: the same tracks byte for byte before and after a speed-up).

The stages are the tracker's own steps (methods wrapped on one instance, or step functions
wrapped in the modules that call them), for one extra run (never on the runs whose frames/s
are quoted); a stage's time excludes the stages it calls, so the stages and "other" add up
to ``update``.
"""

from __future__ import annotations

import argparse
import hashlib
import importlib
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np


_ABSENT = object()


class StageClock:
    """Exclusive CPU time (``time.process_time``) of wrapped methods, per label."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}
        self._stack: list[list[float]] = []  # per open stage: [start, time of its children]
        self._wrapped: list[tuple[object, str, object]] = []  # (owner, attr, original)

    def wrap(self, owner: object, attr: str, label: str | None = None) -> None:
        """Time ``owner.attr`` (a method or callable attribute; a module's function is
        timed wherever that module calls it by name) under ``label`` until ``unwrap``."""
        fn = getattr(owner, attr)
        self._wrapped.append((owner, attr, vars(owner).get(attr, _ABSENT)))
        name = label or attr.lstrip("_")
        self.seconds.setdefault(name, 0.0)

        def timed(*args, **kwargs):
            self._stack.append([time.process_time(), 0.0])
            try:
                return fn(*args, **kwargs)
            finally:
                start, children = self._stack.pop()
                spent = time.process_time() - start
                self.seconds[name] += spent - children
                if self._stack:
                    self._stack[-1][1] += spent

        setattr(owner, attr, timed)

    def unwrap(self) -> None:
        """Put back every attribute ``wrap`` replaced (a wrapped module's functions are
        shared by every later run in the process)."""
        for owner, attr, original in reversed(self._wrapped):
            if original is _ABSENT:
                delattr(owner, attr)
            else:
                setattr(owner, attr, original)
        self._wrapped.clear()

    def table(self, total: float, frames: int) -> str:
        """One line per stage, ms per frame and share of ``total`` seconds, then 'other'."""
        rows = sorted(self.seconds.items(), key=lambda kv: -kv[1])
        rows.append(("other", total - sum(self.seconds.values())))
        return "\n".join(f"    {name:28s} {1e3 * s / frames:7.3f} ms/frame {100 * s / total:5.1f} %"
                         for name, s in rows)


def cpu_seconds(run: Callable[[], object]) -> float:
    """CPU seconds of one call of ``run``."""
    t0 = time.process_time()
    run()
    return time.process_time() - t0


def reference_seconds(repeats: int = 5) -> float:
    """Median CPU seconds of a fixed workload (numpy sorting, bincount, a Python loop): the
    yardstick a tracker's time is divided by, so runs on a loaded machine compare."""
    data = np.random.default_rng(0).random(200_000)

    def work() -> None:
        np.sort(data)
        np.bincount((data * 4096).astype(np.int64), minlength=4096)
        total = 0.0
        for v in data[:50_000].tolist():
            total += v * v

    return statistics.median(cpu_seconds(work) for _ in range(repeats))


def import_other(tree: Path, package: str, alias: str):
    """``package`` (e.g. ``occbench.trackers.three_hypothesis``) of another checkout ``tree``,
    imported as the top-level package ``alias`` beside this tree's: its files copied (once per
    content, under the temp dir, so numba's disk cache is kept between runs) with every
    ``package`` name in them renamed, and the files of its subfolders (data) as they are. What it imports from outside ``package`` is this tree's.
    Raises ``FileNotFoundError`` naming the folder when ``tree`` has no such package."""
    src = Path(tree) / "trackers" / package.rsplit(".", 1)[-1]
    files = sorted(src.glob("*.py"))
    if not files:
        raise FileNotFoundError(f"no {package} at {src}")
    texts = {f.name: f.read_text().replace(package, alias) for f in files}
    data = {str(f.relative_to(src)): f.read_bytes() for f in sorted(src.glob("*/**/*"))
            if f.is_file() and "__pycache__" not in f.parts}  # e.g. layered/data/*.yaml
    h = hashlib.sha256(json.dumps(texts, sort_keys=True).encode())
    for name, blob in data.items():
        h.update(name.encode() + b"\0" + blob)
    root = Path(tempfile.gettempdir()) / f"occbench_vs_{alias}_{h.hexdigest()[:16]}"
    if not (root / alias / "__init__.py").exists():
        (root / alias).mkdir(parents=True, exist_ok=True)
        for name, blob in data.items():
            (root / alias / name).parent.mkdir(parents=True, exist_ok=True)
            (root / alias / name).write_bytes(blob)
        for name in sorted(texts, key=lambda name: name == "__init__.py"):  # __init__ last
            (root / alias / name).write_text(texts[name])
    if alias in sys.modules:
        raise RuntimeError(f"{alias} is imported already")
    sys.path.insert(0, str(root))
    try:
        return importlib.import_module(alias)
    finally:
        sys.path.remove(str(root))


def instructions(argv: list[str], env: dict[str, str] | None = None) -> int:
    """Instructions the command ``argv`` executes under valgrind's callgrind (its
    ``summary:`` count, every instruction of the process from start to exit): a count that,
    unlike time, does not move with the machine's load. ``PYTHONHASHSEED`` is fixed to 0 so
    that a Python command runs the same way each time; ``env`` is added to the environment.
    Raises ``RuntimeError`` naming the command when valgrind is missing or the command fails
    (with the end of its output)."""
    valgrind = shutil.which("valgrind")
    if valgrind is None:
        raise RuntimeError("valgrind not found on PATH (needed to count instructions)")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "callgrind.out"
        done = subprocess.run([valgrind, "--tool=callgrind", f"--callgrind-out-file={out}", *argv],
                              env={**os.environ, **(env or {}), "PYTHONHASHSEED": "0"},
                              capture_output=True, text=True)
        if done.returncode != 0 or not out.exists():
            raise RuntimeError(f"{' '.join(argv)} failed under callgrind (exit "
                               f"{done.returncode}):\n{done.stderr[-2000:]}")
        for line in out.read_text().splitlines():
            if line.startswith("summary:"):
                return int(line.split()[1])
    raise RuntimeError(f"no summary line in callgrind's output of {' '.join(argv)}")


def paired_seconds(runs: dict[str, Callable[[], object]], rounds: int) -> dict[str, list[float]]:
    """CPU seconds of each of two ``runs`` (label -> call), ``rounds`` rounds taken in turn
    ABBA (round k runs them in order when k is even, reversed when odd): a slow spell of the
    machine falls on both alike."""
    labels = list(runs)
    out: dict[str, list[float]] = {label: [] for label in labels}
    for k in range(rounds):
        for label in (labels if k % 2 == 0 else labels[::-1]):
            out[label].append(cpu_seconds(runs[label]))
    return out


def rows_digest(frames: Iterable[list]) -> str:
    """sha256 of every reported Track row (frame, id, state, score, box float64 bytes)."""
    h = hashlib.sha256()
    for k, tracks in enumerate(frames):
        for t in tracks:
            h.update(f"{k} {t.id} {t.state.name} {float(t.score)!r} ".encode())
            h.update(np.asarray(t.box, dtype=np.float64).tobytes())
    return h.hexdigest()


def check_digests(path: Path | None, digests: dict[str, str]) -> bool:
    """Print the digests; with ``path``: write them when the file is absent, else compare
    with the file (False and the keys that differ when any does)."""
    for key, value in digests.items():
        print(f"  rows {key}: {value}")
    if path is None:
        return True
    if not path.exists():
        path.write_text(json.dumps(digests, indent=1, sort_keys=True) + "\n")
        print(f"  digests written to {path}")
        return True
    expected = json.loads(path.read_text())
    differ = [k for k in digests if expected.get(k) != digests[k]]
    missing = [k for k in digests if k not in expected]
    if differ:
        print(f"  DIFFERENT from {path}: {', '.join(differ)}"
              + (f" (not in the file: {', '.join(missing)})" if missing else ""))
        return False
    print(f"  identical to {path}")
    return True


def frame_size(text: str) -> tuple[int, int]:
    """``--size WxH`` (e.g. ``1920x1080``) as (width, height); argparse names a bad value."""
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, e.g. 1920x1080, got {text!r}") from None
    if w < 64 or h < 64:
        raise argparse.ArgumentTypeError(f"frame size {w}x{h} is below 64x64")
    return w, h
