"""Packaging: the import names resolve to this repository, the console script is declared,
every package of the source folders is installed.

The import packages live under ``occbench`` (harness/ is ``occbench``, trackers/ is
``occbench.trackers``: pyproject.toml's package-dir), so that roboflow's ``trackers`` (an
unrelated PyPI project whose import name is ``trackers``) installs beside this one.
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
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())


@pytest.mark.parametrize("name, folder", [("occbench.trackers", "trackers"),
                                          ("occbench", "harness")])
def test_import_names_come_from_this_repository(name, folder):
    module = importlib.import_module(name)
    path = Path(module.__file__).resolve()
    assert path == ROOT / folder / "__init__.py", f"{name} imported from {path}"
    # and it is ours: modules only this project has
    ours = {"trackers": "occbench.trackers.records", "harness": "occbench.pipeline.experiment"}[folder]
    assert Path(importlib.import_module(ours).__file__).resolve().is_relative_to(ROOT)


def test_no_top_level_name_of_another_project():
    """The distribution's packages are ``occbench...`` and Hydra's shared plugin namespace only:
    no top-level ``trackers`` or ``harness`` to overwrite another project's."""
    setup = PYPROJECT["tool"]["setuptools"]
    tops = {p.split(".")[0] for p in setup["packages"]}
    assert tops == {"occbench", "hydra_plugins"}
    assert setup["package-dir"] == {"occbench": "harness", "occbench.trackers": "trackers",
                                    "hydra_plugins": "hydra_plugins"}


def test_every_source_package_is_listed():
    """A new folder with an ``__init__.py`` must be added to pyproject.toml's ``packages``
    (listed by hand because of the package-dir mapping), or an installed copy lacks it."""
    found = {"occbench" + "".join(f".{p}" for p in d.relative_to(ROOT / "harness").parts)
             for d in (p.parent for p in (ROOT / "harness").rglob("__init__.py"))}
    found |= {"occbench.trackers" + "".join(f".{p}" for p in d.relative_to(ROOT / "trackers").parts)
              for d in (p.parent for p in (ROOT / "trackers").rglob("__init__.py"))}
    found |= {"hydra_plugins." + d.parent.name
              for d in (ROOT / "hydra_plugins").glob("*/__init__.py")}
    assert found == set(PYPROJECT["tool"]["setuptools"]["packages"])


def test_console_script_is_the_app():
    project = PYPROJECT["project"]
    assert project["scripts"]["occbench"] == "occbench.__main__:main"  # -> occbench.commands.cli.main
    from occbench.__main__ import main

    assert callable(main)


def test_installed_console_script_points_to_the_app():
    try:
        eps = importlib.metadata.entry_points(group="console_scripts", name="occbench")
    except importlib.metadata.PackageNotFoundError:  # pragma: no cover
        eps = ()
    if not eps:
        pytest.skip("occbench is not installed (pip install -e .): no console script")
    assert next(iter(eps)).value == "occbench.__main__:main"


def test_app_finds_its_configs():
    import occbench.commands.run as app

    assert Path(app.CONF_DIR).is_absolute()
    assert (Path(app.CONF_DIR) / "config.yaml").is_file()


def test_console_script_runs_from_anywhere(tmp_path):
    """``occbench`` (not ``python -m occbench``) finds conf/ from another working directory."""
    script = Path(sys.executable).parent / "occbench"
    if not script.is_file():
        pytest.skip(f"no console script at {script} (pip install -e .)")
    p = subprocess.run([str(script), "--cfg", "job", "tracker=baseline"], cwd=tmp_path,
                       capture_output=True, text=True, timeout=120, check=False)
    assert p.returncode == 0, p.stderr
    assert "_target_: occbench.trackers.baseline.BaselineTracker" in p.stdout


def _on_sys_path() -> bool:
    """Whether ``occbench`` is a regular package on ``sys.path`` (the README's strict editable
    install, or a wheel), not only behind setuptools' lenient import hook."""
    import importlib.machinery

    spec = importlib.machinery.PathFinder.find_spec("occbench")
    return spec is not None and spec.origin is not None


def test_a_folder_named_occbench_in_the_working_directory_does_not_shadow_it(tmp_path):
    """A clone named ``occbench`` seen from its parent (``python -m occbench`` there, as CI
    runs a paper table) is a namespace portion; the installed package must win over it."""
    if not _on_sys_path():
        pytest.skip("this environment's editable install is lenient (the README installs with "
                    "--config-settings editable_mode=strict)")
    (tmp_path / "occbench" / "datasets").mkdir(parents=True)
    p = subprocess.run([sys.executable, "-c", "import occbench.datasets.base, occbench.trackers"],
                       cwd=tmp_path, capture_output=True, text=True, timeout=120, check=False)
    assert p.returncode == 0, p.stderr
