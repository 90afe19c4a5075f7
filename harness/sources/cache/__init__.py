"""The front-end cache: each sequence's detections, foreground masks and learnt scene
calibration, computed once per frames, detector config and code version, and read by every
later run and every job of a sweep.

Where: ``OCCBENCH_CACHE`` (a folder; ``off`` disables the cache), by default
``$XDG_CACHE_HOME/occbench`` or ``~/.cache/occbench``. The folder may be shared by jobs on
several machines (``occbench.sources.cache.store``, ``.lock``).

``cached(source, config)`` wraps a detection source built from ``config`` when the source
says it is worth caching (a true ``cacheable`` attribute: the front end,
``occbench.sources.frontend.FrontendSource``); sources read from annotations cost nothing to
recompute and are returned as they are.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from occbench.sources.cache.source import CachedSource
from occbench.sources.cache.store import Store

ENV = "OCCBENCH_CACHE"
OFF = "off"


def cache_root() -> Path | None:
    """The cache folder, or None when ``OCCBENCH_CACHE=off``."""
    value = os.environ.get(ENV, "").strip()
    if value.lower() == OFF:
        return None
    if value:
        return Path(value).expanduser()
    base = os.environ.get("XDG_CACHE_HOME", "").strip() or str(Path.home() / ".cache")
    return Path(base).expanduser() / "occbench"


def worth_caching(source: Any) -> bool:
    """Whether ``source`` declares its outputs worth caching (``cacheable = True``)."""
    return bool(getattr(source, "cacheable", False))


def cached(source: Any, config: dict[str, Any]) -> Any:
    """``source`` behind the cache (``CachedSource``; with the cache off, one that only says
    so in the log), or ``source`` itself when it is not worth caching."""
    if not worth_caching(source):
        return source
    root = cache_root()
    return CachedSource(source, config, None if root is None else Store(root))


__all__ = ["ENV", "CachedSource", "Store", "cache_root", "cached", "worth_caching"]
