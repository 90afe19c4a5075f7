"""Each dataset's default detector (conf/detector/default_<dataset>.yaml): the silhouette front
end on real pixels, ground truth + noise on rendered scenes, named wherever results appear;
a run folder's config.yaml names its data by absolute paths."""

from __future__ import annotations

import pytest
from omegaconf import OmegaConf
from run_scenes import compose_cfg

from occbench.errors import RunError
from occbench.pipeline.plan import detector_label, plan_run
from occbench.sources.annotations import NoisyGroundTruth

NOISY = "occbench.sources.annotations.NoisyGroundTruth"
FRONTEND = "occbench.sources.frontend.FrontendSource"


@pytest.mark.parametrize(("overrides", "target"), [
    ([], NOISY),                                   # the synthetic suite
    (["dataset=replay"], NOISY),
    (["dataset=caviar"], FRONTEND),
    (["dataset=video", "dataset.path=x.mp4"], FRONTEND),
    (["dataset=mot", "dataset.root=x"], FRONTEND),
    (["dataset=caviar", "detector=noisy_gt"], NOISY),  # one override away
    (["+experiment=reta_table2"], FRONTEND),
    (["+experiment=reta_table3"], NOISY),           # states its detector
])
def test_each_dataset_has_its_default_detector(overrides, target):
    cfg = compose_cfg(*overrides)
    assert cfg.detector._target_ == target
    if target == FRONTEND:
        assert cfg.detector.detector._target_.endswith("SilhouetteDetector")


def test_the_label_names_ground_truth_plus_noise():
    noisy = NoisyGroundTruth()
    assert detector_label(noisy, "noisy_gt") == "noisy_gt (ground truth + noise)"
    assert detector_label(noisy, "default_synthetic") == "ground truth + noise"
    assert detector_label(noisy, None) == "ground truth + noise"


def test_a_box_only_dataset_with_the_pixel_detector_is_refused_before_the_run(tmp_path,
                                                                              mot_root):
    cfg = compose_cfg("dataset=mot", f"dataset.root={mot_root}", "tracker=baseline")
    with pytest.raises(RunError, match=r"cross-a, cross-b has none: choose detector=noisy_gt "
                                       r"\(ground truth \+ noise\)"):
        plan_run(cfg, tmp_path / "r", "baseline")


def test_config_yaml_names_the_data_by_absolute_paths(tmp_path, mot_root, monkeypatch):
    monkeypatch.chdir(mot_root.parent)
    cfg = compose_cfg("dataset=mot", f"dataset.root={mot_root.name}", "detector=noisy_gt",
                      "tracker=baseline")
    plan = plan_run(cfg, tmp_path / "r", "baseline")
    saved = OmegaConf.load(tmp_path / "r" / "config.yaml")
    assert saved.dataset.root == str(mot_root)
    assert plan.title.endswith("(2 sequences), detector ground truth + noise")
