"""The README's equation table and docs/adaptations.md point at code that runs.

Each row of the README's table names a readable definition (plain numpy), the functions a
default run calls, and the tests that tie the two where they differ. Here the default
``tracker=reta`` and ``tracker=pbm`` (and ``pbm_paper``, for the paper's head detector)
run once on a short synthetic scene with every call traced, compiled kernels included
(``tests/traced_run.py``); a row whose running function is not called, whose definition
no longer exists, or whose tie test is missing or does not call the definition fails.
docs/adaptations.md's code references must exist and run, or be recorded there as
removed (then they must not exist).
"""

from __future__ import annotations

import ast
import functools
import importlib
import re
from pathlib import Path

import pytest
from traced_run import calls

ROOT = Path(__file__).resolve().parents[1]
HEADER = "| paper | equation or step | definition | a default run calls | tied by |"
TRACKER = {"Reta": "reta", "PBM": "pbm"}


@functools.cache
def traced() -> dict[str, set[tuple[str, str]]]:
    return calls("reta", "pbm", "pbm_paper")


def table_rows() -> list[list[str]]:
    """The equation table's rows, five cells each."""
    lines = (ROOT / "README.md").read_text().splitlines()
    start = lines.index(HEADER) + 2
    rows = []
    for line in lines[start:]:
        if not line.startswith("|"):
            break
        cells = [c.strip() for c in line.strip()[1:-1].split("|")]
        assert len(cells) == 5, f"README equation table: not 5 cells: {line}"
        rows.append(cells)
    return rows


def references(cell: str) -> list[tuple[str, str]]:
    """(path, name) of every backticked ``path: name, name`` or ``name`` of a cell; a bare
    name belongs to the last path named before it."""
    out, path = [], None
    for token in re.findall(r"`([^`]+)`", cell):
        if ": " in token:
            path, token = token.split(": ", 1)
        assert path is not None, f"{token!r} names no file ({cell})"
        out += [(path, name.strip()) for name in token.split(",")]
    return out


def resolve(path: str, name: str) -> object:
    """The object ``name`` (``Class.method`` allowed) of module ``trackers/<path>``."""
    obj = importlib.import_module("occbench.trackers." + path.removesuffix(".py").replace("/", "."))
    for part in name.split("."):
        obj = getattr(obj, part)
    return obj


def functions_of(path: Path) -> dict[str, set[str]]:
    """{test function of a test file: every name and attribute its body uses}."""
    out = {}
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.FunctionDef):
            out[node.name] = {n.id for n in ast.walk(node) if isinstance(n, ast.Name)} | {
                n.attr for n in ast.walk(node) if isinstance(n, ast.Attribute)}
    return out


ROWS = table_rows()


def test_the_table_has_both_papers_rows():
    assert {row[0] for row in ROWS} == {"Reta", "PBM"} and len(ROWS) >= 12


@pytest.mark.parametrize("row", ROWS, ids=[f"{r[0]} {r[1]}" for r in ROWS])
def test_each_row_names_code_a_default_run_calls(row):
    paper, step, definition, runs, tied = row
    called = traced()[TRACKER[paper]]
    running = references(runs)
    assert running, f"{step}: names no running function"
    for path, name in running:
        resolve(path, name)
        assert (path, name) in called, f"{paper} {step}: {path}: {name} not called by a default run"
    defined = references(definition)
    for path, name in defined:
        resolve(path, name)
    if defined and set(defined) != set(running):
        tests = references(tied)
        assert tests, f"{step}: the definition differs from what runs, and no test ties them"
        used: set[str] = set()
        for path, name in tests:
            functions = functions_of(ROOT / "tests" / "trackers" / path)
            assert name in functions, f"{step}: tests/trackers/{path} has no {name}"
            used |= functions[name]
        missing = [name for _, name in defined if name.split(".")[-1] not in used]
        assert not missing, f"{step}: no tie test calls the definition {missing}"


# ----------------------------------------------------------------------- docs/adaptations.md

# Code docs/adaptations.md records as built, measured and removed: it must not exist.
REMOVED = {
    "trackers/common/noise.py": "noise14, removed in commit 1233596",
    "occbench.trackers.common.noise.KalmanNoiseML": "noise14",
    "KalmanNoiseML": "noise14",
    "KalmanNoiseML.predicted": "noise14",
    "tests/test_position_gate.py": "pbmnoise14, 'of that commit'",
    "layered rules.PositionGate": "pbmnoise14, removed",
    "layered rules.AppearanceMargin": "pbmswap, removed (reta's rule of that name stays)",
    "layered rules.MergeStacked": "dup14, removed",
}
# Code named there that a default run does not call, and the test that ties it instead.
NOT_RUN = {  # named in the doc, run by no tracker: the test that runs it instead
    "Adaptations.paper()": ("three_hypothesis/test_tracker.py",
                            "test_paper_mode_turns_every_adaptation_off"),
    # the paper's detector (front end, detector=active_basis), not a tracker's code
    "trackers/frontend/shape_search.py": (
        "frontend/test_shape_search.py",
        "test_greedy_search_finds_each_person_once_and_stops_when_the_foreground_is_explained"),
    # the comparators' loss and restart rules (tracker=meanshift, particle_filter)
    "trackers/comparators/loss.py": (
        "comparators/test_loss.py",
        "test_a_hidden_person_is_lost_after_k_frames_and_restarted_under_a_new_id"),
    "NeverLost": ("comparators/test_loss.py",
                  "test_never_lost_keeps_one_track_and_loss_changes_nothing_before_it"),
}


def _defined_classes() -> dict[str, list[str]]:
    """{class name: [paths under trackers/]} of every class the trackers define."""
    out: dict[str, list[str]] = {}
    for path in sorted((ROOT / "trackers").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ClassDef):
                out.setdefault(node.name, []).append(path.relative_to(ROOT / "trackers").as_posix())
    return out


def adaptation_references() -> list[tuple[str, str]]:
    """(section tracker, reference) of every backticked code reference: a .py path, a
    dotted ``trackers.``/``harness.`` name, ``rules.X`` (a name in the tracker's rules.py or
    a step of its ``Rules``), a class (``Name`` or
    ``Name.member``) or a test function."""
    out, section = [], "three_hypothesis"
    code = re.compile(r"^([\w/]+\.py|(trackers|harness)\.[\w.]+|rules\.\w+|[A-Z][a-z]+[A-Z]\w*"
                      r"(\.\w+(\(\))?)?|[A-Z]\w+\.\w+(\(\))?|test_\w+(\.\.\.)?)$")
    for line in (ROOT / "docs" / "adaptations.md").read_text().splitlines():
        if line.startswith("## "):
            section = "layered" if line.startswith("## PBM") else "three_hypothesis"
        out += [(section, t) for t in re.findall(r"`([^`]+)`", line) if code.match(t)]
    return out


def _exists(section: str, ref: str, classes: dict[str, list[str]]) -> tuple[bool, set]:
    """Whether ``ref`` exists, and the (path, qualname prefix) pairs a run calling it shows."""
    if ref.endswith(".py"):
        path = ROOT / ref
        rel = ref.removeprefix("trackers/")
        return path.is_file(), {(rel, "")} if ref.startswith("trackers/") else set()
    if ref.startswith("occbench."):
        module, _, name = ref.rpartition(".")
        try:
            getattr(importlib.import_module(module), name)
        except (ImportError, AttributeError):
            return False, set()
        path = module.removeprefix("occbench.trackers.").replace(".", "/") + ".py"
        return True, {(path, name)} if ref.startswith("occbench.trackers.") else set()
    if ref.startswith("rules."):
        name = ref.split(".")[1]
        module = importlib.import_module(f"occbench.trackers.{section}.rules")
        if name in module.Rules._fields:  # a step of Rules: build_rules fills it on every run
            return True, {(f"{section}/rules.py", "build_rules")}
        return hasattr(module, name), {(f"{section}/rules.py", name)}
    if ref.startswith("test_"):
        prefix = ref.removesuffix("...")
        names = [n for p in (ROOT / "tests").rglob("test_*.py") for n in functions_of(p)]
        return any(n == prefix or (ref.endswith("...") and n.startswith(prefix))
                   for n in names), set()
    name = ref.removesuffix("()")
    paths = classes.get(name.split(".")[0], [])
    path = next((p for p in paths if p.startswith(section + "/")), paths[0] if paths else None)
    if path is None:
        return False, set()
    try:
        resolve(path, name)
    except AttributeError:
        return False, set()
    return True, {(path, name)}


def test_adaptations_doc_names_code_that_exists_and_runs():
    classes = _defined_classes()
    called = set().union(*traced().values())
    refs = adaptation_references()
    assert len(refs) > 10
    for section, ref in refs:
        key = f"{section} {ref}" if ref.startswith("rules.") else ref
        ok, shows = _exists(section, ref, classes)
        if key in REMOVED:
            assert not ok, f"docs/adaptations.md records {ref} removed ({REMOVED[key]}): it exists"
            continue
        assert ok, f"docs/adaptations.md names {ref}, which does not exist (removed? say so)"
        if ref in NOT_RUN:
            path, test = NOT_RUN[ref]
            assert test in functions_of(ROOT / "tests" / "trackers" / path), (ref, test)
            continue
        for path, name in shows:
            assert any(p == path and (name in ("", q) or q.startswith(name + "."))
                       for p, q in called), (
                f"docs/adaptations.md names {ref}: not called by tracker=reta, pbm or pbm_paper")
