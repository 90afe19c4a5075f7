"""Paper mode is the paper (issue 26, item 1 for PBM): every rule the audit found on in
``tracker=pbm_paper`` is a paper-mode switch or a documented reading, and each switch picks
the paper's behaviour when off."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hydra.utils import instantiate

from occbench.trackers.layered import Adaptations, CandidateParams, PBMTracker
from occbench.trackers.layered.candidates import CandidateFinder, DetectorHeads, ProfileHeads
from occbench.trackers.layered.rules import build_rules
from occbench.trackers.records import Detections
from occbench.config.meta import without_meta

ADAPTATIONS_MD = Path(__file__).resolve().parents[3] / "docs" / "adaptations.md"

# The audit (issue 26): the rule, and its switch (an ``Adaptations`` field, off in paper
# mode) or the config key of a documented reading (paper mode keeps it; docs/adaptations.md
# names the key in the PBM part).
SWITCHES = {
    "difference models compared motion-compensated": "motion_compensation",
    "one-to-one Hungarian sharing": "one_to_one",
    "differences divided by (1 + m) after a gap": "gap_division",
    "KF2 holding an unfound target's size": "hold_size",
    "blob heads from top-profile peaks": "profile_heads",
    "blob boxes rescaled by a learnt ratio": "blob_box_ratio",
    "a blob with several heads always counted as merged": "several_heads_merge",
}
READINGS = {
    "births from detections, 3 matches to confirm": "life_cycle.min_hits",
    "90 frames to drop": "life_cycle.max_misses",
    "5 OCCLUDED frames": "reporting.max_misses",
    "p(d | theta) used as a survival function": "trackers/layered/feature_models.py",
    "a size floor on the gate": "gate.min_fraction",
    "normalised features": "PartFeatureExtractor",
}


def _trackers() -> tuple[PBMTracker, PBMTracker]:
    from occbench.config.build import compose_config

    return (instantiate(without_meta(compose_config(["tracker=pbm"]).tracker)),
            instantiate(without_meta(compose_config(["tracker=pbm_paper"]).tracker)))


def test_every_rule_of_the_audit_is_a_paper_mode_switch_or_a_documented_reading():
    ours, paper = _trackers()
    assert paper.adaptations == Adaptations.paper() and paper.adaptations.changed() == []
    assert ours.adaptations == Adaptations()
    for rule, name in SWITCHES.items():
        assert getattr(ours.adaptations, name) != getattr(paper.adaptations, name), rule
        assert name in ours.adaptations.changed(), rule
    text = ADAPTATIONS_MD.read_text()
    pbm_part = text[text.index("## PBM"):text.index("## Localisation")]
    for rule, key in {**READINGS, **{r: f"adaptations.{k}" for r, k in SWITCHES.items()}}.items():
        assert f"`{key}`" in pbm_part, f"{rule}: `{key}` not in the PBM part of {ADAPTATIONS_MD}"


def test_alone_lets_two_targets_take_one_candidate_and_one_to_one_does_not():
    """PBM 3, 4 step 4: each target tracked alone takes its best candidate; ours shares
    them one-to-one (as many pairs as possible)."""
    cost = np.array([[0.2, 0.5], [0.3, np.inf], [0.9, 0.95]])  # 1 - p; max cost 0.75
    alone = build_rules(Adaptations.paper()).sharing
    ours = build_rules(Adaptations()).sharing
    m, lost, free = alone.assign(cost, 0.75)
    assert m.tolist() == [[0, 0], [1, 0]] and lost.tolist() == [2] and free.tolist() == [1]
    m, lost, free = ours.assign(cost, 0.75)
    assert m.tolist() == [[0, 1], [1, 0]] and lost.tolist() == [2] and free.tolist() == []
    m, lost, free = alone.assign(np.zeros((0, 3)), 0.75)
    assert m.shape == (0, 2) and free.tolist() == [0, 1, 2]


def _two_people_blob() -> tuple[np.ndarray, np.ndarray]:
    """A 160 x 120 frame, one foreground blob of two people side by side (heads at columns
    30 and 70, the left one taller), dark hair on skin-coloured faces."""
    frame = np.full((120, 160, 3), 200, np.uint8)
    fg = np.zeros((120, 160), bool)
    for cx, top in ((30, 20), (70, 26)):
        fg[top:110, cx - 14:cx + 14] = True
        frame[top:110, cx - 14:cx + 14] = (90, 60, 40)  # clothes
        frame[top:top + 12, cx - 6:cx + 6] = (20, 20, 25)  # hair
        frame[top + 4:top + 14, cx - 5:cx + 5] = (120, 150, 200)  # face (BGR)
    fg[40:110, 44:56] = True  # joined at the shoulders
    return frame, fg


class _FixedHeads:
    """A head detector finding one head at a fixed xywh box (for DetectorHeads)."""

    def __init__(self, head: tuple[float, float, float, float]) -> None:
        self.head = np.array([head], dtype=np.float64)
        self.calls: list[np.ndarray] = []

    def detect(self, frame, foreground, boxes):
        return np.full((len(boxes), 4), np.nan)

    def heads_in(self, frame, foreground, box, max_heads):
        self.calls.append(np.asarray(box))
        return self.head[:max_heads]


@pytest.mark.parametrize("downsample", [1, 2])
def test_blob_heads_from_the_profile_or_from_the_head_detector(downsample):
    """``profile_heads``: a blob's heads are its top-profile peaks (two here); off, the head
    detector's heads in the blob's box (PBM 2.3), placed where it found them."""
    frame, fg = _two_people_blob()
    params = CandidateParams(min_blob_area=50, blob_downsample=downsample)
    cand = CandidateFinder(params, ProfileHeads(params)).find(fg, Detections.empty(), frame)
    assert len(cand) == 2 and (cand.heads_in_region == 2).all()
    assert sorted(np.round(cand.head[:, 0] / 10).tolist()) == [3, 7]
    detector = _FixedHeads((64.0, 26.0, 12.0, 14.0))
    params = CandidateParams(min_blob_area=50, blob_downsample=downsample, head_detector=detector)
    cand = CandidateFinder(params, DetectorHeads(params)).find(fg, Detections.empty(), frame)
    assert len(cand) == 1 and cand.heads_in_region.tolist() == [1]
    assert cand.head[0, 0] == pytest.approx(70.0, abs=downsample)
    assert cand.head[0, 1] == pytest.approx(26.0, abs=downsample)
    np.testing.assert_allclose(detector.calls[0], cand.region[0])


def test_the_papers_blob_heads_need_a_head_detector():
    with pytest.raises(ValueError,
                       match=r"^candidates\.head_detector .* adaptations\.profile_heads=false"):
        PBMTracker(adaptations=Adaptations(profile_heads=False))


def test_blob_boxes_are_rescaled_by_the_learnt_ratio_only_with_blob_box_ratio():
    """``blob_box_ratio``: an isolated person's detection is 1.25 x its blob's span, so a
    second, unexplained blob's box is grown by 1.25; off, it is the blob's span (PBM 2.1)."""
    fg = np.zeros((120, 200), bool)
    fg[20:100, 20:52] = True  # a person with a detection
    fg[20:100, 120:152] = True  # a person without
    det = Detections(np.array([[16.0, 15.0, 40.0, 100.0]]), np.ones(1))
    params = CandidateParams(min_blob_area=50, blob_downsample=1)
    for ratio, width in ((True, 40.0), (False, 32.0)):
        cand = CandidateFinder(params, blob_box_ratio=ratio).find(fg, det, None)
        blob = cand.blob.nonzero()[0]
        assert len(blob) == 1
        assert cand.box[blob[0], 2] == pytest.approx(width), ratio
        np.testing.assert_array_equal(cand.region[blob[0]], [120.0, 20.0, 32.0, 80.0])
