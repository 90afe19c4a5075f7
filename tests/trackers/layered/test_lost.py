"""``adaptations.reported_first``: the reported targets share the candidates first; a target
unfound past ``reporting.max_misses`` takes none they take (``lost.ReportedFirst``); off,
every target in one assignment (``lost.AllAtOnce``)."""

from types import SimpleNamespace

import numpy as np

from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.lost import AllAtOnce, ReportedFirst
from occbench.trackers.layered.rules import Alone, OneToOne, build_rules


def _targets(*misses):
    return SimpleNamespace(misses=np.array(misses))


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


def test_paper_and_default_share_in_one_assignment_and_the_switch_builds_the_rule():
    assert isinstance(build_rules(Adaptations.paper()).lost, AllAtOnce)
    assert isinstance(build_rules(Adaptations()).lost, AllAtOnce)
    assert build_rules(Adaptations(reported_first=True), 3).lost == ReportedFirst(3)
    assert "reported_first" not in Adaptations.paper().changed()
