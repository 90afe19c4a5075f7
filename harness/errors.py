"""The errors the harness's rooms share: raised in one room, caught or reported in another."""

import os
import signal

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
