"""benchmarks/bench_startup.py --vs: the processes timed for a checkout import that checkout's
code (PYTHONPATH=CHECKOUT imported the editable install's: both columns timed one checkout)."""

from __future__ import annotations

from pathlib import Path

import pytest
from benchmark_scripts import load

ROOT = Path(__file__).resolve().parents[2]
startup = load("bench_startup")


def _checkout(folder: Path) -> Path:
    """A checkout with the project's package-dir and an empty package in each folder."""
    text = (ROOT / "pyproject.toml").read_text()
    start = text.index("[tool.setuptools.package-dir]")
    (folder / "pyproject.toml").parent.mkdir(parents=True)
    (folder / "pyproject.toml").write_text(text[start:text.index("\n\n", start)] + "\n")
    for package in ("harness", "trackers", "hydra_plugins/occbench_launcher"):
        (folder / package).mkdir(parents=True)
        (folder / package / "__init__.py").write_text("")
    return folder


def test_each_checkout_is_timed_on_its_own_code(tmp_path):
    other = _checkout(tmp_path / "other")
    assert startup.packages(other) == {
        "occbench": str(other / "harness"), "occbench.trackers": str(other / "trackers"),
        "hydra_plugins.occbench_launcher": str(other / "hydra_plugins" / "occbench_launcher")}
    files = startup.imported_from(other)
    assert files == [other / "harness" / "__init__.py", other / "trackers" / "__init__.py",
                     other / "hydra_plugins" / "occbench_launcher" / "__init__.py"]
    assert all(f.is_relative_to(ROOT) for f in startup.imported_from(ROOT))


def test_a_checkout_whose_code_is_not_imported_is_refused(tmp_path, monkeypatch):
    other = _checkout(tmp_path / "other")
    monkeypatch.setattr(startup, "packages", lambda root: {})  # the install's mapping wins
    with pytest.raises(SystemExit, match="not that checkout's code"):
        startup.imported_from(other)
