"""occbench harness: datasets, detection sources, runs, evaluation and reports.

Importing the package imports nothing else: the console script's fast path
(``occbench.server.client``) must know whether a warm server answers before any library
loads. The project's OmegaConf resolvers are registered by ``occbench.pipeline`` (every run,
build and sweep imports it) and by Hydra's plugin scan (``hydra_plugins.occbench_launcher``),
which runs before Hydra composes any config.
"""
