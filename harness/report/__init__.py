"""Reports of a run: comparison tables (CSV, Markdown, LaTeX, text) and bar charts."""

from harness.report.bars import metric_bars
from harness.report.tables import (
    COMBINED,
    best_mask,
    comparison,
    direction,
    per_sequence,
    to_latex,
    to_markdown,
    to_text,
)

__all__ = ["COMBINED", "best_mask", "comparison", "direction", "metric_bars", "per_sequence",
           "to_latex", "to_markdown", "to_text"]
