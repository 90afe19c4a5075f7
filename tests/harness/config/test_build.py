"""Tracker configs by name (harness/config/build.py)."""

from __future__ import annotations

import pytest
from run_scenes import (
    compose_cfg,
)

from occbench.errors import RunError
from occbench.config.build import tracker_configs


def test_tracker_configs_single_and_dict():
    cfg = compose_cfg("dataset=mot", "dataset.root=x", "tracker=baseline")
    assert list(tracker_configs(cfg.tracker, "baseline")) == ["baseline"]
    cfg = compose_cfg("dataset=mot", "dataset.root=x", "tracker=all")
    names = list(tracker_configs(cfg.tracker, "all"))
    assert "baseline" in names
    with pytest.raises(RunError, match="_target_"):
        tracker_configs({"x": {"a": 1}})


# ----------------------------------------------------------------------------- experiment
