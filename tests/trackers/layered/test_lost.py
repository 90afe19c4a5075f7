"""``adaptations.reported_first``: the reported targets share the candidates first; a target
unfound past ``reporting.max_misses`` takes none they take (``lost.ReportedFirst``); off,
every target in one assignment (``lost.AllAtOnce``)."""

from types import SimpleNamespace

import numpy as np
import pytest

from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.lost import AllAtOnce, ReportedFirst
from occbench.trackers.layered.rules import Alone, OneToOne, build_rules


def _targets(*misses, boxes=None, shift=None):
    T = len(misses)
    boxes = np.zeros((T, 4)) if boxes is None else np.array(boxes, dtype=float)
    shift = np.zeros((T, 2)) if shift is None else np.array(shift, dtype=float)
    return SimpleNamespace(misses=np.array(misses), boxes=boxes, predicted_shift=lambda: shift)


def _shared(rule, S, misses, sharing=OneToOne()):
    """The (target, candidate) pairs ``sharing`` makes after ``rule`` struck S."""
    S = np.array(S, dtype=float)
    rule.strike(S, _targets(*misses), sharing, 0.75)
    matches, _, _ = sharing.assign(np.where(np.isfinite(S), 1.0 - S, np.inf), 0.75)
    return sorted(map(tuple, matches.tolist()))


def test_a_lost_target_does_not_take_a_reported_targets_candidate():
    # the stairwell at 168: target 0 lost (9 frames), target 1 found last frame; one detection
    S = [[0.513], [0.463]]
    assert _shared(AllAtOnce(), S, (9, 0)) == [(0, 0)]
    assert _shared(ReportedFirst(5), S, (9, 0)) == [(1, 0)]


def test_a_lost_target_keeps_a_candidate_no_reported_target_takes():
    S = [[0.6, 0.5], [0.7, -np.inf]]
    assert _shared(ReportedFirst(5), S, (9, 0)) == [(0, 1), (1, 0)]
    S = [[0.6, 0.5], [0.2, -np.inf]]  # below the threshold (cost 0.8 > 0.75): not taken
    assert _shared(ReportedFirst(5), S, (9, 0)) == [(0, 0)]


def test_the_tier_is_reporting_max_misses():
    S = [[0.513], [0.463]]
    assert _shared(ReportedFirst(5), S, (5, 0)) == [(0, 0)]  # still reported: one assignment
    assert _shared(ReportedFirst(5), S, (6, 0)) == [(1, 0)]
    assert _shared(ReportedFirst(5), S, (9, 7)) == [(0, 0)]  # both lost: as before


def test_the_reported_targets_choose_by_the_sharing_given():
    # alone, both reported targets take candidate 0: the lost one may not take it either
    S = [[0.9, 0.3], [0.8, -np.inf], [0.95, 0.2]]
    rule = ReportedFirst(5)
    S1 = np.array(S)
    rule.strike(S1, _targets(0, 0, 9), Alone(), 0.75)
    assert S1[2].tolist() == [-np.inf, 0.2]
    S2 = np.array(S)
    rule.strike(S2, _targets(0, 0, 9), OneToOne(), 0.75)
    assert S2[2].tolist() == [-np.inf, -np.inf]  # one-to-one: 0 takes 1 (0.3), 1 takes 0


def test_with_stay_a_lost_target_keeps_a_candidate_where_it_would_be_reported():
    S = np.array([[0.513], [0.463]])
    det = np.array([[163.0, 64.0, 31.0, 91.0]])
    # ecp1-180 sil frame 98: person 2's target, last at [167 66 23 62], IoU 0.505 with the box
    behind = _targets(13, 0, boxes=[[167, 66, 23, 62], [165, 62, 31, 91]])
    kept = S.copy()
    ReportedFirst(5, 0.5).strike(kept, behind, OneToOne(), 0.75, det)
    assert kept.tolist() == S.tolist()
    struck = S.copy()
    ReportedFirst(5).strike(struck, behind, OneToOne(), 0.75, det)  # no stay: struck
    assert struck[0, 0] == -np.inf
    # the stairwell: target 4's last box [54 108 15 63] against person 4's [62 86 27 102]
    stair = _targets(9, 0, boxes=[[54, 108, 15, 63], [54, 86, 29, 101]])
    S2 = S.copy()
    ReportedFirst(5, 0.5).strike(S2, stair, OneToOne(), 0.75, np.array([[62.0, 86, 27, 102]]))
    assert S2[0, 0] == -np.inf and S2[1, 0] == 0.463


def test_stay_reads_the_box_moved_by_kf1s_prediction():
    S = np.array([[0.6], [0.5]])
    det = np.array([[130.0, 66.0, 23.0, 62.0]])  # 30 px right of the last box
    still = _targets(9, 0, boxes=[[100, 66, 23, 62], [125, 60, 25, 70]])
    S1 = S.copy()
    ReportedFirst(5, 0.5).strike(S1, still, OneToOne(), 0.75, det)
    assert S1[0, 0] == -np.inf
    moving = _targets(9, 0, boxes=[[100, 66, 23, 62], [125, 60, 25, 70]],
                      shift=[[30, 0], [0, 0]])
    S2 = S.copy()
    ReportedFirst(5, 0.5).strike(S2, moving, OneToOne(), 0.75, det)
    assert S2[0, 0] == 0.6


def test_paper_and_default_share_in_one_assignment_and_the_switch_builds_the_rule():
    assert isinstance(build_rules(Adaptations.paper()).lost, AllAtOnce)
    assert isinstance(build_rules(Adaptations()).lost, AllAtOnce)
    assert build_rules(Adaptations(reported_first=True), 3).lost == ReportedFirst(3)
    assert build_rules(Adaptations(reported_first=True, reported_first_stay=0.5),
                       3).lost == ReportedFirst(3, 0.5)
    with pytest.raises(ValueError, match="reported_first_stay"):
        Adaptations(reported_first_stay=0.5)
    assert "reported_first" not in Adaptations.paper().changed()


def test_with_head_a_lost_target_keeps_a_candidate_whose_head_is_at_its_heads_height():
    S = np.array([[0.513], [0.463]])
    # ecp1-180 sil frame 98: person 2's target, head band rows 66-75, the pair's box's 64-77
    behind = _targets(13, 0, boxes=[[167, 66, 23, 62], [165, 62, 31, 91]])
    kept = S.copy()
    ReportedFirst(5, head=True).strike(kept, behind, OneToOne(), 0.75,
                                       np.array([[163.0, 64, 31, 91]]))
    assert kept.tolist() == S.tolist()
    # the stairwell (ecp1-180 gt 168): target 4's head band, rows 108-117, below person 4's, 86-100
    stair = _targets(9, 0, boxes=[[54, 108, 15, 63], [54, 86, 29, 101]])
    S2 = S.copy()
    ReportedFirst(5, head=True).strike(S2, stair, OneToOne(), 0.75,
                                       np.array([[62.0, 86, 27, 102]]))
    assert S2[0, 0] == -np.inf and S2[1, 0] == 0.463
    # anywhere along the row: the head's height, not the box's place, decides
    far = _targets(13, 0, boxes=[[20, 66, 23, 62], [165, 62, 31, 91]])
    S3 = S.copy()
    ReportedFirst(5, head=True).strike(S3, far, OneToOne(), 0.75, np.array([[163.0, 64, 31, 91]]))
    assert S3.tolist() == S.tolist()


def test_head_reads_the_last_box_not_kf1s_prediction():
    # cav1-150 sil frame 19: person 5's target, unfound 10 frames, last at [91 50 23 63], KF1's
    # prediction 9 rows lower; his detection [89 48 23 63]: kept
    S = np.array([[0.590], [0.422]])
    det = np.array([[89.0, 48.0, 23.0, 63.0]])
    stood = _targets(10, 0, boxes=[[91, 50, 23, 63], [95, 52, 23, 63]], shift=[[6, 9], [0, 0]])
    S1 = S.copy()
    ReportedFirst(5, head=True).strike(S1, stood, OneToOne(), 0.75, det)
    assert S1.tolist() == S.tolist()
    S2 = S.copy()
    ReportedFirst(5).strike(S2, stood, OneToOne(), 0.75, det)  # no head: struck
    assert S2[0, 0] == -np.inf


def test_the_head_switch_builds_the_rule_and_needs_reported_first():
    assert build_rules(Adaptations(reported_first=True, reported_first_head=True),
                       3).lost == ReportedFirst(3, 0.0, True)
    with pytest.raises(ValueError, match="reported_first_head"):
        Adaptations(reported_first_head=True)
    assert "reported_first_head" not in Adaptations.paper().changed()
