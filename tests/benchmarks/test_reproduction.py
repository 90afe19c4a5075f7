"""benchmarks/reproduction.py: a multirun's paper tables merged into one, and a table's section
of docs/reproduction.md replaced while the others stay as they are (no harness run here)."""

from __future__ import annotations

import pytest
from benchmark_scripts import load

repro = load("reproduction")

TABLE = """## A title

| method | P | R |
|---|---|---|
| reported: paper | 87 | 62 |
| ours: {det} | {p} | {r} |

Our data: one sequence.
"""


def test_a_multiruns_jobs_give_one_table_with_every_ours_row(tmp_path):
    jobs = []
    for i, (det, p, r) in enumerate([("silhouette", 94.8, 75), ("hog", 78.5, 27.7)]):
        (tmp_path / str(i)).mkdir()
        jobs.append(tmp_path / str(i) / "paper_table.md")
        jobs[-1].write_text(TABLE.format(det=det, p=p, r=r))
    merged = repro.merge(jobs)
    rows = [line for line in merged.splitlines() if line.startswith("| ")]
    assert rows[-2:] == ["| ours: silhouette | 94.8 | 75 |", "| ours: hog | 78.5 | 27.7 |"]
    assert merged.count("reported: paper") == 1 and merged.rstrip().endswith("one sequence.")


COLUMNS = """## A title

| PETS 2009 | reported: PBM | {ours} |
|---|---|{bar}
| mostly tracked | 10 | {x} |
| ID switches | 0 | {y} |

Our data: real pixels.
"""


def test_a_column_tables_second_run_adds_its_ours_columns(tmp_path):
    jobs = []
    for i, (ours, x, y) in enumerate([("ours: pbm | ours: meanshift", "3 | 1", "0.5 | 2"),
                                      ("ours: pbm_paper (whole)", "7", "1.8")]):
        (tmp_path / str(i)).mkdir()
        jobs.append(tmp_path / str(i) / "paper_table.md")
        jobs[-1].write_text(COLUMNS.format(ours=ours, x=x, y=y, bar="---|" * (ours.count("|") + 1)))
    merged = repro.merge(jobs)
    lines = [line for line in merged.splitlines() if line.startswith("|")]
    assert lines == [("| PETS 2009 | reported: PBM | ours: pbm | ours: meanshift | "
                      "ours: pbm_paper (whole) |"), "|---|---|---|---|---|",
                     "| mostly tracked | 10 | 3 | 1 | 7 |", "| ID switches | 0 | 0.5 | 2 | 1.8 |"]
    assert merged.startswith("## A title") and merged.rstrip().endswith("real pixels.")
    jobs[1].write_text(jobs[1].read_text().replace("ID switches", "IDS"))
    with pytest.raises(RuntimeError, match="rows differ"):
        repro.merge(jobs)


def test_writing_one_section_keeps_the_others(tmp_path):
    doc = tmp_path / "reproduction.md"
    repro.write({"reta_table2": repro.section("reta_table2", "## T2\n\nfirst\n", 1.0)}, doc)
    text = doc.read_text()
    assert text.startswith("# Reproducing the papers' tables")
    assert all(repro.BEGIN.format(t) in text for t in repro.TABLES)
    assert "Not generated yet: `python benchmarks/reproduction.py pbm_table1`" in text
    assert "`occbench +experiment=reta_table2 progress=false` and `occbench +experiment=reta_table2 tracker=reta_paper progress=false`" in text
    repro.write({"pbm_table1": repro.section("pbm_table1", "## T1\n\nsecond\n", 2.0)}, doc)
    repro.write({"reta_table2": repro.section("reta_table2", "## T2\n\nthird\n", 3.0)}, doc)
    text = doc.read_text()
    assert "second" in text and "third" in text and "first" not in text
    assert text.count(repro.BEGIN.format("reta_table2")) == 1


def test_an_unknown_table_is_named(capsys):
    with pytest.raises(SystemExit):
        repro.main(["reta_tabel2"])
    assert "unknown table 'reta_tabel2'" in capsys.readouterr().err


def test_a_table_reuses_another_tables_runs_only_when_nothing_but_the_table_differs(monkeypatch):
    configs = {"pbm_table1_real": {"tracker": "t", "paper_table": {"name": "a"}},
               "pbm_segmentation_real": {"tracker": "t", "paper_table": {"name": "b"}}}
    monkeypatch.setattr(repro, "_config", lambda table, args: dict(configs[table]))
    specs = repro.same_runs("pbm_segmentation_real", "pbm_table1_real")
    assert [s["name"] for s in specs] == ["b"] * len(repro.TABLES["pbm_table1_real"])
    configs["pbm_segmentation_real"] = {"tracker": "other", "paper_table": {"name": "b"}}
    assert repro.same_runs("pbm_segmentation_real", "pbm_table1_real") is None
    monkeypatch.setitem(repro.TABLES, "pbm_segmentation_real", [["+experiment=x"]])
    assert repro.same_runs("pbm_segmentation_real", "pbm_table1_real") is None
