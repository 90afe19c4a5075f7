"""Each of our trackers against the best outside tracker of every set of a generalisation
table (``occbench.sweeps.generalisation``): issue 28's acceptance ("each paper tracker ahead
of every outside tracker, tuned or not, on IDF1 and HOTA"), computed from the table rather
than read off it by eye.

*Outside* is every tracker of the table whose config's ``meta:`` block gives the role
``outside`` (``occbench.config.meta``; not our SORT baseline, the two paper trackers or their
paper modes), so tuned and BoxMOT rows count; *ours* are those of role ``ours``.
Per metric the best outside tracker is taken on its own (the best IDF1 and the best HOTA may
be two trackers), as the acceptance asks to beat every one of them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import pandas as pd

from occbench.config.meta import metas
from occbench.report.tables import number
from occbench.sweeps.generalisation import METRICS, TUNING, EvalSet


def versus_outside(table: pd.DataFrame, ours: Sequence[str] | None = None) -> pd.DataFrame:
    """One row per (set, tracker of ``ours``, default: the table's trackers of role ``ours``)
    present in ``table`` (the long table: set, role, tracker, IDF1, HOTA, MOTA, ...): the
    tracker's metrics, the best outside tracker's per metric (``best_<M>``, ``best_<M>_by``)
    and the margin ``<M> - best`` (``margin_<M>``). A set without an outside tracker gives
    no row."""
    roles = _roles(table)
    if ours is None:
        ours = [n for n, role in roles.items() if role == "ours"]
    bests = best_outside(table)
    rows = []
    for name, s in table.groupby("set", sort=False):
        if name not in bests:
            continue
        best = bests[name]
        for t in ours:
            mine = s[s["tracker"] == t]
            if mine.empty:
                continue
            row = {"set": name, "role": mine["role"].iloc[0], "tracker": t}
            for m in METRICS:
                row[m] = float(mine[m].iloc[0])
                b = best.get(m)  # None: no outside tracker scored on m
                row[f"best_{m}"] = float("nan") if b is None else float(b[m])
                row[f"best_{m}_by"] = "" if b is None else b["tracker"]
                row[f"margin_{m}"] = row[m] - row[f"best_{m}"]
            rows.append(row)
    return pd.DataFrame(rows)


def _roles(table: pd.DataFrame) -> dict[str, str]:
    return {n: m.role for n, m in metas(dict.fromkeys(table["tracker"].astype(str))).items()}


def best_outside(table: pd.DataFrame, metrics: Sequence[str] = METRICS,
                 ) -> dict[str, dict[str, pd.Series]]:
    """Set -> metric of ``metrics`` -> the table row of the best outside tracker of that set
    on that metric (each metric on its own; a metric no outside tracker of the set scored is
    absent); a set with no outside tracker scored on any of ``metrics`` is absent."""
    roles = _roles(table)
    out = {}
    for name, s in table.groupby("set", sort=False):
        outside = s[s["tracker"].astype(str).map(roles) == "outside"].dropna(
            subset=list(metrics), how="all")
        if not outside.empty:
            out[name] = {m: outside.loc[outside[m].idxmax()] for m in metrics
                         if outside[m].notna().any()}
    return out


def verdict(row: pd.Series) -> str:
    """"ahead" when IDF1 and HOTA both beat the best outside tracker's at three decimals
    (the table's precision); else which are level and which behind, by how much; "no score"
    when either side of IDF1 or HOTA is missing (NaN), never a verdict on a missing figure."""
    if any(math.isnan(row[k]) for m in ("IDF1", "HOTA") for k in (m, f"best_{m}")):
        return "no score"
    level, behind = [], []
    for m in ("IDF1", "HOTA"):
        gap = round(round(row[m], 3) - round(row[f"best_{m}"], 3), 3)
        if gap == 0:
            level.append(m)
        elif gap < 0:
            behind.append(f"{m} {gap:+.3f}")
    parts = ([f"level: {', '.join(level)}"] if level else []) + (
        [f"behind: {', '.join(behind)}"] if behind else [])
    return "; ".join(parts) or "ahead"


def markdown(versus: pd.DataFrame, sets: Sequence[EvalSet]) -> str:
    """The verdicts as a table, sets in ``sets``' order, choosing (T) and reporting (U) sets
    side by side; one sentence when no set has both one of ours and an outside tracker (the
    outside extras not installed)."""
    if versus.empty:
        return ("No set has an outside tracker beside ours (are the outside extras installed? "
                "README, 'Outside trackers'): nothing to compare against.\n")
    order = {s.name: i for i, s in enumerate(sets)}
    v = versus.sort_values("set", key=lambda c: c.map(lambda n: order.get(n, len(order))),
                           kind="stable")
    lines = ["| set | tracker | IDF1 / HOTA / MOTA | best outside: IDF1; HOTA; MOTA | verdict |",
             "|---|---|---|---|---|"]
    for _, r in v.iterrows():
        mark = "T" if r["role"] == TUNING else "U"
        ours = " / ".join(number(r[m]) for m in METRICS)
        best = "; ".join(f"{r[f'best_{m}_by']} {number(r[f'best_{m}'])}" for m in METRICS)
        lines.append(f"| {r['set']} ({mark}) | {r['tracker']} | {ours} | {best} | {verdict(r)} |")
    return "\n".join(lines) + "\n"
