"""CLEAR MOT / identity metrics, combination, ignore rules and the evaluate CLI.

Golden figures: the MOTChallenge devkit's table for TUD-Campus and TUD-Stadtmitte as held
by py-motmetrics' own test suite (motmetrics/tests/test_metrics.py,
``test_motchallenge_files``); the data files ship with motmetrics.
"""

from __future__ import annotations

import logging
import math
import os
import shutil
from pathlib import Path

import motmetrics
import numpy as np
import pandas as pd
import pytest
from mot_tables import table

from occbench.commands.evaluate import main, pair_files
from occbench.io.mot import MotTable, read_mot
from occbench.metrics import COLUMNS, COMBINED, combine, score_sequence, summarize

MM_DATA = Path(os.path.dirname(motmetrics.__file__)) / "data"
TUD = ["TUD-Campus", "TUD-Stadtmitte"]

# motmetrics' test_motchallenge_files: idf1, idp, idr, recall, precision, num_unique_objects,
# mostly_tracked, partially_tracked, mostly_lost, num_false_positives, num_misses,
# num_switches, num_fragmentations, mota, motp (motp there is a distance, 1 - IoU)
DEVKIT = {
    "TUD-Campus": [0.557659, 0.729730, 0.451253, 0.582173, 0.941441,
                   8, 1, 6, 1, 13, 150, 7, 7, 0.526462, 0.277201],
    "TUD-Stadtmitte": [0.644619, 0.819760, 0.531142, 0.608997, 0.939920,
                       10, 5, 4, 1, 45, 452, 7, 6, 0.564014, 0.345904],
    COMBINED: [0.624296, 0.799176, 0.512211, 0.602640, 0.940268,
               18, 6, 10, 2, 58, 602, 14, 13, 0.555116, 0.330177],
}  # fmt: skip
DEVKIT_COLUMNS = ["IDF1", "IDP", "IDR", "Recall", "Precision", "GT", "MT", "PT", "ML",
                  "FP", "FN", "IDs", "Frag", "MOTA", "MOTP"]  # fmt: skip


@pytest.fixture(scope="module")
def tud_scores():
    return {
        s: score_sequence(
            read_mot(MM_DATA / s / "gt.txt", gt=True), read_mot(MM_DATA / s / "test.txt")
        )
        for s in TUD
    }


def test_columns_contract():
    assert COLUMNS == ["MOTA", "MOTP", "IDF1", "IDP", "IDR", "Recall", "Precision", "GT", "MT",
                       "PT", "ML", "FP", "FN", "IDs", "Frag", "HOTA", "DetA", "AssA", "LocA",
                       "DetRe", "DetPr", "AssRe", "AssPr"]  # fmt: skip


def test_devkit_figures_for_tud(tud_scores):
    summary = summarize(tud_scores).set_index("sequence")
    assert summary.index.tolist() == [*TUD, COMBINED]
    for seq, expected in DEVKIT.items():
        row = summary.loc[seq]
        for col, want in zip(DEVKIT_COLUMNS, expected):
            got = row[col]
            if col == "MOTP":  # ours is the mean IoU of the matches
                want = 1.0 - want
            if isinstance(want, int):
                assert got == want, (seq, col)
            else:
                assert got == pytest.approx(want, abs=1e-6), (seq, col)


def test_combined_sums_counts_and_recomputes_ratios(tud_scores):
    summary = summarize(tud_scores).set_index("sequence")
    per_seq = summary.loc[TUD]
    for col in ["GT", "MT", "PT", "ML", "FP", "FN", "IDs", "Frag"]:
        assert summary.loc[COMBINED, col] == per_seq[col].sum(), col
    c = combine(tud_scores).clear
    parts = [s.clear for s in tud_scores.values()]
    for name in ("objects", "matches", "switches", "misses", "false_positives", "idtp", "idfp"):
        assert getattr(c, name) == sum(getattr(p, name) for p in parts), name
    mota = 1 - (c.misses + c.false_positives + c.switches) / c.objects
    assert summary.loc[COMBINED, "MOTA"] == pytest.approx(mota, abs=1e-12)
    # ... which is not the mean of the per-sequence MOTA (0.5452 vs 0.5551)
    assert abs(summary.loc[COMBINED, "MOTA"] - per_seq["MOTA"].mean()) > 5e-3
    motp = sum(p.iou_sum for p in parts) / sum(p.detections for p in parts)
    assert summary.loc[COMBINED, "MOTP"] == pytest.approx(motp, abs=1e-12)


def test_combined_hota_follows_trackeval(tud_scores):
    summary = summarize(tud_scores).set_index("sequence")
    h = [s.hota for s in tud_scores.values()]
    tp = h[0].tp + h[1].tp
    det_a = tp / (tp + h[0].fn + h[1].fn + h[0].fp + h[1].fp)
    ass_a = (h[0].ass_a * h[0].tp + h[1].ass_a * h[1].tp) / np.maximum(1.0, tp)  # TrackEval
    assert summary.loc[COMBINED, "HOTA"] == pytest.approx(np.sqrt(det_a * ass_a).mean())
    assert summary.loc[COMBINED, "DetA"] == pytest.approx(det_a.mean())
    assert summary.loc[COMBINED, "AssA"] == pytest.approx(ass_a.mean())


def test_figure_3_of_clear_mot_paper():
    # 4 people missed for 4 frames, then only person 4 tracked for 4 frames: MOTA 0.2
    gt = table(
        [(f, i, 50 * i, 0, 20, 40) for f in range(1, 9) for i in range(1, 5) if f <= 4 or i == 4]
    )
    res = table([(f, 9, 200, 0, 20, 40) for f in range(5, 9)])
    row = summarize({"fig3": score_sequence(gt, res)}).iloc[0]
    assert row["MOTA"] == pytest.approx(0.2)
    assert (row["FN"], row["FP"], row["IDs"]) == (16, 0, 0)
    assert row["MOTP"] == pytest.approx(1.0)


def test_identity_switch_and_fragmentation_hand_case():
    # one person, 6 frames: id 1 in frames 1-2, missed in 3, id 2 in frames 4-6
    gt = table([(f, 1, 10 * f, 0, 10, 20) for f in range(1, 7)])
    res = table([(f, 1 if f < 3 else 2, 10 * f, 0, 10, 20) for f in (1, 2, 4, 5, 6)])
    row = summarize({"s": score_sequence(gt, res)}).iloc[0]
    # a frame without any tracker box does not end a tracked stretch (TrackEval, devkit)
    assert (row["FN"], row["FP"], row["IDs"], row["Frag"]) == (1, 0, 1, 0)
    assert row["MOTA"] == pytest.approx(1 - 2 / 6)
    # with another box in frame 3 the person goes untracked there: one fragmentation
    other = table([(f, 1 if f < 3 else 2, 10 * f, 0, 10, 20) for f in (1, 2, 4, 5, 6)]
                  + [(3, 9, 200, 100, 10, 20)])
    row2 = summarize({"s": score_sequence(gt, other)}).iloc[0]
    assert (row2["FN"], row2["FP"], row2["IDs"], row2["Frag"]) == (1, 1, 1, 1)
    # best identity mapping: gt 1 <-> id 2 (3 frames): IDP = 3/5, IDR = 3/6
    assert row["IDP"] == pytest.approx(3 / 5)
    assert row["IDR"] == pytest.approx(3 / 6)
    assert row["IDF1"] == pytest.approx(2 * 3 / (5 + 6))
    assert row["Recall"] == pytest.approx(5 / 6)
    assert row["Precision"] == pytest.approx(1.0)


def test_iou_threshold_is_an_iou_and_inclusive():
    gt = table([(1, 1, 0, 0, 10, 10)])
    res = table([(1, 1, 0, 0, 5, 10)])  # IoU exactly 0.5
    at = summarize({"s": score_sequence(gt, res, iou_threshold=0.5)}).iloc[0]
    assert (at["FP"], at["FN"]) == (0, 0)
    assert at["MOTP"] == pytest.approx(0.5)
    above = summarize({"s": score_sequence(gt, res, iou_threshold=0.6)}).iloc[0]
    assert (above["FP"], above["FN"]) == (1, 1)
    with pytest.raises(ValueError, match="iou_threshold"):
        score_sequence(gt, res, iou_threshold=0.0)


def test_empty_result_and_empty_gt():
    gt = table([(1, 1, 0, 0, 10, 10), (2, 1, 0, 0, 10, 10)])
    row = summarize({"s": score_sequence(gt, MotTable.empty())}).iloc[0]
    assert (row["FN"], row["FP"], row["MOTA"], row["HOTA"]) == (2, 0, 0.0, 0.0)
    assert math.isnan(row["Precision"]) and math.isnan(row["MOTP"])
    row = summarize({"s": score_sequence(MotTable.empty(), gt)}).iloc[0]
    assert (row["FN"], row["FP"], row["GT"]) == (0, 2, 0)
    assert math.isnan(row["MOTA"]) and row["Precision"] == 0.0
    row = summarize({"s": score_sequence(MotTable.empty(), MotTable.empty())}).iloc[0]
    assert math.isnan(row["MOTA"]) and (row["GT"], row["FP"], row["HOTA"]) == (0, 0, 0.0)


def test_mot16_ignore_rules(tmp_path: Path):
    # frame 1: pedestrian (class 1), pedestrian marked conf 0, static person (class 7,
    # a distractor), car (class 3). The tracker covers all four.
    (tmp_path / "gt.txt").write_text(
        "1,1,1,1,10,20,1,1,1.0\n"
        "1,2,101,1,10,20,0,1,0.5\n"
        "1,3,201,1,10,20,0,7,1.0\n"
        "1,4,301,1,10,20,0,3,1.0\n"
    )
    gt = read_mot(tmp_path / "gt.txt", gt=True)
    assert gt.classes.tolist() == [1, 1, 7, 3]
    res = table([(1, i, 100 * (i - 1), 0, 10, 20) for i in (1, 2, 3, 4)])
    score = score_sequence(gt, res)
    assert score.ignored_gt == 3  # conf-0 pedestrian, distractor, car
    assert score.removed_tracker == 1  # the box on the static person
    row = summarize({"s": score}).iloc[0]
    # scored: one gt; the boxes on the conf-0 pedestrian and the car are false positives
    assert (row["GT"], row["FN"], row["FP"]) == (1, 0, 2)
    assert score.hota.fp[0] == 2 and score.hota.tp[0] == 1


def test_mot15_gt_world_coordinates_are_not_classes(tmp_path: Path):
    # MOT15 gt: columns 8-10 are world x, y, z (TUD-Stadtmitte), not class/visibility
    (tmp_path / "gt.txt").write_text("1,1,1,1,10,20,1,4.48,5.50,0\n1,2,51,1,10,20,1,7.2,0.3,0\n")
    gt = read_mot(tmp_path / "gt.txt", gt=True)
    assert gt.classes.tolist() == [-1, -1]
    score = score_sequence(gt, table([(1, 5, 0, 0, 10, 20)]))
    assert score.ignored_gt == 0
    assert (score.clear.objects, score.clear.misses) == (2, 1)


def test_repeated_id_in_a_frame_is_an_error():
    gt = table([(1, 1, 0, 0, 10, 10)])
    res = table([(1, 3, 0, 0, 10, 10), (1, 3, 20, 0, 10, 10)])
    with pytest.raises(ValueError, match="tracker id 3 occurs more than once in frame 1"):
        score_sequence(gt, res)


def test_summarize_rejects_nothing_and_reserved_name(tud_scores):
    with pytest.raises(ValueError):
        summarize({})
    with pytest.raises(ValueError, match=COMBINED):
        summarize({COMBINED: tud_scores["TUD-Campus"]})


def test_perfect_copy_of_a_larger_scene_scores_one():
    # a perfect copy of 300 frames x 15 moving people (ids 0..14, random boxes)
    rng = np.random.default_rng(0)
    rows = [(f, i, *rng.uniform(0, 900, 2), 30, 80) for f in range(1, 301) for i in range(15)]
    row = summarize({"s": score_sequence(table(rows), table(rows))}).iloc[0]
    assert row[["MOTA", "MOTP", "IDF1", "HOTA", "DetA", "AssA", "LocA"]].tolist() == [1.0] * 7


# ------------------------------------------------------------------------------------ CLI


@pytest.fixture()
def tud_dirs(tmp_path: Path) -> tuple[Path, Path, Path]:
    nested, flat, res = tmp_path / "nested", tmp_path / "flat", tmp_path / "res"
    for s in TUD:
        (nested / s / "gt").mkdir(parents=True)
        shutil.copy(MM_DATA / s / "gt.txt", nested / s / "gt" / "gt.txt")
        flat.mkdir(exist_ok=True)
        shutil.copy(MM_DATA / s / "gt.txt", flat / f"{s}.txt")
        res.mkdir(exist_ok=True)
        shutil.copy(MM_DATA / s / "test.txt", res / f"{s}.txt")
    return nested, flat, res


@pytest.mark.parametrize("layout", ["nested", "flat"])
def test_cli_folders_print_and_write_csv(tud_dirs, layout, tmp_path, capsys):
    nested, flat, res = tud_dirs
    out = tmp_path / "out" / "table.csv"
    gt = nested if layout == "nested" else flat
    assert main([str(gt), str(res), "--csv", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "TUD-Campus" in printed and COMBINED in printed and "0.555" in printed  # fractions
    assert "55.5" not in printed
    csv = pd.read_csv(out)
    assert csv.columns.tolist() == ["sequence", *COLUMNS]
    assert csv["sequence"].tolist() == [*TUD, COMBINED]
    assert csv.loc[2, "MOTA"] == pytest.approx(0.555116, abs=1e-6)
    assert csv.loc[0, "HOTA"] == pytest.approx(0.3914, abs=5e-5)
    first = out.read_bytes()
    assert main([str(gt), str(res), "--csv", str(out)]) == 0
    assert out.read_bytes() == first  # same input, same bytes


def test_cli_single_files_and_iou(tud_dirs, tmp_path, capsys):
    nested, _, res = tud_dirs
    gt = nested / "TUD-Campus" / "gt" / "gt.txt"
    out = tmp_path / "one.csv"
    assert main([str(gt), str(res / "TUD-Campus.txt"), "--csv", str(out)]) == 0
    csv = pd.read_csv(out)
    assert csv["sequence"].tolist() == ["TUD-Campus", COMBINED]
    assert csv.loc[0, "IDF1"] == pytest.approx(0.557659, abs=1e-6)
    assert main([str(gt), str(res / "TUD-Campus.txt"), "--csv", str(out), "--iou", "0.8"]) == 0
    assert pd.read_csv(out).loc[0, "MOTA"] < 0.3  # stricter matching
    # a gt file against a results folder finds <seq>.txt
    assert pair_files(gt, res)["TUD-Campus"] == (gt, res / "TUD-Campus.txt")
    # motmetrics' own layout <seq>/gt.txt is named after the folder too
    assert list(pair_files(MM_DATA / "TUD-Campus" / "gt.txt", res)) == ["TUD-Campus"]


def test_cli_missing_result_is_empty_with_warning(tud_dirs, tmp_path, caplog):
    nested, _, res = tud_dirs
    (res / "TUD-Campus.txt").unlink()
    out = tmp_path / "t.csv"
    with caplog.at_level(logging.WARNING):
        assert main([str(nested), str(res), "--csv", str(out)]) == 0
    assert any("TUD-Campus" in r.getMessage() and "empty" in r.getMessage() for r in caplog.records)
    csv = pd.read_csv(out).set_index("sequence")
    assert csv.loc["TUD-Campus", "FN"] == 359 and csv.loc["TUD-Campus", "MOTA"] == 0.0
    assert csv.loc[COMBINED, "FN"] == 359 + 452


def test_cli_missing_path_is_a_clear_error(tud_dirs, tmp_path, capsys):
    nested, _, res = tud_dirs
    assert main([str(tmp_path / "nope"), str(res)]) == 1  # a refused input
    assert f"ground truth not found: {tmp_path / 'nope'}" in capsys.readouterr().err
    assert main([str(nested), str(tmp_path / "none")]) == 1
    assert "results not found" in capsys.readouterr().err
    # one result file cannot be scored against two sequences
    assert main([str(nested), str(res / "TUD-Campus.txt")]) == 1
    assert "holds 2 sequences" in capsys.readouterr().err


def test_cli_malformed_file_names_file_and_line(tud_dirs, capsys):
    nested, _, res = tud_dirs
    (res / "TUD-Campus.txt").write_text("1,1,0,0,10,10,1,-1,-1,-1\n1,2,zero,0,1,1\n")
    assert main([str(nested), str(res)]) == 1
    assert capsys.readouterr().err.startswith(f"occbench: {res / 'TUD-Campus.txt'}:2")


def test_cli_scores_only_the_sequences_of_the_seqmap(tud_dirs, tmp_path, capsys, caplog):
    """A run folder's gt/ with its seqmap (issue 39: an interrupted run's gt/ holds the
    sequence it began and never finished; eval scored it as an empty result)."""
    nested, _, res = tud_dirs
    (nested / "seqmap.txt").write_text("name\nTUD-Stadtmitte\n")
    (res / "TUD-Campus.txt").unlink()  # the run never reached it
    out = tmp_path / "t.csv"
    with caplog.at_level(logging.WARNING):
        assert main([str(nested), str(res), "--csv", str(out)]) == 0
    assert pd.read_csv(out)["sequence"].tolist() == ["TUD-Stadtmitte", COMBINED]
    assert "TUD-Campus not listed" in caplog.text and "empty" not in caplog.text
    (nested / "seqmap.txt").write_text("name\nTUD-Stadtmitte\nTUD-Nowhere\n")
    assert main([str(nested), str(res)]) != 0
    assert "names TUD-Nowhere but there is no" in capsys.readouterr().err


def test_cli_refuses_a_folder_of_tracker_folders_naming_them(tud_dirs, tmp_path, capsys):
    """A run's tracks/ (one folder per tracker) in place of one tracker's folder: every
    sequence was scored as an empty result, exit 0, a table of zeros (issue 39 item 5)."""
    nested, _, res = tud_dirs
    tracks = tmp_path / "run" / "tracks"
    tracks.mkdir(parents=True)
    shutil.copytree(res, tracks / "reta")
    assert main([str(nested), str(tracks)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"occbench: {tracks} holds no result file")
    assert f"(reta): give one, e.g. {tracks / 'reta'}" in err[0]
    assert main([str(nested), str(tracks / "reta")]) == 0


def test_cli_refuses_a_box_100_frames_wide_naming_file_and_line(tud_dirs, capsys):
    """seqinfo.ini's frame size bounds the boxes of gt and results (issue 39)."""
    nested, _, res = tud_dirs
    (nested / "TUD-Campus" / "seqinfo.ini").write_text(
        "[Sequence]\nname=TUD-Campus\nseqLength=71\nimWidth=640\nimHeight=480\n")
    assert main([str(nested), str(res)]) == 0
    result = res / "TUD-Campus.txt"
    lines = result.read_text().splitlines()
    fields = lines[1].split(",")
    fields[4] = "70000"
    result.write_text("\n".join([lines[0], ",".join(fields), *lines[2:]]) + "\n")
    assert main([str(nested), str(res)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"occbench: {result}:2: box 70000x")
