"""occbench's Hydra launcher: local parallel sweeps that survive their workers
(``hydra/launcher=parallel``, see ``launcher.ProcessLauncher``)."""
