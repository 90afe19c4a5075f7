"""``report.html``: one self-contained page per run (``write_run_report``), charts drawn by
Vega-Lite (Altair) with the Vega bundle inlined; a sweep's page is built from the same parts
by ``occbench.sweeps.page``."""

from __future__ import annotations

from occbench.report.html.run import write_run_report

__all__ = ["write_run_report"]
