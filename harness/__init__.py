"""occbench harness: datasets, detection sources, runs, evaluation and reports."""

from harness.paths import register_resolver as _register_resolver
from harness.pipeline import choose as _choose  # noqa: F401 - the ${occbench.choose:...} resolver
from harness.pipeline import rundir as _rundir  # noqa: F401 - the ${occbench.unique_dir:...} resolver

_register_resolver()  # configs name data files as ${occbench.data:...} (harness.paths)
