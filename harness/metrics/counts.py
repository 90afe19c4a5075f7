"""Combining per-sequence counts: sum the counts, then recompute every ratio from the sums."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any


def combine_counts(counts: Mapping[str, Any], empty: Any) -> dict[str, dict[str, float]]:
    """Per-sequence ``columns()`` plus a ``COMBINED`` entry from the summed counts.

    Args:
        counts: sequence name -> a counts record supporting ``+`` and ``columns()``.
        empty: the zero record of that type (the start of the sum).
    """
    out = {name: c.columns() for name, c in counts.items()}
    total = empty
    for c in counts.values():
        total = total + c
    out["COMBINED"] = total.columns()
    return out
