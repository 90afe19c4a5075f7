"""Progress bars of the app (tqdm on stderr); library code takes a factory and never prints."""

from __future__ import annotations

import sys
from typing import Any, TextIO


def bars_wanted(enabled: bool = True, multirun: bool = False, stream: TextIO | None = None) -> bool:
    """Whether to draw bars: asked for, not a multirun job (jobs of a sweep run side by side,
    on joblib, Ray or SLURM, whose stderr is a log file), and stderr is a terminal (a bar
    redraws itself with carriage returns, which pile up in a file or pipe)."""
    stream = sys.stderr if stream is None else stream
    if not enabled or multirun:
        return False
    isatty = getattr(stream, "isatty", None)
    try:
        return bool(isatty and isatty())
    except (OSError, ValueError):  # a closed or detached stream
        return False


def progress_factory(enabled: bool = True, multirun: bool = False,
                     stream: TextIO | None = None):
    """A factory ``(total=, desc=) -> bar`` of tqdm bars, or None when no bars are wanted
    (``bars_wanted``).

    Bars go to stderr, one per sequence (frames), and vanish when the sequence is done.
    """
    if not bars_wanted(enabled, multirun, stream):
        return None
    from tqdm import tqdm

    def make(total: int = 0, desc: str = "", unit: str = "frame", **kwargs: Any):
        return tqdm(total=total, desc=desc, unit=unit, leave=False, dynamic_ncols=True,
                    file=stream, **kwargs)

    return make
