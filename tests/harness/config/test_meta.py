"""How the views show a tracker: its config's meta: block (harness/config/meta.py)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from occbench.config.build import build_tracker
from occbench.config.meta import TrackerMeta, config_nodes, metas, shipped, without_meta
from occbench.errors import RunError
from run_scenes import compose_cfg


def test_the_views_read_the_config_and_a_tracker_never_sees_it():
    cfg = compose_cfg("dataset=mot", "dataset.root=x", "tracker=all")
    assert "meta" in cfg.tracker.reta and "meta" not in without_meta(cfg.tracker.reta)
    assert build_tracker("reta", cfg.tracker.reta) is not None  # meta is no argument of it
    found = metas(["baseline", "reta", "pbm", "sort"], config_nodes(cfg, ["baseline", "reta",
                                                                           "pbm", "sort"]))
    assert [found[n].role for n in found] == ["baseline", "ours", "ours", "outside"]
    assert found["reta"] == shipped("reta") and found["reta"].style == "ellipses"
    # an external result folder: outside, its own colour, none of the others'
    assert found["sort"].label == "sort"
    assert found["sort"].colour not in {found[n].colour for n in ("baseline", "reta", "pbm")}


def test_a_run_config_s_own_meta_wins_and_a_bad_one_is_refused_by_key():
    cfg = compose_cfg("dataset=mot", "dataset.root=x", "tracker=baseline",
                      "tracker.meta.colour='#123456'", "tracker.meta.label=mine")
    found = metas(["baseline"], config_nodes(cfg, ["baseline"]))
    assert found["baseline"] == TrackerMeta("mine", "#123456", "baseline", "boxes")
    cfg = compose_cfg("dataset=mot", "dataset.root=x", "tracker=baseline", "tracker.meta.role=us")
    with pytest.raises(RunError, match=r"tracker\.meta\.role: one of ours, paper"):
        build_tracker("baseline", cfg.tracker, "tracker")


def test_the_bar_plot_draws_each_tracker_in_its_colour(tmp_path):
    import cv2
    from occbench.report.bars import metric_bars

    rows = pd.DataFrame({"tracker": ["baseline", "reta"], "sequence": ["COMBINED"] * 2,
                         "IDF1": [0.5, 0.7]})
    path = metric_bars(rows, tmp_path / "m.png", ["IDF1"],
                       shown={"baseline": TrackerMeta("b", "#ff0000", "baseline")})
    img = cv2.imread(str(path))
    red = np.all(img == (0, 0, 255), axis=2).sum()  # BGR
    orange = np.all(img == (14, 127, 255), axis=2).sum()  # reta's shipped #ff7f0e
    assert red > 100 and orange > 100
