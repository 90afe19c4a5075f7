"""``occbench bench`` (harness/commands/bench.py): every stage timed."""

from __future__ import annotations

from report_scenes import GtSource, Walk


def test_bench_times_every_stage():
    from occbench.commands.bench import bench_sequence
    from occbench.trackers.baseline import BaselineTracker

    timings = bench_sequence(Walk(), GtSource, lambda: {"baseline": BaselineTracker()},
                             frames=6, repeats=2)
    rows = [t.row() for t in timings]
    assert [r["stage"] for r in rows] == ["decode", "front end", "tracker baseline"]
    assert all(r["frames"] == 6 and r["runs"] == 2 and r["fps_median"] > 0 for r in rows)
