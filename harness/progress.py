"""Progress bars of the app (tqdm on stderr); library code takes a factory and never prints."""

from __future__ import annotations

from typing import Any


def progress_factory(enabled: bool = True):
    """A factory ``(total=, desc=) -> bar`` of tqdm bars, or None when ``enabled`` is False.

    Bars go to stderr, one per sequence (frames), and vanish when the sequence is done.
    """
    if not enabled:
        return None
    from tqdm.auto import tqdm

    def make(total: int = 0, desc: str = "", unit: str = "frame", **kwargs: Any):
        return tqdm(total=total, desc=desc, unit=unit, leave=False, dynamic_ncols=True, **kwargs)

    return make
