"""Run folders that never collide: the ``occbench.unique_dir`` config resolver.

``hydra.run.dir`` and ``hydra.sweep.dir`` default to
``${occbench.unique_dir:results/<date>/<time>}``: the resolver creates the folder atomically
(``mkdir`` without ``exist_ok``) and, when it exists already (another run started in the
same second, or an earlier one), takes the first free ``<folder>-2``, ``<folder>-3``, ...
so two runs never share a folder. The choice is remembered per process and in the config's
resolver cache (Hydra copies that cache into every job's config), so every later
resolution in the run, and in a sweep's jobs, gives the same folder.
"""

from __future__ import annotations

from pathlib import Path

from omegaconf import OmegaConf

RESOLVER = "occbench.unique_dir"
_CLAIMED: dict[str, str] = {}


def unique_dir(path: str) -> str:
    """Create and return ``path``, or ``path-2``, ``path-3``, ... when it exists."""
    if path in _CLAIMED:
        return _CLAIMED[path]
    base = Path(path)
    base.parent.mkdir(parents=True, exist_ok=True)
    candidate, n = base, 1
    while True:
        try:
            candidate.mkdir()
            break
        except FileExistsError:
            n += 1
            candidate = base.with_name(f"{base.name}-{n}")
    _CLAIMED[path] = str(candidate)
    return str(candidate)


def register() -> None:
    """Register the resolver (once per process)."""
    if not OmegaConf.has_resolver(RESOLVER):
        OmegaConf.register_new_resolver(RESOLVER, unique_dir, use_cache=True)


register()
