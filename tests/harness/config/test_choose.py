"""The detector follows the tracker choice in the Reta tables (harness/config/choose.py)."""

from __future__ import annotations

import pytest
from hydra.utils import instantiate

from occbench.config.build import build_tracker, compose_config
from occbench.config.choose import choose

ACTIVE_BASIS = "occbench.trackers.frontend.shape_search.ActiveBasisDetector"
SILHOUETTE = "occbench.trackers.frontend.detectors.SilhouetteDetector"


def test_choose_picks_by_key_else_the_default():
    assert choose("reta_paper", {"reta_paper": "active_basis"}, "silhouette") == "active_basis"
    assert choose("papers", {"reta_paper": "active_basis"}, "silhouette") == "silhouette"
    with pytest.raises(ValueError, match="mapping"):
        choose("a", "not a table", "b")


@pytest.mark.parametrize("overrides, target", [
    (["tracker=reta_paper"], ACTIVE_BASIS),             # the paper, detector and all
    ([], SILHOUETTE),                                   # tracker=papers: one shared source
    (["tracker=reta"], SILHOUETTE),
    (["tracker=reta_paper", "detector=hog"], "occbench.trackers.frontend.hog.HogDetector"),
])
def test_reta_table2_detector_follows_the_tracker(overrides, target):
    cfg = compose_config(["+experiment=reta_table2", *overrides])
    assert cfg.detector.detector._target_ == target


def test_reta_table2_with_reta_paper_builds_the_active_basis_search():
    cfg = compose_config(["+experiment=reta_table2", "tracker=reta_paper"])
    source = instantiate(cfg.detector)
    det = source.detector
    assert type(det).__name__ == "ActiveBasisDetector"
    assert det.search.template.n == 30 and det.verifier is None


def test_reta_table2_runs_its_particle_filter_row_beside_the_papers_trackers():
    cfg = compose_config(["+experiment=reta_table2"])
    assert list(cfg.tracker) == ["baseline", "reta", "reta_paper", "pbm", "pbm_paper",
                                 "particle_filter", "meanshift_scale", "ccmspf"]
    assert cfg.tracker.ccmspf._target_.endswith("ConnectedComponentMeanShiftPF")
    assert cfg.tracker.meanshift_scale._target_.endswith("ScaleAdaptiveMeanShift")
    assert cfg.tracker.particle_filter._target_ == "occbench.trackers.comparators.ColourParticleFilter"
    assert "Basic particle filter [22]" in cfg.paper_table.reported.rows


def test_pbm_table1_runs_the_papers_comparators_as_single_target_trackers():
    cfg = compose_config(["+experiment=pbm_table1"])
    for name in ("meanshift", "meanshift_scale", "ccmspf", "particle_filter"):
        assert cfg.tracker[name].max_targets == 1, name
    # the rules chosen on the choosing sets (docs/adaptations.md, "PBM's comparators")
    rules = {name: (cfg.tracker[name].loss.threshold, cfg.tracker[name].loss.frames,
                    cfg.tracker[name].restart.min_similarity)
             for name in ("meanshift_scale", "ccmspf")}
    assert rules == {"meanshift_scale": (0.9, 11, 0.9), "ccmspf": (0.9, 5, 0.9)}
    trackers = [build_tracker(n, cfg.tracker[n]) for n in ("ccmspf", "meanshift_scale")]
    assert [type(t).__name__ for t in trackers] == ["ConnectedComponentMeanShiftPF",
                                                    "ScaleAdaptiveMeanShift"]
