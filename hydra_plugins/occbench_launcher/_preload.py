"""Imported once by the launcher's fork server (``multiprocessing``'s forkserver preload,
which can only import modules): the preload of ``occbench.pipeline.warmup`` with the spec
``ProcessLauncher`` left in the environment (``OCCBENCH_PRELOAD``). Hydra's plugin scan
skips this module (its name starts with ``_``), so no other process runs it."""

import json
import os

from occbench.pipeline.warmup import preload

try:
    _SPEC = json.loads(os.environ.get("OCCBENCH_PRELOAD") or "null")
except ValueError:
    _SPEC = None
if isinstance(_SPEC, dict):
    preload(_SPEC)
