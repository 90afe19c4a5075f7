"""Progress of the app: tqdm bars on a terminal's stderr, else log lines (``LogProgress``:
a long step says where it is at least every ``EVERY`` seconds); library code takes a
factory and never prints."""

from __future__ import annotations

import logging
import sys
import threading
import time
from typing import Any, TextIO

from tqdm import tqdm

log = logging.getLogger(__name__)
#: The one form of every command's log lines: a run's and a sweep's (Hydra's job_logging and
#: hydra_logging, conf/config.yaml and conf/detect.yaml, checked by tests/test_configs.py)
#: and the argparse commands' (``log_to_stderr``).
LOG_FORMAT = "[%(asctime)s][%(name)s][%(levelname)s] - %(message)s"
EVERY = 15.0  # seconds of silence after which a step without a terminal says where it is


def log_to_stderr(level: int = logging.INFO) -> None:
    """An argparse command's log lines on stderr, in ``LOG_FORMAT``."""
    logging.basicConfig(level=level, format=LOG_FORMAT)


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
    """A factory ``(total=, desc=) -> bar`` of tqdm bars when bars are wanted
    (``bars_wanted``); otherwise (no terminal, ``progress=false``, a multirun job) of
    ``LogProgress`` bars: nothing drawn, one log line when the app has said nothing for
    ``EVERY`` seconds, so a long step is never silent for longer.

    Bars go to stderr, one per sequence (frames), and vanish when the sequence is done.
    """
    if not bars_wanted(enabled, multirun, stream):
        return LOG_PROGRESS.bar

    def make(total: int = 0, desc: str = "", unit: str = "frame", **kwargs: Any):
        return tqdm(total=total, desc=desc, unit=unit, leave=False, dynamic_ncols=True,
                    file=stream, **kwargs)

    return make


class _Clock(logging.Handler):
    """When the process last logged a line (a root handler that writes nothing)."""

    def __init__(self) -> None:
        super().__init__()
        self.last = time.monotonic()

    def emit(self, record: logging.LogRecord) -> None:
        self.last = time.monotonic()


class _LogBar:
    """One step's count, shown by ``LogProgress``'s lines."""

    def __init__(self, owner: LogProgress, total: int, desc: str, unit: str) -> None:
        self.owner, self.total, self.desc, self.unit, self.n = owner, total, desc, unit, 0

    def update(self, n: int = 1) -> None:
        self.n += n

    def close(self) -> None:
        self.owner.close(self)

    def __str__(self) -> str:
        if not self.total and not self.n:  # a step without a count: its name
            return self.desc
        of = f"/{self.total}" if self.total else ""
        return f"{self.desc} {self.n}{of} {self.unit}{'s' if self.unit else ''}".strip()


class LogProgress:
    """Progress without a terminal: while any of its bars is open, a daemon thread logs one
    line ("still working (N s): <each open bar's count>") whenever nothing was logged for
    ``every`` seconds, so a long step is never silent for longer; a step that ends sooner
    (or keeps logging) adds nothing."""

    def __init__(self, every: float = EVERY) -> None:
        self.every = every
        self.bars: list[_LogBar] = []
        self.lock = threading.Lock()
        self.clock = _Clock()
        self.stop: threading.Event | None = None
        self.start = 0.0

    def bar(self, total: int = 0, desc: str = "", unit: str = "frame", **_: Any) -> _LogBar:
        bar = _LogBar(self, total, desc, unit)
        with self.lock:
            self.bars.append(bar)
            if self.stop is None:
                self.start = self.clock.last = time.monotonic()
                logging.getLogger().addHandler(self.clock)
                self.stop = threading.Event()
                threading.Thread(target=self._watch, args=(self.stop,), daemon=True,
                                 name="progress lines").start()
        return bar

    def close(self, bar: _LogBar) -> None:
        with self.lock:
            if bar in self.bars:
                self.bars.remove(bar)
            if not self.bars and self.stop is not None:
                self.stop.set()
                self.stop = None
                logging.getLogger().removeHandler(self.clock)

    def _watch(self, stop: threading.Event) -> None:
        while not stop.wait(min(1.0, self.every / 4)):
            if time.monotonic() - self.clock.last < self.every:
                continue
            with self.lock:
                shown = ", ".join(str(b) for b in self.bars)
            if shown and not stop.is_set():
                self.clock.last = time.monotonic()  # also when the line is filtered out
                log.info("still working (%.0f s): %s", time.monotonic() - self.start, shown)


LOG_PROGRESS = LogProgress()  # one per process: its lines cover every open step
