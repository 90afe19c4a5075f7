"""Reports of a run: comparison tables (CSV, Markdown, LaTeX, text) and bar charts.

The names below are loaded on first use (PEP 562): importing one module of the room, e.g.
``occbench.report.graph`` before a run's first frame, does not import pandas with the
tables."""

from __future__ import annotations

import importlib
from typing import Any

_WHERE = {"metric_bars": "occbench.report.bars"} | dict.fromkeys(
    ("COMBINED", "best_mask", "comparison", "direction", "per_sequence", "to_latex",
     "to_markdown", "to_text"), "occbench.report.tables")

__all__ = ["COMBINED", "best_mask", "comparison", "direction", "metric_bars", "per_sequence",
           "to_latex", "to_markdown", "to_text"]


def __getattr__(name: str) -> Any:
    if name not in _WHERE:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(_WHERE[name]), name)
