"""``report.html`` of a run folder: tables, paired differences, error timelines with the
annotated video, the run's plots, its config and the command that reproduces it.

Everything is read from the folder (``metrics.csv``, ``gt/``, ``tracks/``, ``plots/``,
``report/*.mp4``, ``config.yaml``, ``.hydra/``), so that ``occbench report RUN`` can write
the page again with the video it renders; a run hands its per-frame counts in to save
scoring twice.
"""

from __future__ import annotations

import logging
import shlex
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import pandas as pd
import yaml

from occbench.io.mot import read_mot
from occbench.metrics import COMBINED
from occbench.metrics.paired import Bootstrap, PairedDifference, all_pairs
from occbench.metrics.timeline import FrameCounts, frame_counts
from occbench.report.html import charts
from occbench.report.html.page import Page, esc, table_html
from occbench.report.paired import NOT_DISTINGUISHABLE, by_pair, cell
from occbench.report.tables import direction
from occbench.report.tracks import EXPLAINED, counted

log = logging.getLogger(__name__)

SHOWN = ("HOTA", "DetA", "AssA", "IDF1", "MOTA", "MOTP", "Recall", "Precision", "MT", "ML",
         "FP", "FN", "IDs", "Frag")
PER_SEQUENCE = ("HOTA", "IDF1", "MOTA", "FP", "FN", "IDs")


def run_status_line(run_dir: Path) -> tuple[str, str] | None:
    """summary.md's opening status (``occbench.pipeline.summary.run_status``: an
    interrupted or partly failed run) as (its bold words, the rest); None for a complete run.
    Read from summary.md, written before the page, so the page says what summary.md says."""
    path = run_dir / "summary.md"
    text = path.read_text(encoding="utf-8") if path.is_file() else ""
    for line in text.split("\n## ", 1)[0].splitlines():
        if line.startswith(("**Incomplete run**", "**Partly failed run**")):
            bold, _, rest = line[2:].partition("**")
            return bold, rest
    return None


def read_frame_counts(run_dir: Path, iou_threshold: float = 0.5
                      ) -> dict[str, dict[str, FrameCounts]]:
    """tracker -> sequence -> ``FrameCounts`` from the run folder's gt/ and tracks/ (the
    files the run scored), each tracker's sequences in the order the run tracked them
    (``gt/seqmap.txt``): the bootstrap draws sequence by sequence, so that order is part of
    the paired intervals, which must come out as the run's own."""
    out: dict[str, dict[str, FrameCounts]] = {}
    for folder in sorted(p for p in (run_dir / "tracks").glob("*") if p.is_dir()):
        for path in sorted(folder.glob("*.txt"), key=run_order(run_dir)):
            gt = run_dir / "gt" / path.stem / "gt" / "gt.txt"
            if gt.is_file():
                out.setdefault(folder.name, {})[path.stem] = frame_counts(
                    read_mot(gt, gt=True), read_mot(path, kind="result"), iou_threshold)
    return out


def run_order(run_dir: Path):
    """A sort key putting a sequence's file where ``gt/seqmap.txt`` (a header, then the
    sequences in the order tracked) names it; unnamed ones after, by name."""
    seqmap = run_dir / "gt" / "seqmap.txt"
    names = seqmap.read_text().split()[1:] if seqmap.is_file() else []
    rank = {n: i for i, n in enumerate(names)}
    return lambda path: (rank.get(path.stem, len(rank)), path.stem)


def _order(counts: Mapping[str, Any], metrics: pd.DataFrame) -> dict[str, Any]:
    """``counts`` in the run's tracker order (metrics.csv's)."""
    names = list(dict.fromkeys(metrics["tracker"])) if "tracker" in metrics else []
    return {n: counts[n] for n in [*names, *counts] if n in counts}


def reproduce(run_dir: Path) -> str:
    """The command line that runs this run again (from Hydra's record of it)."""
    hydra = run_dir / ".hydra"
    task = yaml.safe_load((hydra / "overrides.yaml").read_text()) if (
        hydra / "overrides.yaml").is_file() else []
    cwd, extra = None, []
    if (hydra / "hydra.yaml").is_file():
        h = (yaml.safe_load((hydra / "hydra.yaml").read_text()) or {}).get("hydra") or {}
        cwd = (h.get("runtime") or {}).get("cwd")
        extra = (h.get("overrides") or {}).get("hydra") or []
    words = ["occbench", *(task or []), *[o for o in extra if o.startswith("hydra.run.dir")]]
    line = " ".join(shlex.quote(str(w)) for w in words)
    return f"cd {shlex.quote(str(cwd))} && {line}" if cwd else line


def videos(run_dir: Path, first: Mapping[str, int] | None = None) -> dict[str, tuple[str, int,
                                                                                    float]]:
    """sequence -> (relative path, first frame, frames/s) of each ``report/<seq>.mp4``; the
    first frame is ``first[seq]`` when given, else the run's first frame (its
    ``dataset.frames`` window, else 1)."""
    out = {}
    start = 1
    cfg = run_dir / "config.yaml"
    if cfg.is_file():
        window = ((yaml.safe_load(cfg.read_text()) or {}).get("dataset") or {}).get("frames")
        start = int(window[0]) if window else 1
    for path in sorted((run_dir / "report").glob("*.mp4")):
        import av  # start-up: PyAV, ~50 ms CPU; only a run with videos reads one

        with av.open(str(path)) as box:
            fps = float(box.streams.video[0].average_rate or 25)
        out[path.stem] = (f"report/{path.name}", int((first or {}).get(path.stem, start)), fps)
    return out


def write_run_report(run_dir: str | Path, frames: Mapping[str, Mapping[str, FrameCounts]]
                     | None = None, title: str = "", first: Mapping[str, int] | None = None,
                     paired: Sequence[PairedDifference] | None = None) -> Path:
    """Write ``<run_dir>/report.html`` (module docstring); ``frames`` are the run's per-frame
    counts (None: scored again from the folder's files), ``first`` the first frame of a
    sequence's video when it is not the run's first, ``paired`` the run's paired differences
    (those of summary.md; None: computed from the counts, in the run's order)."""
    run_dir = Path(run_dir)
    metrics = pd.read_csv(run_dir / "metrics.csv") if (run_dir / "metrics.csv").is_file() \
        else pd.DataFrame()
    counts = _order(read_frame_counts(run_dir) if frames is None else frames, metrics)
    page = Page(f"occbench run {run_dir.name}" + (f": {title}" if title else ""))
    page.text(f"Run folder: {run_dir.resolve()}")
    status = run_status_line(run_dir)
    if status:
        page.add(f'<p class="status"><strong>{esc(status[0])}</strong>{esc(status[1])}</p>')
    _tables(page, metrics, counted(run_dir, unscored=True))
    diffs = list(paired) if paired is not None else all_pairs(counts)
    if diffs:
        _paired(page, diffs)
    order = list(dict.fromkeys(metrics["sequence"])) if "sequence" in metrics else []
    _timelines(page, counts, videos(run_dir, first), order)
    _pictures(page, run_dir)
    page.section("config", "Config and command")
    page.add("<p>Run it again (same config and seed, same numbers):</p>")
    page.pre(reproduce(run_dir))
    if (run_dir / "config.yaml").is_file():
        page.add("<h3>config.yaml</h3>")
        page.pre((run_dir / "config.yaml").read_text())
    return page.write(run_dir / "report.html")


def _tables(page: Page, metrics: pd.DataFrame, tracks: pd.DataFrame) -> None:
    """The metrics of the scored sequences, then the tracks counted on those without ground
    truth (``occbench.report.tracks``, summary.md's table)."""
    page.section("tables", "Metrics" if not metrics.empty or tracks.empty else "Tracks")
    if metrics.empty and tracks.empty:
        page.text("No sequence was scored (no ground truth, or the run failed first).")
    if not metrics.empty:
        _metric_tables(page, metrics)
    if not tracks.empty:
        page.add("<h3>Tracks (sequences without ground truth: counted, not scored)</h3>")
        page.add(table_html(tracks))
        page.text(EXPLAINED)


def _metric_tables(page: Page, metrics: pd.DataFrame) -> None:
    combined = metrics[metrics["sequence"] == COMBINED]
    cols = ["tracker", *[c for c in SHOWN if c in metrics.columns]]
    page.add("<h3>COMBINED (click a header to sort; best per column marked)</h3>")
    page.add(table_html(combined[cols], senses={c: direction(c) for c in cols[1:]}))
    per = metrics[metrics["sequence"] != COMBINED]
    cols = ["tracker", "sequence", *[c for c in PER_SEQUENCE if c in metrics.columns]]
    page.add(f"<details><summary>Per sequence ({per['sequence'].nunique()} sequences; click "
             "to open)</summary>" + table_html(per[cols]) + "</details>")
    page.text("Ratios are fractions; FP, FN, IDs, Frag, ML: lower is better. Every column of "
              "metrics.csv is in summary.md.")


def _paired(page: Page, diffs: Sequence[PairedDifference]) -> None:
    page.section("paired", "Paired differences")
    page.text(f"{Bootstrap().describe()}. A difference whose interval contains 0 is "
              f"{NOT_DISTINGUISHABLE} (n.d.).")
    metrics = list(dict.fromkeys(d.metric for d in diffs))
    rows = [{"A": a, "B": b, **{d.metric: cell(d) for d in g}} for (a, b), g in
            by_pair(diffs).items()]
    page.add(table_html(pd.DataFrame(rows, columns=["A", "B", *metrics])))
    page.chart(charts.paired_forest(diffs))


def _timelines(page: Page, counts: Mapping[str, Mapping[str, FrameCounts]],
               clips: Mapping[str, tuple[str, int, float]], order: Sequence[str]) -> None:
    """Each sequence's video (``occbench report`` renders it) and, when it was scored, its
    error timeline, one row per tracker (a tracker without errors too)."""
    scored = {s for c in counts.values() for s in c}
    sequences = [s for s in dict.fromkeys([*order, *sorted(scored), *clips])
                 if s in scored or s in clips]
    sequences.sort(key=lambda s: s not in clips)  # those with a video first
    if not sequences:
        return
    if scored:
        page.section("timeline", "Errors over time")
        page.text("Misses, false positives and identity switches per frame, from the same "
                  "matching as the metrics. Click a bar to show its first frame in the video "
                  "(rendered by: occbench report RUN --sequence NAME).")
    else:
        page.section("video", "Video")
    for seq in sequences:
        page.add(f'<h3 id="seq-{esc(seq)}">{esc(seq)}</h3>')
        if seq in clips:
            src, first, fps = clips[seq]
            page.video(src, seq, first, fps)
        else:
            page.text(f"No video of {seq} yet: occbench report RUN --sequence {seq}")
        if seq in scored:
            page.chart(charts.timeline(seq, {t: c[seq] for t, c in counts.items() if seq in c},
                                       video=seq in clips),
                       sequence=seq if seq in clips else None)
        else:
            page.text(f"{seq} has no ground truth: no errors to show.")


def _pictures(page: Page, run_dir: Path) -> None:
    """The run's plots, embedded (small); ``occbench report``'s contact sheets, megabytes
    each, shown from their files beside the page, as the video is."""
    pngs = sorted((run_dir / "plots").glob("*.png"))
    sheets = sorted((run_dir / "report").glob("*.png"))
    if not pngs and not sheets:
        return
    page.section("plots", "Plots")
    for path in pngs:
        page.image(path, f"plots/{path.name}")
    for path in sheets:
        page.image(path, f"report/{path.name}", embed=False)
