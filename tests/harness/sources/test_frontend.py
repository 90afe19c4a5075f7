"""Front-end configs, the harness adapter, ``occbench detect`` and the fit commands."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hydra.utils import instantiate

from occbench.commands.detect import DetectionCounts, match_count, metrics_table, run_detection
from occbench.io.mot import read_mot
from occbench.config.build import compose_config
from occbench.sources.frontend import FrontendSource

TINY = ["dataset=synthetic", "dataset.scenarios=[pair_walk]", "dataset.length=12",
        "dataset.width=320", "dataset.height=240"]


def test_imports_come_from_this_repository():
    import occbench.sources.frontend
    import occbench.trackers.frontend

    root = Path(__file__).resolve().parents[3]
    assert Path(occbench.trackers.frontend.__file__).resolve().parents[2] == root
    assert Path(occbench.sources.frontend.__file__).resolve().parents[2] == root


@pytest.mark.parametrize("name", ["foreground", "silhouette", "hog"])
def test_detector_configs_compose_and_instantiate(name):
    cfg = compose_config([f"detector={name}"], config_name="detect")
    source = instantiate(cfg.detector)
    assert isinstance(source, FrontendSource)
    assert type(source.detector).__name__.lower().startswith(name[:3])


def test_match_count_hand_cases():
    gt = np.array([[0, 0, 10, 10], [20, 0, 10, 10]], float)
    det = np.array([[1, 0, 10, 10], [100, 100, 5, 5], [0, 0, 10, 10]], float)
    assert match_count(gt, det) == 1  # one-to-one: two detections on gt 0 count once
    assert match_count(gt, det[:0]) == 0
    assert match_count(gt, np.array([[25, 0, 10, 10]], float)) == 0  # IoU 1/3 < 0.5
    assert match_count(gt, np.array([[25, 0, 10, 10]], float), iou_threshold=0.3) == 1


def test_metrics_table_sums_counts():
    t = metrics_table({"a": DetectionCounts(10, 10, 5, 5, 1.0), "b": DetectionCounts(10, 30, 15, 5, 1.0)})
    combined = t[t.sequence == "COMBINED"].iloc[0]
    assert combined.TP == 10 and combined.FP == 10 and combined.FN == 30
    assert combined.precision == pytest.approx(0.5) and combined.recall == pytest.approx(0.25)
    assert combined.F1 == pytest.approx(2 * 10 / 60)  # not the mean of per-sequence F1


def test_run_detection_writes_det_files_metrics_and_overlays(tmp_path):
    cfg = compose_config([*TINY, "detector=foreground", "overlays.frames=[3,4]",
                          "detector.detector.background.start.warmup_frames=6"], config_name="detect")
    table = run_detection(cfg, tmp_path)
    assert list(table.sequence) == ["pair_walk", "COMBINED"]
    det = read_mot(tmp_path / "det" / "pair_walk.txt")
    assert len(det) > 0 and (det.ids == -1).all() and det.frames.max() <= 12
    saved = pd.read_csv(tmp_path / "detection_metrics.csv")
    assert saved.TP.iloc[-1] == table.TP.iloc[-1] and saved.recall.iloc[-1] > 0.3
    assert sorted(p.name for p in (tmp_path / "overlays" / "pair_walk").iterdir()) == [
        "000003.png", "000004.png"]
    # the same run gives the same bytes; its progress goes through the app's factory (log
    # lines without a terminal: issue 39 item 8), one step per sequence, every frame counted
    steps = []

    class Step:
        def __init__(self, total=0, desc="", unit="frame"):
            self.total, self.desc, self.n, self.closed = total, desc, 0, False
            steps.append(self)

        def update(self, n=1):
            self.n += n

        def close(self):
            self.closed = True

    run_detection(cfg, tmp_path / "again", progress=Step)
    assert [(s.desc, s.total, s.n, s.closed) for s in steps] == [("pair_walk", 12, 12, True)]
    assert (tmp_path / "again" / "det" / "pair_walk.txt").read_bytes() == (
        tmp_path / "det" / "pair_walk.txt").read_bytes()


def test_frontend_source_requires_start_and_pixels():
    src = instantiate(compose_config(["detector=foreground"], config_name="detect").detector)
    with pytest.raises(RuntimeError, match="start"):
        src.detect(1, np.zeros((10, 10, 3), np.uint8))
    with pytest.raises(ValueError, match="reset"):
        FrontendSource(object())


def test_fit_silhouette_and_heads_commands(tmp_path):
    from occbench.fit.heads import main as fit_heads
    from occbench.fit.silhouette import main as fit_silhouette
    from occbench.trackers.frontend.heads import ColourMixtures
    from occbench.trackers.frontend.silhouette_template import load_template

    assert fit_silhouette([*TINY, "--step", "3", "--out", str(tmp_path / "t.npy")]) == 0
    t = load_template(tmp_path / "t.npy")
    assert t.shape[0] == 64 and 0.3 < t.shape[1] / t.shape[0] < 0.6
    assert t[32, t.shape[1] // 2] > 0.9 and t[0, 0] < 0.1  # body centre in, corner out
    assert fit_heads([*TINY, "--step", "3", "--min-pixels", "50",
                      "--out", str(tmp_path / "h.npz")]) == 0
    mix = ColourMixtures.load(tmp_path / "h.npz")
    assert "annotated head pixels" in mix.provenance
    assert fit_heads(["--references", "--out", str(tmp_path / "r.npz")]) == 0
    shipped = ColourMixtures.load()
    np.testing.assert_allclose(ColourMixtures.load(tmp_path / "r.npz").means, shipped.means)


def test_label_says_when_detections_used_future_frames():
    """issue 37 item 4: summary and report name the source by its label, which says so."""
    from occbench.sources.frontend import FrontendSource
    from occbench.trackers.frontend.background import BackgroundModel
    from occbench.trackers.frontend.background_params import WarmUp
    from occbench.trackers.frontend.foreground import ForegroundDetector

    def source(**warm_up: object) -> FrontendSource:
        return FrontendSource(ForegroundDetector(BackgroundModel(start=WarmUp(**warm_up))))

    offline, online = source(warmup_span="sequence"), source(warmup_span="online")
    assert offline.label == "foreground front end (warm-up on the whole sequence: future frames)"
    assert online.label == "foreground front end"
    no_warm_up = source(warmup_frames=0)
    assert no_warm_up.label == "foreground front end"


@pytest.mark.parametrize("module", ["heads", "silhouette", "active_basis"])
def test_fit_never_overwrites_a_shipped_file_by_default(module, capsys):
    """issue 39 item 9: without --out, fit heads|silhouette wrote over the tracked files in
    trackers/frontend/data; --out is now required (a usage error, exit 2, before any work)."""
    import importlib

    fit = importlib.import_module(f"occbench.fit.{module}")
    shipped = fit.DEFAULT_OUT.read_bytes() if fit.DEFAULT_OUT.is_file() else None
    with pytest.raises(SystemExit) as err:
        fit.main(["dataset=synthetic"])
    assert err.value.code == 2 and "--out" in capsys.readouterr().err
    assert (fit.DEFAULT_OUT.read_bytes() if fit.DEFAULT_OUT.is_file() else None) == shipped
