"""Every paper-vs-ours difference larger than a third of the paper's figure (issue 37 item 6),
read from the tables of docs/reproduction.md (themselves written by benchmarks/reproduction.py),
as one markdown table that names, for each, the diagnosis below it in the document.

    python benchmarks/paper_differences.py              # print the table
    python benchmarks/paper_differences.py --write      # replace it in docs/reproduction.md

What is compared with what (``PAIRS``): each paper's own tracker against our trackers of that
paper (defaults and paper mode; in Reta's Table 3 PBM's too, since the table runs them), each
comparator against ours of the same name, the paper's detector against ours. Counts are put on
a common scale first, as the tables' data differ in size: Frag and IDS per ground-truth
trajectory (Reta's tables), PBM Table 1's trajectory counts as shares of the trajectories; the
rest (percentages, per-trajectory averages) as they are. A difference is listed when
``|ours - paper| > paper / 3`` (for a paper figure of 0: any difference). Each listed
difference names its diagnosis (``CAUSES``, the first rule that fits); one without a rule is
printed as ``undiagnosed`` and makes ``--check`` fail.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from fnmatch import fnmatch
from pathlib import Path

DOC = Path(__file__).resolve().parents[1] / "docs" / "reproduction.md"
BEGIN, END = "<!-- begin differences -->", "<!-- end differences -->"

_RETA = ("reta", "reta_paper")
_PBM = ("pbm", "pbm_paper")
#: table -> (the paper's row or column label starts with, our trackers, our label holds)
PAIRS: dict[str, list[tuple[str, tuple[str, ...], str]]] = {
    "reta_table2": [("Reta et al. 2015", _RETA, ""),
                    ("Basic particle filter", ("particle_filter",), "")],
    "reta_table3": [("Reta et al. 2015 on CAVIAR", _RETA + _PBM, "CAVIAR"),
                    ("Reta et al. 2015 on PETS", _RETA + _PBM, "PETS09-S2L1")],
    "reta_table3_real": [("Reta et al. 2015 on PETS", _RETA + _PBM, "")],
    "reta_detection": [("Reta et al. 2015 detection", ("active_basis", "silhouette"), ""),
                       ("HOG", ("hog",), "")],
    **{t: [("PBM", _PBM, ""), ("MS", ("meanshift", "meanshift_scale"), ""),
           ("CCMSPF", ("ccmspf",), "")] for t in ("pbm_table1", "pbm_table1_real")},
    **{t: [("PBM, PETS", _PBM, ""), ("MS, PETS", ("meanshift", "meanshift_scale"), ""),
           ("CCMSPF, PETS", ("ccmspf",), "")]
       for t in ("pbm_segmentation", "pbm_segmentation_real")},
}

#: (table pattern, tracker pattern, quantity pattern, diagnosis anchor): first match wins
CAUSES: list[tuple[str, str, str, str]] = [
    ("reta_table2", "*", "*", "few-people"),
    ("reta_table3", "*", "* (CAVIAR*", "few-people"),
    ("reta_table3", "pbm_paper", "[FI]*", "pbm-paper-stacks"),
    ("reta_table3", "reta_paper", "[FI]*", "reta-paper-switches"),
    ("reta_table3", "*", "*", "replay-tracking-alone"),
    ("reta_table3_real", "*", "*", "real-pets-multi"),
    ("reta_detection", "*", "*", "detection"),
    ("pbm_segmentation", "pbm*", "*", "replay-width"),
    ("pbm_segmentation", "*", "*", "comparators"),
    ("pbm_table1", "pbm*", "*", "pbm-follower"),
    ("pbm_table1", "*", "*", "comparators"),
    ("pbm_*_real", "*", "*", "real-pets-blobs"),
]


def sections(text: str) -> dict[str, list[list[str]]]:
    """table name -> its markdown table's rows (cells), for every generated section."""
    found = {}
    for name, body in re.findall(r"<!-- begin (\w+) -->(.*?)<!-- end \1 -->", text, re.DOTALL):
        rows = [[c.strip() for c in line.strip().strip("|").split("|")]
                for line in body.splitlines() if line.startswith("|")]
        if rows:
            found[name] = [r for r in rows if not set("".join(r)) <= set("-")]
    return found


def _number(cell: str) -> float:
    try:
        return float(cell)
    except ValueError:
        return math.nan


def methods(rows: list[list[str]]) -> dict[str, dict[str, float]]:
    """label -> quantity -> value, whichever way round the table is laid out."""
    head = rows[0]
    if any(c.startswith("ours:") for c in head):          # one column per method
        return {m: {r[0]: _number(r[j]) for r in rows[1:]} for j, m in enumerate(head) if j}
    return {r[0]: {q: _number(v) for q, v in zip(head[1:], r[1:], strict=True)} for r in rows[1:]}


def scaled(table: str, values: dict[str, float]) -> dict[str, float]:
    """The values on the common scale (see the module docstring)."""
    out = dict(values)
    if "GT" in values:                                   # Reta's (Song et al.) tables
        n = values["GT"]
        out.pop("GT")
        for q in ("Frag", "IDS"):
            out[f"{q} per trajectory"] = values[q] / n
            out.pop(q)
    trajectories = values.get("No. of trajectories")
    if table.startswith("pbm_table1"):
        n = 10.0 if math.isnan(trajectories) else trajectories   # the paper's GT column: 10
        out.pop("No. of trajectories")
        for q, v in values.items():
            if q.startswith("No. of") and q != "No. of trajectories":
                out[f"share of {q[len('No. of '):]}"] = v / n
                out.pop(q)
    return out


def _tracker(label: str) -> tuple[str, str]:
    """``ours: name (note)`` -> (name, note)."""
    name, _, note = label[len("ours: "):].partition(" (")
    return name, note.rstrip(")")


def cause(table: str, tracker: str, quantity: str) -> str:
    return next((c for t, k, q, c in CAUSES if fnmatch(table, t) and fnmatch(tracker, k)
                 and fnmatch(quantity, q)), "undiagnosed")


def differences(text: str) -> list[dict]:
    """One record per (table, our row, the paper's row) with a difference larger than a third."""
    out = []
    for table, rows in sections(text).items():
        by = methods(rows)
        for paper, trackers, holds in PAIRS.get(table, []):
            ref = next((m for m in by if m.startswith(f"reported: {paper}")), None)
            if ref is None:
                raise ValueError(f"{table}: no reported row starts with {paper!r}")
            p = scaled(table, by[ref])
            for label, values in by.items():
                name, note = _tracker(label) if label.startswith("ours:") else ("", "")
                if name not in trackers or holds not in note:
                    continue
                o = scaled(table, values)
                big = [(q, o[q], p[q]) for q in p if not math.isnan(p[q]) and q in o
                       and not math.isnan(o[q]) and abs(o[q] - p[q]) > abs(p[q]) / 3]
                if big:
                    out.append({"table": table, "ours": label[len("ours: "):],
                                "paper": ref[len("reported: "):], "big": big,
                                "cause": _causes(table, name, note, big)})
    return out


def _causes(table: str, name: str, note: str, big: list) -> list[str]:
    keys = [cause(table, name, f"{q} ({note})" if note else q) for q, _, _ in big]
    return list(dict.fromkeys(keys))


def _fmt(v: float) -> str:
    return f"{v:.3g}"


def markdown(diffs: list[dict]) -> str:
    lines = ["| table | ours | the paper's | quantity: ours vs the paper's | diagnosis |",
             "|---|---|---|---|---|"]
    for d in diffs:
        shown = "; ".join(f"{q} {_fmt(o)} vs {_fmt(p)}" for q, o, p in d["big"])
        causes = ", ".join(f"[{c}](#{c})" if c != "undiagnosed" else c for c in d["cause"])
        lines.append(f"| {d['table']} | {d['ours']} | {d['paper']} | {shown} | {causes} |")
    return "\n".join(lines) + "\n"


def _block() -> re.Pattern:
    return re.compile(re.escape(BEGIN) + ".*?" + re.escape(END), re.DOTALL)


def refresh(text: str) -> str:
    """``text`` with its differences table (if it has the block) rebuilt from its tables."""
    new = f"{BEGIN}\n{markdown(differences(text))}{END}"
    return _block().sub(lambda _: new, text) if _block().search(text) else text


def problems(text: str) -> list[str]:
    """What is wrong with the document's differences table: stale, undiagnosed, or a
    diagnosis named that has no ``<a id=...>`` anchor in the document."""
    out = []
    if not _block().search(text):
        out.append(f"no {BEGIN} ... {END} block")
    elif refresh(text) != text:
        out.append("the differences table is stale "
                   "(python benchmarks/paper_differences.py --write)")
    named = {c for d in differences(text) for c in d["cause"]}
    if "undiagnosed" in named:
        out.append("a difference has no diagnosis (paper_differences.CAUSES)")
    for c in sorted(named - {"undiagnosed"}):
        anchor = f'<a id="{c}"></a>'
        if anchor not in text:
            out.append(f"diagnosis {c!r} has no {anchor} in the document")
            continue
        body = text.split(anchor, 1)[1].split('<a id="', 1)[0]
        figures = re.findall(r"\]\((img/[^)]+\.png)\)", body)
        if not figures:
            out.append(f"diagnosis {c!r} shows no figure (![...](img/....png))")
        out += [f"diagnosis {c!r}: {f} does not exist" for f in figures
                if not (DOC.parent / f).is_file()]
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--doc", type=Path, default=DOC)
    p.add_argument("--write", action="store_true", help="replace the table in the document")
    p.add_argument("--check", action="store_true",
                   help="exit 1 when the table is stale, a difference undiagnosed or unanchored")
    args = p.parse_args(argv)
    text = args.doc.read_text()
    if args.check:
        found = problems(text)
        for problem in found:
            print(f"occbench: {args.doc}: {problem}", file=sys.stderr)
        return 1 if found else 0
    if args.write:
        if not _block().search(text):
            raise SystemExit(f"occbench: {args.doc}: no {BEGIN} ... {END} block to replace")
        args.doc.write_text(refresh(text))
    print(markdown(differences(text)), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
