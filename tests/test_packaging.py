"""Packaging: the import names resolve to this repository, the console script is declared.

``trackers`` is also the import name of an unrelated PyPI project (roboflow's ``trackers``);
with both installed, the one found first on ``sys.path`` wins. These tests fail loudly when
the other one shadows ours.
"""

from __future__ import annotations

import importlib
import importlib.metadata
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("name", ["trackers", "harness"])
def test_import_names_come_from_this_repository(name):
    module = importlib.import_module(name)
    path = Path(module.__file__).resolve()
    assert path.is_relative_to(ROOT), f"{name} imported from {path}, not from {ROOT}"
    # and it is ours: modules only this project has
    ours = {"trackers": "trackers.records", "harness": "harness.pipeline.experiment"}[name]
    assert Path(importlib.import_module(ours).__file__).resolve().is_relative_to(ROOT)


def test_console_script_is_the_app():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["scripts"]["occbench"] == "harness.__main__:main"  # -> harness.commands.cli.main
    from harness.__main__ import main

    assert callable(main)


def test_installed_console_script_points_to_the_app():
    try:
        eps = importlib.metadata.entry_points(group="console_scripts", name="occbench")
    except importlib.metadata.PackageNotFoundError:  # pragma: no cover
        eps = ()
    if not eps:
        pytest.skip("occbench is not installed (pip install -e .): no console script")
    assert next(iter(eps)).value == "harness.__main__:main"


def test_app_finds_its_configs():
    import harness.commands.run as app

    assert Path(app.CONF_DIR).is_absolute()
    assert (Path(app.CONF_DIR) / "config.yaml").is_file()


def test_console_script_runs_from_anywhere(tmp_path):
    """``occbench`` (not ``python -m harness``) finds conf/ from another working directory."""
    script = Path(sys.executable).parent / "occbench"
    if not script.is_file():
        pytest.skip(f"no console script at {script} (pip install -e .)")
    p = subprocess.run([str(script), "--cfg", "job", "tracker=baseline"], cwd=tmp_path,
                       capture_output=True, text=True, timeout=120, check=False)
    assert p.returncode == 0, p.stderr
    assert "_target_: trackers.baseline.BaselineTracker" in p.stdout
