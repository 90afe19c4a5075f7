"""The layout's rules, read from the source (every import, function-level ones too).

- No import circles: no module in ``trackers/`` or ``harness/`` imports (directly or through
  other modules of ours) a module that imports it back; no room of ``harness/`` imports
  (directly or round a loop) a room that imports it back.
- ``trackers`` never imports ``harness``.
- ``harness/report/`` imports nothing from ``occbench.pipeline.experiment``.
- ``harness/``'s rooms: at most 8 top modules, only the rooms; no library room imports a
  command; no module over 400 lines and no function over 80 (kernel files excepted); no
  private name (``_x``, or a ``_x`` module) imported from another package; only the tracker
  bank (``harness/pipeline/bank.py``) calls a tracker's ``update``; no import inside a
  function without its reason in a comment (``IMPORT_MARKER``); the config room registers
  its resolvers by an explicit call, not on import; ``report/`` imports no room that runs
  something.

Run as a script (``python tests/test_architecture.py``) to print every circle found.
"""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: source folder -> the import package it is installed as (pyproject.toml's package-dir)
PACKAGES = {"harness": "occbench", "trackers": "occbench.trackers"}


def module_files() -> dict[str, Path]:
    """Dotted module name -> source file, for every module of ``PACKAGES``."""
    out: dict[str, Path] = {}
    for pkg in PACKAGES:
        for path in sorted((ROOT / pkg).rglob("*.py")):
            parts = list(path.relative_to(ROOT / pkg).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join([PACKAGES[pkg], *parts])] = path
    return out


def _absolute(node: ast.ImportFrom, module: str, is_package: bool) -> str:
    if node.level == 0:
        return node.module or ""
    base = module.split(".") if is_package else module.split(".")[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _runtime_nodes(tree: ast.AST):
    """Every node of ``tree`` except those under ``if TYPE_CHECKING:`` (annotations only,
    never executed)."""
    todo = [tree]
    while todo:
        node = todo.pop()
        yield node
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and "TYPE_CHECKING" in ast.unparse(child.test):
                todo.extend(child.orelse)
                continue
            todo.append(child)


def imports(modules: dict[str, Path]) -> dict[str, set[str]]:
    """Module -> the modules of ours it imports anywhere in its source (top level or in a
    function; not under ``if TYPE_CHECKING:``). ``from a.b import c`` counts as importing
    ``a.b.c`` when that is a module, else ``a.b``; ``import a.b`` counts as importing ``a.b``."""
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        is_package = path.name == "__init__.py"
        targets: set[str] = set()
        for node in _runtime_nodes(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, ast.Import):
                targets.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom):
                base = _absolute(node, name, is_package)
                for alias in node.names:
                    sub = f"{base}.{alias.name}"
                    targets.add(sub if sub in modules else base)
        graph[name] = {t for t in targets if t in modules and t != name}
    return graph


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(found)


def _graph() -> dict[str, set[str]]:
    return imports(module_files())


def test_checker_sees_function_level_imports_and_circles() -> None:
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert circles(graph) == [["a", "b", "c"]]
    assert circles({"a": {"b"}, "b": set()}) == []
    src = "def f():\n    from occbench.pipeline.experiment import run_sequence\n"
    tree = ast.parse(src)
    node = next(n for n in ast.walk(tree) if isinstance(n, ast.ImportFrom))
    assert _absolute(node, "occbench.replay.video", False) == "occbench.pipeline.experiment"
    assert len([n for n in _runtime_nodes(tree) if isinstance(n, ast.ImportFrom)]) == 1
    guarded = ast.parse("if TYPE_CHECKING:\n    from a import b\nelse:\n    import c\n")
    found = [n for n in _runtime_nodes(guarded) if isinstance(n, ast.Import | ast.ImportFrom)]
    assert [type(n).__name__ for n in found] == ["Import"]


def test_no_import_circles() -> None:
    found = circles(_graph())
    assert found == [], "import circles (each a set of modules that import each other):\n" + (
        "\n".join(" <-> ".join(c) for c in found))


def _in_trackers(module: str) -> bool:
    return module == "occbench.trackers" or module.startswith("occbench.trackers.")


def test_trackers_never_import_harness() -> None:
    bad = {m: sorted(t for t in ts if not _in_trackers(t))
           for m, ts in _graph().items() if _in_trackers(m)}
    assert {m: ts for m, ts in bad.items() if ts} == {}


def test_report_imports_nothing_from_the_run() -> None:
    graph = _graph()
    bad = {m: sorted(t for t in ts if t == "occbench.pipeline.experiment")
           for m, ts in graph.items() if m.startswith("occbench.report")}
    assert {m: ts for m, ts in bad.items() if ts} == {}


# harness/'s rooms: the commands apart from the library rooms they call
ROOMS = {"config", "replay", "commands", "pipeline", "sources", "sweeps", "metrics", "datasets", "report", "fit", "io",
         "server"}
MAX_TOP_MODULES = 8


def test_harness_top_holds_few_modules_and_only_rooms() -> None:
    top = sorted(p.name for p in (ROOT / "harness").glob("*.py"))
    assert len(top) <= MAX_TOP_MODULES, top
    rooms = {p.name for p in (ROOT / "harness").iterdir() if (p / "__init__.py").is_file()}
    assert rooms <= ROOMS, sorted(rooms - ROOMS)


def room(module: str) -> str:
    """The room of a module of ours: ``trackers`` for the trackers, else the harness room (or
    top module) it sits in: ``occbench.pipeline.loop`` -> ``pipeline``."""
    if _in_trackers(module):
        return "trackers"
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "occbench"


def room_graph(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """Room -> the other rooms its modules import (anywhere in their source)."""
    out: dict[str, set[str]] = {}
    for module, targets in graph.items():
        out.setdefault(room(module), set()).update(
            room(t) for t in targets if room(t) != room(module))
    return out


def test_rooms_of_a_graph() -> None:
    graph = {"occbench.report.tables": {"occbench.metrics.rows"},
             "occbench.metrics.rows": {"occbench.trackers.common.assignment"},
             "occbench.trackers.common.assignment": set()}
    assert room_graph(graph) == {"report": {"metrics"}, "metrics": {"trackers"},
                                 "trackers": set()}


def test_harness_rooms_import_each_other_in_one_direction() -> None:
    """No two rooms import each other, directly or round a loop (``report`` only reads run
    folders: the ``pipeline`` writes them through it; ``replay`` re-runs and draws a run)."""
    found = circles(room_graph(_graph()))
    assert found == [], "rooms that import each other: " + "; ".join(" <-> ".join(c) for c in found)


def test_library_rooms_never_import_a_command() -> None:
    bad = {m: sorted(t for t in ts if t.startswith("occbench.commands"))
           for m, ts in _graph().items()
           if m.startswith("occbench.") and not _in_trackers(m)
           and not m.startswith(("occbench.commands", "occbench.__main__"))}
    assert {m: ts for m, ts in bad.items() if ts} == {}


MAX_MODULE_LINES = 400
MAX_FUNCTION_LINES = 80
KERNEL_FILES = ("_kernels.py", "_kernel.py")  # compiled forms of named equations: exempt
# over the limits (none since io/mot.py's writers became io/write.py); nothing joins the list
TOO_LONG_ALLOWED: dict[str, str] = {}


def _harness_files() -> list[Path]:
    return sorted((ROOT / "harness").rglob("*.py"))


def too_long(paths: list[Path]) -> list[str]:
    """``path`` (module over ``MAX_MODULE_LINES``) and ``path:function`` (function or
    method over ``MAX_FUNCTION_LINES``, decorators excluded) outside kernel files."""
    out = []
    for path in paths:
        if path.name.endswith(KERNEL_FILES):
            continue
        rel = path.relative_to(ROOT).as_posix()
        src = path.read_text()
        if len(src.splitlines()) > MAX_MODULE_LINES:
            out.append(rel)
        for node in ast.walk(ast.parse(src)):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and (
                    node.end_lineno - node.lineno + 1 > MAX_FUNCTION_LINES):
                out.append(f"{rel}:{node.name}")
    return sorted(out)


def test_no_long_module_or_function_in_harness() -> None:
    found = too_long(_harness_files())
    assert sorted(set(found) - set(TOO_LONG_ALLOWED)) == []
    assert sorted(set(TOO_LONG_ALLOWED) - set(found)) == [], "split: drop from the allow-list"


# the same rules in trackers/ (issue 36 item 6): over them when the rule came, each to be
# split; an entry leaves when its module is split, and nothing joins the list
TRACKERS_TOO_LONG_ALLOWED = {
}


def test_no_long_module_or_function_in_trackers() -> None:
    found = too_long(sorted((ROOT / "trackers").rglob("*.py")))
    assert sorted(set(found) - set(TRACKERS_TOO_LONG_ALLOWED)) == []
    assert sorted(set(TRACKERS_TOO_LONG_ALLOWED) - set(found)) == [], (
        "split: drop from the allow-list")


def _private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def private_imports(name: str, src: str, packages: set[str], modules: set[str]) -> list[str]:
    """``name <- module.x`` for every private name ``_x``, or name from a private module,
    that module ``name`` (source ``src``) imports from another package; a package's own
    modules share their privates. ``packages``: the dotted names that are packages,
    ``modules``: every module and package."""
    is_package = name in packages
    home = name if is_package else name.rsplit(".", 1)[0]
    out = []
    for node in _runtime_nodes(ast.parse(src)):
        if isinstance(node, ast.ImportFrom):
            base = _absolute(node, name, is_package)
            pairs = [(base, a.name) for a in node.names]
        elif isinstance(node, ast.Import):
            pairs = [tuple(a.name.rsplit(".", 1)) for a in node.names if "." in a.name]
        else:
            continue
        for base, alias in pairs:
            module = f"{base}.{alias}" if f"{base}.{alias}" in modules else base
            if module not in modules:  # not ours
                continue
            where = module if module in packages else module.rsplit(".", 1)[0]
            if (_private(alias) or any(_private(p) for p in base.split("."))) and where != home:
                out.append(f"{name} <- {base}.{alias}")
    return out


def test_private_import_checker_sees_names_and_modules() -> None:
    packages = {"a", "b"}
    modules = {"a", "a.m", "a.p", "b", "b.n", "b._k"}
    src = "from a.p import _x\nfrom b._k import y\nfrom . import _z\n"
    assert private_imports("a.m", src, packages, modules) == ["a.m <- b._k.y"]
    src = "from a.m import _y\nimport a._q\nfrom a.m import y\n"
    assert sorted(private_imports("b.n", src, packages, modules)) == ["b.n <- a._q", "b.n <- a.m._y"]


def test_no_private_name_imported_across_packages() -> None:
    files = module_files()
    packages = {m for m, p in files.items() if p.name == "__init__.py"}
    found = [f for m, p in files.items()
             for f in private_imports(m, p.read_text(), packages, set(files))]
    assert found == []


def update_calls(paths: list[Path]) -> list[str]:
    """``path:line`` of every ``<x>.update(...)`` call whose receiver names a tracker
    (``tracker``, ``self._tracker``, ``trackers[name]``...)."""
    out = []
    for path in paths:
        for node in ast.walk(ast.parse(path.read_text())):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                    and node.func.attr == "update"
                    and "tracker" in ast.unparse(node.func.value).lower()):
                out.append(f"{path.relative_to(ROOT).as_posix()}:{node.lineno}")
    return out


def test_only_the_tracker_bank_feeds_trackers() -> None:
    calls = update_calls(_harness_files())
    assert [c.split(":")[0] for c in calls] == ["harness/pipeline/bank.py"], calls


# an import inside a function says why it is not at the top of its module, in a comment on
# its line or the comment lines right above it: "# optional: <library>" (not a core
# dependency of pyproject.toml), "# start-up: <what, measured cost>" (kept off the path to a
# run's first frame, benchmarks/bench_startup.py), "# cycle: <modules>" (an import circle it
# breaks) or "# order: <why>" (it must run after a call, e.g. Hydra's plugin scan)
IMPORT_MARKER = re.compile(r"#\s*(optional|start-up|cycle|order):\s*\S")


def unmarked_function_imports(src: str, name: str) -> list[str]:
    """``name:line`` of every import inside a function (not under ``if TYPE_CHECKING:``)
    without an ``IMPORT_MARKER`` on its lines or in the comment lines right above it (other
    imports between them allowed, so one comment may cover a block)."""
    lines = src.splitlines()
    tree = ast.parse(src)
    spans = [(n.lineno, n.end_lineno) for n in ast.walk(tree)
             if isinstance(n, ast.Import | ast.ImportFrom)]
    in_import = {i for a, b in spans for i in range(a, b + 1)}
    found = set()
    for fn in ast.walk(tree):
        if not isinstance(fn, ast.FunctionDef | ast.AsyncFunctionDef):
            continue
        for node in _runtime_nodes(fn):
            if not isinstance(node, ast.Import | ast.ImportFrom):
                continue
            own = lines[node.lineno - 1:node.end_lineno]
            above = []
            i = node.lineno - 1
            while i >= 1 and (lines[i - 1].lstrip().startswith("#") or i in in_import):
                above.append(lines[i - 1])
                i -= 1
            if not any(IMPORT_MARKER.search(x) for x in [*own, *above]):
                found.add(f"{name}:{node.lineno}")
    return sorted(found)


def test_function_import_checker_reads_the_markers() -> None:
    src = ("def f():\n"
           "    import os\n"  # unmarked
           "    import ray  # optional: ray\n"
           "    # start-up: pandas, ~0.7 s\n"
           "    import pandas as pd\n"
           "    from matplotlib import (  # start-up: matplotlib\n"
           "        pyplot,\n"
           "    )\n"
           "    x = 1\n"
           "    import json  # the comment says nothing\n"
           "    if TYPE_CHECKING:\n"
           "        import numpy\n"
           "import sys\n")
    assert unmarked_function_imports(src, "m.py") == ["m.py:10", "m.py:2"]


def test_every_function_level_import_says_why() -> None:
    """Issue 36 item 1: no import inside a function except for an optional dependency, a
    measured start-up cost or an import circle, named in a comment (``IMPORT_MARKER``)."""
    paths = [*_harness_files(), *sorted((ROOT / "trackers").rglob("*.py"))]
    found = [f for path in paths for f in unmarked_function_imports(
        path.read_text(), path.relative_to(ROOT).as_posix())]
    assert found == [], "imports inside functions without a reason: " + ", ".join(found)


def test_importing_the_rooms_registers_no_resolver() -> None:
    """Issue 36 item 1: the config room registers its OmegaConf resolvers by an explicit
    call (``occbench.config.register_resolvers``), never on import."""
    code = ("import importlib, sys\n"
            "from omegaconf import OmegaConf\n"
            "for m in sys.argv[1:]:\n"
            "    importlib.import_module(m)\n"
            "names = ['occbench.data', 'occbench.choose', 'occbench.unique_dir']\n"
            "before = [OmegaConf.has_resolver(n) for n in names]\n"
            "from occbench.config import register_resolvers\n"
            "register_resolvers()\n"
            "print(before, [OmegaConf.has_resolver(n) for n in names])\n")
    modules = ["occbench.config", "occbench.config.build", "occbench.config.check",
               "occbench.config.choose", "occbench.config.paths", "occbench.config.rundir",
               "occbench.pipeline.experiment", "occbench.commands.run"]
    out = subprocess.run([sys.executable, "-c", code, *modules], capture_output=True,
                         text=True, check=True, cwd=ROOT).stdout
    assert out.split("\n")[0] == "[False, False, False] [True, True, True]"


# the rooms that run something (a run, a replay, a sweep, a command, the server, a fit):
# report/ only reads finished run folders, so it imports none of them
RUNNING_ROOMS = {"pipeline", "replay", "sweeps", "commands", "server", "fit"}


def test_report_reads_run_folders_and_runs_nothing() -> None:
    graph = _graph()
    bad = {m: sorted(t for t in ts if room(t) in RUNNING_ROOMS)
           for m, ts in graph.items() if room(m) == "report"}
    assert {m: ts for m, ts in bad.items() if ts} == {}


# Issue 36 item 6: the trackers' parameters. A constructor checks its parameters through
# occbench.trackers.common.checks (one message format naming the config key), never by a
# hand-written ``raise ValueError``; and a component takes at most MAX_LOOSE_PARAMETERS loose
# settings (int, float, bool, str, or sequences of them): more go in parameter groups (frozen
# dataclasses that check themselves in __post_init__, one per part of the method, as the paper
# trackers and SilhouetteMatcher take them). Each exception says why; an entry leaves when its
# class is converted (a stale entry fails), and nothing joins the lists but for their reasons.
CONSTRUCTOR_RAISES_ALLOWED = {
    # data records: the consistency of arrays read from a file, not a config key
    "trackers/records.py:Detections": "data record (arrays of one frame)",
    "trackers/frontend/active_basis.py:ActiveBasis": "data record (a learnt template)",
    "trackers/frontend/heads.py:ColourMixtures": "data record (fitted colour mixtures)",
    "trackers/layered/feature_models.py:FoldedMixture": "data record (fitted feature models)",
    "trackers/layered/feature_models.py:FeatureModels": "data record (fitted feature models)",
}
MAX_LOOSE_PARAMETERS = 5  # SORT's baseline takes 5; the paper trackers take 1 (min_score)
LOOSE_PARAMETERS_ALLOWED = {
    # adapters of published trackers keep their library's keyword names, flat, as its docs
    # and the tuned configs (conf/tracker/*_tuned*.yaml) spell them
    "trackers/outside/motpy.py:MotpyTracker": "motpy's own keywords",
    "trackers/outside/ocsort.py:OCSortTracker": "OC-SORT's own keywords",
    "trackers/outside/norfair.py:NorfairTracker": "norfair's own keywords",
    "trackers/bytetrack.py:ByteTrackTracker": "ByteTrack's own keywords",
}
_LOOSE_NAMES = {"int", "float", "bool", "str", "None", "tuple", "list", "Sequence", "Path"}


def _constructors(sources: dict[str, str]):
    """``(path:Class, constructor)`` for every ``__init__`` and ``__post_init__`` of
    ``sources`` (path -> source text)."""
    for rel, src in sources.items():
        for cls in ast.walk(ast.parse(src)):
            if isinstance(cls, ast.ClassDef):
                for fn in cls.body:
                    if isinstance(fn, ast.FunctionDef) and fn.name in ("__init__", "__post_init__"):
                        yield f"{rel}:{cls.name}", fn


def constructor_raises(sources: dict[str, str]) -> list[str]:
    """``path:Class`` of every class whose constructor raises a ValueError by hand."""
    return sorted({name for name, fn in _constructors(sources) for node in ast.walk(fn)
                   if isinstance(node, ast.Raise) and isinstance(node.exc, ast.Call)
                   and ast.unparse(node.exc.func) == "ValueError"})


def loose_parameters(fn: ast.FunctionDef) -> list[str]:
    """The parameters of ``fn`` (not ``self``) annotated with scalars or sequences of them
    only (or not at all): settings, not components or parameter groups."""
    args = [*fn.args.posonlyargs, *fn.args.args, *fn.args.kwonlyargs][1:]
    return [a.arg for a in args if a.annotation is None or set(
        re.findall(r"[A-Za-z_][A-Za-z_0-9]*", ast.unparse(a.annotation))) <= _LOOSE_NAMES]


def too_loose(sources: dict[str, str]) -> list[str]:
    """``path:Class`` of every public class whose ``__init__`` takes more than
    ``MAX_LOOSE_PARAMETERS`` loose settings."""
    return sorted(name for name, fn in _constructors(sources)
                  if fn.name == "__init__" and not name.rsplit(":", 1)[1].startswith("_")
                  and len(loose_parameters(fn)) > MAX_LOOSE_PARAMETERS)


def test_parameter_rules_read_the_source() -> None:
    src = ("class A:\n"
           "    def __init__(self, a: int, b: float | None = None, c: Sequence[float] = (),\n"
           "                 d=1, e: str = '', f: bool = True, g: Group | None = None) -> None:\n"
           "        if a < 0:\n"
           "            raise ValueError('a')\n"
           "class B:\n"
           "    def __post_init__(self) -> None:\n"
           "        require('b.x', True, 'ok', 1)\n"
           "        raise TypeError('not a ValueError')\n"
           "class _C(A):\n"
           "    def __init__(self, a: int, b: int, c: int, d: int, e: int, f: int) -> None:\n"
           "        pass\n")
    fn = ast.parse(src).body[0].body[0]
    assert loose_parameters(fn) == ["a", "b", "c", "d", "e", "f"]
    assert constructor_raises({"m.py": src}) == ["m.py:A"]
    assert too_loose({"m.py": src}) == ["m.py:A"]


def _trackers_sources() -> dict[str, str]:
    return {p.relative_to(ROOT).as_posix(): p.read_text()
            for p in sorted((ROOT / "trackers").rglob("*.py"))}


def test_constructors_check_through_checks() -> None:
    found = constructor_raises(_trackers_sources())
    assert sorted(set(found) - set(CONSTRUCTOR_RAISES_ALLOWED)) == [], (
        "check parameters through occbench.trackers.common.checks (require, unit, at_least)")
    assert sorted(set(CONSTRUCTOR_RAISES_ALLOWED) - set(found)) == [], (
        "converted: drop from the allow-list")


def test_components_take_parameter_groups() -> None:
    found = too_loose(_trackers_sources())
    assert sorted(set(found) - set(LOOSE_PARAMETERS_ALLOWED)) == [], (
        f"more than {MAX_LOOSE_PARAMETERS} loose settings: group them (frozen dataclasses)")
    assert sorted(set(LOOSE_PARAMETERS_ALLOWED) - set(found)) == [], (
        "grouped: drop from the allow-list")


if __name__ == "__main__":
    for c in circles(_graph()):
        print(" <-> ".join(c))
