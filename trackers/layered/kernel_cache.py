"""One cache stamp for PBM's compiled kernels, which call each other across modules.

numba's on-disk cache (``cache=True``) keys a kernel on the text of its own file only: a
kernel of ``scores.py`` calling one of ``sampling_kernels.py`` would be loaded stale from the
cache after ``sampling_kernels.py`` changed. Each module of ``KERNEL_MODULES`` imports this one
before it defines a kernel; its kernels are then cached under a stamp of the text of all
of them, so a change to any one recompiles them all (the cache stays where numba puts
it: ``__pycache__`` beside the file, or ``NUMBA_CACHE_DIR``).
"""

from __future__ import annotations

import functools
import hashlib
from pathlib import Path

from numba.core import caching

KERNEL_MODULES = ("split", "colour_kernels", "sampling_kernels", "dynamics", "gating",
                  "differences", "scores", "box_groups", "box_search", "model_update")
"""The modules of this package whose kernels call kernels of another of them."""
_HERE = Path(__file__).resolve().parent
_FILES = frozenset(str(_HERE / f"{m}.py") for m in KERNEL_MODULES)


@functools.cache
def stamp() -> str:
    """sha256 of the text of every module of ``KERNEL_MODULES``."""
    h = hashlib.sha256()
    for path in sorted(_FILES):
        h.update(Path(path).read_bytes())
    return h.hexdigest()


class _SharedStamp:
    """A locator whose source stamp is ``stamp()``, for the files of ``KERNEL_MODULES``."""

    def get_source_stamp(self) -> str:
        return stamp()

    @classmethod
    def from_function(cls, py_func, py_file):
        if str(Path(py_file).resolve()) not in _FILES:
            return None
        return super().from_function(py_func, py_file)


class _InTree(_SharedStamp, caching.InTreeCacheLocator):
    pass


class _UserDir(_SharedStamp, caching.UserProvidedCacheLocator):
    pass


if _UserDir not in caching.CacheImpl._locator_classes:
    caching.CacheImpl._locator_classes[:0] = [_UserDir, _InTree]
