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


def test_the_paired_change_is_per_seed_with_a_t_interval():
    import pandas as pd
    from scipy import stats
    rows = []
    base = {"IDF1": [0.50, 0.60, 0.70, 0.80], "HOTA": [0.4, 0.4, 0.4, 0.4],
            "MOTA": [0.1, 0.2, 0.3, 0.4]}
    delta = {"IDF1": [-0.01, 0.02, -0.03, 0.00], "HOTA": [0.0] * 4, "MOTA": [0.1] * 4}
    for i, seed in enumerate([1003, 1000, 1002, 1001]):
        rows.append({"set": "crowd", "seed": seed, "tracker": "pbm",
                     **{m: base[m][i] for m in bench.METRICS}})
        rows.append({"set": "crowd", "seed": seed, "tracker": "pbm+switch",
                     **{m: base[m][i] + delta[m][i] for m in bench.METRICS}})
    out = bench.paired(pd.DataFrame(rows), "pbm", "pbm+switch").set_index("metric")
    idf1 = out.loc["IDF1"]
    d = pd.Series(delta["IDF1"])
    half = stats.t.ppf(0.975, 3) * d.std(ddof=1) / 2
    assert idf1["seeds"] == 4 and idf1["seeds losing"] == 2
    assert idf1["mean change"] == pytest.approx(-0.005, abs=1e-12)
    assert idf1["95% low"] == pytest.approx(-0.005 - half, abs=1e-12)
    assert idf1["95% high"] == pytest.approx(-0.005 + half, abs=1e-12)
    assert out.loc["HOTA", "seeds losing"] == 0 and out.loc["HOTA", "sd"] == pytest.approx(0)
    assert out.loc["MOTA", "mean change"] == pytest.approx(0.1)
