"""Every reading or rule of ours that a tracker's docstring names has its row in
docs/adaptations.md (issue 37 item 5).

A docstring clause (split at '.' and ';') that calls something ours, a reading, or not in the
paper must say which row records it: a tag ``reading:NAME`` (the row's key column holds
`reading:NAME`), a field of the tracker's ``Adaptations`` (every field has its row:
``test_paper_mode``), a config key ``group.key`` written in the tracker's part of the file,
or the adaptations as a whole (a clause about all of them)."""

from __future__ import annotations

import ast
import dataclasses
import re
from pathlib import Path

import pytest

from occbench.trackers.comparators import loss as comparators_loss
from occbench.trackers.layered.adaptations import Adaptations as PBMAdaptations
from occbench.trackers.three_hypothesis.params import Adaptations as RetaAdaptations

ROOT = Path(__file__).resolve().parents[2]
DOC = (ROOT / "docs" / "adaptations.md").read_text()
MARK = re.compile(r"\bours\b|\b(?:our|a|the other|the paper's) reading\b|\breadings\b"
                  r"|not in the paper|paper does not have|beyond PBM|the paper gives no",
                  re.IGNORECASE)
SENTENCE = re.compile(r"(?<=\.)\s+(?=[A-Z(`*])")
#: a clause about the adaptations as a whole (every field has its row: test_paper_mode)
GENERAL = re.compile(r"\badaptations?\b|\bevery rule\b|``rules(?:\.py)?``", re.IGNORECASE)
TICKED = re.compile(r"``([^`]+)``")


def _part(start: str, end: str | None) -> str:
    i = DOC.index(start)
    return DOC[i:DOC.index(end, i)] if end else DOC[i:]


#: package folder -> (the part of docs/adaptations.md that records it, its Adaptations fields)
PACKAGES = {
    "three_hypothesis": (_part("## Reta et al. 2015", "## PBM"),
                         {f.name for f in dataclasses.fields(RetaAdaptations)}),
    "layered": (_part("## PBM", "## Localisation"),
                {f.name for f in dataclasses.fields(PBMAdaptations)}),
    "comparators": (_part("## PBM's comparators", "## The shared front end"), set()),
    "frontend": (_part("## The shared front end", None), set()),
}
TRACKERS = Path(comparators_loss.__file__).resolve().parents[1]


def _clauses(doc: str) -> list[str]:
    """The sentences of ``doc``, each cut at its semicolons outside parentheses."""
    out = []
    for sentence in SENTENCE.split(doc):
        depth, start = 0, 0
        for i, ch in enumerate(sentence):
            depth += (ch == "(") - (ch == ")")
            if ch == ";" and depth == 0:
                out.append(sentence[start:i + 1])
                start = i + 1
        out.append(sentence[start:])
    return [c.strip() for c in out if c.strip()]


def _docstrings(folder: Path):
    for path in sorted(folder.glob("*.py")):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef):
                doc = ast.get_docstring(node)
                if doc:
                    yield f"{path.name}:{getattr(node, 'name', '<module>')}", " ".join(doc.split())


def _recorded(clause: str, part: str, fields: set[str]) -> list[str]:
    """What is wrong with a marked clause: [] when it names its row."""
    ticked = TICKED.findall(clause)
    tags = [t.removeprefix("reading:") for t in ticked if t.startswith("reading:")]
    missing = [f"reading:{t}" for t in tags if f"`reading:{t}`" not in part]
    if tags:
        return missing
    if GENERAL.search(clause.replace("docs/adaptations.md", "")):
        return []
    for t in ticked:
        name = t.split("(")[0].removeprefix("adaptations.").removeprefix("Adaptations.")
        if name in fields or t.endswith("Adaptations") or ("." in t and f"`{t}`" in part):
            return []
    return ["no ``reading:NAME`` tag, Adaptations field or recorded config key"]


@pytest.mark.parametrize("package", sorted(PACKAGES))
def test_every_reading_a_docstring_names_has_its_row(package):
    part, fields = PACKAGES[package]
    problems = []
    for where, doc in _docstrings(TRACKERS / package):
        for clause in _clauses(doc):
            if MARK.search(clause):
                problems += [f"{where}: {why}: {clause[:160]}"
                             for why in _recorded(clause, part, fields)]
    assert not problems, "\n".join(problems)


def test_clauses_cut_at_semicolons_outside_parentheses():
    assert _clauses("A (ours; ``x``) b; c. D.") == ["A (ours; ``x``) b;", "c.", "D."]


def test_the_check_fails_on_an_unrecorded_reading():
    part, fields = PACKAGES["three_hypothesis"]
    assert _recorded("Our reading: the moon is made of cheese.", part, fields)
    assert _recorded("Ours (``reading:moon_cheese``).", part, fields) == ["reading:moon_cheese"]
    assert _recorded("Ours (``adaptations.gate_sigmas``).", part, fields) == []
