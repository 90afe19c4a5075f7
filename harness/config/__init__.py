"""Config to objects, the ground floor the run's rooms build on: composing a config
(``build.compose_config``), checking it against the constructors (``check``), building
trackers, sequences and detection sources from it (``build``), the data-path rules
(``paths``) and the project's OmegaConf resolvers (``paths``, ``choose``, ``rundir``).

``register()`` makes the project's configs composable in this process. Call it before any
``hydra.main`` app or ``hydra.compose``: the commands, the library's own compositions
(``build.compose_config``) and the test session do. Nothing is registered on import. Hydra's
plugin scan finds the project's launcher by itself in a regular install, but it lists
``hydra_plugins`` with ``pkgutil``, which cannot see the packages of a lenient editable install
(plain ``pip install -e .``), mapped through setuptools' import hook (pyproject.toml's
package-dir), so nothing here relies on that scan.
"""

from __future__ import annotations

from hydra.core.plugins import Plugins

from occbench.config import choose, paths, rundir


def register_resolvers() -> None:
    """Register ``${occbench.data:...}``, ``${occbench.choose:...}`` and
    ``${occbench.unique_dir:...}`` with OmegaConf (idempotent)."""
    paths.register_resolver()
    choose.register()
    rundir.register()


def register() -> None:
    """Register the resolvers and the project's Hydra launcher (config
    ``hydra/launcher=processes`` and its class). Idempotent."""
    register_resolvers()
    plugins = Plugins.instance()
    # order: Hydra's scan (above) re-executes every hydra_plugins module: ours after it, so
    # that the class registered is the one the scan leaves
    from hydra_plugins.occbench_launcher import config  # noqa: F401 - the ConfigStore node
    from hydra_plugins.occbench_launcher.launcher import ProcessLauncher

    plugins.register(ProcessLauncher)
