"""benchmarks/bench_reacquisition.py's stack counts on hand-made tables."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
from mot_tables import table

_PATH = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_reacquisition.py"
_spec = importlib.util.spec_from_file_location("bench_reacquisition", _PATH)
bench = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = bench  # its dataclasses resolve their module
_spec.loader.exec_module(bench)


def test_one_detection_taken_in_turn_is_a_duplicate_and_a_hidden_person_is_not():
    # person 1 alone at x 100; persons 3 and 4 overlapping (IoU 0.67) at x 300 / 308
    gt = table([(f, g, x, 50, 40, 100) for f in range(1, 5)
                for g, x in ((1, 100), (3, 300), (4, 308))])
    rows, hidden = [], []
    for f in range(1, 5):
        # ids 1 and 2 both on person 1, the detection going to each in turn
        rows += [(f, 1, 100, 50, 40, 100), (f, 2, 101, 50, 40, 100)]
        hidden += [f % 2 == 0, f % 2 == 1]
        # ids 3 and 4 on persons 3 and 4, 4 hidden behind 3 throughout
        rows += [(f, 3, 300, 50, 40, 100), (f, 4, 308, 50, 40, 100)]
        hidden += [False, True]
    res = table(rows)  # rows already in (frame, id) order
    c = bench.stack_counts(gt, res, np.array(hidden))
    assert c["one_person"] == 1 and c["duplicates"] == 1
    assert c["two_people"] == 1 and c["two_in_turn"] == 0
    # one of ids 1 and 2 is a false positive every frame, all in the duplicate
    assert c["false_positives"] == 4 and c["fp_one_person"] == 4 and c["fp_duplicates"] == 4
    assert c["switches"] == 0


def test_short_stacks_do_not_count():
    gt = table([(f, 1, 100, 50, 40, 100) for f in range(1, 3)])
    res = table([(f, i, 100, 50, 40, 100) for f in range(1, 3) for i in (1, 2)])
    c = bench.stack_counts(gt, res, np.array([False, True, True, False]))
    assert c["one_person"] == c["two_people"] == 0 and c["fp_one_person"] == 0
    assert c["false_positives"] == 2
