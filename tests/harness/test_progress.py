"""Progress on the long waits (harness/progress.py): ``occbench bench``, the report's
drawing, the trackers' warm-up. On a terminal a bar appears on stderr; on anything else
(a log file, a pipe), with progress=false or in a sweep's job, nothing is drawn and a step
silent for EVERY seconds logs a line."""

from __future__ import annotations

import io

import pytest
from report_scenes import GtSource, Walk

from occbench.pipeline.warmup import STEPS
from occbench.progress import progress_factory
from occbench.trackers.baseline import BaselineTracker


class FakeTerminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def _bench(progress) -> None:
    from occbench.commands.bench import bench_sequence

    bench_sequence(Walk(), GtSource, lambda: {"baseline": BaselineTracker()}, frames=4,
                   repeats=2, progress=progress)


def _render(progress, tmp_path) -> None:
    from occbench.replay.video import render

    render({"baseline": BaselineTracker()}, Walk(), GtSource(), sheet=tmp_path / "s.png",
           progress=progress)


def _warm_up(progress) -> None:
    from occbench.pipeline.warmup import WarmUp

    WarmUp()({"baseline": BaselineTracker}, progress=progress)  # a fresh one: not yet warm


CASES = {"bench": (_bench, "bench", "/6"),  # 2 runs x (decode, front end, baseline)
         "render": (_render, "drawing walk", "/12"),  # the 12 frames tracked
         "warm-up": (_warm_up, "warm-up", f"/{STEPS}")}  # the scene's frames


@pytest.mark.parametrize("case", sorted(CASES))
def test_a_bar_on_a_terminal_nothing_elsewhere(case, tmp_path, monkeypatch):
    run, desc, total = CASES[case]
    args = (tmp_path,) if case == "render" else ()
    terminal = FakeTerminal()
    run(progress_factory(stream=terminal), *args)
    shown = terminal.getvalue()
    assert desc in shown and total in shown and "\r" in shown

    log = io.StringIO()  # a log file or a pipe: log lines, none for a step this short
    monkeypatch.setattr("sys.stderr", log)
    factory = progress_factory()
    assert factory is not None and factory is not progress_factory(stream=terminal)
    run(factory, *args)
    assert log.getvalue() == ""


@pytest.mark.parametrize("how", [{"enabled": False}, {"multirun": True}])
def test_switched_off_or_in_a_multirun_job_no_bar_but_a_long_step_says_where_it_is(
        how, monkeypatch):
    """issue 39: a long step without a terminal logs a line at least every EVERY seconds;
    with progress=false or in a sweep's job the factory was None, so a job's sequence (and
    its outputs) stayed silent to its end. Even on a terminal nothing is drawn there."""
    from occbench import progress

    terminal = FakeTerminal()
    factory = progress.progress_factory(stream=terminal, **how)
    assert factory is not None
    lines = _heard(monkeypatch, progress.LOG_PROGRESS, lambda: factory(total=30, desc="walk"))
    assert "walk 0/30 frames" in lines[0] and terminal.getvalue() == ""
    assert progress.LOG_PROGRESS.stop is None  # no watcher left running


def _heard(monkeypatch, logs, open_step) -> list[str]:
    """The 'still working' lines ``logs`` (a LogProgress, its every made short) logs while
    the step ``open_step()`` opens is open and silent; the step closed after the first."""
    import logging
    import threading

    heard = threading.Event()
    lines: list[str] = []

    class Ear(logging.Handler):
        def emit(self, record):
            if "still working" in record.getMessage():
                lines.append(record.getMessage())
                heard.set()

    monkeypatch.setattr(logs, "every", 0.05)
    logger = logging.getLogger("occbench.progress")
    monkeypatch.setattr(logger, "propagate", False)  # other tests' root handlers: closed
    monkeypatch.setattr(logger, "level", logging.INFO)
    ear = Ear()
    logger.addHandler(ear)
    try:
        step = open_step()
        try:
            assert heard.wait(30)  # a silent step is never silent for long
        finally:
            step.close()
    finally:
        logger.removeHandler(ear)
    return lines


def test_a_long_step_without_a_terminal_says_where_it_is(monkeypatch):
    """issue 39 item 8: +experiment=pbm_table1 printed nothing for 92 s without a terminal.
    A step that logs nothing for EVERY seconds gets one line with each open step's count;
    the lines stop when the step ends."""
    from occbench.progress import LogProgress

    progress = LogProgress(every=0.05)
    outer = progress.bar(total=8, desc="sequences", unit="seq")

    def inner():
        bar = progress.bar(total=150, desc="crossing")
        bar.update(45)
        return bar

    try:
        lines = _heard(monkeypatch, progress, inner)
    finally:
        outer.close()
    assert "sequences 0/8 seqs, crossing 45/150 frames" in lines[0]
    assert progress.stop is None and not progress.bars
