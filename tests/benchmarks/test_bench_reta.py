"""benchmarks/bench_reta.py --vs: another checkout's three_hypothesis imported beside this
tree's (``tracker_timing.import_other``) and timed on the same scene in turn; --instructions:
instructions a frame as the difference of two counted runs."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest
from benchmark_scripts import load

ROOT = Path(__file__).resolve().parents[2]
bench = load("bench_reta")


def test_vs_times_the_other_checkouts_code_on_the_same_scene(tmp_path):
    package = tmp_path / "trackers" / "three_hypothesis"
    shutil.copytree(ROOT / "trackers" / "three_hypothesis", package,
                    ignore=shutil.ignore_patterns("__pycache__"))
    with open(package / "__init__.py", "a") as f:
        f.write("\nMARK = 'the other checkout'\n")
    other = bench.import_other(tmp_path, bench.three_hypothesis.__name__, "reta_vs_test")
    assert other.MARK == "the other checkout"  # its files, not this tree's
    assert other.RetaTracker is not bench.RetaTracker
    assert other.RetaTracker.update.__module__ == "reta_vs_test.tracker"
    table = bench.versus(other, people_counts=(3,), frames=4, rounds=2)
    row = table.iloc[0]
    assert row.same_rows  # the same code: the same rows
    assert row.this_fps > 0 and row.other_fps > 0
    assert row.ratio_min <= row.ratio <= row.ratio_max


def test_vs_names_a_checkout_without_the_package(tmp_path):
    with pytest.raises(FileNotFoundError, match="three_hypothesis"):
        bench.import_other(tmp_path, bench.three_hypothesis.__name__, "reta_vs_missing")


def test_instructions_a_frame_are_the_difference_of_two_runs_over_their_frames(monkeypatch):
    counted = []

    def fake(argv, env=None):  # each command run for real, outside valgrind
        subprocess.run(argv, check=True, env=env)
        upto = int(argv[argv.index("--instructions-upto") + 1])
        counted.append(upto)
        return 1_000_000 + 7_000 * upto  # start-up, then 7,000 a frame

    monkeypatch.setattr(bench, "instructions", fake)
    table = bench.instructions_per_frame(people_counts=(3,), frames=4)
    assert sorted(counted) == [2, 4]  # to the half and to the end (at once)
    assert table.iloc[0].this_per_frame == 7_000
    with pytest.raises(ValueError, match="2 frames"):
        bench.instructions_per_frame(people_counts=(3,), frames=1)


def test_instructions_refuse_a_checkout_whose_tracker_did_not_run(tmp_path, monkeypatch):
    monkeypatch.setattr(bench, "instructions", lambda argv, env=None: pytest.fail("counted"))
    with pytest.raises(RuntimeError, match="occbench linked to its harness"):  # no occbench there
        bench.instructions_per_frame(people_counts=(3,), frames=2, other=tmp_path)
