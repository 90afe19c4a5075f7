"""A run's plan (harness/pipeline/plan.py): everything checked and built before the first
frame, the tracker names and their config keys, a bad key refused before anything runs."""

from __future__ import annotations

import pytest
from omegaconf import OmegaConf
from run_scenes import mot_cfg

from occbench.errors import RunError
from occbench.pipeline.plan import buildable_trackers, plan_run


def test_a_plan_holds_the_run_checked_and_built(tmp_path, mot_root):
    plan = plan_run(mot_cfg(mot_root, "evaluation.iou_threshold=0.4"), tmp_path / "r",
                    "baseline")
    assert plan.names == ["baseline"] and plan.keys == {"baseline": "tracker"}
    assert [s.info.name for s in plan.sequences] == ["cross-a", "cross-b"]
    assert plan.iou_threshold == 0.4 and plan.protocol == "multi"
    assert (tmp_path / "r" / "config.yaml").is_file()  # written first
    a, b = plan.build("baseline"), plan.build("baseline")
    assert a is not b  # a fresh tracker each time


def test_a_group_names_each_tracker_by_its_key():
    node = OmegaConf.create({"one": {"_target_": "occbench.trackers.baseline.BaselineTracker"},
                             "two": {"_target_": "occbench.trackers.baseline.BaselineTracker",
                                     "max_age": 3}})
    configs, keys = buildable_trackers(node, None)
    assert list(configs) == ["one", "two"]
    assert keys == {"one": "tracker.one", "two": "tracker.two"}


def test_a_bad_plan_fails_before_anything_runs(tmp_path, mot_root):
    with pytest.raises(RunError, match="protocol.name"):
        plan_run(mot_cfg(mot_root, "protocol.name=both"), tmp_path / "p", "baseline")
    with pytest.raises(RunError, match="objective.tracker=nobody"):
        plan_run(mot_cfg(mot_root, "objective.tracker=nobody"), tmp_path / "o", "baseline")
    with pytest.raises(RunError, match="foreground"):
        plan_run(mot_cfg(mot_root, "foreground=sideways"), tmp_path / "f", "baseline")


def test_a_group_leaves_out_trackers_without_their_library_in_one_line(monkeypatch, caplog):
    """tracker=everyone without the extras: one warning naming every tracker left out, the
    missing libraries and the install commands (not one warning per tracker)."""
    import sys

    for module in ("norfair", "motpy"):
        monkeypatch.setitem(sys.modules, module, None)  # import fails as if not installed
    node = OmegaConf.create({
        "baseline": {"_target_": "occbench.trackers.baseline.BaselineTracker"},
        "norfair": {"_target_": "occbench.trackers.outside.norfair.NorfairTracker"},
        "norfair_tuned": {"_target_": "occbench.trackers.outside.norfair.NorfairTracker"},
        "motpy": {"_target_": "occbench.trackers.outside.motpy.MotpyTracker"}})
    with caplog.at_level("WARNING", logger="occbench.pipeline.plan"):
        configs, _ = buildable_trackers(node, None)
    assert list(configs) == ["baseline"]
    warnings = [r.getMessage() for r in caplog.records if r.levelname == "WARNING"]
    assert len(warnings) == 1 and "\n" not in warnings[0]
    assert "3 outside tracker(s) left out" in warnings[0]
    assert "(motpy, norfair)" in warnings[0] and "norfair, norfair_tuned, motpy;" in warnings[0]
    assert warnings[0].count('pip install -e ".[outside]"') == 1  # one command, not three
    with pytest.raises(RunError, match="norfair"):  # chosen alone, it stops the run
        buildable_trackers(node.norfair, "norfair")
