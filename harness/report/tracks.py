"""What a run says without ground truth: per tracker and sequence, the number of tracks, the
distribution of their lengths and the frames per second (summary.md, the printed table,
``occbench report``). Nothing here is a score: no ground truth, no accuracy."""

from __future__ import annotations

import csv
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from occbench.io.mot import read_mot

#: Columns of ``track_rows``: lengths are in frames (a track's frames with a box).
COLUMNS = ("tracks", "boxes", "len_min", "len_median", "len_p90", "len_max", "fps")

EXPLAINED = (
    "Tracks: ids reported; boxes: boxes reported; len_min / len_median / len_p90 / len_max: "
    "the tracks' lengths in frames with a box (minimum, median, 90th percentile, maximum); "
    "fps: frames per second of the tracker's update (wall clock).")


def track_stats(ids: np.ndarray) -> dict[str, Any]:
    """Counts and length distribution of one track file.

    Args:
        ids: (N,) int track id of each reported box (MOT column 2).
    """
    ids = np.asarray(ids)
    if ids.size == 0:
        return {"tracks": 0, "boxes": 0, "len_min": 0, "len_median": 0.0, "len_p90": 0.0,
                "len_max": 0}
    _, lengths = np.unique(ids, return_counts=True)
    return {"tracks": int(lengths.size), "boxes": int(ids.size),
            "len_min": int(lengths.min()), "len_median": float(np.median(lengths)),
            "len_p90": float(np.percentile(lengths, 90)), "len_max": int(lengths.max())}


def track_rows(stats: dict[str, dict[str, dict[str, Any]]],
               timings: Iterable[dict[str, Any]] = ()):
    """One row per tracker and sequence (``stats[tracker][sequence]``, ``track_stats``) with
    its frames/s from ``timings`` (rows of ``timings.csv``), as a DataFrame of ``tracker,
    sequence`` + ``COLUMNS``."""
    import pandas as pd  # start-up: pandas, ~0.25 s CPU

    fps = {(t["tracker"], t["sequence"]): t.get("fps", "") for t in timings}
    rows = [{"tracker": n, "sequence": s, **st, "fps": fps.get((n, s), "")}
            for n, per in stats.items() for s, st in per.items()]
    return pd.DataFrame(rows, columns=["tracker", "sequence", *COLUMNS])


def tracks_markdown(rows) -> list[str]:
    """summary.md's section for the sequences without ground truth (lines)."""
    if rows.empty:
        return []
    head = ["tracker", "sequence", *COLUMNS]
    lines = ["## Tracks (sequences without ground truth: counted, not scored)", "",
             EXPLAINED, "",
             "| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in head) + "|"]
    for r in rows.itertuples(index=False):
        cells = [f"{v:g}" if isinstance(v, float) else str(v) for v in r]
        lines.append("| " + " | ".join(cells) + " |")
    return [*lines, ""]


def tracks_text(rows) -> str:
    """The printed table of a run without ground truth."""
    return rows.to_string(index=False, float_format=lambda v: f"{v:g}") + "\n"


def counted(run_dir: Path, unscored: bool = False):
    """``track_rows`` of a run folder, read from its track files and timings.csv: what a run
    without ground truth can say. ``unscored``: only the sequences the run had no ground
    truth for (no ``gt/<sequence>/gt/gt.txt``), as summary.md counts them."""
    stats: dict[str, dict] = {}
    folders = (run_dir / "tracks").iterdir() if (run_dir / "tracks").is_dir() else []
    for folder in sorted(p for p in folders if p.is_dir()):
        for path in sorted(folder.glob("*.txt")):
            if unscored and (run_dir / "gt" / path.stem / "gt" / "gt.txt").is_file():
                continue
            stats.setdefault(folder.name, {})[path.stem] = track_stats(read_mot(path).ids)
    timings = run_dir / "timings.csv"
    rows = list(csv.DictReader(timings.open())) if timings.is_file() else []
    return track_rows(stats, rows)
