"""``adaptations.distinct_detections`` (``selection.DetectionsApart``): coinciding heads are
one response (``duplicate_radius``) only when a blob's head is among them; two detections
are two people, left to the one-to-one assignment."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from occbench.trackers.layered import Adaptations
from occbench.trackers.layered.params import MatchParams, PruneParams
from occbench.trackers.layered.rules import OneToOne
from occbench.trackers.layered.selection import (DetectionsApart, FrameScores,
                                                 MultipleResponsePruning, OneResponse)


def _matches(distinct: bool, S: np.ndarray, blob: list[bool]) -> list[tuple[int, int]]:
    """Pruning of two targets found last frame (no head templates) over two candidates
    whose heads lie 1.4 px apart, then the one-to-one assignment."""
    scores = FrameScores.empty(*S.shape)
    scores.S[:] = S
    cand = SimpleNamespace(head=np.array([[112.0, 47.5, 11.5], [113.0, 48.5, 11.0]]),
                           blob=np.array(blob))
    frame = np.zeros((200, 200, 3), dtype=np.uint8)
    targets = SimpleNamespace(misses=np.array([0, 0]), head_template=[None, None])
    MultipleResponsePruning(MatchParams(), PruneParams(),
                            Adaptations(distinct_detections=distinct))(scores, cand, targets, frame)
    cost = np.where(np.isfinite(scores.S), 1.0 - scores.S, np.inf)
    matches, _, _ = OneToOne().assign(cost, 1.0 - MatchParams().match_threshold)
    return sorted(map(tuple, matches.tolist()))


def test_two_detections_with_coinciding_heads_are_two_people():
    # cav1-150 gt seed 1001, frame 37 (docs/generalisation.md, eighth round): the walker
    # (target 1) passes in front of the standing person (target 0); the walker scores the
    # standing person's detection 0.570, its own 0.564; the standing person's target 0.82
    # and 0.75. One response each: both keep detection 0 and the walker is left with none.
    S = np.array([[0.82, 0.75], [0.570, 0.564]])
    assert _matches(False, S, [False, False]) == [(0, 0)]
    assert _matches(True, S, [False, False]) == [(0, 0), (1, 1)]


def test_a_blob_head_among_them_keeps_one_response():
    S = np.array([[0.82, 0.75], [0.570, 0.564]])
    assert _matches(True, S, [False, True]) == [(0, 0)]


def test_off_by_default_and_in_paper_mode():
    paper = Adaptations.paper()
    assert isinstance(MultipleResponsePruning(MatchParams(), PruneParams(), paper).coinciding,
                      OneResponse)
    assert isinstance(MultipleResponsePruning(MatchParams(), PruneParams(),
                                              Adaptations()).coinciding, OneResponse)
    on = Adaptations(distinct_detections=True)
    assert isinstance(MultipleResponsePruning(MatchParams(), PruneParams(), on).coinciding,
                      DetectionsApart)
    assert paper.changed() == [] and "distinct_detections" in on.changed()
