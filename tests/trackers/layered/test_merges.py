"""``adaptations.merge_found_elsewhere``: a larger detection PBM 3.1 searched as a merge,
whose other holders all took other candidates as measured, is the target grown
(``merges.FoundElsewhere``; issue 35, docs/adaptations.md)."""

from types import SimpleNamespace

import numpy as np

from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.merges import AllHolders, FoundElsewhere
from occbench.trackers.layered.rules import build_rules
from occbench.trackers.layered.search import Candidates


def _scene(blob=False, heads=1):
    """cav1-150 gt seed 1001 frame 35 in small: target 0 (13 x 63, the walker) and target
    1 (23 x 63, the standing person, whose last box was the walker's detection) both lie in
    candidate 0 (22 x 63, the walker's detection); candidate 1 is the standing person's own."""
    region = np.array([[101.0, 49.0, 22.0, 63.0], [100.0, 47.0, 25.0, 68.0]])
    cand = Candidates(region, region.copy(), np.array([[112.0, 49.0, 6.0], [112.0, 47.0, 6.0]]),
                      np.array([blob, False]), np.array([heads, 1]))
    dof = np.array([[97.0, 49.0, 103.5, 80.5, 13.0, 63.0],
                    [98.0, 49.0, 109.5, 80.5, 23.0, 63.0]])
    kinds = np.array([[1, 1], [0, 0]])  # candidate 0 larger than target 0's prediction
    return kinds, cand, SimpleNamespace(dof=dof), np.array([True, True])


class _Targets(SimpleNamespace):
    def __len__(self):
        return len(self.dof)


def _found(matches, occluded):
    return SimpleNamespace(matches=np.array(matches, dtype=np.intp).reshape(-1, 2),
                           chosen=SimpleNamespace(occluded=np.array(occluded, dtype=bool)))


def _first_pass(rule, blob=False, heads=1):
    kinds, cand, t, live = _scene(blob, heads)
    targets = _Targets(dof=t.dof)
    rule.apply(kinds, cand, targets, live, 0.5)
    return targets, cand


def test_a_merge_whose_other_holder_took_its_own_detection_is_the_target_grown():
    rule = FoundElsewhere()
    targets, cand = _first_pass(rule)
    pairs = rule.grown_pairs(_found([[0, 0], [1, 1]], [True, False]), targets, cand)
    assert pairs.tolist() == [[0, 0]]


def test_a_merge_stands_while_the_other_holder_is_unfound_or_inside_it():
    rule = FoundElsewhere()
    targets, cand = _first_pass(rule)
    assert rule.grown_pairs(_found([[0, 0]], [True]), targets, cand).size == 0  # 1 unfound
    targets, cand = _first_pass(rule)
    assert rule.grown_pairs(_found([[0, 0], [1, 1]], [True, True]), targets, cand).size == 0
    targets, cand = _first_pass(rule)  # target 0 taken unoccluded: nothing to re-read
    assert rule.grown_pairs(_found([[0, 0], [1, 1]], [False, False]), targets, cand).size == 0


def test_blobs_and_several_heads_keep_the_merge():
    for blob, heads in ((True, 1), (False, 2)):
        rule = FoundElsewhere()
        targets, cand = _first_pass(rule, blob, heads)
        assert rule.grown_pairs(_found([[0, 0], [1, 1]], [True, False]), targets, cand).size == 0


def test_the_second_pass_reads_the_pair_unoccluded_and_the_paper_passes_once():
    rule = FoundElsewhere()
    calls, seen = [], []

    def block(frame, targets, cand, *rest):
        kinds, _, _, live = _scene()
        rule.apply(kinds, cand, targets, live, 0.5)
        seen.append(kinds.tolist())
        calls.append(1)
        return _found([[0, 0], [1, 1]], [len(calls) == 1, False])

    _, cand, t, _ = _scene()
    found = rule.associate(block, None, _Targets(dof=t.dof), cand)
    assert len(calls) == 2 and seen == [[[1, 1], [0, 0]], [[0, 1], [0, 0]]]
    assert not found.chosen.occluded.any()
    calls.clear()
    AllHolders().associate(lambda *a: calls.append(1), None, None, None)
    assert len(calls) == 1


def test_on_by_default_and_off_in_paper_mode():
    assert isinstance(build_rules(Adaptations()).merge, FoundElsewhere)
    assert isinstance(build_rules(Adaptations.paper()).merge, AllHolders)
    assert isinstance(build_rules(Adaptations(merge_found_elsewhere=False)).merge, AllHolders)
    assert Adaptations.paper().changed() == [] and Adaptations().merge_found_elsewhere
