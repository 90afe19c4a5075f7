"""``adaptations.weak_ranked`` (``selection.RankedAtThreshold``): weak candidates the head
template validates (PBM 4.1) enter the assignment ranked by their own scores, not tied at
``matching.match_threshold``."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from occbench.trackers.layered import Adaptations
from occbench.trackers.layered.params import MatchParams, PruneParams
from occbench.trackers.layered.rules import OneToOne
from occbench.trackers.layered.selection import (
    AtThreshold,
    FrameScores,
    MultipleResponsePruning,
    RankedAtThreshold,
)


def _matches(weak_ranked: bool, S: np.ndarray) -> list[tuple[int, int]]:
    """Pruning of two targets whose head templates both match at the one candidate's head
    (the frame's patch there), then the one-to-one assignment."""
    frame = np.random.default_rng(1).integers(0, 256, (120, 120, 3), dtype=np.uint8)
    own = frame[50:58, 56:64].copy()
    scores = FrameScores.empty(*S.shape)
    scores.S[:] = S
    cand = SimpleNamespace(head=np.array([[60.0, 50.0, 8.0]]))
    targets = SimpleNamespace(misses=np.array([1, 0]), head_template=[own, own.copy()])
    MultipleResponsePruning(MatchParams(), PruneParams(), Adaptations(weak_ranked=weak_ranked))(
        scores, cand, targets, frame)
    cost = np.where(np.isfinite(scores.S), 1.0 - scores.S, np.inf)
    matches, _, _ = OneToOne().assign(cost, 1.0 - MatchParams().match_threshold)
    return matches.tolist()


def test_two_validated_weak_targets_are_ranked_by_their_scores():
    # pets1-400 sil frame 53 (docs/generalisation.md): target 2 (standing person 16's, first
    # row) scores person 20's detection 0.141, target 3 (person 20's) 0.2; both weak, both
    # templates validate it, both rows then hold 0.25 and the tie goes to the first row
    S = np.array([[0.141], [0.2]])
    assert _matches(False, S) == [[0, 0]]
    assert _matches(True, S) == [[1, 0]]


def test_the_rank_keeps_validated_weak_matches_below_real_ones():
    assert AtThreshold().value(0.2, 0.25) == 0.25
    assert AtThreshold().value(0.3, 0.25) == 0.3
    ranked = RankedAtThreshold()
    assert 0.25 < ranked.value(0.141, 0.25) < ranked.value(0.2, 0.25) < 0.25 + 1e-6
    assert ranked.value(0.3, 0.25) == 0.3


def test_paper_mode_ties_validated_weak_candidates():
    paper = Adaptations.paper()
    assert isinstance(MultipleResponsePruning(MatchParams(), PruneParams(), paper).weak, AtThreshold)
    assert not Adaptations().weak_ranked  # off until measured
    on = Adaptations(weak_ranked=True)
    assert "weak_ranked" in on.changed() and paper.changed() == []
