"""occbench.sweeps.plots: intervals that respect each metric's range, a grid with one legend."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from occbench.config.meta import shipped
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


def _generalisation() -> pd.DataFrame:
    rows = [  # set, role, tracker, IDF1, HOTA
        ("synth", "untouched", "reta", 0.90, 0.80),
        ("synth", "untouched", "pbm", 0.70, 0.85),
        ("synth", "untouched", "reta_tuned_real", 0.99, 0.99),  # ours: never the best outside
        ("synth", "untouched", "norfair_tuned", 0.85, 0.82),
        ("synth", "untouched", "motpy", 0.80, 0.84),
        ("cav1-150 gt", "tuning", "reta", 0.60, 0.50),
        ("cav1-150 gt", "tuning", "pbm", 0.65, 0.55),
        ("cav1-150 gt", "tuning", "bytetrack", 0.70, 0.45),
    ]
    return pd.DataFrame(rows, columns=["set", "role", "tracker", "IDF1", "HOTA"]).assign(
        MOTA=0.5, n_seeds=1, failures=0)


def _drawn(table: pd.DataFrame, monkeypatch, tmp_path) -> list:
    """The figure ``plot_generalisation`` would write, kept open: its two panels."""
    import occbench.sweeps.plots as P

    kept = []
    monkeypatch.setattr(P, "save_figure", lambda fig, path: kept.append(fig) or Path(path))
    P.plot_generalisation(table, tmp_path / "g.png", ["synth", "cav1-150 gt"])
    P.plt.close(kept[0])
    return [ax for ax in kept[0].axes if ax.get_xlabel()]


def test_the_generalisation_figure_shows_ours_and_the_best_outside_tracker_per_set(
        tmp_path, monkeypatch):
    idf1, hota = _drawn(_generalisation(), monkeypatch, tmp_path)
    # tuning sets above untouched ones, whatever the order asked for
    assert [t.get_text() for t in idf1.get_yticklabels()] == ["cav1-150 gt (T)", "synth (U)"]
    texts = {t.get_text() for t in idf1.texts}
    assert {"0.850 norfair_tuned", "0.700 bytetrack", "0.900", "0.650"} <= texts
    assert "0.840 motpy" in {t.get_text() for t in hota.texts}  # best per metric on its own
    assert not any("tuned_real" in t for t in texts)
    widths = sorted(round(p.get_width(), 3) for p in idf1.patches)
    assert widths == [0.6, 0.65, 0.7, 0.7, 0.85, 0.9]  # reta, pbm, best outside per set
    colours = {round(p.get_width(), 3): p.get_facecolor() for p in idf1.patches}
    from matplotlib.colors import to_rgba

    assert colours[0.9] == to_rgba(shipped("reta").colour)
    assert colours[0.85] == to_rgba(shipped("norfair_tuned").colour)


def test_a_missing_score_is_marked_never_a_bar_and_a_missing_column_is_named(
        tmp_path, monkeypatch):
    import pytest

    import occbench.sweeps.plots as P

    t = _generalisation()
    t.loc[(t["set"] == "synth") & (t["tracker"] == "pbm"), "IDF1"] = float("nan")
    idf1, _ = _drawn(t, monkeypatch, tmp_path)
    assert "pbm: no score" in {x.get_text() for x in idf1.texts}
    assert len(idf1.patches) == 5 and 0.0 not in {p.get_width() for p in idf1.patches}
    with pytest.raises(ValueError, match="no column 'HOTA'"):
        P.plot_generalisation(t.drop(columns="HOTA"), tmp_path / "x.png")
    assert not (tmp_path / "x.png").exists()


def test_the_generalisation_figure_is_the_same_bytes_twice(tmp_path):
    from occbench.sweeps.plots import plot_generalisation

    a = plot_generalisation(_generalisation(), tmp_path / "a.png")
    b = plot_generalisation(_generalisation(), tmp_path / "b.png")
    assert a.read_bytes() == b.read_bytes() and a.stat().st_size > 0


def test_a_table_without_mota_is_drawn_and_a_nan_best_outside_is_marked(tmp_path, monkeypatch):
    t = _generalisation().drop(columns="MOTA")
    t.loc[t["tracker"] == "bytetrack", "IDF1"] = float("nan")  # the set's only outside one
    idf1, hota = _drawn(t, monkeypatch, tmp_path)
    assert "no outside tracker" in {x.get_text() for x in idf1.texts}
    assert "0.450 bytetrack" in {x.get_text() for x in hota.texts}
