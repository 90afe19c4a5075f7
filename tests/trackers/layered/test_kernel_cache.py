"""PBM's kernels call kernels of other modules (``kernel_cache``): every module that does,
and every module it calls, caches its kernels under one stamp of all their texts, so a
change to a callee's file recompiles its callers instead of loading them stale."""

from __future__ import annotations

import importlib
import pkgutil
from pathlib import Path

from numba.core.registry import CPUDispatcher

from occbench.trackers import layered
from occbench.trackers.layered.kernel_cache import KERNEL_MODULES, stamp


def _kernels(module) -> tuple[list, set[str]]:
    """The module's own kernels, and the modules of the kernels it imports from others."""
    own, imported = [], set()
    for obj in vars(module).values():
        if isinstance(obj, CPUDispatcher):
            home = obj.py_func.__module__
            (own.append(obj) if home == module.__name__ else imported.add(home))
    return own, imported


def test_kernels_calling_across_modules_share_one_stamp_of_all_their_files():
    listed = {f"{layered.__name__}.{m}" for m in KERNEL_MODULES}
    for info in pkgutil.iter_modules(layered.__path__):
        module = importlib.import_module(f"{layered.__name__}.{info.name}")
        own, imported = _kernels(module)
        if own and imported:  # a kernel module using another's kernels: both listed
            assert module.__name__ in listed, module.__name__
            assert imported <= listed, (module.__name__, imported - listed)
    for name in listed:
        own, _ = _kernels(importlib.import_module(name))
        assert own, f"{name} defines no kernel"
        for kernel in own:
            assert kernel._cache._impl.locator.get_source_stamp() == stamp(), kernel


def test_the_stamp_covers_the_text_of_every_listed_module(tmp_path, monkeypatch):
    from occbench.trackers.layered import kernel_cache

    copies = []
    for name in sorted(kernel_cache._FILES):
        copy = tmp_path / name.rsplit("/", 1)[-1]
        copy.write_text(Path(name).read_text())
        copies.append(str(copy))
    monkeypatch.setattr(kernel_cache, "_FILES", frozenset(copies))
    kernel_cache.stamp.cache_clear()
    try:
        before = kernel_cache.stamp()
        kernel_cache.stamp.cache_clear()
        with open(copies[-1], "a") as f:
            f.write("\n# changed\n")
        assert kernel_cache.stamp() != before
    finally:
        kernel_cache.stamp.cache_clear()
