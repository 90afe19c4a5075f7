"""``adaptations.rival_match`` (``rules.RivalMatch``): a target found last frame takes no
candidate scoring below ``rival`` x its last match's score when another target may take it."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.trackers.layered import Adaptations
from occbench.trackers.layered.dynamics import Gate
from occbench.trackers.layered.rules import OneToOne, RelativeMatch, RivalMatch, build_rules
from occbench.trackers.layered.targets import Targets


def _targets(misses, score) -> Targets:
    tg = Targets(Gate(3.0, 0.5, 2.0, 1.15, 6.0), (0.5, 0.2, 0.5), (0.2, 0.02, 0.5), 4, 3, 4)
    tg.misses, tg.score = np.array(misses), np.array(score, dtype=float)
    return tg


def _taker(rule, S, tg):
    """Which target takes candidate 0 after the rule (one-to-one, threshold 0.25)."""
    S = S.copy()
    rule.withhold(S, tg, 0.25)
    cost = np.where(np.isfinite(S), 1.0 - S, np.inf)
    matches, _, _ = OneToOne().assign(cost, 0.75)
    return {int(c): int(t) for t, c in matches}.get(0)


def test_a_neighbour_whose_person_was_missed_leaves_the_rivals_person_alone():
    # the case of cav1-150 gt seed 1001, frame 38: target 0 matched its person at 0.82 last
    # frame; its person is missed now, and the one detection is target 1's person (unfound
    # for 2 frames), which scores 0.63 for target 0 and 0.49 for target 1
    tg = _targets([0, 2], [0.82, 0.5])
    S = np.array([[0.63], [0.49]])
    assert _taker(RelativeMatch(0.5), S, tg) == 0  # off: the neighbour takes it
    assert _taker(RivalMatch(0.5, 0.8), S, tg) == 1  # on: its own target does
    # no rival (target 1 out of the gate): target 0 keeps what relative_match allows
    S1 = np.array([[0.63], [-np.inf]])
    assert _taker(RivalMatch(0.5, 0.8), S1, tg) == 0
    # a rival below the threshold is no rival
    assert _taker(RivalMatch(0.5, 0.8), np.array([[0.63], [0.2]]), tg) == 0
    # both found last frame and both below rival x their score: neither is held back
    tg2 = _targets([0, 0], [0.9, 0.9])
    assert _taker(RivalMatch(0.5, 0.8), np.array([[0.63], [0.6]]), tg2) == 0


def test_rival_match_keeps_relative_match_and_is_off_in_paper_mode():
    tg = _targets([0, 3], [0.8, 0.9])
    S = np.array([[0.3, 0.7], [0.3, -np.inf]])
    withheld = RivalMatch(0.5, 0.8).withhold(S, tg, 0.25)
    assert S[0, 0] == -np.inf and withheld.tolist() == [True, False]  # relative_match's strike
    assert isinstance(build_rules(Adaptations(rival_match=0.8)).match, RivalMatch)
    assert Adaptations.paper().rival_match == 0.0
    with pytest.raises(ValueError, match="rival_match"):
        Adaptations(rival_match=1.5)
