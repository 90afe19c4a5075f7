"""Comparison tables: one row per tracker, one column per metric, best value per column marked.

Input is a metrics frame as ``occbench.pipeline.experiment`` writes to ``metrics.csv``: columns ``tracker``,
``sequence`` plus metric columns. ``comparison`` picks one sequence (``COMBINED`` by
default) and indexes the rows by tracker; the writers format it as Markdown (best value in
``**bold**``), LaTeX (booktabs, ``\\textbf``) or aligned plain text (best value followed by
``*``). CSV output is plain numbers (``DataFrame.to_csv``): the machine-readable copy.

Which value is best depends on the column: higher is better for scores (IDF1, HOTA, MOTA,
MOTP as a mean IoU, Recall, MT, ReID ...), lower is better for errors (FP, FN, IDs, Frag, ML,
the paper tables' ML/Frag/IDS/Missed/Under/Over/dx%..., per-visibility IDs_*), and columns
that are neither (PT, GT counts) are never marked.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

import numpy as np
import pandas as pd

COMBINED = "COMBINED"

# Lower is better: error counts and rates (a distance MOTP is not listed: ours is an IoU).
LOWER_IS_BETTER: frozenset[str] = frozenset({
    "FP", "FN", "IDs", "IDSW", "Frag", "ML", "IDFP", "IDFN",
    # paper tables (occbench.metrics.paper): Song et al. for Reta, PBM Tables 1-4
    "Song_ML%", "Song_Frag", "Song_IDS", "PBM_ML", "PBM_Missed", "PBM_Under", "PBM_Over",
    "PBM_IDsw/traj", "PBM_IDs/traj", "PBM_IDs/frame", "PBM_dx%", "PBM_dy%", "PBM_dw%",
    "PBM_dh%",
    # occlusion (occbench.metrics.occlusion): frames to re-identify after a total occlusion
    "ReID_frames",
})
LOWER_PREFIXES = ("IDs_", "FP_", "FN_", "Frag_")  # per-bin error counts, e.g. IDs_v0-25
# Neither: sizes of the ground truth or of the evaluation, not a quality.
NEUTRAL: frozenset[str] = frozenset({
    "PT", "GT", "Song_GT", "Song_PT%", "PBM_GT", "ReID_n", "frames", "num_frames",
})
#: Decimals of every figure a table shows that is not a count (``number``).
DIGITS = 3
# Columns written as whole numbers (when their values are whole).
COUNTS: frozenset[str] = frozenset({
    "GT", "MT", "PT", "ML", "FP", "FN", "IDs", "Frag", "TP", "IDTP", "IDFP", "IDFN",
    "Song_GT", "Song_Frag", "Song_IDS", "PBM_GT", "PBM_MT", "PBM_MT1", "PBM_ML", "PBM_Missed",
    "PBM_Under", "PBM_Over", "ReID_n",
})


def direction(column: str) -> int:
    """+1 when a higher value of ``column`` is better, -1 when lower is, 0 when neither."""
    if column in LOWER_IS_BETTER or column.startswith(LOWER_PREFIXES):
        return -1
    if column in NEUTRAL or column in ("tracker", "sequence", "status"):
        return 0
    return 1


def comparison(
    metrics: pd.DataFrame, columns: Iterable[str] | None = None, sequence: str = COMBINED
) -> pd.DataFrame:
    """Rows of ``sequence`` (default the COMBINED rows), indexed by tracker.

    Args:
        metrics: frame with ``tracker`` and ``sequence`` columns plus metric columns.
        columns: metric columns to keep, in this order; names absent from ``metrics`` are
            dropped. None keeps every metric column.
    """
    rows = metrics[metrics["sequence"] == sequence].set_index("tracker")
    rows = rows.drop(columns=["sequence", "complete"], errors="ignore")
    if columns is not None:
        rows = rows[[c for c in columns if c in rows.columns]]
    rows.index.name = "tracker"
    return rows


def is_count(column: str, values: pd.Series) -> bool:
    """Whether ``column``'s ``values`` are shown as whole numbers: an integer column, or a
    count (``COUNTS``, per-bin errors) whose finite values are all whole."""
    finite = pd.to_numeric(values, errors="coerce").to_numpy(dtype=float)
    finite = finite[np.isfinite(finite)]
    if pd.api.types.is_integer_dtype(values.dtype):
        return True
    counted = column in COUNTS or column.startswith(LOWER_PREFIXES)
    return counted and bool(np.all(finite == np.round(finite)))


def _is_count(df: pd.DataFrame, column: str) -> bool:
    return is_count(str(column), df[column])


def number(value: float, count: bool = False, digits: int = DIGITS) -> str:
    """A figure as every table shows it (run and sweep tables, their pages, ``occbench
    eval``): a count as a whole number, any other number with ``digits`` decimals, NaN '-'."""
    if math.isnan(value):
        return "-"
    return str(round(float(value))) if count else f"{float(value):.{digits}f}"


def _rounded(df: pd.DataFrame, digits: int) -> pd.DataFrame:
    out = pd.DataFrame(index=df.index)
    for c in df.columns:
        v = pd.to_numeric(df[c], errors="coerce").astype(float)
        out[c] = v.round(0 if _is_count(df, c) else digits)
    return out


def best_mask(df: pd.DataFrame, digits: int = DIGITS, sense: int | None = None) -> pd.DataFrame:
    """Boolean frame, True where a cell holds its column's best value (ties all True, but a
    column where every value ties is not marked).

    Values are compared as displayed (rounded to ``digits``, counts to whole numbers); a
    column with fewer than two finite values or no direction is never marked. ``sense``
    (+1 higher is better, -1 lower is better) overrides ``direction`` for every column, for
    tables whose columns are not metrics (``per_sequence``).
    """
    rounded = _rounded(df, digits)
    mask = pd.DataFrame(False, index=df.index, columns=df.columns)
    for c in df.columns:
        d = direction(str(c)) if sense is None else sense
        v = rounded[c].to_numpy(dtype=float)
        finite = np.isfinite(v)
        if d == 0 or finite.sum() < 2:
            continue
        best = np.max(d * v[finite])
        if np.all(d * v[finite] == best):  # every value ties (all zero...): nothing is best
            continue
        mask[c] = finite & (d * np.where(finite, v, 0.0) == best)
    return mask


def format_values(df: pd.DataFrame, digits: int = DIGITS) -> pd.DataFrame:
    """Cells as strings: counts as integers, other numbers with ``digits`` decimals, NaN as '-'."""
    out = pd.DataFrame(index=df.index, columns=df.columns, dtype=object)
    for c in df.columns:
        count = _is_count(df, c)
        for i, v in zip(df.index, df[c]):
            if isinstance(v, str):
                out.loc[i, c] = v
            elif v is None or (isinstance(v, float) and math.isnan(v)):
                out.loc[i, c] = "-"
            else:
                out.loc[i, c] = number(float(v), count, digits)
    return out


def _cells(df: pd.DataFrame, digits: int, mark_best: bool, mark: str,
           sense: int | None) -> list[list[str]]:
    text = format_values(df, digits)
    best = best_mask(df, digits, sense) if mark_best else None
    rows = []
    for i in df.index:
        row = [str(i)]
        for c in df.columns:
            s = text.loc[i, c]
            if best is not None and best.loc[i, c]:
                s = mark.format(s)
            row.append(s)
        rows.append(row)
    return rows


def _header(df: pd.DataFrame) -> list[str]:
    return [str(df.index.name or "")] + [str(c) for c in df.columns]


def to_markdown(df: pd.DataFrame, digits: int = DIGITS, mark_best: bool = True,
                sense: int | None = None) -> str:
    """GitHub Markdown table, index as the first column, best values in ``**bold**``."""
    header = _header(df)
    rows = _cells(df, digits, mark_best, "**{}**", sense)
    lines = ["| " + " | ".join(header) + " |",
             "|" + "|".join(["---"] + ["---:"] * (len(header) - 1)) + "|"]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines) + "\n"


_LATEX_SPECIAL = {"\\": r"\textbackslash{}", "_": r"\_", "%": r"\%", "&": r"\&", "#": r"\#",
                  "$": r"\$", "{": r"\{", "}": r"\}", "~": r"\textasciitilde{}",
                  "^": r"\textasciicircum{}"}


def latex_escape(text: str) -> str:
    """``text`` with LaTeX's special characters escaped."""
    return "".join(_LATEX_SPECIAL.get(ch, ch) for ch in text)


def to_latex(df: pd.DataFrame, digits: int = DIGITS, mark_best: bool = True,
             caption: str | None = None, sense: int | None = None) -> str:
    """A booktabs ``tabular`` (inside a ``table`` when ``caption``), best values in \\textbf."""
    header = [latex_escape(h) for h in _header(df)]
    text = format_values(df, digits)
    best = best_mask(df, digits, sense) if mark_best else None
    body = []
    for i in df.index:
        cells = [latex_escape(str(i))]
        for c in df.columns:
            s = latex_escape(text.loc[i, c])
            if best is not None and best.loc[i, c]:
                s = r"\textbf{" + s + "}"
            cells.append(s)
        body.append(" & ".join(cells) + r" \\")
    lines = [r"\begin{tabular}{l" + "r" * (len(header) - 1) + "}", r"\toprule",
             " & ".join(header) + r" \\", r"\midrule", *body, r"\bottomrule", r"\end{tabular}"]
    if caption is not None:
        lines = [r"\begin{table}", r"\centering", r"\caption{" + latex_escape(caption) + "}",
                 *lines, r"\end{table}"]
    return "\n".join(lines) + "\n"


def to_text(df: pd.DataFrame, digits: int = DIGITS, mark_best: bool = True,
            sense: int | None = None) -> str:
    """Aligned plain-text table for a terminal; best values followed by ``*``."""
    header = _header(df)
    rows = _cells(df, digits, mark_best, "{}*", sense)
    table = [header, *rows]
    widths = [max(len(r[j]) for r in table) for j in range(len(header))]
    lines = []
    for n, r in enumerate(table):
        cells = [r[0].ljust(widths[0])] + [s.rjust(w) for s, w in zip(r[1:], widths[1:])]
        lines.append("  ".join(cells).rstrip())
        if n == 0:
            lines.append("  ".join("-" * w for w in widths))
    return "\n".join(lines) + "\n"


def per_sequence(metrics: pd.DataFrame, metric: str,
                 sequences: Sequence[str] | None = None) -> pd.DataFrame:
    """One metric as a tracker x sequence table (COMBINED last), for per-sequence reports."""
    table = metrics.pivot(index="tracker", columns="sequence", values=metric)
    order = list(dict.fromkeys(metrics["tracker"]))
    seqs = list(sequences) if sequences is not None else [
        s for s in dict.fromkeys(metrics["sequence"]) if s != COMBINED]
    if COMBINED in table.columns:
        seqs.append(COMBINED)
    table = table.reindex(index=order, columns=[s for s in seqs if s in table.columns])
    table.columns.name = None
    return table
