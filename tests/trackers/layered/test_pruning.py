"""PBM multiple-response pruning (PBM 4.1): ambiguous candidates whose heads coincide are
one response, kept without a head-template match (``duplicate_radius``); a long-lost
target's stale template prunes nothing (``prune_max_misses``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hydra.utils import instantiate
from omegaconf import OmegaConf

from occbench.datasets.synthetic import load_scenario
from occbench.sources.annotations import NoisyGroundTruth
from occbench.config.meta import without_meta
from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.params import MatchParams, PruneParams
from occbench.trackers.layered.selection import MultipleResponsePruning, _norms

ROOT = Path(__file__).resolve().parents[3]


def _template_matches(duplicate_radius: float, prune_max_misses: int = 5,
                      misses: list | None = None) -> list[np.ndarray]:
    """The candidate heads (K, 2) of every head-template match of pbm on a crowd (and, in
    ``misses``, the frames the matched target had been unfound)."""
    cfg = without_meta(OmegaConf.load(ROOT / "conf" / "tracker" / "pbm.yaml"))
    cfg.adaptations.duplicate_radius = duplicate_radius
    cfg.adaptations.prune_max_misses = prune_max_misses
    tracker = instantiate(cfg)
    calls: list[np.ndarray] = []
    prune = tracker._pruning.match_template

    def recorded(template, cands, heads, frame):
        calls.append(np.array(heads, dtype=np.float64))
        if misses is not None:
            tg = tracker.targets
            (ti,) = [i for i, t in enumerate(tg.head_template) if t is template]
            misses.append(int(tg.misses[ti]))
        return prune(template, cands, heads, frame)

    tracker._pruning.match_template = recorded
    seq = load_scenario("crowd", seed=0, length=60, people=10)
    src = NoisyGroundTruth(seed=0)
    src.start(seq)
    for k in range(1, 61):
        frame = seq.frame(k)
        tracker.update(frame, src.detect(k, frame)[0], seq.foreground(k))
    return calls


def _coinciding(calls: list[np.ndarray]) -> int:
    """Matches among at least two candidates whose heads all lie within 1 pixel."""
    return sum(len(h) > 1 and np.ptp(h, axis=0).max() <= 1.0 for h in calls)


def test_coinciding_heads_are_one_response():
    always = _template_matches(-1.0)
    default = _template_matches(0.25)
    assert _coinciding(always) > 0  # the crowd has such responses
    assert _coinciding(default) == 0
    assert len(default) < len(always)


def test_a_long_lost_target_is_not_pruned_by_its_stale_template():
    always, default = [], []
    _template_matches(0.25, 10_000, always)
    _template_matches(0.25, 5, default)
    assert max(always) > 5  # the crowd has such targets
    assert default and max(default) <= 5


def _nearby_row(pruning, row, amb, best, heads):
    """One row's responses as the pruning loop read them before they were stacked: the
    candidates at p >= its threshold, their distances from r's head, those within the radius."""
    m = pruning.matching
    lo = m.match_threshold if amb else m.weak_threshold
    cands = (row >= lo).nonzero()[0]
    r = best if best >= 0 else int(np.argmax(row))
    hw = max(heads[r, 2], 1.0)
    dist = _norms(heads[cands, :2] - heads[r, :2])
    near = dist <= pruning.pruning.radius * hw
    return cands[near], hw, dist[near]


def test_stacked_responses_equal_each_rows_own_bit_for_bit():
    pruning = MultipleResponsePruning(MatchParams(), PruneParams(), Adaptations())
    m, rng = pruning.matching, np.random.default_rng(3)
    checked = 0
    for case in range(60):
        R, N = int(rng.integers(1, 7)), int(rng.integers(1, 12))
        S = rng.choice([-np.inf, m.weak_threshold, m.match_threshold, 0.3, 0.95], size=(R, N))
        S = np.where(rng.random((R, N)) < 0.5, rng.random((R, N)), S)
        if case % 7 == 0:
            S[0, 0] = np.nan
        heads = np.c_[rng.normal(100, 30, (N, 2)), rng.choice([0.0, 0.5, 1.0, 9.0, 20.0], N)]
        heads[rng.random(N) < 0.2, :2] = heads[0, :2]  # ties: coincident heads
        amb = rng.random(R) < 0.5
        best = np.where(amb, rng.integers(0, N, R), -1)
        near, hw, dist = pruning._nearby(S, amb, best, heads)
        for k in range(R):
            cands, hw_k, dist_k = _nearby_row(pruning, S[k], bool(amb[k]), int(best[k]), heads)
            assert np.array_equal(near[k].nonzero()[0], cands)
            assert hw[k].tobytes() == np.float64(hw_k).tobytes()
            assert dist[k][cands].tobytes() == dist_k.tobytes()
            checked += len(cands)
    assert checked > 100
    empty = pruning._nearby(np.zeros((0, 4)), np.zeros(0, bool), np.zeros(0, np.intp),
                            np.ones((4, 3)))
    assert [v.shape for v in empty] == [(0, 4), (0,), (0, 4)]


def test_a_kept_template_match_is_made_once_per_row_and_candidates():
    """``matched`` (a block's passes, ``merges.FoundElsewhere``) keeps each (row,
    candidates) match: the second pass's same row and candidates take the first's, another
    row or other candidates are matched; without it every call matches."""
    pruning = MultipleResponsePruning(MatchParams(), PruneParams(), Adaptations())
    calls = []
    pruning.match_template = lambda template, cands, heads, frame: calls.append(cands) or (
        len(calls), None)
    a, b = np.array([1, 2]), np.array([1, 3])
    kept: dict = {}
    got = [pruning._matched(kept, ti, None, c, None, None) for ti, c in ((0, a), (0, a), (1, a), (0, b))]
    assert [g[0] for g in got] == [1, 1, 2, 3] and len(calls) == 3
    assert pruning._matched(None, 0, None, a, None, None)[0] == 4
