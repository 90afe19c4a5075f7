"""The errors the harness's rooms share: raised in one room, caught or reported in another."""

import os
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager

EXIT_SIGINT, EXIT_SIGTERM = 128 + signal.SIGINT, 128 + signal.SIGTERM  # a stopped run's status
REFUSED = 1  # exit status of a refused input (a missing file, a malformed row, a bad value)
USAGE = 2  # exit status of a command line that cannot be parsed


VERBOSE = "OCCBENCH_VERBOSE"  # 1: a failure shows its traceback (``occbench -v`` sets it)


def verbose() -> bool:
    """Whether a failure shows its full traceback, not one line: ``occbench -v`` or
    ``OCCBENCH_VERBOSE=1`` (what a command starts, a sweep's jobs, reads it here)."""
    return os.environ.get(VERBOSE, "") not in ("", "0")


def refusal(err: object) -> str:
    """``occbench: <err>``: the one line, one prefix, of every command's mistake."""
    text = str(err).strip() or type(err).__name__
    return text if text.startswith("occbench:") else f"occbench: {text}"


class RunError(RuntimeError):
    """A run that cannot start or go on: bad config, unbuilt tracker, unreadable dataset."""


class ConfigError(ValueError):
    """A config value of the wrong type or outside its range; the message names the key."""


class Terminated(BaseException):  # a signal, named as KeyboardInterrupt
    """SIGTERM received: raised in the main thread (``occbench.commands.cli.run``) so that a
    run stops as on Ctrl-C (its summary says interrupted, errors.txt says where) and exits
    143."""


@contextmanager
def signals_held() -> Iterator[None]:
    """Within: Ctrl-C (SIGINT) and SIGTERM do not cut the block; the first one received is
    acted on as it would have been (KeyboardInterrupt, ``Terminated``) once the block ends.
    For a block that must not stop halfway: an import cut by a signal leaves its
    half-imported submodules in ``sys.modules``, and every later import of the package in
    the process fails (matplotlib: "module 'matplotlib' has no attribute
    'get_data_path'"), the interrupted run's own summary included. Python runs signal
    handlers in the main thread only: in another thread the block runs as it is."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[tuple[int, object]] = []
    saved = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    for s in saved:
        signal.signal(s, lambda signum, frame: caught.append((signum, frame)))
    try:
        yield
    finally:
        for s, handler in saved.items():
            signal.signal(s, handler)
        if caught:
            signum, frame = caught[0]
            handler = saved[signum]
            if callable(handler):
                handler(signum, frame)
            elif handler != signal.SIG_IGN:  # the default action (None: not set from Python)
                os.kill(os.getpid(), signum)
