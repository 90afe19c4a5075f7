"""occbench's Hydra launcher: local parallel sweeps that survive their workers
(``hydra/launcher=parallel``, see ``launcher.ProcessLauncher``).

Hydra's plugin scan imports this package before it composes any config: importing
``occbench.pipeline`` here registers the project's resolvers (``${occbench.data:...}`` and
the others) for every composition, a test's or a script's own ``hydra.compose`` too."""

import occbench.pipeline  # noqa: F401 - registers the project's OmegaConf resolvers
