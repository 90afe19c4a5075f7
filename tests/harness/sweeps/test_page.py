"""The sweep page agrees with the sweep's PNG and sweep.md (issue 39 item 6): one interval
computation (``aggregate``'s bootstrap, never below 0 for counts), the trackers' own colours,
the best settings ranked on ours, never on the baseline."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pandas as pd
import yaml

from occbench.report.html import charts
from occbench.sweeps.gather import aggregate, gather, write_sweep
from occbench.sweeps.resume import write_status

# miss_rate -> seed -> (baseline IDF1, reta IDF1, reta IDs): the baseline is best at 0.0,
# reta at 0.1; reta's IDs at 0.1 (0, 0, 38) gave "12.67 ± 54" on the page (a t-interval)
FIGURES = {0.0: [(0.9, 0.5, 1), (0.9, 0.5, 2), (0.9, 0.5, 1)],
           0.1: [(0.6, 0.8, 0), (0.6, 0.8, 0), (0.6, 0.8, 38)]}


def _stress_sweep(root: Path) -> None:
    num = 0
    for rate, seeds in FIGURES.items():
        for seed, (base, reta, ids) in enumerate(seeds):
            d = root / str(num)
            (d / ".hydra").mkdir(parents=True)
            overrides = [f"detector.miss_rate={rate}", f"seed={seed}"]
            (d / ".hydra" / "overrides.yaml").write_text(yaml.safe_dump(overrides))
            (d / "config.yaml").write_text(yaml.safe_dump({"objective": {"tracker": None}}))
            rows = [{"tracker": t, "sequence": s, "IDF1": f, "IDs": i}
                    for t, f, i in (("baseline", base, 3), ("reta", reta, ids))
                    for s in ("a", "COMBINED")]
            pd.DataFrame(rows).to_csv(d / "metrics.csv", index=False)
            write_status(d, "done", overrides, base)
            num += 1


def test_the_page_reads_the_plots_intervals_colours_and_ranks_on_ours(tmp_path):
    _stress_sweep(tmp_path)
    write_sweep(tmp_path, ["IDF1", "IDs"])
    page = (tmp_path / "report.html").read_text()
    md = (tmp_path / "sweep.md").read_text()
    assert "Ranked on the COMBINED IDF1 of reta" in page  # not the baseline, listed first
    best = page[page.index("Ranked on"):page.index('id="parameters"')]
    assert best.index("0.1") < best.index("0.0")  # reta's best miss rate first
    assert "±" not in page and "±" not in md
    agg = aggregate(gather(tmp_path), ["detector.miss_rate"], ["IDs"])
    assert (agg["IDs_low"] >= 0).all()  # inside the values seen: counts never below 0
    reta = agg[(agg["tracker"] == "reta") & (agg["detector.miss_rate"] == "0.1")].iloc[0]
    shown = f"{reta['IDs']:.3f} [{reta['IDs_low']:.3f}, {reta['IDs_high']:.3f}]"
    assert shown in md and reta["IDs_low"] == 0  # sweep.md shows aggregate's interval
    spec = json.dumps(charts.metric_lines(agg, "detector.miss_rate", "IDs"))
    assert '"#ff7f0e"' in spec and '"#1f77b4"' in spec  # reta's and the baseline's colours
    lows = [float(v) for v in re.findall(r'"low": ([-0-9.e]+)', spec)]
    assert lows and min(lows) >= 0 and reta["IDs_low"] in lows
