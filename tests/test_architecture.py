"""The layout's rules, read from the source (every import, function-level ones too).

- No import circles: no module in ``trackers/`` or ``harness/`` imports (directly or through
  other modules of ours) a module that imports it back.
- ``trackers`` never imports ``harness``.
- ``harness/report/`` imports nothing from ``harness.pipeline.experiment``.

Run as a script (``python tests/test_architecture.py``) to print every circle found.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("trackers", "harness")


def module_files() -> dict[str, Path]:
    """Dotted module name -> source file, for every module of ``PACKAGES``."""
    out: dict[str, Path] = {}
    for pkg in PACKAGES:
        for path in sorted((ROOT / pkg).rglob("*.py")):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(parts)] = path
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
    src = "def f():\n    from harness.pipeline.experiment import run_sequence\n"
    tree = ast.parse(src)
    node = next(n for n in ast.walk(tree) if isinstance(n, ast.ImportFrom))
    assert _absolute(node, "harness.report.video", False) == "harness.pipeline.experiment"
    assert len([n for n in _runtime_nodes(tree) if isinstance(n, ast.ImportFrom)]) == 1
    guarded = ast.parse("if TYPE_CHECKING:\n    from a import b\nelse:\n    import c\n")
    found = [n for n in _runtime_nodes(guarded) if isinstance(n, ast.Import | ast.ImportFrom)]
    assert [type(n).__name__ for n in found] == ["Import"]


def test_no_import_circles() -> None:
    found = circles(_graph())
    assert found == [], "import circles (each a set of modules that import each other):\n" + (
        "\n".join(" <-> ".join(c) for c in found))


def test_trackers_never_import_harness() -> None:
    bad = {m: sorted(t for t in ts if t.split(".")[0] == "harness")
           for m, ts in _graph().items() if m.split(".")[0] == "trackers"}
    assert {m: ts for m, ts in bad.items() if ts} == {}


def test_report_imports_nothing_from_the_run() -> None:
    graph = _graph()
    bad = {m: sorted(t for t in ts if t == "harness.pipeline.experiment")
           for m, ts in graph.items() if m.startswith("harness.report")}
    assert {m: ts for m, ts in bad.items() if ts} == {}


# harness/'s rooms: the commands apart from the library rooms they call
ROOMS = {"commands", "pipeline", "sources", "sweeps", "metrics", "datasets", "report", "fit", "io"}
MAX_TOP_MODULES = 8


def test_harness_top_holds_few_modules_and_only_rooms() -> None:
    top = sorted(p.name for p in (ROOT / "harness").glob("*.py"))
    assert len(top) <= MAX_TOP_MODULES, top
    rooms = {p.name for p in (ROOT / "harness").iterdir() if (p / "__init__.py").is_file()}
    assert rooms <= ROOMS, sorted(rooms - ROOMS)


def test_library_rooms_never_import_a_command() -> None:
    bad = {m: sorted(t for t in ts if t.startswith("harness.commands"))
           for m, ts in _graph().items()
           if m.startswith("harness.") and not m.startswith(("harness.commands", "harness.__main__"))}
    assert {m: ts for m, ts in bad.items() if ts} == {}


if __name__ == "__main__":
    for c in circles(_graph()):
        print(" <-> ".join(c))
