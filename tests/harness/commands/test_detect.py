"""``occbench detect``'s tables (harness/commands/detect.py): sequences without ground truth
are counted, never scored with zeros or NaN; COMBINED scores the labelled sequences only and
says so; a multirun prints one table for all its jobs."""

from __future__ import annotations

import pandas as pd
import pytest
import yaml
from omegaconf import OmegaConf

from occbench.commands.detect import (
    DetectionCounts,
    GatherDetections,
    metrics_table,
    table_notes,
    table_text,
)


def _unlabelled(frames: int, detections: int) -> DetectionCounts:
    return DetectionCounts(frames=frames, detections=detections, seconds=1.0, labelled=False)


def test_without_ground_truth_detections_are_counted_not_scored():
    table = metrics_table({"own": _unlabelled(50, 120)})
    own, combined = table.iloc[0], table.iloc[1]
    assert own.ground_truth == "no" and own.detections == 120 and own.per_frame == 2.4
    assert own[["gt", "TP", "FP", "FN", "precision", "recall", "F1"]].isna().all()
    assert combined.detections == 120 and pd.isna(combined.precision)
    text = table_text(table)
    assert "nan" not in text.lower() and "no ground truth" in text
    assert " 0.000" not in text  # no zero standing for a score


def test_combined_scores_only_the_labelled_sequences_and_says_so():
    table = metrics_table({"a": DetectionCounts(10, 20, 10, 8, 1.0),
                           "own": _unlabelled(40, 90)})
    combined = table[table.sequence == "COMBINED"].iloc[0]
    assert combined.ground_truth == "1 of 2"
    assert combined.frames == 10 and combined.detections == 10  # a's alone, not a + own
    assert combined.precision == pytest.approx(0.8) and combined.recall == pytest.approx(0.4)
    (note,) = table_notes(table)
    assert "own" in note and "1 labelled sequence(s) only" in note
    assert table_notes(metrics_table({"a": DetectionCounts(10, 20, 10, 8, 1.0)})) == []


def test_the_csv_leaves_scores_blank_without_ground_truth(tmp_path):
    table = metrics_table({"a": DetectionCounts(10, 20, 10, 8, 1.0), "own": _unlabelled(4, 6)})
    path = tmp_path / "m.csv"
    path.write_text(table.to_csv(index=False, float_format="%.4f", lineterminator="\n"))
    lines = path.read_text().splitlines()
    assert lines[1].startswith("a,yes,10,10,1.0000,20,8,2,12,")  # whole counts stay whole
    assert lines[2] == "own,no,4,6,1.5000,,,,,,,,4.0000"


def _job(root, num, overrides, table):
    job = root / str(num)
    (job / ".hydra").mkdir(parents=True)
    (job / ".hydra" / "overrides.yaml").write_text(yaml.safe_dump(overrides))
    (job / "detection_metrics.csv").write_text(table.to_csv(index=False, float_format="%.4f"))


def test_a_multirun_prints_one_table_of_its_jobs(tmp_path, capsys):
    gather = GatherDetections()
    _job(tmp_path, 7, ["detector=old"], metrics_table({"a": DetectionCounts(1, 1, 1, 1, 1.0)}))
    for f in (tmp_path / "7").rglob("*"):  # an earlier sweep's job in the same folder
        import os

        os.utime(f, (0, 0))
    gather.on_multirun_start(OmegaConf.create({}))
    _job(tmp_path, 0, ["detector=silhouette"],
         metrics_table({"a": DetectionCounts(10, 20, 10, 8, 1.0)}))
    _job(tmp_path, 1, ["detector=hog"], metrics_table({"a": DetectionCounts(10, 20, 5, 5, 1.0),
                                                       "own": _unlabelled(4, 6)}))
    gather.on_multirun_end(OmegaConf.create({"hydra": {"sweep": {"dir": str(tmp_path)}}}))
    out = capsys.readouterr().out
    assert out.count("precision") == 1  # one header: one table
    lines = out.splitlines()
    row0 = next(line for line in lines if "detector=silhouette" in line)
    row1 = next(line for line in lines if "detector=hog" in line)
    assert "0.800" in row0 and "1 of 2" in row1 and "1.000" in row1
    assert "detector=old" not in out
    assert "labelled sequences only" in out


def test_a_multirun_prints_the_scores_a_single_run_prints(tmp_path, capsys):
    """``detect -m`` scores each job from its counts, not from the CSV's rounded ratios
    (issue 39: F1 0.838 against 0.837). F1 = 2 * 2 / (9 + 10) = 0.21053: 0.211, where the
    file's 0.2105 printed at 3 decimals gives 0.210."""
    table = metrics_table({"a": DetectionCounts(10, 10, 9, 2, 1.0)})
    assert table_text(table, []).count("0.211") >= 1
    gather = GatherDetections()
    gather.on_multirun_start(OmegaConf.create({}))
    _job(tmp_path, 0, ["detector=silhouette"], table)
    gather.on_multirun_end(OmegaConf.create({"hydra": {"sweep": {"dir": str(tmp_path)}}}))
    row = next(line for line in capsys.readouterr().out.splitlines() if "silhouette" in line)
    assert "0.211" in row and "0.210" not in row
