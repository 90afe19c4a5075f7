"""occbench harness: datasets, detection sources, runs, evaluation and reports."""

from harness import rundir as _rundir  # noqa: F401 - the ${occbench.unique_dir:...} resolver
from harness.paths import register_resolver as _register_resolver

_register_resolver()  # configs name data files as ${occbench.data:...} (harness.paths)
