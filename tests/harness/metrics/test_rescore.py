"""Run folders are MOTChallenge benchmark folders: the ground truth scored against is written
beside the tracks (synthetic, replayed and real sequences alike), with seqinfo.ini and a
seqmap, and re-scoring the written files (with our scorer and with TrackEval) gives
metrics.csv again. HOTA's per-alpha table and plot."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hydra import compose, initialize_config_dir
from hydra.utils import instantiate

from occbench.datasets.mot import read_seqinfo
from occbench.io.mot import read_mot
from occbench.metrics import COMBINED, HOTA_ALPHA_COLUMNS, score_sequence, summarize
from occbench.metrics.hota import ALPHAS
from occbench.pipeline.experiment import run_experiment

CONF = Path(__file__).resolve().parents[3] / "conf"
RUNS = {  # small runs of each kind of ground truth: rendered, replayed real, real CAVIAR
    "synthetic": ["dataset=synthetic", "dataset.scenarios=[crossing,stop_behind]",
                  "dataset.length=30"],
    "replay": ["dataset=replay", "dataset.max_frames=30"],
    "caviar": ["dataset=caviar", "detector=noisy_gt", "detector.miss_rate=0.3"],
}
SAME = ("HOTA", "DetA", "AssA", "IDF1", "MOTA", "DetRe", "DetPr", "AssRe", "AssPr", "LocA")


def _compose(overrides: list[str]):
    with initialize_config_dir(config_dir=str(CONF), version_base="1.3"):
        return compose("config", overrides=["tracker=baseline", "detector=noisy_gt",
                                            *overrides])


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[str, tuple]:
    out = {}
    for kind, overrides in RUNS.items():
        cfg = _compose(overrides)
        folder = tmp_path_factory.mktemp(kind)
        result = run_experiment(cfg, folder, tracker_name="baseline")
        assert not result.failures, result.failures
        out[kind] = (cfg, folder, result)
    return out


@pytest.mark.parametrize("kind", list(RUNS))
def test_run_writes_the_ground_truth_it_scored(runs, kind):
    cfg, folder, result = runs[kind]
    seqs = list(instantiate(cfg.dataset))
    names = [s.info.name for s in seqs]
    assert (folder / "gt" / "seqmap.txt").read_text().split() == ["name", *names]
    rescored = {}
    for seq in seqs:
        gt_file = folder / "gt" / seq.info.name / "gt" / "gt.txt"
        written, scored = read_mot(gt_file, gt=True), seq.gt.table
        assert np.array_equal(written.frames, scored.frames)
        assert np.array_equal(written.ids, scored.ids)
        np.testing.assert_allclose(written.boxes, scored.boxes, rtol=0, atol=1e-6)
        assert np.array_equal(written.conf, scored.conf)
        # MOT15-style rows without a class are pedestrians, for us and for TrackEval
        assert np.array_equal(written.classes, np.where(scored.classes < 0, 1, scored.classes))
        np.testing.assert_allclose(written.visibility, scored.visibility, atol=1e-6)
        info = read_seqinfo(folder / "gt" / seq.info.name / "seqinfo.ini")
        assert info["name"] == seq.info.name and int(info["seqLength"]) == seq.info.length
        assert (int(info["imWidth"]), int(info["imHeight"])) == (seq.info.width, seq.info.height)
        assert float(info["frameRate"]) == seq.info.fps
        tracks = read_mot(folder / "tracks" / "baseline" / f"{seq.info.name}.txt")
        rescored[seq.info.name] = score_sequence(written, tracks)
    ours = result.metrics.set_index("sequence")
    again = summarize(rescored).set_index("sequence")
    for col in (*SAME, "FP", "FN", "IDs", "Frag", "MT", "ML"):
        np.testing.assert_allclose(again[col], ours.loc[again.index, col], atol=1e-6,
                                   err_msg=col)


@pytest.mark.parametrize("kind", list(RUNS))
def test_trackeval_rescores_the_run_folder(runs, kind):
    # not in the test extra: its metadata pulls opencv-python, whose 5.x has no HOG and
    # shadows our opencv-python-headless; .ci/run installs it as the README says
    trackeval = pytest.importorskip(
        "trackeval", reason="TrackEval not installed: pip install --no-deps trackeval==1.3.0 "
                            "pycocotools tabulate")
    _, folder, result = runs[kind]
    evaluator = trackeval.Evaluator({  # the README's call, quiet
        "USE_PARALLEL": False, "PRINT_RESULTS": False, "PRINT_CONFIG": False,
        "TIME_PROGRESS": False, "OUTPUT_SUMMARY": False, "OUTPUT_DETAILED": False,
        "PLOT_CURVES": False})
    dataset = trackeval.datasets.MotChallenge2DBox({
        "GT_FOLDER": str(folder / "gt"), "TRACKERS_FOLDER": str(folder / "tracks"),
        "TRACKER_SUB_FOLDER": "", "SEQMAP_FILE": str(folder / "gt" / "seqmap.txt"),
        "SKIP_SPLIT_FOL": True, "OUTPUT_FOLDER": str(folder / "trackeval"),
        "PRINT_CONFIG": False})
    metrics = [trackeval.metrics.HOTA(), trackeval.metrics.CLEAR(), trackeval.metrics.Identity()]
    res, _ = evaluator.evaluate([dataset], metrics)
    ours = result.metrics.set_index("sequence")
    seqs = res["MotChallenge2DBox"]["baseline"]
    assert set(seqs) == {*ours.index.drop(COMBINED), "COMBINED_SEQ"}
    for seq, r in seqs.items():
        r = r["pedestrian"]
        theirs = {k: float(np.mean(r["HOTA"][k])) for k in
                  ("HOTA", "DetA", "AssA", "DetRe", "DetPr", "AssRe", "AssPr", "LocA")}
        theirs.update(IDF1=r["Identity"]["IDF1"], MOTA=r["CLEAR"]["MOTA"])
        row = ours.loc[COMBINED if seq == "COMBINED_SEQ" else seq]
        for col in SAME:
            assert row[col] == pytest.approx(theirs[col], abs=5e-5), (seq, col)
        assert row["IDs"] == r["CLEAR"]["IDSW"] and row["FP"] == r["CLEAR"]["CLR_FP"]


def test_hota_alpha_table_and_plot(runs):
    _, folder, result = runs["synthetic"]
    table = pd.read_csv(folder / "hota_alpha.csv")
    assert list(table.columns) == ["tracker", "sequence", "alpha", *HOTA_ALPHA_COLUMNS]
    ours = result.metrics.set_index("sequence")
    for seq, rows in table.groupby("sequence"):
        assert np.allclose(rows["alpha"], np.round(ALPHAS, 2))
        for col in HOTA_ALPHA_COLUMNS:  # metrics.csv holds their means over alpha
            assert rows[col].mean() == pytest.approx(ours.loc[seq, col], abs=2e-6), (seq, col)
        assert (np.diff(rows["DetA"]) <= 1e-9).all()  # a stricter threshold matches less
    assert set(table["sequence"]) == set(ours.index)
    assert (folder / "plots" / "hota_alpha.png").stat().st_size > 10_000
