"""occbench's Hydra launcher: local parallel sweeps that survive their workers
(``hydra/launcher=parallel``, see ``launcher.ProcessLauncher``).

Hydra's plugin scan imports this package before it composes any config (in a regular
install; an editable one relies on ``occbench.config.register()``): it registers the project's
resolvers (``${occbench.data:...}`` and the others) for every composition."""

from occbench.config import register_resolvers

register_resolvers()
