"""occbench.sweeps.plots: intervals that respect each metric's range, a grid with one legend."""

from __future__ import annotations

import numpy as np
import pandas as pd

from occbench.sweeps.plots import plot_sweep
from occbench.sweeps.tables import interval


def test_the_interval_stays_inside_the_values_seen():
    v = np.array([0.99, 1.0, 0.97])  # a t-interval of these three reaches above 1
    mean, low, high = interval(v)
    assert 0.97 <= low <= mean <= high <= 1.0
    assert interval(np.array([0.0, 0.0, 0.0])) == (0.0, 0.0, 0.0)  # IDs never below 0
    assert interval(np.array([0.5])) == (0.5, 0.5, 0.5)
    assert interval(v) == interval(v)  # seeded: the same figure twice


def test_a_sweep_plot_is_written_per_parameter(tmp_path):
    rng = np.random.default_rng(1000)
    rows = [{"job": j, "tracker.max_age": a, "seed": s, "status": "done",
             "sequence": "COMBINED", "tracker": t, "HOTA": rng.uniform(0.5, 1.0),
             "IDs": int(rng.integers(0, 3))}
            for j, (a, s) in enumerate((a, s) for a in (1, 3) for s in range(3))
            for t in ("baseline", "reta")]
    written = plot_sweep(pd.DataFrame(rows), tmp_path, ["HOTA", "IDs"])
    assert [p.name for p in written] == ["sweep_tracker_max_age.png"]
    assert written[0].stat().st_size > 0
