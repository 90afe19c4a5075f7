"""benchmarks/bench_switch_hd.py: a tracker switch against its defaults on synthetic crowd
scenes at a large frame size, on seeds nobody chose anything on."""

from __future__ import annotations

import pytest
from benchmark_scripts import load
from omegaconf import OmegaConf

bench = load("bench_switch_hd")


def test_the_switch_row_differs_from_the_defaults_in_that_key_only():
    configs = bench.trackers("pbm", ["adaptations.large_head_pyramid=48",
                                     "adaptations.large_head_peaks=3"])
    base, changed = configs["pbm"], configs["pbm+switch"]
    assert base.adaptations.large_head_pyramid == 0 and changed.adaptations.large_head_pyramid == 48
    assert base.adaptations.large_head_peaks == 1 and changed.adaptations.large_head_peaks == 3
    changed.adaptations.large_head_pyramid, changed.adaptations.large_head_peaks = 0, 1
    assert OmegaConf.to_container(changed) == OmegaConf.to_container(base)


def test_an_unknown_key_and_a_chosen_on_seed_are_refused():
    with pytest.raises(SystemExit, match="no key adaptations.no_such_switch"):
        bench.trackers("pbm", ["adaptations.large_head_peaks=3", "adaptations.no_such_switch=1"])
    with pytest.raises(SystemExit, match="below 1000"):
        bench.crowd_set(150, (1920, 1080), [1000, 15], 150, 0.3)
    s = bench.crowd_set(150, (1920, 1080), [1000, 1001], 150, 0.3)
    assert s.seeds == (1000, 1001) and "dataset.width=1920" in s.overrides
