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
