"""Reports: drawing styles, annotated video and contact sheet, trajectory plots, paper
tables with reported figures, the bench tool and the experiment configs."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pandas as pd
import pytest
import yaml

from harness.datasets.base import GroundTruth, Sequence
from harness.io.mot import MotTable
from harness.report.draw import draw_tracks, grid, infer_style
from harness.report.paper_tables import (
    PaperTableError,
    combined_dataset,
    paper_table,
    to_markdown,
    write_paper_table,
)
from harness.report.trajectories import most_occluded_person, person_paths, plot_person
from trackers.records import Detections, SequenceInfo, Track, TrackState

ROOT = Path(__file__).resolve().parents[3]
EXPERIMENTS = ROOT / "conf" / "experiment"


def mot(rows, vis=None) -> MotTable:
    a = np.asarray(rows, dtype=np.float64).reshape(-1, 6)
    n = len(a)
    v = np.full(n, np.nan) if vis is None else np.asarray(vis, dtype=np.float64)
    order = np.lexsort((a[:, 1], a[:, 0]))
    return MotTable(a[order, 0].astype(np.int64), a[order, 1].astype(np.int64),
                    a[order, 2:6].copy(), np.ones(n), np.full(n, -1, np.int64), v[order])


# --------------------------------------------------------------------------- drawing


def _frame() -> np.ndarray:
    return np.full((120, 160, 3), 100, np.uint8)


def test_each_tracker_is_drawn_its_own_way():
    box = np.array([40.0, 20.0, 30.0, 60.0])
    plain = Track(3, box)
    ellipse = Track(4, box, extra={"ellipse": np.array([55.0, 50.0, 0.0, 15.0, 30.0])})
    hyp = Track(4, box + [30, 0, 0, 0], TrackState.HYPOTHESIS,
                extra={"ellipse": np.array([85.0, 50.0, 0.0, 15.0, 30.0]),
                       "hypothesis": "still"})
    parts = np.array([[40, 20, 30, 9], [40, 29, 15, 25], [55, 29, 15, 25], [40, 54, 15, 26],
                      [55, 54, 15, 26]], float)
    pbm = Track(5, box, extra={"parts": parts, "occluded_parts": np.array([0, 0, 0, 1, 1], bool)})
    assert infer_style([plain]) == "boxes"
    assert infer_style([ellipse]) == "ellipses" and infer_style([pbm]) == "parts"
    a = draw_tracks(_frame(), [plain], "boxes")
    b = draw_tracks(_frame(), [ellipse, hyp], "ellipses")
    c = draw_tracks(_frame(), [pbm], "parts")
    for img in (a, b, c):
        assert img.shape == (120, 160, 3) and (img != 100).any()
    # a box's corner is drawn, an ellipse leaves the box corner untouched
    assert (a[20, 40] != 100).any() and (b[20, 40] == 100).all()
    # the solid ellipse is closed, the dashed hypothesis leaves gaps along its outline
    solid = cv2.ellipse2Poly((55, 50), (15, 30), 0, 0, 360, 2)
    dashed = cv2.ellipse2Poly((85, 50), (15, 30), 0, 0, 360, 2)
    on = lambda pts: np.mean([(b[y, x] != 100).any() for x, y in pts])
    assert on(solid[10:40]) > 0.9 and on(dashed[10:40]) < 0.9
    # the part rectangles split the box: the line between torso and legs is drawn
    assert (c[54, 47] != 100).any() and (a[54, 47] == 100).all()
    # frames are never drawn on in place
    frame = _frame()
    draw_tracks(frame, [plain], gt=(box[None], np.array([1])), title="baseline")
    assert (frame == 100).all()
    with pytest.raises(ValueError, match="style"):
        draw_tracks(frame, [plain], "circles")
    g = grid([a, b, c], columns=2)
    assert g.shape == (240, 320, 3)


class _Walk(Sequence):
    """Two people crossing on a plain background: boxes, frames and visibility."""

    def __init__(self, n: int = 12) -> None:
        self.info = SequenceInfo("walk", 160, 120, 10.0, n)
        rows, vis = [], []
        for k in range(1, n + 1):
            rows += [(k, 1, 10 + 8 * k, 30, 20, 50), (k, 2, 130 - 8 * k, 32, 20, 50)]
            hidden = 5 <= k <= 7
            vis += [1.0, 0.0 if hidden else 1.0]
        self.gt = GroundTruth(mot(rows, vis))

    def frame(self, index: int) -> np.ndarray:
        img = np.full((120, 160, 3), 90, np.uint8)
        t = self.gt.table
        for r in self.gt.rows_of(index):
            x, y, w, h = t.boxes[r].astype(int)
            cv2.rectangle(img, (x, y), (x + w, y + h), (40, 40, 200 if t.ids[r] == 1 else 40), -1)
        return img


class _GtSource:
    def start(self, sequence) -> None:
        self.seq = sequence

    def detect(self, k, frame):
        t = self.seq.gt.table
        rows = self.seq.gt.rows_of(k)
        keep = rows[np.nan_to_num(t.visibility[rows], nan=1.0) > 0.5]
        return Detections(t.boxes[keep], np.ones(len(keep))), None


def test_video_and_contact_sheet_side_by_side(tmp_path):
    from harness.report.video import render
    from trackers.baseline import BaselineTracker

    seq = _Walk()
    trackers = {"baseline": BaselineTracker(min_hits=1), "other": BaselineTracker(max_age=0)}
    out = render(trackers, seq, _GtSource(), tmp_path / "v.mp4", tmp_path / "s.png",
                 sheet_frames=[2, 6, 10])
    assert set(out) == {"video", "sheet"}
    cap = cv2.VideoCapture(str(out["video"]))
    n, size = 0, None
    while True:
        ok, img = cap.read()
        if not ok:
            break
        n, size = n + 1, img.shape
    cap.release()
    assert n == 12 and size == (120, 320, 3)  # two panels side by side
    data = out["video"].read_bytes()
    assert b"ftyp" in data[:32] and b"avc1" in data  # H.264 (browsers do not play mp4v)
    sheet = cv2.imread(str(out["sheet"]))
    assert sheet.shape == (360, 320, 3)  # 3 frames x 2 trackers
    with pytest.raises(ValueError, match="sheet_frames"):
        render(trackers, seq, _GtSource(), sheet=tmp_path / "x.png", sheet_frames=[99])


def test_trajectory_plot_follows_the_matched_ids(tmp_path):
    seq = _Walk()
    assert most_occluded_person(seq.gt) == 2
    t = seq.gt.table
    # tracker A follows person 2 as id 7 then id 8 after the occlusion; B never finds it
    p2 = t.ids == 2
    rows_a = [(f, 7 if f < 6 else 8, *b) for f, b in zip(t.frames[p2], t.boxes[p2])]
    res = {"A": mot(rows_a), "B": mot([(1, 1, 0, 0, 5, 5)])}
    paths = person_paths(t, res, 2)
    assert sorted(paths["A"]) == [7, 8] and paths["B"] == {}
    assert len(paths["A"][7]) == 5 and paths["A"][8][0, 0] == 6
    path = plot_person(seq.gt, res, 2, tmp_path / "traj.png")
    assert cv2.imread(str(path)) is not None
    with pytest.raises(ValueError, match="no ground-truth person"):
        person_paths(t, res, 9)


# --------------------------------------------------------------------------- paper tables


def _spec(name: str) -> dict:
    text = (EXPERIMENTS / f"{name}.yaml").read_text()
    return yaml.safe_load(text)["paper_table"]


@pytest.mark.parametrize("name", ["reta_table2", "reta_table3", "reta_detection",
                                  "pbm_table1", "pbm_segmentation"])
def test_experiment_tables_have_reported_figures_matching_their_columns(name):
    spec = _spec(name)
    n = len(spec["columns"])
    rows = spec["reported"]["rows"]
    assert rows and all(len(v) == n for v in rows.values())
    assert spec["reported"]["citation"]


def test_reported_figures_are_the_papers():
    t2 = _spec("reta_table2")["reported"]["rows"]
    assert t2["Reta et al. 2015 (three-hypothesis graph)"] == [72, 88.9, 11.1, 0, 21, 6]
    t1 = _spec("pbm_table1")["reported"]["rows"]
    assert t1["MS"][1:] == [8, 0, 0, 1, 1, 5, 3.11, 3, 1.61]
    seg = _spec("pbm_segmentation")["reported"]["rows"]
    assert seg["KSP, ETISEO (Table 4)"] == [6.6, 4.5, 12.2, 3.2]


def test_paper_table_puts_ours_beside_reported(tmp_path):
    spec = _spec("reta_table2")
    spec["our_label"] = "test data"
    metrics = pd.DataFrame([
        {"tracker": "reta", "sequence": "s1", "Song_GT": 3, "Song_MT%": 100.0},
        {"tracker": "reta", "sequence": "COMBINED", "Song_GT": 6, "Song_MT%": 50.0,
         "Song_PT%": 50.0, "Song_ML%": 0.0, "Song_Frag": 2, "Song_IDS": 1},
    ])
    table = paper_table(metrics, spec)
    assert table.loc["ours: reta (test data)"].tolist() == [6, 50.0, 50.0, 0.0, 2, 1]
    assert table.loc["reported: Basic particle filter [22]", "MT (%)"] == 53.3
    md = to_markdown(table, spec)
    assert "| reported: Reta et al. 2015 (three-hypothesis graph) | 72 | 88.9 |" in md
    assert "reference only" in md
    metrics.to_csv(tmp_path / "metrics.csv", index=False)
    assert write_paper_table(tmp_path, spec).is_file()
    assert (tmp_path / "paper_table.csv").is_file()
    # PBM's layout: criteria as rows, trackers as columns
    pbm = _spec("pbm_table1")
    md = to_markdown(paper_table(pd.DataFrame([{"tracker": "pbm", "sequence": "COMBINED",
                                                "PBM_MT": 7}]), pbm), pbm)
    assert "| No. of mostly-tracked trajectories | 10 | 10 | 8 | 5 | 7 |" in md
    bad = dict(spec, columns={"Song_GT": "GT"})
    with pytest.raises(PaperTableError, match="has 6 values"):
        paper_table(metrics, bad)


def test_combined_dataset_appends_extra_parts():
    seqs = combined_dataset(f"{__name__}._two", extra={"more": ["c"]}, prefix="s")
    assert seqs == ["s1", "s2", "c"]


def _two(prefix: str) -> list[str]:
    return [f"{prefix}1", f"{prefix}2"]


def test_bench_times_every_stage():
    from harness.commands.bench import bench_sequence
    from trackers.baseline import BaselineTracker

    timings = bench_sequence(_Walk(), _GtSource, lambda: {"baseline": BaselineTracker()},
                             frames=6, repeats=2)
    rows = [t.row() for t in timings]
    assert [r["stage"] for r in rows] == ["decode", "front end", "tracker baseline"]
    assert all(r["frames"] == 6 and r["runs"] == 2 and r["fps_median"] > 0 for r in rows)


def test_experiment_run_writes_paper_table_with_our_rows(tmp_path):
    import subprocess
    import sys

    seq = tmp_path / "data" / "walk"
    (seq / "gt").mkdir(parents=True)
    rows = [f"{k},{i},{10 + 4 * k if i == 1 else 150 - 4 * k},20,20,50,1,-1,-1,-1"
            for k in range(1, 21) for i in (1, 2)]
    (seq / "gt" / "gt.txt").write_text("\n".join(rows) + "\n")
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=walk\nimWidth=200\nimHeight=100\n"
                                     "frameRate=10\nseqLength=20\n")
    out = tmp_path / "run"
    cmd = [sys.executable, "-m", "harness", "+experiment=reta_table2", "tracker=baseline",
           "detector=noisy_gt", "dataset=mot", f"dataset.root={tmp_path / 'data'}",
           "progress=false", f"hydra.run.dir={out}"]
    proc = subprocess.run(cmd, check=False, cwd=ROOT, capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    md = (out / "paper_table.md").read_text()
    assert "| ours: baseline (dataset mot, noisy_gt detections) | 2 | 100 |" in md
    assert "reported: Stochastic graph evolution framework [22]" in md


def test_h264_writer_pads_odd_sizes_and_checks_frames(tmp_path):
    from harness.report.video import H264Writer

    rng = np.random.default_rng(0)
    writer = H264Writer(tmp_path / "odd.mp4", 25.0, (33, 21))
    frames = [rng.integers(0, 255, (21, 33, 3), dtype=np.uint8) for _ in range(5)]
    for f in frames:
        writer.write(f)
    with pytest.raises(ValueError, match="33x21"):
        writer.write(frames[0][:, :32])
    writer.release()
    cap = cv2.VideoCapture(str(tmp_path / "odd.mp4"))
    shapes = []
    while True:
        ok, img = cap.read()
        if not ok:
            break
        shapes.append(img.shape)
    cap.release()
    assert shapes == [(22, 34, 3)] * 5  # one black row and column added
