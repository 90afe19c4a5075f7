"""Config to objects: the ground floor every other room builds on.

``register()`` makes the project's configs composable in this process. Call it before any
``hydra.main`` app or ``hydra.compose`` (the commands, the library's own compositions and the
test session do). Hydra's plugin scan would do part of this by itself for a regular install,
but it lists ``hydra_plugins`` with ``pkgutil``, which cannot see the packages of an editable
install (``pip install -e .``) mapped through setuptools' import hook (pyproject.toml's
package-dir), so nothing here relies on that scan.
"""

from __future__ import annotations


def register() -> None:
    """Register the OmegaConf resolvers (``${occbench.data:...}``, ``${occbench.choose:...}``,
    ``${occbench.unique_dir:...}``) and the project's Hydra launcher (config
    ``hydra/launcher=processes`` and its class). Idempotent."""
    from hydra.core.plugins import Plugins

    from occbench.paths import register_resolver
    from occbench.pipeline import choose, rundir

    register_resolver()
    choose.register()
    rundir.register()
    plugins = Plugins.instance()  # Hydra's scan first, so that it never replaces our class
    from hydra_plugins.occbench_launcher import config  # noqa: F401 - the ConfigStore node
    from hydra_plugins.occbench_launcher.launcher import ProcessLauncher

    plugins.register(ProcessLauncher)
