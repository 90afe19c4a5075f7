"""benchmarks/bench_reacquisition.py's stack counts on hand-made tables."""

from __future__ import annotations

import numpy as np
from benchmark_scripts import load
from mot_tables import table

bench = load("bench_reacquisition")


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


def test_failure_modes_counted_on_a_hand_made_table():
    # person 1 at x 100 in frames 1-4, then gone; person 2 enters at x 300 in frame 10
    gt = table([(f, 1, 100, 50, 40, 100) for f in range(1, 5)]
               + [(f, 2, 300, 50, 40, 100) for f in range(10, 13)])
    # id 1 on person 1, reported hidden beside it in frame 4 (IoU 0.33) and on empty floor
    # in frame 5, then on person 2: a lost id re-used for a newcomer (a) and two hidden
    # reports matched to nobody, one of them overlapping nobody (b)
    rows = [(f, 1, 100, 50, 40, 100) for f in range(1, 4)]
    rows += [(4, 1, 120, 50, 40, 100), (5, 1, 150, 50, 40, 100)]
    rows += [(f, 1, 300, 50, 40, 100) for f in range(10, 13)]
    hidden = np.array([False] * 3 + [True] * 2 + [False] * 3)
    dets = {f: np.array([[100.0, 50, 40, 100]]) for f in range(1, 4)}
    c = bench.mode_counts(gt, table(rows), hidden, dets, gap=5)
    assert c["reused"] == 1 and c["reused_new"] == 1 and c["outlived"] == 1
    assert c["hidden"] == 2 and c["phantom"] == 2 and c["phantom_empty"] == 1
    assert c["handed"] == 0


def test_a_switch_is_put_down_to_a_merged_box_or_a_run_of_misses():
    # persons 1 and 2 side by side in frames 1-6; the tracker hands person 1 from id 1 to id 3
    # at frame 4 (one detection covering both people there), and person 2 from id 2 to id 4
    # at frame 6 (person 2 undetected in frames 3-5)
    gt = table([(f, g, x, 50, 40, 100) for f in range(1, 7) for g, x in ((1, 100), (2, 300))])
    rows = [(f, 1 if f < 4 else 3, 100, 50, 40, 100) for f in range(1, 7)]
    rows += [(f, 2 if f < 6 else 4, 300, 50, 40, 100) for f in range(1, 7)]
    rows.sort()
    both = np.array([[95.0, 45, 250, 110]])
    dets = {1: np.array([[100.0, 50, 40, 100], [300, 50, 40, 100]]),
            2: np.array([[100.0, 50, 40, 100], [300, 50, 40, 100]]),
            3: np.array([[100.0, 50, 40, 100]]), 4: both, 5: np.array([[100.0, 50, 40, 100]]),
            6: np.array([[100.0, 50, 40, 100], [300, 50, 40, 100]])}
    c = bench.mode_counts(gt, table(rows), np.zeros(len(rows), dtype=bool), dets, gap=5)
    assert c["handed"] == 2 and c["merged"] == 1 and c["misses"] == 1
    assert c["reused"] == c["phantom"] == c["outlived"] == 0


def test_idf1_misses_put_down_to_causes():
    from idf1_losses import idf1_losses

    # person 1 in frames 1-6 tracked by id 1 (frames 1-3), then by id 2 (4-5, id 1 elsewhere
    # in frame 4), unreported but tentative in frame 6; id 3 hidden on nobody in frame 6
    gt = table([(f, 1, 100, 50, 40, 100) for f in range(1, 7)])
    rows = [(f, 1, 100, 50, 40, 100) for f in range(1, 4)]
    rows += [(4, 1, 400, 50, 40, 100), (4, 2, 100, 50, 40, 100), (5, 2, 100, 50, 40, 100),
             (6, 3, 600, 50, 40, 100)]
    hidden = np.array([False] * 6 + [True])
    tentative = {6: np.array([[100.0, 50, 40, 100]])}
    fn, fp = idf1_losses(gt, table(rows), hidden, tentative)
    assert (fn["other_id_found"], fn["tentative"], fn["unreported"]) == (2, 1, 0)
    assert fn[(1, "other_id_found")] == 2
    assert (fp["on_person"], fp["found_nobody"], fp["hidden_nobody"], fp["nobody_empty"]) == (2, 1, 1, 2)


def _causes(gt, rows, hidden, dets):
    res = table(sorted(rows))
    hid = np.array([hidden.get((f, i), False) for f, i, *_ in sorted(rows)])
    m = bench.match_rows(bench.considered(gt), res)
    return bench.idf1_causes(gt, res, m, hid, {}, dets)


def test_idf1_lost_to_a_split_a_run_of_misses_and_a_phantom():
    # person 1 (x 100, frames 1-12): id 1 in 1-4, undetected and unreported in 5-7, id 2 in
    # 8-12 (IDF1 takes id 2: id 1's 4 boxes are lost twice, to the run of misses);
    # person 3 (x 300, frames 1-9): id 3 in 1-4; id 4 born at frame 3 on its upper part
    # (a split box) takes it in 5-9; id 9: a hidden report on nobody at frame 3
    gt = table(sorted([(f, 1, 100, 50, 40, 100) for f in range(1, 13)]
                      + [(f, 3, 300, 50, 40, 100) for f in range(1, 10)]))
    rows = [(f, 1, 100, 50, 40, 100) for f in range(1, 5)]
    rows += [(f, 2, 100, 50, 40, 100) for f in range(8, 13)]
    rows += [(f, 3, 300, 50, 40, 100) for f in range(1, 5)]
    rows += [(f, 4, 300, 50, 40, 40) for f in (3, 4)] + [(f, 4, 300, 50, 40, 100)
                                                       for f in range(5, 10)]
    rows += [(3, 9, 600, 50, 40, 100)]
    det = {f: np.array([[100.0, 50, 40, 100]]) for f in (*range(1, 5), *range(8, 13))}
    causes, denominator = _causes(gt, rows, {(3, 9): True}, det)
    assert causes["dropped_misses"] == 8 and causes["unreported"] == 3
    assert causes["split"] == 4 + 4 + 2  # id 3's boxes (IDFN, IDFP), id 4's fragment boxes
    assert causes["phantom"] == 1 and sum(causes.values()) == 8 + 3 + 10 + 1
    # 2 IDTP + IDFP + IDFN: 10 credited boxes (5 + 5), 13 false, 3 + 4 + 4 missed
    assert denominator == 2 * 10 + (4 + 4 + 2 + 1) + (3 + 4 + 4)


def test_idf1_lost_at_a_swap_is_a_merged_box_or_a_contact():
    # persons 1 and 2 walk side by side (x 100 and 130, boxes overlapping) in frames 1-10;
    # ids 1 and 2 swap at frame 7: 4 + 4 boxes missed and 4 + 4 false
    gt = table(sorted((f, g, x, 50, 40, 100) for f in range(1, 11)
                      for g, x in ((1, 100), (2, 130))))
    rows = [(f, 1 if f < 7 else 2, 100, 50, 40, 100) for f in range(1, 11)]
    rows += [(f, 2 if f < 7 else 1, 130, 50, 40, 100) for f in range(1, 11)]
    apart = {f: np.array([[100.0, 50, 40, 100], [130, 50, 40, 100]]) for f in range(1, 11)}
    causes, _ = _causes(gt, rows, {}, apart)
    assert causes == {"contact": 16}
    merged = dict(apart)
    merged[6] = np.array([[98.0, 48, 75, 104]])  # one box over both people
    causes, _ = _causes(gt, rows, {}, merged)
    assert causes == {"merged": 16}


def test_the_causes_figure_is_written_beside_its_table_with_every_cause(tmp_path):
    import pandas as pd
    from idf1_losses import CAUSES, LABELS

    rows = [{"set": "cav1-150 sil", "tracker": "reta", "IDF1": 0.7, "HOTA": 0.5, "MOTA": 0.6,
             **{c: 0.0 for c in CAUSES}, "merged": 0.2, "unreported": 0.1},
            {"set": "cav1-150 sil", "tracker": "pbm", "IDF1": 0.8, "HOTA": 0.6, "MOTA": 0.7,
             **{c: 0.01 * (k + 1) for k, c in enumerate(CAUSES)}}]
    fig = bench.causes_figure(rows)
    ax = fig.axes[0]
    # every cause in the legend, in CAUSES's order, those no row has too
    assert [t.get_text() for t in ax.get_legend().get_texts()] == [LABELS[c] for c in CAUSES]
    # each bar's segments, in cause order, are the row's points
    for k, r in enumerate(rows):
        widths = [c.patches[k].get_width() for c in ax.containers]
        assert np.allclose(widths, [r[c] for c in CAUSES])
    written = bench.write_causes(rows, tmp_path / "out", "test")
    assert [p.name for p in written] == ["idf1_causes.csv", "idf1_causes.md", "idf1_causes.png"]
    assert (tmp_path / "out" / "idf1_causes.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    table = pd.read_csv(tmp_path / "out" / "idf1_causes.csv")
    assert list(table.columns) == ["set", "tracker", "IDF1", "HOTA", "MOTA", *CAUSES]
    assert table.loc[0, "merged"] == 0.2 and table.loc[1, "unreported"] == 0.12
    md = (tmp_path / "out" / "idf1_causes.md").read_text().splitlines()
    assert md[0].endswith("| found on nobody | late confirm | unreported |")
    assert md[2] == ("| cav1-150 sil | reta | 0.700 / 0.500 / 0.600 | 0 | 0.200 | 0 | 0 | 0 | 0 "
                     "| 0 | 0 | 0 | 0 | 0 | 0.100 |")
