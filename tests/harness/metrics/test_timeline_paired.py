"""Per-frame counts (occbench.metrics.timeline) sum to the sequence's scores, and the paired
bootstrap (occbench.metrics.paired) says what differs and what does not."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.io.mot import MotTable
from occbench.metrics import combine, score_sequence
from occbench.metrics.paired import Bootstrap, all_pairs
from occbench.metrics.timeline import frame_counts, scores, sequence_totals


def walkers(length: int, people: int, rng: np.random.Generator) -> MotTable:
    """Ground truth: ``people`` boxes walking right, one row each per frame (0-based xywh)."""
    rows = []
    for k in range(1, length + 1):
        for i in range(people):
            rows.append((k, i + 1, 10.0 + 3 * k + 5 * rng.normal(), 60.0 * i, 40.0, 50.0))
    return table(rows)


def table(rows) -> MotTable:
    a = np.asarray(rows, dtype=np.float64)
    n = len(a)
    return MotTable(a[:, 0].astype(np.int64), a[:, 1].astype(np.int64), a[:, 2:6].copy(),
                    np.ones(n), np.full(n, -1, np.int64), np.full(n, np.nan))


def tracker(gt: MotTable, rng: np.random.Generator, miss: float = 0.1, jitter: float = 4.0,
            switch_every: int = 0) -> MotTable:
    """gt with misses, jitter, a few false positives; ``switch_every`` > 0 gives each person
    a new id every that many frames (added identity switches)."""
    keep = rng.random(len(gt)) >= miss
    boxes = gt.boxes[keep] + rng.normal(0, jitter, (int(keep.sum()), 4)) * [1, 1, 0, 0]
    ids = gt.ids[keep].copy()
    frames = gt.frames[keep]
    if switch_every:
        ids = ids + 100 * (frames // switch_every)
    fp = rng.random(len(np.unique(frames))) < 0.2
    extra = [(f, 999, 300.0, 300.0, 30.0, 30.0) for f in np.unique(frames)[fp]]
    rows = [*zip(frames, ids, *boxes.T), *extra]
    rows.sort(key=lambda r: (r[0], r[1]))
    return table(rows)


def test_frame_counts_sum_to_the_sequence_scores() -> None:
    rng = np.random.default_rng(1000)
    seqs = {f"s{i}": walkers(60 + 10 * i, 3, rng) for i in range(3)}
    res = {s: tracker(g, rng, switch_every=25 if s == "s1" else 0) for s, g in seqs.items()}
    per = {s: frame_counts(seqs[s], res[s]) for s in seqs}
    for s, g in seqs.items():
        row = score_sequence(g, res[s]).row()
        got = scores(per[s].total())
        for m in ("MOTA", "IDF1", "HOTA"):
            assert got[m] == pytest.approx(row[m], abs=1e-12), (s, m)
        assert per[s].switches.sum() == row["IDs"] and per[s].false_positives.sum() == row["FP"]
    combined = combine({s: score_sequence(seqs[s], res[s]) for s in seqs}).row()
    got = scores(sequence_totals(per))
    for m in ("MOTA", "IDF1", "HOTA"):
        assert got[m] == pytest.approx(combined[m], abs=1e-12), m


def test_identical_trackers_give_an_interval_around_zero() -> None:
    rng = np.random.default_rng(1001)
    gt = {f"s{i}": walkers(80, 3, rng) for i in range(2)}
    counts = {s: frame_counts(g, tracker(g, rng)) for s, g in gt.items()}
    diffs = all_pairs({"a": counts, "b": dict(counts)})
    assert [d.metric for d in diffs] == ["IDF1", "HOTA", "MOTA"]
    for d in diffs:
        assert d.difference == 0 and d.low == 0 and d.high == 0
        assert not d.distinguishable


def test_added_id_switches_are_worse_with_an_interval_excluding_zero() -> None:
    rng = np.random.default_rng(1002)
    gt = {f"s{i}": walkers(120, 3, rng) for i in range(2)}
    good, bad = {}, {}
    for s, g in gt.items():
        seed = int(rng.integers(1 << 30))
        good[s] = frame_counts(g, tracker(g, np.random.default_rng(seed)))
        bad[s] = frame_counts(g, tracker(g, np.random.default_rng(seed), switch_every=15))
    diffs = {d.metric: d for d in all_pairs({"bad": bad, "good": good})}
    for m in ("IDF1", "HOTA", "MOTA"):
        d = diffs[m]
        assert d.a == "bad" and d.difference < 0
        assert d.low <= d.difference <= d.high and d.high < 0 and d.distinguishable, d
    # the same seed and data give the same interval, byte for byte
    again = {d.metric: d for d in all_pairs({"bad": bad, "good": good})}
    assert again == diffs


def test_trackers_differing_only_by_noise_are_mostly_not_distinguishable() -> None:
    """Two independent draws of the same error process: the 95% interval should hold 0 in
    most of 12 such pairs (a coverage check of the interval, not of one lucky draw)."""
    rng = np.random.default_rng(1003)
    covered = 0
    for _ in range(12):
        gt = {"s": walkers(80, 3, rng)}
        a = {"s": frame_counts(gt["s"], tracker(gt["s"], rng))}
        b = {"s": frame_counts(gt["s"], tracker(gt["s"], rng))}
        d = {d.metric: d for d in all_pairs({"a": a, "b": b})}["MOTA"]
        covered += not d.distinguishable
    assert covered >= 9, covered


def test_bootstrap_refuses_bad_settings() -> None:
    with pytest.raises(ValueError, match="block"):
        Bootstrap(block=0)
    with pytest.raises(ValueError, match="level"):
        Bootstrap(level=1.5)


def test_summary_section_and_footer_say_what_is_not_distinguishable() -> None:
    from occbench.metrics.paired import PairedDifference
    from occbench.report.paired import paired_footer, paired_markdown

    real = PairedDifference("reta", "baseline", "IDF1", 0.9, 0.8, 0.05, 0.15, 2, 300)
    tie = PairedDifference("reta", "baseline", "MOTA", 0.8, 0.79, -0.02, 0.04, 2, 300)
    md = paired_markdown([real, tie])
    assert "| reta | baseline | +0.100 [+0.050, +0.150] | +0.010 [-0.020, +0.040] (n.d.) |" in md
    assert "not distinguishable on this data" in md and "blocks of 10 consecutive frames" in md
    foot = paired_footer([real, tie])
    assert "IDF1 +0.100 [+0.050, +0.150]; MOTA +0.010 [-0.020, +0.040] not distinguishable" in foot
    assert paired_markdown([]) == "" and paired_footer([]) == ""


def test_footer_of_many_trackers_prints_the_leaders_pairs_and_says_where_the_rest_are() -> None:
    from itertools import combinations

    from occbench.metrics.paired import PairedDifference
    from occbench.report.paired import paired_footer, paired_markdown

    idf1 = {"a": 0.6, "b": 0.9, "c": 0.7, "d": 0.5, "e": 0.4}  # 10 pairs; leader b
    diffs = [PairedDifference(x, y, "IDF1", idf1[x], idf1[y], -1.0, 1.0, 1, 100)
             for x, y in combinations(idf1, 2)]
    foot = paired_footer(diffs)
    printed = [line for line in foot.splitlines() if line.startswith("  ") and ": IDF1" in line]
    assert len(printed) == 4 and all("b" in line.split(":")[0].strip().split(" - ") for line in printed)
    assert "6 more pairs without the leader by IDF1" in foot and "give all 10" in foot
    assert paired_markdown(diffs).count("\n| ") == 11  # the header and every pair, in summary.md
    assert "more pairs" not in paired_footer(diffs, most=10)
