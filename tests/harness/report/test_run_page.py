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


def _unlabelled_clip(folder) -> tuple:
    """A 20-frame video of one walking box and its detections (MOT det rows), no gt."""
    import cv2
    import numpy as np

    video, det = folder / "walk.avi", folder / "walk_det.txt"
    out = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 10, (96, 64))
    rows = []
    for k in range(1, 21):
        img = np.full((64, 96, 3), 30, np.uint8)
        x = 4 + 3 * k
        img[10:50, x:x + 16] = 220
        out.write(img)
        rows.append(f"{k},-1,{x},10,16,40,0.9,-1,-1,-1\n")
    out.release()
    det.write_text("".join(rows))
    return video, det


def test_the_page_of_an_unlabelled_run_shows_its_tracks_and_its_video(tmp_path) -> None:
    """issue 39 item 5: an unlabelled video run's page said only 'No sequence was scored':
    no tracks table, no player even after occbench report wrote the MP4."""
    from occbench.commands.report import main as report_main

    video, det = _unlabelled_clip(tmp_path)
    run = tmp_path / "run"
    cfg = compose_cfg("dataset=video", f"dataset.path={video}", f"dataset.det={det}",
                      "detector=public", "tracker=baseline", "progress=false")
    assert run_experiment(cfg, run, tracker_name="baseline").ok
    page = (run / "report.html").read_text()
    assert "Tracks (sequences without ground truth: counted, not scored)" in page
    assert "len_median" in page and "No sequence was scored" not in page
    assert "click to seek the video" not in page  # there is no video yet
    assert report_main([str(run), "--no-trajectories"]) == 0
    page = (run / "report.html").read_text()
    assert 'src="report/walk.mp4"' in page and "len_median" in page


def test_a_tracker_without_errors_keeps_its_timeline_row() -> None:
    import json

    import numpy as np

    from occbench.metrics.timeline import FrameCounts
    from occbench.report.html.charts import timeline

    def counts(errors: int) -> FrameCounts:
        n = np.arange(1, 6)
        z = np.zeros(5, np.int64)
        hota = np.zeros((5, 19))
        return FrameCounts(n, z + 1, z + 1, z + errors, z, z, z + 1 - errors, hota, hota,
                           hota, hota)

    spec = timeline("s", {"reta": counts(1), "pbm": counts(0)})
    assert spec["encoding"]["y"]["scale"]["domain"] == ["reta", "pbm"]  # pbm's row stays
    assert "click to seek" not in json.dumps(spec["title"])
    assert "click to seek" in json.dumps(timeline("s", {"reta": counts(1)}, video=True)["title"])
