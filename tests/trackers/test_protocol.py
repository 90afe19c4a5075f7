"""The tracker contract (``occbench.trackers.protocol``): every tracker a config names
declares ``needs_frames``, and the declaration is what its ``update`` does with a frameless
frame; the optional hooks are found by ``isinstance``."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from occbench.config.build import build_tracker, compose_config, missing_library
from occbench.errors import RunError
from occbench.pipeline.warmup import SIZE, scene
from occbench.trackers.outside import MissingLibrary
from occbench.trackers.protocol import KeepsGraph, StartsSequence, Tracker, needs_frames
from occbench.trackers.records import SequenceInfo

CONF = Path(__file__).resolve().parents[2] / "conf" / "tracker"


def _single(path: Path) -> bool:
    """A conf/tracker file that builds one tracker: a ``_target_``, or a defaults list whose
    one other entry is such a file (``reta_paper``: ``reta`` with the paper's values)."""
    node = yaml.safe_load(path.read_text())
    others = [d for d in node.get("defaults", []) if d != "_self_"]
    return "_target_" in node or (len(others) == 1 and isinstance(others[0], str)
                                  and "@" not in others[0] and _single(CONF / f"{others[0]}.yaml"))


SINGLE = sorted(p.stem for p in CONF.glob("*.yaml") if _single(p))


def _build(name: str):
    try:
        return build_tracker(name, compose_config([f"tracker={name}"]).tracker)
    except (MissingLibrary, RunError) as err:
        missing = missing_library(err)
        if missing is None:
            raise
        pytest.skip(f"optional library {missing.module} is not installed")


def test_every_single_tracker_config_is_listed():
    assert {"baseline", "reta", "reta_paper", "pbm", "pbm_paper", "meanshift"} <= set(SINGLE)


@pytest.mark.parametrize("name", SINGLE)
def test_needs_frames_is_declared_and_true_to_the_update(name):
    tracker = _build(name)
    assert isinstance(tracker, Tracker)
    declared = needs_frames(tracker)
    _, _, dets = scene(0)
    if isinstance(tracker, StartsSequence):  # as the bank does before a sequence's first frame
        tracker.start_sequence(SequenceInfo("scene", SIZE[1], SIZE[0], 25.0, 10))
    tracker.reset()
    if declared:
        with pytest.raises(ValueError):
            tracker.update(None, dets, None)
    else:
        assert isinstance(tracker.update(None, dets, None), list)


def test_optional_hooks_by_isinstance():
    assert isinstance(_build("reta"), KeepsGraph)
    assert not isinstance(_build("pbm"), KeepsGraph)
    assert not isinstance(_build("baseline"), StartsSequence)


def test_an_undeclared_tracker_is_named():
    class Mine:
        def reset(self) -> None: ...

        def update(self, frame, detections, foreground=None):
            return []

    with pytest.raises(TypeError, match="Mine does not declare needs_frames"):
        needs_frames(Mine())
    Mine.needs_frames = False
    assert needs_frames(Mine()) is False
    assert isinstance(Mine(), Tracker)
