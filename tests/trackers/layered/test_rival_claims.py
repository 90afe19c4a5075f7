"""``adaptations.rival_claims`` (``selection.RivalClaims``): PBM 4.1's multiple-response
pruning of a target passes over the candidates another target claims, and leaves them to
the one-to-one assignment."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from occbench.trackers.layered import Adaptations
from occbench.trackers.layered.params import MatchParams, PruneParams
from occbench.trackers.layered.rules import OneToOne
from occbench.trackers.layered.selection import (
    FrameScores,
    MultipleResponsePruning,
    OwnRow,
    RivalClaims,
)


def _matches(rival_claims: bool, S: np.ndarray, heads: list | None = None,
             templates: bool = False) -> list[tuple[int, int]]:
    """Pruning of two targets found last frame (by default without head templates, with
    candidates whose heads lie 1 px apart), then the one-to-one assignment. With
    ``templates`` target 0's head template is the frame's patch at candidate 1's head."""
    scores = FrameScores.empty(*S.shape)
    scores.S[:] = S
    heads = [[112.0, 47.5, 11.5], [113.0, 48.5, 11.0]] if heads is None else heads
    cand = SimpleNamespace(head=np.array(heads))
    frame = np.random.default_rng(0).integers(0, 256, (200, 200, 3), dtype=np.uint8)
    hx, hy = int(heads[1][0]), int(heads[1][1])
    own = frame[hy:hy + 8, hx - 4:hx + 4].copy() if templates else None
    targets = SimpleNamespace(misses=np.array([0, 0]), head_template=[own, None])
    MultipleResponsePruning(MatchParams(), PruneParams(), Adaptations(rival_claims=rival_claims))(
        scores, cand, targets, frame)
    cost = np.where(np.isfinite(scores.S), 1.0 - scores.S, np.inf)
    matches, _, _ = OneToOne().assign(cost, 1.0 - MatchParams().match_threshold)
    return sorted(map(tuple, matches.tolist()))


def test_a_candidate_a_rival_claims_is_not_one_of_this_targets_responses():
    # cav1-150 gt seed 1001, frame 37 (docs/generalisation.md): the walker (target 1) passes
    # in front of the standing person (target 0); their detections' heads lie 1 px apart.
    # The walker scores the standing person's detection 0.484, its own 0.477; the standing
    # person's target scores them 0.82 and 0.75.
    S = np.array([[0.82, 0.75], [0.484, 0.477]])
    # the paper's pruning: one response (duplicate_radius) for each, the walker keeps the
    # standing person's detection and has none left after the assignment
    assert _matches(False, S) == [(0, 0)]
    # the standing person's target claims its detection: the walker keeps its own
    assert _matches(True, S) == [(0, 0), (1, 1)]


def test_where_the_head_template_decides_claims_do_not():
    # cav1-150 gt seed 1000, frame 39: heads 4 px apart (more than duplicate_radius), the
    # walker's (target 0's) template finds its own detection (1); the standing person's
    # target prefers that detection too (0.802 against its own 0.66)
    S = np.array([[0.516, 0.475], [0.66, 0.802]])
    heads = [[111.0, 47.0, 11.0], [115.0, 48.0, 9.5]]
    assert _matches(False, S, heads, templates=True) == [(0, 1), (1, 0)]
    assert _matches(True, S, heads, templates=True) == [(0, 1), (1, 0)]


def test_claims_are_a_rivals_best_scored_higher():
    S = np.array([[0.82, 0.75], [0.484, 0.477], [0.2, 0.3]])
    claimed = RivalClaims().claimed(S, 0.25)
    # candidate 0 is target 0's best: claimed against 1 and 2 (scored lower), never against 0;
    # candidate 1 is nobody's best at >= 0.25 (target 2's best is below the threshold)
    assert claimed.tolist() == [[False, False], [True, False], [True, False]]
    assert OwnRow().claimed(S, 0.25) is None
    assert RivalClaims().claimed(np.full((2, 2), -np.inf), 0.25) is None


def test_paper_mode_prunes_along_a_targets_own_row():
    paper = Adaptations.paper()
    assert isinstance(MultipleResponsePruning(MatchParams(), PruneParams(), paper).claims, OwnRow)
    assert not Adaptations().rival_claims  # off until measured
    on = Adaptations(rival_claims=True)
    assert set(on.changed()) - set(Adaptations().changed()) == {"rival_claims"}
    assert paper.changed() == []

