"""Config schema of ``ProcessLauncher`` (group ``hydra/launcher``, name ``processes``)."""

from dataclasses import dataclass

from hydra.core.config_store import ConfigStore


@dataclass
class ProcessLauncherConf:
    _target_: str = "hydra_plugins.occbench_launcher.launcher.ProcessLauncher"
    # concurrent jobs (-1 = every core); each job is its own process
    n_jobs: int = 2
    # fork each job from a warm process (imports done, trackers warmed up once); false =
    # every job imports and warms up by itself
    preload: bool = True


ConfigStore.instance().store(group="hydra/launcher", name="processes",
                             node=ProcessLauncherConf, provider="occbench")
