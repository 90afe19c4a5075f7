"""Progress on the long waits (harness/progress.py): ``occbench bench``, the report's
drawing, the trackers' warm-up. On a terminal a bar appears on stderr; on anything else
(a log file, a pipe) nothing is printed."""

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


def test_no_bar_when_switched_off_or_in_a_multirun_job():
    assert progress_factory(enabled=False, stream=FakeTerminal()) is None
    assert progress_factory(multirun=True, stream=FakeTerminal()) is None


def test_a_long_step_without_a_terminal_says_where_it_is():
    """issue 39 item 8: +experiment=pbm_table1 printed nothing for 92 s without a terminal.
    A step that logs nothing for EVERY seconds gets one line with each open step's count;
    the lines stop when the step ends."""
    import logging
    import threading

    from occbench.progress import LogProgress

    heard = threading.Event()
    lines: list[str] = []

    class Ear(logging.Handler):
        def emit(self, record):
            if "still working" in record.getMessage():
                lines.append(record.getMessage())
                heard.set()

    ear = Ear()
    logger = logging.getLogger("occbench.progress")
    level, propagate = logger.level, logger.propagate
    logger.addHandler(ear)
    logger.setLevel(logging.INFO)
    logger.propagate = False  # other tests' root handlers (closed streams) hear nothing
    try:
        progress = LogProgress(every=0.05)
        outer = progress.bar(total=8, desc="sequences", unit="seq")
        inner = progress.bar(total=150, desc="crossing")
        inner.update(45)
        assert heard.wait(30)  # a silent step is never silent for long
        assert "sequences 0/8 seqs, crossing 45/150 frames" in lines[0]
        inner.close()
        outer.close()
        assert progress.stop is None and not progress.bars  # no watcher left running
    finally:
        logger.removeHandler(ear)
        logger.setLevel(level)
        logger.propagate = propagate
