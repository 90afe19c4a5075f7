"""``adaptations.merge_found_elsewhere``: a larger detection PBM 3.1 searched as a merge,
whose other holders all took other candidates as measured, is the target grown
(``merges.FoundElsewhere``; issue 35, docs/adaptations.md)."""

from types import SimpleNamespace

import numpy as np

from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.gating import Carved, Gated
from occbench.trackers.layered.merges import AllHolders, FoundElsewhere
from occbench.trackers.layered.rules import build_rules
from occbench.trackers.layered.search import Candidates
from occbench.trackers.layered.selection import FrameScores


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
    assert isinstance(build_rules(Adaptations(merge_found_elsewhere=False,
                                              merge_recent_holder=False)).merge, AllHolders)
    assert Adaptations.paper().changed() == [] and Adaptations().merge_found_elsewhere


def _stairwell():
    """ecp1-180 gt seed 1000 frame 161 in small: candidate 0 (29 x 99, person 4 seen whole)
    holds the last box of target 0 (person 3's, 15 x 63, unfound 2 frames) and of target 1
    (person 4's, 29 x 47, found last frame); both are larger-region pairs."""
    region = np.array([[53.0, 87.0, 29.0, 99.0]])
    cand = Candidates(region, region.copy(), np.array([[68.0, 87.5, 14.5]]),
                      np.array([False]), np.array([1]))
    dof = np.array([[53.0, 107.0, 60.5, 138.5, 15.0, 63.0],
                    [51.0, 139.0, 65.5, 162.5, 29.0, 47.0]])
    targets = _Targets(dof=dof, misses=np.array([2, 0]))
    return np.array([[1], [1]]), cand, targets, np.array([True, True])


def _stairwell_pass(rule):
    kinds, cand, targets, live = _stairwell()
    rule.apply(kinds, cand, targets, live, 0.5)
    return targets, cand


def test_a_merge_taken_by_the_longer_missed_holder_is_the_recent_holder_grown():
    rule = FoundElsewhere(recent_holder=True)
    targets, cand = _stairwell_pass(rule)
    held, struck = rule.recent_pairs(_found([[0, 0]], [True]), targets, cand)
    assert held.tolist() == [[1, 0]] and struck.tolist() == [[0, 0]]
    targets, cand = _stairwell_pass(rule)  # the recent holder took something: the merge stands
    assert rule.recent_pairs(_found([[0, 0], [1, 1]], [True, False]), targets, cand)[0].size == 0
    targets, cand = _stairwell_pass(rule)
    targets.misses = np.array([2, 2])  # not found more recently: the merge stands
    assert rule.recent_pairs(_found([[0, 0]], [True]), targets, cand)[0].size == 0


def test_the_recent_holder_second_pass_strikes_the_merge_and_off_passes_once():
    for on in (True, False):
        rule = FoundElsewhere(recent_holder=on)
        calls, seen = [], []

        def block(frame, targets, cand, *rest, rule=rule, calls=calls, seen=seen):
            kinds, _, _, live = _stairwell()
            rule.apply(kinds, cand, targets, live, 0.5)
            S = np.array([[0.374], [0.366]])
            rule.strike(S)
            seen.append((kinds.tolist(), S[:, 0].tolist()))
            calls.append(1)
            return _found([[0, 0]] if len(calls) == 1 else [[1, 0]], [len(calls) == 1])

        _, cand, targets, _ = _stairwell()
        found = rule.associate(block, None, targets, cand)
        if on:
            assert seen == [([[1], [1]], [0.374, 0.366]), ([[1], [0]], [-np.inf, 0.366])]
            assert found.matches.tolist() == [[1, 0]]
        else:
            assert len(calls) == 1 and found.matches.tolist() == [[0, 0]]


def test_recent_holder_on_by_default_off_in_paper_mode_and_switched_apart():
    assert build_rules(Adaptations()).merge.recent_holder
    assert not build_rules(Adaptations(merge_recent_holder=False)).merge.recent_holder
    assert "merge_recent_holder" not in Adaptations.paper().changed()
    assert "merge_recent_holder" in Adaptations().changed()
    alone = build_rules(Adaptations(merge_found_elsewhere=False)).merge
    assert alone.recent_holder and not alone.found_elsewhere
    assert isinstance(build_rules(Adaptations(merge_found_elsewhere=False,
                                              merge_recent_holder=False)).merge, AllHolders)


def _pair_scores(calls):
    """Each pair's own p_j and p (as eqs. 11-13 are), recording the pairs scored."""
    def score(ti, n):
        calls.extend(zip(ti.tolist(), n.tolist()))
        p = 10.0 * ti + n
        return p[:, None] + np.arange(5.0), p
    return score


def _search(pairs, calls):
    """A ``Carved`` of each searched pair's own (kept when ti + n is even)."""
    def search():
        calls.append(len(pairs.search_ti))
        p = 100.0 + 10.0 * pairs.search_ti + pairs.search_n
        return Carved((pairs.search_ti + pairs.search_n) % 2 == 0, p, p[:, None] + np.zeros(5),
                      None, np.arange(len(p)), p[:, None] + np.arange(6.0))
    return search


def _gated(ti, n, search_ti, search_n, kind):
    return Gated(*(np.array(v, dtype=np.intp) for v in (ti, n, search_ti, search_n, kind)))


def test_the_second_pass_scores_only_what_the_first_did_not_score_alike():
    """The second pass (a grown pair moved from the searched to the measured pairs) takes
    every other pair's scores from the first and equals the pairs scored afresh
    (``AllHolders.score``), even after the pruning re-anchored a first-pass DOF; a pair the
    first pass did not search alike is searched again. Fails when the reuse mis-indexes."""
    first = _gated([0, 1], [0, 1], [0, 2, 2, 1], [2, 0, 2, 0], [1, 1, -1, 1])
    second = _gated([0, 0, 1], [0, 2, 1], [2, 2, 1], [0, 2, 0], [1, -1, 1])  # (0, 2) grown
    fe, calls, searches = FoundElsewhere(), [], []
    s1 = FrameScores.empty(3, 3)
    fe.score(s1, first, _pair_scores(calls), _search(first, searches))
    s1.dof_h[2] = -1.0  # the pruning re-anchors pair (2, 2)'s carved box
    fe._grown = np.array([[0, 2]])
    s2, ref = FrameScores.empty(3, 3), FrameScores.empty(3, 3)
    calls.clear()
    fe.score(s2, second, _pair_scores(calls), _search(second, searches))
    assert calls == [(0, 2)] and searches == [4]
    AllHolders().score(ref, second, _pair_scores([]), _search(second, []))
    assert np.array_equal(s2.S, ref.S) and np.array_equal(s2.pj, ref.pj)
    assert np.array_equal(s2.hyp >= 0, ref.hyp >= 0)
    on = ref.hyp >= 0
    assert np.array_equal(s2.dof_h[s2.hyp[on]], ref.dof_h[ref.hyp[on]])
    assert np.array_equal(s2.pj_h[s2.hyp[on]], ref.pj_h[ref.hyp[on]])
    other = _gated([0, 0, 1], [0, 2, 1], [2, 1], [1, 0], [1, 1])  # (2, 1): not searched before
    fe.score(FrameScores.empty(3, 3), other, _pair_scores([]), _search(other, searches))
    assert searches == [4, 2]


def test_a_block_starts_and_ends_with_no_template_match_kept():
    """Template matches are kept over one block's passes only (a match of another block's
    row ti is another target's)."""
    fe = FoundElsewhere()
    fe.matched[(0, b"")] = (1, None)
    seen = []
    found = SimpleNamespace(matches=np.zeros((0, 2), np.intp), chosen=None)
    fe.associate(lambda *a: seen.append(dict(fe.matched)) or found, None, None, None)
    assert seen == [{}] and fe.matched == {}


def test_the_holders_are_read_in_the_merge_candidates_own_region():
    # the cav1 scene with its two candidates swapped (the merge is candidate 1 now) and the
    # other moved away: the merge's holders are read in candidate 1's region, not 0's
    kinds, cand, t, live = _scene()
    swap = [1, 0]
    region = cand.region[swap]
    region[0, 0] += 100.0  # the standing person's own detection, moved off the merge
    cand = Candidates(region, region.copy(), cand.head[swap], cand.blob[swap],
                      cand.heads_in_region[swap])
    rule = FoundElsewhere(recent_holder=True)
    targets = _Targets(dof=t.dof, misses=np.array([0, 0]))
    rule.apply(kinds[:, swap].copy(), cand, targets, live, 0.5)
    found = _found([[0, 1], [1, 0]], [True, False])
    assert rule.grown_pairs(found, targets, cand).tolist() == [[0, 1]]
    targets.misses = np.array([2, 0])  # target 1 took its own: no recent holder left
    assert rule.recent_pairs(found, targets, cand)[0].size == 0
