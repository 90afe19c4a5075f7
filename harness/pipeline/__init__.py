"""One run, from config to run folder: build (``build``, ``config_check``), the frame loop
(``loop``), the tracker bank that feeds every tracker (``bank``), the run in three steps
(``experiment``: ``plan``, the bank, ``record``; the single-target ``protocols``), the warm-up
before timing (``warmup``) and the run folder (``rundir``, ``writer``, ``summary``).

Importing it registers the project's OmegaConf resolvers, which its configs use:
``${occbench.data:...}`` (``occbench.paths``), ``${occbench.choose:...}`` (``choose``) and
``${occbench.unique_dir:...}`` (``rundir``)."""

from occbench.paths import register_resolver as _register_resolver
from occbench.pipeline import choose as _choose  # noqa: F401 - the ${occbench.choose:...} resolver
from occbench.pipeline import rundir as _rundir  # noqa: F401 - the ${occbench.unique_dir:...} resolver

_register_resolver()  # configs name data files as ${occbench.data:...} (occbench.paths)
