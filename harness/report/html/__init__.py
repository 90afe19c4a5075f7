"""``report.html``: one self-contained page per run (``write_run_report``) and per sweep
(``write_sweep_report``), charts drawn by Vega-Lite (Altair) with the Vega bundle inlined."""

from __future__ import annotations

from occbench.report.html.run import write_run_report
from occbench.report.html.sweep import write_sweep_report

__all__ = ["write_run_report", "write_sweep_report"]
