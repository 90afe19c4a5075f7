"""report.html written again by ``occbench report`` shows the run's own figures: the paired
intervals of summary.md, whatever order the sequences' files sort in (issue 39 item 3)."""

from __future__ import annotations

import re

from run_scenes import compose_cfg, run_experiment


def _summary_cells(text: str) -> list[str]:
    """The paired-difference cells of summary.md's section ('-0.129 [-0.169, -0.090]')."""
    section = text.split("## Paired differences", 1)[1]
    return re.findall(r"[+-]\d\.\d{3} \[[+-]\d\.\d{3}, [+-]\d\.\d{3}\]", section)


def test_report_rewrites_the_page_with_the_runs_own_paired_intervals(tmp_path) -> None:
    from occbench.commands.report import main as report_main

    # tracked in an order that is not the files' alphabetical one
    cfg = compose_cfg("dataset=synthetic", "dataset.scenarios=[stop_behind,crossing,crowd]",
                      "dataset.length=30", "progress=false", "tracker=all", "~tracker.pbm")
    result = run_experiment(cfg, tmp_path, tracker_name="all")
    assert result.ok
    cells = _summary_cells((tmp_path / "summary.md").read_text())
    assert len(cells) == 3
    page = (tmp_path / "report.html").read_text()
    assert all(c in page for c in cells)  # the run's page
    assert report_main([str(tmp_path), "--no-video", "--no-trajectories"]) == 0
    page = (tmp_path / "report.html").read_text()
    assert all(c in page for c in cells), cells  # redrawn: the same figures
