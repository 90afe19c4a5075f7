"""Paired comparisons as text: the ``summary.md`` section, the printed table's footer and the
rows of the HTML report (``occbench.metrics.paired`` computes them)."""

from __future__ import annotations

from collections.abc import Sequence

from occbench.metrics.paired import Bootstrap, PairedDifference

NOT_DISTINGUISHABLE = "not distinguishable on this data"


def cell(d: PairedDifference) -> str:
    """``+0.032 [+0.010, +0.055]``, with ``(n.d.)`` when the interval contains 0."""
    text = f"{d.difference:+.3f} [{d.low:+.3f}, {d.high:+.3f}]"
    return text if d.distinguishable else f"{text} (n.d.)"


def by_pair(diffs: Sequence[PairedDifference]) -> dict[tuple[str, str], list[PairedDifference]]:
    """The differences grouped by (a, b), in order."""
    out: dict[tuple[str, str], list[PairedDifference]] = {}
    for d in diffs:
        out.setdefault((d.a, d.b), []).append(d)
    return out


def paired_markdown(diffs: Sequence[PairedDifference], bootstrap: Bootstrap | None = None,
                    what: str = "trackers") -> str:
    """The ``summary.md`` section (empty text when there is no pair)."""
    if not diffs:
        return ""
    boot = bootstrap or Bootstrap()
    metrics = list(dict.fromkeys(d.metric for d in diffs))
    lines = [f"## Paired differences of {what} (A - B, COMBINED)", "",
             (f"{boot.describe()}. (n.d.): the interval contains 0, the difference is "
              f"{NOT_DISTINGUISHABLE}."), "",
             "| A | B | " + " | ".join(metrics) + " |", "|---|---|" + "---|" * len(metrics)]
    for (a, b), group in by_pair(diffs).items():
        cells = {d.metric: cell(d) for d in group}
        lines.append(f"| {a} | {b} | " + " | ".join(cells.get(m, "-") for m in metrics) + " |")
    first = diffs[0]
    lines += ["", f"Resampled: {first.frames} frames of {first.sequences} sequence(s).", ""]
    return "\n".join(lines)


def paired_footer(diffs: Sequence[PairedDifference], bootstrap: Bootstrap | None = None,
                  most: int = 6) -> str:
    """Lines under the printed table: one per pair, then how the interval was made.

    With more than ``most`` pairs (``tracker=everyone`` has 190), only the pairs of the
    leader (the highest value of the first metric, IDF1) are printed, and a line says where
    the others are.
    """
    if not diffs:
        return ""
    boot = bootstrap or Bootstrap()
    pairs = by_pair(diffs)
    shown = pairs
    if len(pairs) > most:
        values = {}
        for d in diffs:
            if d.metric == diffs[0].metric:
                values.update({d.a: d.value_a, d.b: d.value_b})
        leader = max(values, key=lambda name: values[name])  # first of equals, in order
        shown = {ab: group for ab, group in pairs.items() if leader in ab}
    lines = ["paired differences A - B [95% interval]:"]
    for (a, b), group in shown.items():
        parts = [f"{d.metric} {d.difference:+.3f} [{d.low:+.3f}, {d.high:+.3f}]"
                 + ("" if d.distinguishable else f" {NOT_DISTINGUISHABLE}") for d in group]
        lines.append(f"  {a} - {b}: " + "; ".join(parts))
    if len(shown) < len(pairs):
        lines.append(f"  ({len(pairs) - len(shown)} more pairs without the leader by "
                     f"{diffs[0].metric}: summary.md and report.html give all {len(pairs)})")
    lines.append(f"  ({boot.describe()})")
    return "\n".join(lines) + "\n"
