"""The harness's warm-up before timing (harness/pipeline/warmup.py): it loads every kernel a PBM or
reta run uses, it leaves a tracker exactly as built, it runs once per tracker class and process, and a
tracker that needs frames is refused before a run on frameless data."""

from __future__ import annotations

import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from hydra.utils import instantiate
from omegaconf import OmegaConf

from occbench.config.meta import without_meta
from occbench.datasets.synthetic import load_scenario
from occbench.pipeline.loop import run_sequence
from occbench.pipeline.warmup import STEPS, WarmUp, warm_up
from occbench.sources.annotations import NoisyGroundTruth

ROOT = Path(__file__).resolve().parents[3]

# in a fresh process: warm a tracker up as the harness does, then count the numba
# signatures a crowd run adds, with and without a foreground mask
_FRESH = r"""
import importlib, pkgutil, sys
from hydra.utils import instantiate
from numba.core.registry import CPUDispatcher
from omegaconf import OmegaConf
import occbench.trackers
from occbench.datasets.synthetic import load_scenario
from occbench.sources.annotations import NoisyGroundTruth
from occbench.pipeline.loop import run_sequence
from occbench.pipeline.warmup import warm_up_once
from occbench.config.meta import without_meta

warm_up_once({"pbm": lambda: instantiate(without_meta(OmegaConf.load(sys.argv[1])))})
kernels = {}
for m in pkgutil.walk_packages(occbench.trackers.__path__, "occbench.trackers."):
    if m.name.startswith("occbench.trackers.outside"):
        continue
    for v in vars(importlib.import_module(m.name)).values():
        if isinstance(v, CPUDispatcher):
            kernels[f"{v.__module__}.{v.__name__}"] = v
before = {k: len(v.signatures) for k, v in kernels.items()}
for seq in (load_scenario("crowd", seed=0, length=60, people=8),
            load_scenario("crossing", seed=0, length=60)):  # often one match or none a frame
    for fg in ("exact", "none"):
        run_sequence({"pbm": instantiate(without_meta(OmegaConf.load(sys.argv[1])))}, seq,
                     NoisyGroundTruth(miss_rate=0.3, seed=0), foreground=fg)
print(sorted(k for k, v in kernels.items() if len(v.signatures) != before[k]))
print(sum(before.values()))
"""


@pytest.mark.parametrize(("tracker", "kernels"), [("pbm", 20), ("reta", 5)])
def test_a_warmed_up_process_has_loaded_every_kernel_a_run_uses(tracker, kernels):
    config = ROOT / "conf" / "tracker" / f"{tracker}.yaml"
    out = subprocess.run([sys.executable, "-c", _FRESH.replace('"pbm"', repr(tracker)), str(config)],
                         capture_output=True, text=True, cwd=ROOT, check=True).stdout.splitlines()
    assert out[-2] == "[]"  # no kernel compiled or loaded during the run
    assert int(out[-1]) >= kernels  # and the warm-up did load the kernels


def test_warm_up_leaves_the_tracker_as_built():
    cfg = without_meta(OmegaConf.load(ROOT / "conf" / "tracker" / "pbm.yaml"))
    seq = load_scenario("pair_walk", seed=1, length=60)
    plain, warmed = instantiate(cfg), instantiate(cfg)
    warm_up(warmed)
    res = run_sequence({"plain": plain, "warmed": warmed}, seq, NoisyGroundTruth(miss_rate=0.3, seed=1),
                       foreground="exact")
    a, b = res["plain"].table, res["warmed"].table
    assert len(a) > 100
    np.testing.assert_array_equal(a.ids, b.ids)
    np.testing.assert_array_equal(a.boxes, b.boxes)


class _Counting:
    """A box-only tracker that counts its updates (class-level: the warm-up builds its own)."""

    updates = 0

    def reset(self) -> None:
        pass

    def update(self, frame, detections, foreground=None):
        type(self).updates += 1
        return []


def update(self, frame, detections, foreground=None):
        if frame is None:
            raise ValueError("needs pixels")
        return super().update(frame, detections, foreground)


def test_warm_up_runs_once_per_tracker_class_and_announces_it():
    once, said = WarmUp(first=0.0), []
    _Counting.updates = 0
    assert once({"a": _Counting, "b": _Counting}, said.append) == ["a"]
    assert _Counting.updates > 0 and len(said) == 1 and "warming up a" in said[0]
    n = _Counting.updates
    assert once({"c": _Counting}, said.append) == []  # the class is warm: nothing run or said
    assert _Counting.updates == n and len(said) == 1



def test_a_quick_warm_up_says_nothing_and_a_long_one_keeps_saying_so():
    """issue 39 item 8: "the first run compiles" was logged on every warm run, and a warm-up
    compiling for 24 s showed a frozen bar and no line without a terminal."""
    said: list[str] = []
    assert WarmUp(first=600.0)({"a": _Counting}, said.append) == ["a"]
    assert said == []  # over before it was worth a word
    spoke = threading.Event()

    class Slow(_Counting):  # compiles until the warm-up has said twice that it goes on
        def update(self, frame, detections, foreground=None):
            spoke.wait(60)
            return []

    def announce(text: str) -> None:
        said.append(text)
        if len(said) >= 2:
            spoke.set()

    assert WarmUp(first=0.0, every=0.01)({"slow": Slow}, announce) == ["slow"]
    assert said[0].startswith("warming up slow") and said[1].startswith("still warming up")
    n = len(said)
    time.sleep(0.05)
    assert len(said) == n  # the heartbeat ended with the warm-up


def test_the_warm_up_bar_moves_every_frame():
    """issue 39 item 8: the bar advanced once a pass (4 a tracker), so a pass compiling for
    24 s froze it at 42 %; it now moves with every frame and ends full."""
    seen: list[tuple[int, int]] = []

    class Bar:
        def __init__(self, total, **_):
            self.total, self.n = total, 0

        def update(self, n=1):
            self.n += n
            seen.append((self.n, _Counting.updates))

        def close(self):
            pass

    class Other(_Counting):  # a second tracker class: warmed up too
        pass

    _Counting.updates = 0
    assert WarmUp()({"a": _Counting, "b": Other}, progress=Bar) == ["a", "b"]
    assert [n for n, _ in seen] == list(range(1, 2 * STEPS + 1))  # one a frame, to the total
    assert seen[0][1] == 1  # the first step is shown as soon as the first frame is through


def test_the_warm_up_says_it_compiles_only_when_numba_compiles():
    """issue 39 item 8: a warm run (kernels loaded from the cache) slower than the
    announcement's delay, under load, said "the first run after an install compiles"."""
    import numba

    said: list[str] = []

    class Loads(_Counting):  # slow, compiles nothing
        def update(self, frame, detections, foreground=None):
            time.sleep(0.01)
            return []

    WarmUp(first=0.0, every=600.0)({"loads": Loads}, said.append)
    assert said and "compil" not in said[0]

    @numba.njit(cache=False)
    def fresh(x):  # compiled on its first call: numba's compile event
        return x + 1

    class Compiles(_Counting):
        def update(self, frame, detections, foreground=None):
            fresh(1)
            time.sleep(0.01)
            return []

    said.clear()
    WarmUp(first=0.05, every=600.0)({"compiles": Compiles}, said.append)
    assert said and "compiling their kernels" in said[0]

    @numba.njit(cache=False)
    def later(x):
        return x + 2

    announced, compiled = threading.Event(), threading.Event()

    def heard(text: str) -> None:
        said.append(text)
        announced.set()
        if "compil" in text:
            compiled.set()

    class CompilesLater(_Counting):  # starts compiling after the first line was said
        tried = False

        def update(self, frame, detections, foreground=None):
            if not CompilesLater.tried and announced.wait(60):
                CompilesLater.tried = True
                later(1)
                compiled.wait(10)  # until a line says it compiles (or gives up)
            return []

    said.clear()
    WarmUp(first=0.0, every=0.01)({"later": CompilesLater}, heard)
    assert "compil" not in said[0]  # the first line: nothing compiled yet
    assert any(t.startswith("still warming up later before timing: compiling their kernels")
               for t in said[1:]), said  # said once known, not left at 'still warming up'


def test_a_tracker_failing_in_the_warm_up_is_left_to_the_run():
    class Failing(_Counting):
        def update(self, frame, detections, foreground=None):
            raise RuntimeError("not on this scene")

    assert WarmUp()({"f": Failing}) == ["f"]  # no exception: the run reports real failures
