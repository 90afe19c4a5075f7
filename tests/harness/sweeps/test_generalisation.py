"""The generalisation table (occbench.sweeps.generalisation, benchmarks/bench_generalisation.py)."""

from __future__ import annotations

import pandas as pd

from occbench.sweeps import generalisation as G


def test_every_set_composes_and_is_marked():
    names = [s.name for s in G.SETS]
    assert len(set(names)) == len(names)
    roles = {s.name: s.role for s in G.SETS}
    assert roles["cav1-150 gt"] == G.TUNING and roles["cav151-295 gt"] == G.UNTOUCHED
    assert roles["synth-tune"] == G.TUNING
    # issue 28's split: choose on real detections of the first halves, report on the second
    assert roles["cav1-150 sil"] == roles["ecp1-180 sil"] == roles["ecp1-180 gt"] == G.TUNING
    assert roles["cav151-295 sil"] == roles["ecp181-383 sil"] == G.UNTOUCHED
    assert roles["ecp181-383 gt"] == roles["lobby gt"] == G.UNTOUCHED
    assert roles["lobby-C gt"] == G.TUNING  # the lobby's choosing clips C, never its R
    # issue 35: PETS09-S2L1 real pixels frames 1-400 choose; the replay's other frames report
    assert roles["pets1-400 sil"] == roles["pets1-400 gt"] == G.TUNING
    assert roles["PETS09 401-795"] == G.UNTOUCHED
    pets = {s.name: s for s in G.SETS}
    assert "dataset.frames=[1,400]" in pets["pets1-400 sil"].overrides
    assert "dataset.frames=[401,795]" in pets["PETS09 401-795"].overrides
    assert not set(G.LOBBY_CHOSEN) & set(G.LOBBY_REPORTED)
    for s in G.SETS:
        assert s.role in (G.TUNING, G.UNTOUCHED)
        if s.role == G.UNTOUCHED and "dataset=synthetic" in s.overrides:
            # untouched synthetic sets never use a seed the project chose anything on
            assert min(s.seeds) >= 1000
        cfg = G.compose(G._resolve(s.overrides, G.trajectories_root()))
        assert "_target_" in cfg.dataset and "_target_" in cfg.detector


def test_not_shipped_sets_name_their_missing_folder(tmp_path):
    ecp = {s.name: s for s in G.SETS}["ecp181-383 sil"]
    trajectories = G.trajectories_root()
    assert G.missing_data(ecp, trajectories) == [
        G.NO_DATA_ROOT / "CAVIAR-EnterExitCrossingPaths1cor"]
    assert G.missing_data(ecp, trajectories, tmp_path) == [
        tmp_path / "CAVIAR-EnterExitCrossingPaths1cor"]
    assert any(str(tmp_path) in o for o in G._resolve(ecp.overrides, trajectories, tmp_path))
    (tmp_path / "CAVIAR-EnterExitCrossingPaths1cor").mkdir()
    assert G.missing_data(ecp, trajectories, tmp_path) == []


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


def test_combine_joins_earlier_tables(tmp_path):
    """``--combine``: rows of separate runs (e.g. tuned trackers run later) in one table,
    a later run's row replacing an earlier one of the same set and tracker."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "bench_generalisation", G.ROOT / "benchmarks" / "bench_generalisation.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    a = pd.DataFrame({"set": ["synth", "synth"], "role": "untouched", "tracker": ["pbm", "reta"],
                      "IDF1": [0.5, 0.6], "HOTA": 0.5, "MOTA": 0.5, "n_seeds": 2, "failures": 0})
    b = pd.DataFrame({"set": ["synth"], "role": "untouched", "tracker": ["norfair_tuned"],
                      "IDF1": [0.7], "HOTA": 0.6, "MOTA": 0.4, "n_seeds": 2, "failures": 0})
    c = a.iloc[[0]].assign(IDF1=0.55)
    for name, t in (("a", a), ("b", b), ("c", c)):
        t.to_csv(tmp_path / f"{name}.csv", index=False)
    assert bench.main(["--combine", *(str(tmp_path / f"{n}.csv") for n in "abc"),
                       "--out", str(tmp_path / "out")]) == 0
    out = pd.read_csv(tmp_path / "out" / "generalisation.csv")
    assert list(out["tracker"]) == ["reta", "pbm", "norfair_tuned"]  # table order
    assert out.set_index("tracker").loc["pbm", "IDF1"] == 0.55
    assert "0.700 / 0.600 / 0.400" in (tmp_path / "out" / "generalisation.md").read_text()
    versus = (tmp_path / "out" / "versus.md").read_text()  # ours against the best outside
    assert "| synth (U) | pbm | 0.550 / 0.500 / 0.500 | norfair_tuned 0.700;" in versus
    assert (tmp_path / "out" / "generalisation.png").stat().st_size > 0  # the table drawn
    assert bench.main(["--combine", str(tmp_path / "a.csv"), "--scores-only",
                       "--out", str(tmp_path / "scores")]) == 0
    assert not (tmp_path / "scores" / "generalisation.png").exists()  # its promise: no plots


def test_docs_section_holds_the_figure_and_versus(tmp_path, monkeypatch):
    """``--docs`` writes the run's figure beside docs/generalisation.md and its section shows
    it, the table and versus.md; with ``--scores-only`` (no plots) no picture line."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "bench_generalisation", G.ROOT / "benchmarks" / "bench_generalisation.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    monkeypatch.setattr(bench, "ROOT", tmp_path)
    pd.DataFrame({"set": ["synth", "synth"], "role": "untouched",
                  "tracker": ["reta", "norfair_tuned"], "IDF1": [0.6, 0.7], "HOTA": 0.5,
                  "MOTA": 0.5, "n_seeds": 2, "failures": 0}).to_csv(tmp_path / "a.csv",
                                                                   index=False)
    assert bench.main(["--combine", str(tmp_path / "a.csv"), "--docs",
                       "--out", str(tmp_path / "out")]) == 0
    doc = (tmp_path / "docs" / "generalisation.md").read_text()
    assert f"]({bench.FIGURE})" in doc and "| synth (U) | reta | 0.600 / 0.500 / 0.500" in doc
    assert ((tmp_path / "docs" / bench.FIGURE).read_bytes()
            == (tmp_path / "out" / "generalisation.png").read_bytes())
    assert bench.main(["--combine", str(tmp_path / "a.csv"), "--docs", "--scores-only",
                       "--out", str(tmp_path / "scores")]) == 0
    doc = (tmp_path / "docs" / "generalisation.md").read_text()
    assert bench.FIGURE not in doc and "| synth (U) | reta |" in doc


def test_the_csv_keeps_full_precision_for_combine(tmp_path):
    """generalisation.csv is read back by ``--combine``: a score written at 4 decimals and
    rounded again to 3 in the tables moved by 0.001 (0.81949 -> 0.8195 -> 0.820)."""
    t = pd.DataFrame({"set": ["synth"], "role": "untouched", "tracker": ["pbm"],
                      "IDF1": [0.81949], "HOTA": [1 / 3], "MOTA": 0.5, "n_seeds": 2,
                      "failures": 0})
    G.write(t, G.SETS, tmp_path)
    back = pd.read_csv(tmp_path / "generalisation.csv")
    assert back["IDF1"].iloc[0] == 0.81949 and back["HOTA"].iloc[0] == 1 / 3
    assert G.markdown(back, G.SETS) == G.markdown(t, G.SETS)


def test_docs_table_replaced_and_the_reading_around_it_kept():
    """``--docs`` replaces only the table section of docs/generalisation.md: the head before
    it and the hand-written reading after it (from the next ``### `` heading) survive."""
    doc = ("# Head\n\nintro\n\n## Latest table (old)\n\n| old |\n\nold legend\n\n"
           "### Reading it\n\nwhy the gaps\n")
    new = G.with_table(doc, "## Latest table (new)\n\n| new |\n")
    assert new == ("# Head\n\nintro\n\n## Latest table (new)\n\n| new |\n\n"
                   "### Reading it\n\nwhy the gaps\n")
    assert G.with_table("# Head\n", "## Latest table (x)\n") == "# Head\n\n## Latest table (x)\n"
    assert G.with_table(new, "## Latest table (new)\n\n| new |\n") == new  # idempotent


def test_list_names_the_sets_whose_data_is_absent(tmp_path, capsys, monkeypatch):
    """``--list`` marks each set whose data folders do not exist (issue 39: it did not say)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "bench_generalisation", G.ROOT / "benchmarks" / "bench_generalisation.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    monkeypatch.setattr(bench, "DATA", tmp_path / "nowhere")
    assert bench.main(["--list", "--trackers", "baseline"]) == 0
    out = capsys.readouterr().out.splitlines()

    def line(s):
        return next(v for v in out if v.startswith(f"{s.name:16s} "))

    ecp = next(s for s in G.SETS if any(r.startswith("data:") for r in s.requires))
    assert "[absent: " + str(tmp_path / "nowhere") in line(ecp)
    shipped = next(s for s in G.SETS if not s.requires)
    assert "[absent" not in line(shipped)


def test_a_tuned_real_row_is_listed_after_the_synthetic_one(monkeypatch, tmp_path):
    (tmp_path / "tracker").mkdir()
    for name in ("motpy", "motpy_tuned", "motpy_tuned_real"):
        (tmp_path / "tracker" / f"{name}.yaml").write_text("")
    monkeypatch.setattr(G, "CONF", tmp_path)
    names = G.ordered_trackers()
    assert names[names.index("motpy"):names.index("motpy") + 3] == [
        "motpy", "motpy_tuned", "motpy_tuned_real"]
