"""The fitted PBM models and weights as YAML, and the override that uses them
(``occbench.fit.pbm``)."""

from __future__ import annotations

import numpy as np
import pytest
from pbm_scenes import unit_models

from occbench.fit.pbm import load_feature_weights, save_fit, weights_override
from occbench.fit.pbm_weights import WeightFit
from occbench.trackers.layered.feature_models import load_feature_models
from occbench.trackers.layered.parts import FEATURES


def test_yaml_round_trip_and_older_files(tmp_path):
    models = unit_models()
    fit = WeightFit({f: w for f, w in zip(FEATURES, [0.2, 0.0, 0.2, 0.4, 0.2, 0.0], strict=True)},
                    0.9, np.array([0.8, 1.0]), 0.85, 0.7, {"grid_step": 0.2})
    path = tmp_path / "m.yaml"
    save_fit(models, path, "PBM feature-difference models\nsecond line", fit)
    text = path.read_text()
    assert text.startswith("# PBM feature-difference models\n# second line\n")
    assert load_feature_weights(path) == fit.weights
    back = load_feature_models(path)  # the model loader ignores the extra keys
    np.testing.assert_array_equal(back.match_probability(np.full((6, 5), 0.7)),
                                  models.match_probability(np.full((6, 5), 0.7)))
    old = tmp_path / "old.yaml"
    save_fit(models, old, "older fit")
    assert load_feature_weights(old) is None
    load_feature_models(old)
    bad = tmp_path / "bad.yaml"
    assert "\n  overlap: 0.0\n" in text
    bad.write_text(text.replace("\n  overlap: 0.0\n", "\n", 1))
    with pytest.raises(ValueError, match="bad.yaml: feature_weights"):
        load_feature_weights(bad)
    assert weights_override(fit.weights) == (
        "'tracker.pbm.features.feature_weights={area:0.2,perimeter:0,hsv:0.2,xyz:0.4,displacement:0.2,overlap:0}'")


def test_fit_command_on_a_synthetic_scene_with_a_composed_paper_tracker(tmp_path):
    """``occbench fit pbm`` on a tiny synthetic scene, reading gamma, spread and the
    compensation from ``conf/tracker/pbm_paper.yaml`` composed by Hydra (its defaults list
    applied): paper mode compares uncompensated features, and the file says so."""
    from occbench.fit.pbm import _tracker_settings, _window_spec, main

    assert _tracker_settings("pbm_paper")["motion_compensation"] is False
    assert _tracker_settings("pbm_paper")["model_spread"] == 1.0
    out = tmp_path / "m.yaml"
    assert main(["--synthetic", "crossing", "--length", "12", "--tracker-config", "pbm_paper",
                 "--no-weights", "--out", str(out)]) == 0
    models = load_feature_models(out)
    assert "uncompensated" in models.description
    assert _window_spec("a/b@3-40") == ("a/b", [3, 40]) and _window_spec("a/b") == ("a/b", None)
    with pytest.raises(SystemExit, match="'x@3': a frame window is ROOT@FIRST-LAST"):
        _window_spec("x@3")
