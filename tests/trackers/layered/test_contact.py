"""PBM parts at a contact (``adaptations.contact_frozen``, ``contact.FrozenAtContact``;
``adaptations.contact_colour``, ``contact.ColourAtContact``): a matched target's part whose
candidate rectangle lies under another target's box keeps its model (or its colour
histograms), as PBM 1-2 ask of a part under a major occlusion; the paper's 4.2 update by
p_j alone (``contact.AsMatched``) is the default."""

from __future__ import annotations

import numpy as np
import pbm_scenes as S
import pytest

from occbench.trackers.layered import Adaptations, PBMTracker
from occbench.trackers.layered.contact import (AsMatched, ColourAtContact, ContactOcclusion,
                                              FrozenAtContact, SizeOcclusion)
from occbench.trackers.layered.dynamics import Gate
from occbench.trackers.layered.model_update import contact_parts
from occbench.trackers.layered.parts import PartFeatureExtractor
from occbench.trackers.layered.rules import build_rules
from occbench.trackers.layered.targets import PartMatches, PartRates, Targets


def _two_targets() -> tuple[Targets, object]:
    frame = np.full((200, 200, 3), 90, np.uint8)
    full = np.zeros((200, 200), bool)
    full[40:130, 50:80] = True
    ex = PartFeatureExtractor(4, 35, 15)
    ex.start(frame, full)
    cand = ex.extract(np.array([[50.0, 40.0, 30.0, 90.0]]), np.array([0.5]), np.array([0.5]))
    tg = Targets(Gate(3.0, 0.5, 2.0, 1.15, 4.0), (0.5, 0.2, 0.5), (0.2, 0.02, 0.5), 4, 3, 4)
    tg.add(1, np.array([50.0, 40.0, 65.0, 85.0, 30.0, 90.0]), 0.5, 0.5, cand, None)
    # target 2's box lies over target 1's right torso-arm (and 6% of its right leg)
    tg.add(2, np.array([66.0, 54.0, 86.0, 74.0, 40.0, 40.0]), 0.5, 0.5, cand, None)
    return tg, cand


def _matches(tg: Targets, pj: np.ndarray, relearn: np.ndarray | None = None) -> PartMatches:
    return PartMatches(np.array([0]), np.array([0]), pj, np.zeros((1, 2)),
                       tg.dof[[0]][:, [0, 1, 4, 5]], tg.alpha[[0]], tg.beta[[0]], relearn)


def test_a_part_under_another_targets_box_is_at_a_contact():
    tg, cand = _two_targets()
    rows, ks = np.array([0]), np.array([0])
    assert contact_parts(tg.dof, tg.misses, rows, cand.parts, ks, 5, 0.5)[0].tolist() == [
        False, False, True, False, False]
    # a lower share reaches the right leg's 6 %; the image border is no contact
    assert contact_parts(tg.dof, tg.misses, rows, cand.parts, ks, 5, 0.05)[0].tolist() == [
        False, False, True, False, True]
    # an occluder unfound for longer than occluder_misses frames is no longer there
    tg.misses[1] = 6
    assert not contact_parts(tg.dof, tg.misses, rows, cand.parts, ks, 5, 0.05).any()


def _spoiled(tg: Targets) -> None:
    """Target 1's model moved off the candidate's: every feature differs."""
    m = tg.parts
    m.hsv[0] = np.roll(m.hsv[0], 1, axis=-1)
    m.xyz[0] = np.roll(m.xyz[0], 1, axis=-1)
    m.area[0] += 0.2
    m.perimeter[0] += 3.0


def test_each_rule_updates_what_it_says():
    rates, pj = PartRates(0.4, 0.3), np.full((1, 5), 0.9)
    changed = {}
    for rule in (AsMatched(), FrozenAtContact(0.5), ColourAtContact(0.5)):
        tg, cand = _two_targets()
        _spoiled(tg)
        before = tg.parts.copy()
        rule.update(tg, cand, _matches(tg, pj, np.zeros((1, 5), bool)), rates, 5)
        changed[type(rule).__name__] = [
            [not np.array_equal(getattr(tg.parts, f)[0, j], getattr(before, f)[0, j])
             for j in range(5)] for f in ("hsv", "xyz", "area", "perimeter")]
        flagged = tg.occluded_parts[0].tolist()
        assert flagged == ([False, False, True, False, False]
                           if isinstance(rule, FrozenAtContact) else [False] * 5)
    assert changed["AsMatched"] == [[True] * 5] * 4
    at_contact = [True, True, False, True, True]
    assert changed["FrozenAtContact"] == [at_contact] * 4
    assert changed["ColourAtContact"] == [at_contact, at_contact, [True] * 5, [True] * 5]
    # a stale part at a contact is not re-learned when frozen
    tg, cand = _two_targets()
    _spoiled(tg)
    before = tg.parts.copy()
    FrozenAtContact(0.5).update(tg, cand, _matches(tg, np.full((1, 5), 0.1), np.ones((1, 5), bool)),
                                rates, 5)
    assert np.array_equal(tg.parts.hsv[0, 2], before.hsv[0, 2])
    assert not np.array_equal(tg.parts.hsv[0, 1], before.hsv[0, 1])


def test_the_switch_is_off_in_paper_mode_and_by_default_and_checked():
    assert isinstance(build_rules(Adaptations()).contact, AsMatched)
    assert isinstance(build_rules(Adaptations(contact_frozen=0.5)).contact, FrozenAtContact)
    assert isinstance(build_rules(Adaptations(contact_colour=0.5)).contact, ColourAtContact)
    for name in ("contact_frozen", "contact_colour"):
        assert name not in Adaptations().changed()
        assert name not in Adaptations.paper().changed()
        with pytest.raises(ValueError, match=name):
            Adaptations(**{name: 1.5})
    with pytest.raises(ValueError, match="contact_colour"):
        Adaptations(contact_frozen=0.5, contact_colour=0.5)
    assert isinstance(build_rules(Adaptations()).window, SizeOcclusion)
    assert isinstance(build_rules(Adaptations(contact_occluded=0.5)).window, ContactOcclusion)
    assert "contact_occluded" not in Adaptations().changed() + Adaptations.paper().changed()


def _walker_passing() -> S.Scene:
    """Person 1 walks in front of the standing person 2."""
    a = S.walk(70, (30, 70), (3.0, 0.0), (30, 100))
    b = S.walk(70, (120, 62), (0.0, 0.0), (32, 110))
    return S.Scene(300, 220, [
        S.Person(1, a, shirt=(30, 30, 190), pants=(100, 70, 30), depth=1.0),
        S.Person(2, b, shirt=(40, 170, 40), pants=(50, 50, 50), hair=(30, 90, 150), depth=1.5),
    ], seed=4)


def _crossing(tracker: PBMTracker) -> tuple[int, int, int]:
    """Person 1 walks in front of the standing person 2. Counts, over (found target, part,
    frame): parts flagged frozen whose colour model changed, parts flagged frozen though
    they match (p_j >= 0.4), and parts whose colour model changed while their rectangle lay
    at least half under the other target's box."""
    scene = _walker_passing()
    changed_frozen = matched_frozen = learnt_under = 0
    for k in range(scene.length):
        img, lab = scene.render(k)
        before = {int(i): tracker.targets.parts.hsv[r].copy()
                  for r, i in enumerate(tracker.targets.id)}
        tracker.update(img, scene.detections(k, lab), lab)
        tg = tracker.targets
        for r, i in enumerate(tg.id.tolist()):
            if i not in before or tg.misses[r] > 0:
                continue
            after, flags = tg.parts.hsv[r], tg.occluded_parts[r]
            others = [tg.dof[o, [0, 1, 4, 5]] for o in range(len(tg)) if o != r]
            for j in range(5):
                moved = not np.array_equal(after[j], before[i][j])
                if flags[j] and moved:
                    changed_frozen += 1
                if flags[j] and tg.part_scores[r, j] >= 0.4:
                    matched_frozen += 1
                x, y, w, h = tg.parts.parts[r, j]
                under = max((max(min(x + w, o[0] + o[2]) - max(x, o[0]), 0)
                             * max(min(y + h, o[1] + o[3]) - max(y, o[1]), 0) / (w * h)
                             for o in others), default=0.0)
                if moved and under >= 0.5:
                    learnt_under += 1
    return changed_frozen, matched_frozen, learnt_under


def test_a_walker_in_front_of_a_standing_person_keeps_its_covered_parts():
    # the paper's update: parts half under the neighbour's box learn from its pixels
    changed, matched_frozen, learnt_under = _crossing(PBMTracker())
    assert changed == 0 and matched_frozen == 0 and learnt_under > 0
    # frozen at a contact: parts that match are frozen there, and none learns
    changed, matched_frozen, learnt_under = _crossing(PBMTracker(
        adaptations=Adaptations(contact_frozen=0.5)))
    assert changed == 0 and matched_frozen > 0 and learnt_under == 0
    # colour kept at a contact: no colour learnt there either, and no part flagged frozen
    changed, matched_frozen, learnt_under = _crossing(PBMTracker(
        adaptations=Adaptations(contact_colour=0.5)))
    assert matched_frozen == 0 and learnt_under == 0


def test_a_match_at_a_contact_is_occluded_for_the_global_update():
    tg, _ = _two_targets()
    # target 1's candidate box: 0.5 of it under target 2's box, then only 0.25
    dof = np.array([[50.0, 54.0, 66.0, 74.0, 32.0, 40.0], [42.0, 54.0, 58.0, 74.0, 32.0, 40.0]])
    carved = np.array([False, False])
    assert SizeOcclusion().occluded(tg, np.array([0, 0]), dof, carved, 5) is carved
    occluded = ContactOcclusion(0.5).occluded(tg, np.array([0, 0]), dof, carved, 5)
    assert occluded.tolist() == [True, False]
    assert ContactOcclusion(0.2).occluded(tg, np.array([0, 0]), dof, carved, 5).tolist() == [
        True, True]
    # a carved match stays occluded; an occluder unfound too long is no contact
    tg.misses[1] = 6
    assert ContactOcclusion(0.2).occluded(tg, np.array([0, 0]), dof, np.array([True, False]),
                                          5).tolist() == [True, False]
    assert not ContactOcclusion(0.2).occluded(tg, np.array([0, 0]), dof, carved, 5).any()


def test_a_contact_averages_the_global_model_and_keeps_the_carved_flag():
    """The walker in front of the standing person: with ``contact_occluded`` his box is the
    window's mean in some frame (not the candidate's), while ``targets.occluded`` still says
    only whether the match was carved (PBM 3.1), as without the rule."""
    scene = _walker_passing()
    runs = {}
    for share in (0.0, 0.5):
        tracker = PBMTracker(adaptations=Adaptations(contact_occluded=share))
        boxes, flags = [], []
        for k in range(scene.length):
            img, lab = scene.render(k)
            tracker.update(img, scene.detections(k, lab), lab)
            boxes.append(tracker.targets.dof.copy())
            flags.append(tracker.targets.occluded.copy())
        runs[share] = boxes, flags
    differ = [k for k in range(scene.length) if runs[0.0][0][k].shape != runs[0.5][0][k].shape
              or not np.array_equal(runs[0.0][0][k], runs[0.5][0][k])]
    assert differ
    k = differ[0]  # up to the first frame they differ in, the carved flags agree
    assert all(np.array_equal(runs[0.0][1][j], runs[0.5][1][j]) for j in range(k + 1))
