"""The generalisation table (harness.generalisation, benchmarks/bench_generalisation.py)."""

from __future__ import annotations

import pandas as pd

from harness import generalisation as G


def test_every_set_composes_and_is_marked():
    names = [s.name for s in G.SETS]
    assert len(set(names)) == len(names)
    roles = {s.name: s.role for s in G.SETS}
    assert roles["cav1-150 gt"] == G.TUNING and roles["cav151-295 gt"] == G.UNTOUCHED
    assert roles["synth-tune"] == G.TUNING
    for s in G.SETS:
        assert s.role in (G.TUNING, G.UNTOUCHED)
        if s.role == G.UNTOUCHED and "dataset=synthetic" in s.overrides:
            # untouched synthetic sets never use a seed the project chose anything on
            assert min(s.seeds) >= 1000
        cfg = G.compose(G._resolve(s.overrides, G.trajectories_root()))
        assert "_target_" in cfg.dataset and "_target_" in cfg.detector


def test_tiny_table_same_detections_for_every_tracker(tmp_path):
    """Two trackers on a tiny synthetic set: one run per seed, both scored, the table
    marks the set, and a missing data set is skipped, not failed."""
    tiny = G.EvalSet("tiny", G.UNTOUCHED, ("dataset=synthetic", "dataset.scenarios=[crossing]",
                                           "dataset.length=12"), (1000, 1001))
    absent = G.EvalSet("absent", G.UNTOUCHED, ("dataset=synthetic",), (1000,),
                       requires=("no-such-trajectory-folder",))
    trackers, _ = G.available_trackers(["baseline", "bytetrack"])
    table = G.run_table([tiny, absent], trackers, tmp_path)
    assert set(table["set"]) == {"tiny"}
    assert list(table["tracker"]) == ["baseline", "bytetrack"]
    assert (table["n_seeds"] == 2).all() and (table["failures"] == 0).all()
    assert table[["IDF1", "HOTA", "MOTA"]].notna().all().all()
    csv = pd.read_csv(tmp_path / "generalisation.csv")
    assert list(csv["set"]) == ["tiny", "tiny"]
    md = (tmp_path / "generalisation.md").read_text()
    assert "| tiny (U) |" in md
    # each seed's run directory holds both trackers' tracks
    for seed in (1000, 1001):
        assert (tmp_path / "runs" / "tiny" / f"seed{seed}" / "tracks" / "bytetrack"
                / "crossing.txt").is_file()


def test_unknown_tracker_is_skipped_with_its_reason():
    trackers, skipped = G.available_trackers(["baseline", "no_such_tracker"])
    assert list(trackers) == ["baseline"] and "no_such_tracker" in skipped
