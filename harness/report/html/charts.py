"""The report's interactive charts as Vega-Lite specs, built with Altair.

Each function returns a spec (a dict) that ``occbench.report.html.page`` embeds with the
Vega bundle inlined; the data travels inside the spec. Colours: each tracker's own (its
config's ``meta:`` block, ``occbench.config.meta``, as in the PNG plots), one per error kind
in the timeline.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import altair as alt
import numpy as np
import pandas as pd

from occbench.config.meta import TrackerMeta, metas
from occbench.metrics.paired import PairedDifference
from occbench.metrics.timeline import FrameCounts

#: the timeline's error kinds: (FrameCounts attribute, label, colour)
KINDS = (("misses", "miss (FN)", "#9e9e9e"), ("false_positives", "false positive", "#ff9800"),
         ("switches", "identity switch", "#d62728"))
FONT = {"labelFontSize": 12, "titleFontSize": 13}
WIDTH = 900


def _spec(chart: Any) -> dict[str, Any]:
    """The Vega-Lite dict of an Altair chart, with readable fonts. Every row goes in: Altair
    refuses data over 5,000 rows by default (a guard against huge notebooks), which a long
    sequence's timeline of twenty trackers passes; the page is self-contained by design."""
    with alt.data_transformers.disable_max_rows():
        return chart.configure_axis(**FONT).configure_legend(**FONT).configure_title(
            fontSize=14, anchor="start").to_dict()


def segments(frames: np.ndarray, count: np.ndarray) -> list[tuple[int, int, int]]:
    """Runs of consecutive frames with the same nonzero count: (first, last, count)."""
    out: list[tuple[int, int, int]] = []
    for f, n in zip(frames.tolist(), count.tolist()):
        if n <= 0:
            continue
        if out and out[-1][1] == f - 1 and out[-1][2] == n:
            out[-1] = (out[-1][0], f, n)
        else:
            out.append((f, f, n))
    return out


def timeline(sequence: str, counts: Mapping[str, FrameCounts],
             video: bool = False) -> dict[str, Any]:
    """Each tracker's misses, false positives and identity switches over the frames of one
    sequence (``FrameCounts``: the metrics' own matching), one row per tracker, a tracker
    without errors too; with ``video``, a click on a mark seeks the sequence's video to its
    ``frame`` (the title says so only then). Runs of equal counts are one bar
    (``segments``), to keep the page small."""
    rows = []
    for tracker, c in counts.items():
        for attr, label, _ in KINDS:
            for f, g, n in segments(c.frames, getattr(c, attr)):
                rows.append({"tracker": tracker, "kind": label, "frame": f, "end": g + 1,
                             "last": g, "count": n})
    data = pd.DataFrame(rows, columns=["tracker", "kind", "frame", "end", "last", "count"])
    kinds = [k[1] for k in KINDS]
    first = int(min(c.frames.min() for c in counts.values() if len(c.frames)))
    last = int(max(c.frames.max() for c in counts.values() if len(c.frames))) + 1
    chart = alt.Chart(data).mark_rect(cursor="pointer").encode(
        x=alt.X("frame:Q", title="frame", scale=alt.Scale(domain=[first, last], nice=False)),
        x2="end:Q",
        y=alt.Y("tracker:N", title=None, sort=list(counts),
                scale=alt.Scale(domain=list(counts))),
        yOffset=alt.YOffset("kind:N", sort=kinds),
        color=alt.Color("kind:N", title="error", sort=kinds, scale=alt.Scale(
            domain=kinds, range=[k[2] for k in KINDS]), legend=alt.Legend(orient="top")),
        tooltip=[alt.Tooltip("tracker:N"), alt.Tooltip("kind:N"),
                 alt.Tooltip("frame:Q", title="from frame"), alt.Tooltip("last:Q", title="to"),
                 alt.Tooltip("count:Q", title="per frame")],
    ).properties(width=WIDTH, height=alt.Step(9),
                 title=f"{sequence}: errors per frame"
                 + (" (click to seek the video)" if video else ""))
    return _spec(chart)


def paired_forest(diffs: Sequence[PairedDifference]) -> dict[str, Any]:
    """Each pair's difference with its interval, one panel per metric, a rule at 0."""
    data = pd.DataFrame([{"pair": f"{d.a} - {d.b}", "metric": d.metric,
                          "difference": d.difference, "low": d.low, "high": d.high,
                          "verdict": "distinguishable" if d.distinguishable
                          else "not distinguishable"} for d in diffs])
    base = alt.Chart()
    bars = base.mark_rule(strokeWidth=2).encode(
        x=alt.X("low:Q", title="difference A - B (95% interval)"), x2="high:Q",
        y=alt.Y("pair:N", title=None, sort=None, axis=alt.Axis(labelLimit=360)))
    dots = base.mark_point(filled=True, size=70).encode(
        x="difference:Q", y=alt.Y("pair:N", sort=None),
        color=alt.Color("verdict:N", title=None, scale=alt.Scale(
            domain=["distinguishable", "not distinguishable"], range=["#1f77b4", "#9e9e9e"]),
            legend=alt.Legend(orient="top")),
        tooltip=["pair:N", "metric:N", alt.Tooltip("difference:Q", format="+.3f"),
                 alt.Tooltip("low:Q", format="+.3f"), alt.Tooltip("high:Q", format="+.3f"),
                 "verdict:N"])
    zero = base.mark_rule(strokeDash=[4, 3], color="#555").encode(x=alt.datum(0))
    layered = alt.layer(bars, dots, zero, data=data).properties(width=230)
    chart = layered.facet(column=alt.Column("metric:N", title=None, sort=["IDF1", "HOTA",
                                                                          "MOTA"]))
    return _spec(chart.properties(title="Paired differences (A - B)"))


def metric_lines(agg: pd.DataFrame, parameter: str, metric: str,
                 looks: Mapping[str, TrackerMeta] | None = None) -> dict[str, Any]:
    """A sweep's ``metric`` (mean and 95% bootstrap interval over seeds: ``aggregate``'s
    columns, the numbers of the sweep's PNG and sweep.md)
    against one ``parameter``, one line per tracker in its label and colour (``looks``,
    default: the shipped configs' by name)."""
    data = agg[[parameter, "tracker", metric, f"{metric}_low", f"{metric}_high", "n"]].copy()
    data.columns = ["value", "tracker", "mean", "low", "high", "n"]
    looks = metas(dict.fromkeys(data["tracker"].astype(str)), known=looks)
    data["tracker"] = [looks[str(t)].label for t in data["tracker"]]
    numeric = pd.to_numeric(data["value"], errors="coerce").notna().all()
    if numeric:
        data["value"] = pd.to_numeric(data["value"])
    x = alt.X("value:Q" if numeric else "value:N", title=parameter,
              scale=alt.Scale(zero=False) if numeric else alt.Undefined)
    color = alt.Color("tracker:N", title="tracker", legend=alt.Legend(orient="top"),
                      scale=alt.Scale(domain=[m.label for m in looks.values()],
                                      range=[m.colour for m in looks.values()]))
    base = alt.Chart(data)
    line = base.mark_line(point=True).encode(x=x, y=alt.Y("mean:Q", title=metric,
                                                          scale=alt.Scale(zero=False)),
                                             color=color,
                                             tooltip=["tracker:N", "value", alt.Tooltip(
                                                 "mean:Q", format=".4f"), "n:Q"])
    band = base.mark_errorbar(ticks=True).encode(x=x, y=alt.Y("low:Q", title=metric),
                                                 y2="high:Q", color=color)
    chart = alt.layer(band, line).properties(
        width=300, height=200, title=f"{metric} against {parameter} (mean, 95% interval)")
    return _spec(chart)
