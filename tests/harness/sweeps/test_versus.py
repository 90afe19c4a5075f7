"""occbench.sweeps.versus: our trackers against the best outside tracker of each set."""

from __future__ import annotations

import pandas as pd

from occbench.config.meta import shipped
from occbench.sweeps import generalisation as G
from occbench.sweeps import versus as V


def _table() -> pd.DataFrame:
    rows = [  # set, role, tracker, IDF1, HOTA, MOTA
        ("synth", G.UNTOUCHED, "reta", 0.90, 0.80, 0.70),
        ("synth", G.UNTOUCHED, "pbm", 0.70, 0.85, 0.60),
        ("synth", G.UNTOUCHED, "reta_paper", 0.99, 0.99, 0.99),  # ours: never the reference
        ("synth", G.UNTOUCHED, "baseline", 0.99, 0.99, 0.99),
        ("synth", G.UNTOUCHED, "norfair_tuned", 0.85, 0.82, 0.75),
        ("synth", G.UNTOUCHED, "motpy", 0.80, 0.84, 0.50),
        ("synth-tune", G.TUNING, "reta", 0.8004, 0.90, 0.90),
        ("synth-tune", G.TUNING, "motpy", 0.8001, 0.80, 0.80),
        ("cav1-150 gt", G.TUNING, "reta", 0.5, 0.5, 0.5),  # no outside tracker: no row
    ]
    return pd.DataFrame(rows, columns=["set", "role", "tracker", *G.METRICS]).assign(
        n_seeds=1, failures=0)


def test_best_outside_is_per_metric_and_never_ours():
    v = V.versus_outside(_table()).set_index(["set", "tracker"])
    reta = v.loc[("synth", "reta")]
    assert (reta["best_IDF1_by"], reta["best_IDF1"]) == ("norfair_tuned", 0.85)
    assert (reta["best_HOTA_by"], reta["best_HOTA"]) == ("motpy", 0.84)
    assert abs(reta["margin_HOTA"] - (0.80 - 0.84)) < 1e-12
    assert ("cav1-150 gt", "reta") not in v.index
    assert len(v) == 3


def test_verdicts_ahead_level_behind_at_the_tables_precision():
    v = V.versus_outside(_table()).set_index(["set", "tracker"])
    assert V.verdict(v.loc[("synth", "reta")]) == "behind: HOTA -0.040"
    assert V.verdict(v.loc[("synth", "pbm")]) == "behind: IDF1 -0.150"
    assert V.verdict(v.loc[("synth-tune", "reta")]) == "level: IDF1"  # 0.800 both
    ahead = v.loc[("synth", "pbm")].copy()
    ahead[["IDF1", "HOTA"]] = 0.9, 0.9
    assert V.verdict(ahead) == "ahead"


def test_a_missing_score_is_no_verdict_and_shows_as_a_dash():
    """A tracker that failed on a set has NaN scores: `round(nan)` compared neither equal nor
    below, so the verdict read "ahead"."""
    t = _table()
    t.loc[(t["set"] == "synth") & (t["tracker"] == "pbm"), ["IDF1", "HOTA", "MOTA"]] = float("nan")
    v = V.versus_outside(t).set_index(["set", "tracker"])
    assert V.verdict(v.loc[("synth", "pbm")]) == "no score"
    line = next(ln for ln in V.markdown(V.versus_outside(t), G.SETS).splitlines()
                if ln.startswith("| synth (U) | pbm"))
    assert "| - / - / - |" in line and line.endswith("| no score |")


def test_markdown_follows_the_sets_order_and_marks_roles():
    text = V.markdown(V.versus_outside(_table()), G.SETS)
    lines = [ln for ln in text.splitlines() if ln.startswith("| synth")]
    assert lines[0].startswith("| synth-tune (T) | reta")  # G.SETS lists synth-tune first
    assert lines[1].startswith("| synth (U) | reta | 0.900 / 0.800 / 0.700")
    assert "norfair_tuned 0.850; motpy 0.840; norfair_tuned 0.750" in lines[1]


def test_a_table_without_outside_rows_says_so_instead_of_failing():
    """issue 39: without the outside extras the table has only our rows; markdown raised
    KeyError: 'set' after the table was printed and the run exited 1."""
    ours = _table()[lambda t: t["tracker"].map(lambda n: shipped(n).role != "outside")]
    v = V.versus_outside(ours)
    assert v.empty
    assert "nothing to compare against" in V.markdown(v, G.SETS)


def test_a_metric_no_outside_tracker_scored_is_no_verdict_not_a_crash():
    t = _table()
    t.loc[t["tracker"].isin(["norfair_tuned", "motpy"]), "IDF1"] = float("nan")
    v = V.versus_outside(t).set_index(["set", "tracker"])
    reta = v.loc[("synth", "reta")]
    assert (reta["best_HOTA_by"], reta["best_HOTA"]) == ("motpy", 0.84)
    assert V.verdict(reta) == "no score"
