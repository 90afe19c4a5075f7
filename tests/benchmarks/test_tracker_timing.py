"""benchmarks/tracker_timing.py: the rows digest and its check, the stage clock's wrapping, the
instruction count under callgrind."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from benchmark_scripts import load
from occbench.trackers.records import Track, TrackState

timing = load("tracker_timing")


def _frames(x: float) -> list[list[Track]]:
    return [[Track(1, np.array([x, 2.0, 3.0, 4.0]), TrackState.CONFIRMED, 1.0, {})], []]


def test_digest_sees_one_ulp_and_the_check_writes_then_compares(tmp_path):
    a = timing.rows_digest(_frames(1.0))
    assert a == timing.rows_digest(_frames(1.0))
    assert a != timing.rows_digest(_frames(np.nextafter(1.0, 2.0)))
    path = tmp_path / "digests.json"
    assert timing.check_digests(path, {"s": a}) and path.exists()  # written
    assert timing.check_digests(path, {"s": a})
    assert not timing.check_digests(path, {"s": timing.rows_digest(_frames(2.0))})
    assert not timing.check_digests(path, {"other scene": a})


class _Steps:
    def outer(self, x):
        return self.inner(x) + 1

    def inner(self, x):
        return 2 * x


def test_stage_clock_keeps_results_and_counts_every_stage():
    clock, steps = timing.StageClock(), _Steps()
    clock.wrap(steps, "outer")
    clock.wrap(steps, "inner", "the inner step")
    assert steps.outer(3) == 7
    assert set(clock.seconds) == {"outer", "the inner step"}
    assert all(s >= 0 for s in clock.seconds.values())
    lines = clock.table(total=1.0, frames=1).splitlines()
    assert [line.split()[0] for line in lines][-1] == "other" and len(lines) == 3


def test_frame_size_reads_width_by_height_and_names_a_bad_value():
    import argparse

    import pytest
    from tracker_timing import frame_size

    assert frame_size("1920x1080") == (1920, 1080)
    assert frame_size("640X480") == (640, 480)
    for bad in ("1920", "axb", "32x32"):
        with pytest.raises(argparse.ArgumentTypeError, match="1920x1080|below 64x64"):
            frame_size(bad)


def _loop(n: int) -> list[str]:
    return ["/bin/sh", "-c", f"i=0; while [ $i -lt {n} ]; do i=$((i+1)); done"]


@pytest.mark.skipif(shutil.which("valgrind") is None, reason="valgrind not installed")
def test_instructions_count_the_command_and_grow_with_its_work():
    short, again, longer = (timing.instructions(_loop(n)) for n in (200, 200, 2000))
    assert 0 < short < longer
    assert abs(again - short) < 0.001 * short  # the same command: the same count
    with pytest.raises(RuntimeError, match="false"):
        timing.instructions(["/bin/false"])
