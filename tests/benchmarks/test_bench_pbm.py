"""benchmarks/bench_pbm.py --vs: another checkout's trackers/layered imported beside this
tree's (``tracker_timing.import_other``, its data files too), built from that checkout's
config, and timed on the same scene in turn."""

from __future__ import annotations

import shutil
import sys
from functools import partial
from pathlib import Path

import pytest
from benchmark_scripts import load

ROOT = Path(__file__).resolve().parents[2]
bench = load("bench_pbm")


def test_vs_builds_the_other_checkouts_pbm_from_its_config(tmp_path):
    package = tmp_path / "trackers" / "layered"
    shutil.copytree(ROOT / "trackers" / "layered", package, ignore=shutil.ignore_patterns("__pycache__"))
    with open(package / "__init__.py", "a") as f:
        f.write("\nMARK = 'the other checkout'\n")
    (tmp_path / "conf" / "tracker").mkdir(parents=True)
    text = (ROOT / "conf" / "tracker" / "pbm.yaml").read_text()
    (tmp_path / "conf" / "tracker" / "pbm.yaml").write_text(text.replace("margin_ratio: ", "margin_ratio: 1.3 #", 1))
    module, build_other = bench.other_builder(tmp_path, "pbm_vs_test")
    assert module.MARK == "the other checkout"  # its files, not this tree's
    tracker = build_other()
    assert type(tracker) is module.PBMTracker and type(tracker).__module__ == "pbm_vs_test.tracker"
    assert tracker.matching.margin_ratio == 1.3  # its config, not this tree's
    assert bench.build("pbm").matching.margin_ratio != 1.3
    shipped = Path(sys.modules["pbm_vs_test.feature_models"].DEFAULT_MODELS_PATH)
    assert shipped.read_bytes() == (package / "data" / "default_models.yaml").read_bytes()


def test_vs_rows_of_the_same_code_agree():
    rows = bench.versus(partial(bench.build, "pbm"), people=3, frames=4, rounds=2)
    assert [r["mode"] for r in rows] == ["foreground mask", "no foreground"]
    for r in rows:
        assert r["same_rows"] and r["this_fps"] > 0 and r["other_fps"] > 0
        assert r["ratio_min"] <= r["ratio"] <= r["ratio_max"]


def test_vs_names_a_checkout_without_the_package(tmp_path):
    with pytest.raises(FileNotFoundError, match="layered"):
        bench.other_builder(tmp_path, "pbm_vs_missing")
