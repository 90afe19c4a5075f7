"""What a run publishes from what its record holds: the one door from the pipeline's record
(``occbench.pipeline.record``) into the report room's tables, plots and page, with pandas,
matplotlib and altair behind them. ``paired_differences`` and ``paired_section`` give
summary.md its paired differences; ``end_of_run`` writes summary.tex, plots/metrics.png,
hota_alpha.csv and plots/hota_alpha.png, has the record publish metrics.csv and summary.md
as finished, then writes report.html.

A page that cannot be made is handed to the record's ``fail`` (stage, message, traceback)
and the others are still made: a plot is not worth losing the run for."""

from __future__ import annotations

import logging
import traceback
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from occbench.metrics.paired import all_pairs
from occbench.report.bars import metric_bars
from occbench.report.hota_alpha import hota_alpha_plot
from occbench.report.html import write_run_report
from occbench.report.paired import paired_markdown
from occbench.report.tables import comparison, to_latex

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Folder:
    """Where a run's pages go: ``text(name, text)`` writes the run folder's file ``name``
    (atomically), ``path(name)`` names one, ``fail(stage, message or error, traceback)``
    records a page that could not be made."""

    out_dir: Path
    text: Callable[[str, str], Any]
    path: Callable[[str], Path]
    fail: Callable[[str, BaseException | str, str], None]


@dataclass(frozen=True)
class RunPages:
    """What the end-of-run pages are made of. ``alpha``: the HOTA-by-alpha rows, computed
    when the pages need them (``occbench.pipeline.summary.hota_alpha_frame``); ``paired``:
    the paired differences as ``finished`` leaves them (summary.md's); ``finished``:
    publishes metrics.csv and summary.md as finished (before report.html, which shows them,
    and again when report.html fails, so that summary.md counts that failure)."""

    metrics: pd.DataFrame
    alpha: Callable[[], pd.DataFrame]
    frames: Mapping[str, Mapping[str, Any]]
    paired: Callable[[], Sequence[Any]]
    finished: Callable[[], None]
    title: str
    table_columns: Sequence[str]
    plot_metrics: Sequence[str]
    metas: Mapping[str, Any]
    report: bool  # false: no plots, no report.html


def paired_differences(frames: Mapping[str, Mapping[str, Any]]) -> list[Any]:
    """The paired differences of every pair of trackers (``occbench.metrics.paired``)."""
    return all_pairs(frames)


def paired_section(pairs: Sequence[Any]) -> str:
    """summary.md's section of ``pairs`` (none: the run is still going, or report: false)."""
    return paired_markdown(list(pairs))


def end_of_run(folder: Folder, pages: RunPages) -> None:
    """summary.tex, the plots and hota_alpha.csv, then ``pages.finished()``, then
    report.html; each page that fails is recorded and the others are still written."""
    if pages.metrics.empty:
        log.warning("no sequence was scored: metrics.csv has no rows")
    try:
        if not pages.metrics.empty:
            folder.text("summary.tex", to_latex(comparison(pages.metrics, pages.table_columns),
                                                caption=f"occbench: {pages.title} (COMBINED)"))
    except Exception as err:  # noqa: BLE001 - recorded
        folder.fail("summary", err, traceback.format_exc())
    try:
        if pages.report:
            metric_bars(pages.metrics, folder.path("plots/metrics.png"), pages.plot_metrics,
                        pages.title, pages.metas)
    except Exception as err:  # noqa: BLE001 - a plot is not worth losing the run for
        folder.fail("plot", naming("plots/metrics.png", err), traceback.format_exc())
    _hota_alpha(folder, pages)
    try:
        pages.finished()
    except Exception as err:  # noqa: BLE001 - recorded, the run ends failed
        folder.fail("metrics", err, traceback.format_exc())
    if pages.report:
        run_page(folder, pages.frames, pages.title, pages.paired(), pages.finished)


def run_page(folder: Folder, frames: Mapping[str, Mapping[str, Any]], title: str,
             paired: Sequence[Any], republish: Callable[[], None]) -> None:
    """report.html, last: it shows every output of the run folder. A failure is recorded and
    ``republish()`` writes summary.md again, so that it counts that failure too."""
    try:
        write_run_report(folder.out_dir, frames, title, paired=list(paired))
    except Exception as err:  # noqa: BLE001 - recorded, the run's other outputs stand
        folder.fail("report.html", err, traceback.format_exc())
        republish()


def _hota_alpha(folder: Folder, pages: RunPages) -> None:
    """HOTA and its sub-metrics at each alpha: hota_alpha.csv and plots/hota_alpha.png."""
    target = "hota_alpha.csv"  # the file being made when a failure comes, for its message
    try:
        alpha = pages.alpha()
        if not alpha.empty:
            folder.text("hota_alpha.csv", alpha.to_csv(index=False, float_format="%.6f",
                                                       lineterminator="\n"))
            target = "plots/hota_alpha.png"
            if pages.report:
                hota_alpha_plot(alpha, folder.path("plots/hota_alpha.png"), pages.title,
                                pages.metas)
    except Exception as err:  # noqa: BLE001 - recorded, the run's other outputs stand
        folder.fail("hota_alpha", naming(target, err), traceback.format_exc())


def naming(name: str, err: BaseException) -> str:
    """A failure's message naming the output file ``name`` that could not be made (an
    ``OSError`` such as a full disk says only ``[Errno 28] No space left on device``)."""
    return f"{name}: {type(err).__name__}: {err}"
