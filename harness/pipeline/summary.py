"""The run's tables and ``summary.md``: metric rows per tracker, the ``complete`` column,
the status line of an incomplete run, and the Markdown summary."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from occbench.errors import RunError
from occbench.metrics import COLUMNS, COMBINED, hota_alpha_table, summarize
from occbench.metrics.occlusion import extra_rows
from occbench.pipeline.writer import Failure
from occbench.report.legend import column_legend
from occbench.report.tracks import tracks_markdown

if TYPE_CHECKING:  # pandas and the tables are imported where used (start-up time)
    import pandas as pd


def summary_rows(tracker: str, scores: Mapping[str, Any]) -> pd.DataFrame:
    """``summarize(scores)`` with a leading ``tracker`` column."""
    frame = summarize(dict(scores)).reset_index(drop=True)
    if "sequence" not in frame.columns:
        raise RunError("occbench.metrics.summarize returned no 'sequence' column")
    frame.insert(0, "tracker", tracker)
    return frame


def mark_complete(metrics: pd.DataFrame, expected: int, finished: bool) -> pd.DataFrame:
    """``metrics`` with a last column ``complete``: True on a sequence row (scored in full);
    on a COMBINED row, True only when the run has finished and the tracker was scored on
    all ``expected`` sequences (else its COMBINED covers only some of them)."""
    if metrics.empty:
        return metrics
    out = metrics.drop(columns=["complete"], errors="ignore").copy()
    per = out[out["sequence"] != COMBINED].groupby("tracker")["sequence"].nunique()
    combined = out["sequence"] == COMBINED
    whole = out["tracker"].map(per).fillna(0).astype(int) >= expected
    out["complete"] = ~combined | (whole & finished)
    return out


def run_status(state: str, done: int, total: int, failures: list[Failure]) -> str | None:
    """The line summary.md opens with when the run is not (yet) complete, else None."""
    if state == "running":
        return (f"**Incomplete run**: still running ({done} of {total} sequences scored so "
                "far); COMBINED rows cover only those.")
    if state == "interrupted":
        return (f"**Incomplete run**: interrupted after {done} of {total} sequences; COMBINED "
                "rows cover only those (metrics.csv: `complete` false). See errors.txt.")
    if failures:
        return (f"**Partly failed run**: {len(failures)} part(s) failed (see Failures below "
                "and errors.txt); a COMBINED row whose `complete` is false in metrics.csv "
                "misses some sequences.")
    return None


def summary_markdown(metrics: pd.DataFrame, failures: list[Failure],
                     columns: list[str] | None = None, title: str = "",
                     status: str | None = None, paired: str = "",
                     tracks: pd.DataFrame | None = None) -> str:
    """``summary.md``: the COMBINED comparison, per-sequence tables, the ``paired``
    differences section (``occbench.report.paired.paired_markdown``) and failures; opened by
    ``status`` (``run_status``) when the run is incomplete or partly failed; ``tracks``
    (``occbench.report.tracks.track_rows``) counts the tracks of sequences without ground
    truth."""
    # start-up: report.tables imports pandas (~0.25 s CPU)
    from occbench.report.tables import comparison, direction, per_sequence, to_markdown

    lines = ["# occbench results", ""]
    if title:
        lines += [title, ""]
    if status:
        lines += [status, ""]
    if tracks is not None and not tracks.empty:
        lines += tracks_markdown(tracks)
    if metrics.empty:
        if tracks is None or tracks.empty:
            lines += ["No sequence was scored.", ""]
    else:
        shown = [comparison(metrics, columns)]
        lines += ["## Combined (best per column in bold)", "", to_markdown(shown[-1])]
        occlusion = [c for c in metrics.columns if c.startswith(("Recall_v", "IDs_v", "ReID"))]
        if occlusion:
            shown.append(comparison(metrics, occlusion))
            lines += [("## Occlusion (COMBINED): recall and identity switches by gt "
                       "visibility, re-identification after total occlusion"), "",
                      to_markdown(shown[-1])]
        paper = [c for c in metrics.columns if c.startswith(("Song_", "PBM_"))]
        if paper:
            shown.append(comparison(metrics, paper))
            lines += ["## Paper-table metrics (COMBINED): Song et al. (Reta), PBM", "",
                      to_markdown(shown[-1])]
        seqs = [s for s in dict.fromkeys(metrics["sequence"]) if s != COMBINED]
        for metric in [m for m in ("IDF1", "HOTA", "MOTA") if m in metrics.columns]:
            lines += [f"## {metric} per sequence", "",
                      to_markdown(per_sequence(metrics, metric, seqs), sense=direction(metric))]
        if paired:
            lines += [paired]

        lines += column_legend(c for table in shown for c in table.columns)
    if failures:
        lines += ["## Failures", ""]
        lines += [f"- [{f.stage}] tracker={f.tracker} sequence={f.sequence}: {f.message}"
                  for f in failures]
        lines.append("")
    return "\n".join(lines)


def with_extras(metrics: pd.DataFrame, extras: Mapping[str, Mapping[str, Any]]) -> pd.DataFrame:
    """``metrics`` with the paper-table and occlusion columns appended (same rows)."""
    if metrics.empty:
        return metrics
    return metrics.merge(extra_rows(extras), on=["tracker", "sequence"], how="left",
                         validate="one_to_one")


def hota_alpha_frame(scores: Mapping[str, Mapping[str, Any]]) -> pd.DataFrame:
    """``hota_alpha.csv``: ``tracker`` + ``occbench.metrics.hota_alpha_table`` per tracker."""
    import pandas as pd  # start-up: pandas, ~0.25 s CPU

    parts = []
    for name, s in scores.items():
        if s:
            frame = hota_alpha_table(dict(s))
            frame.insert(0, "tracker", name)
            parts.append(frame)
    return pd.concat(parts, ignore_index=True) if parts else pd.DataFrame()


def empty_metrics() -> pd.DataFrame:
    """metrics.csv's columns without a row (no sequence scored yet)."""
    import pandas as pd  # start-up: pandas, ~0.25 s CPU

    return pd.DataFrame(columns=["tracker", "sequence", *COLUMNS, "complete"])


def metrics_frame(scores: Mapping[str, Mapping[str, Any]]) -> pd.DataFrame:
    import pandas as pd  # start-up: pandas, ~0.25 s CPU

    """``summary_rows`` of every tracker with scores, one frame (empty when none)."""
    parts = [summary_rows(n, s) for n, s in scores.items() if s]
    if not parts:
        return pd.DataFrame()
    return pd.concat(parts, ignore_index=True)
