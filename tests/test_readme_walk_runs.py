"""Issue 39's acceptance walk, its runs (the mistakes: tests/test_readme_walk.py): a video cut
short fails its sequence naming the frame, FFmpeg quiet; a sweep whose jobs fail on an input
mistake says each job's cause once, no traceback; and one run's figures are the same in every
view (the printed table, summary.md, metrics.csv, report.html before and after
``occbench report``, ``occbench eval``), as are a sweep's (its printed summary, sweep.md, its
page). Each runs as a user runs it, one ``python -m occbench`` at a time."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd
from test_readme_walk import _mp4, occbench

CELL = r"[+-]\d\.\d{3} \[[+-]\d\.\d{3}, [+-]\d\.\d{3}\]"  # a paired difference and interval
# every command's log line (occbench.progress.LOG_FORMAT): '[time][logger][LEVEL] - message'
LOG_LINE = re.compile(r"\[\d{4}-\d\d-\d\d \d\d:\d\d:\d\d,\d{3}\]\[[\w.]+\]\[[A-Z]+\] - ")


def _logged_in_one_form(stderr: str) -> None:
    logged = [line for line in stderr.splitlines() if line.startswith("[")]
    assert logged and not [line for line in logged if not LOG_LINE.match(line)], stderr


def test_a_video_cut_short_fails_its_sequence_naming_the_frame(tmp_path):
    whole = _mp4(tmp_path / "whole.mp4", faststart=True, frames=60)  # the index first
    (tmp_path / "cut.mp4").write_bytes(whole.read_bytes()[: whole.stat().st_size * 3 // 4])
    (tmp_path / "gt.txt").write_text(
        "".join(f"{k},1,{10 + k},20,30,60,1,1,1\n" for k in range(1, 61)))
    proc = occbench("dataset=video", "dataset.path=cut.mp4", "dataset.gt=gt.txt",
                    "tracker=baseline", "progress=false", "hydra.run.dir=run", cwd=tmp_path)
    lines = proc.stderr.splitlines()
    assert proc.returncode == 1, proc.stderr[-2000:]
    frame = int(re.search(r"cut\.mp4: cannot decode frame (\d+) of 60", proc.stderr).group(1))
    assert frame > 1  # the frame that failed, not the reader's reset position
    assert lines[-1].startswith("occbench: 1 part(s) of the run failed")
    assert "Traceback" not in proc.stderr
    # log lines and the one line: none of FFmpeg's own ('[mpeg4 @ 0x...] ...')
    assert all(line.startswith(("[20", "occbench: ")) for line in lines), proc.stderr


def _row(cells: str) -> list[str]:
    return [c.strip().strip("*") for c in cells.strip().strip("|").split("|")]


def test_a_sweep_with_failing_jobs_says_each_cause_once_and_one_set_of_figures(tmp_path):
    proc = occbench("-m", "tracker=baseline", "tracker.max_age=-1,3", "seed=0,1",
                    "detector.miss_rate=0.3", "dataset.length=20",
                    "dataset.scenarios=[crossing]", "hydra.sweep.dir=sweep", cwd=tmp_path)
    assert proc.returncode == 1, proc.stderr[-2000:]
    assert "Traceback" not in proc.stderr and "AppError" not in proc.stderr
    cause = "tracker 'baseline' (occbench.trackers.baseline.BaselineTracker): ValueError: "
    assert proc.stderr.count(f"job failed: {cause}max_age must be >= 0") == 2
    assert f"occbench: 2 of 4 sweep jobs not done" in proc.stderr
    _logged_in_one_form(proc.stderr)  # the sweep's own lines as a run's ('[HYDRA] ...' before)
    gathered = occbench("sweep", "sweep", cwd=tmp_path)  # gathered again: argparse's logging
    assert gathered.returncode == 1 and "occbench: 2 of 4 sweep jobs not done" in gathered.stderr
    _logged_in_one_form(gathered.stderr)
    # the summary printed, sweep.md's and the page's: one computation (mean [low, high])
    printed = next(line.split() for line in proc.stdout.splitlines()
                   if line.split()[:2] == ["3", "baseline"])
    md = (tmp_path / "sweep" / "sweep.md").read_text()
    table = next(_row(line) for line in md.splitlines() if line.startswith("| 3 | baseline"))
    assert " ".join(printed) == " ".join(table), (printed, table)
    intervals = re.findall(r"\[[^\]]+\]", " ".join(table))
    assert intervals  # seeds differ: intervals, not single values
    page = (tmp_path / "sweep" / "report.html").read_text()
    assert all(i in page for i in intervals), intervals


def test_every_view_of_a_run_shows_the_same_figures(tmp_path):
    proc = occbench("tracker=all", "~tracker.pbm", "dataset.length=20",
                    "dataset.scenarios=[crossing,stop_behind]", "progress=false",
                    "hydra.run.dir=run", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    run = tmp_path / "run"
    out = proc.stdout.splitlines()
    head = next(i for i, line in enumerate(out) if line.split()[:2] == ["tracker", "HOTA"])
    columns = out[head].split()
    printed = {r.split()[0]: dict(zip(columns, (c.strip("*") for c in r.split())))
               for r in out[head + 2:head + 4]}
    md = (run / "summary.md").read_text()
    md_columns = _row(next(line for line in md.splitlines() if line.startswith("| tracker |")))
    summary = {r[0]: dict(zip(md_columns, r)) for r in
               (_row(line) for line in md.split("## Combined", 1)[1].split("##")[0].splitlines()
                if line.startswith(("| baseline", "| reta")))}
    metrics = pd.read_csv(run / "metrics.csv")
    combined = metrics[metrics["sequence"] == "COMBINED"].set_index("tracker")
    scored = occbench("eval", "run/gt", "run/tracks/reta", cwd=tmp_path)
    assert scored.returncode == 0, scored.stderr[-2000:]
    eval_head, *_, eval_combined = [line.split() for line in scored.stdout.splitlines()
                                    if line.split()[:1] in (["sequence"], ["COMBINED"])]
    evaluated = dict(zip(eval_head, eval_combined))
    for tracker in ("baseline", "reta"):
        for column in ("HOTA", "IDF1", "MOTA"):
            shown = f"{combined.loc[tracker, column]:.3f}"
            assert printed[tracker][column] == summary[tracker][column] == shown
            if tracker == "reta":
                assert evaluated[column] == shown
    cells = re.findall(CELL, proc.stdout)
    assert len(cells) == 3 and cells == re.findall(CELL, md.split("## Paired differences")[1])
    assert all(c in (run / "report.html").read_text() for c in cells)
    redrawn = occbench("report", "run", "--no-video", "--no-trajectories", cwd=tmp_path)
    assert redrawn.returncode == 0, redrawn.stderr[-2000:]
    assert all(c in (run / "report.html").read_text() for c in cells), cells
