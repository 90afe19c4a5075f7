"""The served child: a fork of the warm server made into the client's process.

``become_job`` never returns. In order: its own process group (the client forwards its
signals there), the server's descriptors closed and its signal handlers undone, the
client's stdin, stdout and stderr as fds 0, 1 and 2 with new ``sys.stdin``/``stdout``/
``stderr`` objects made as the interpreter makes them at start-up (line buffering when a
terminal, the same encodings: the identity holds ``PYTHONIOENCODING`` and the locale), the
client's folder, umask, environment (``TZ`` re-read) and ``sys.argv``; then the command, and
an exit as the interpreter's own: non-daemon threads joined, ``atexit`` handlers run,
streams flushed, the status of ``SystemExit`` (a traceback and 1 for any other exception).
"""

from __future__ import annotations

import atexit
import io
import os
import signal
import sys
import threading
import time
import traceback
from collections.abc import Callable
from typing import NoReturn


def become_job(request: dict, fds: list[int], close: list[int],
               run: Callable[[list[str]], int]) -> NoReturn:
    status = 1
    try:
        os.setpgid(0, 0)
        signal.set_wakeup_fd(-1)
        for signum in (signal.SIGCHLD, signal.SIGTERM, signal.SIGHUP):
            signal.signal(signum, signal.SIG_DFL)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        for fd in close:
            os.close(fd)
        for target, fd in enumerate(fds):
            os.dup2(fd, target)
        for fd in set(fds) - {0, 1, 2}:
            os.close(fd)
        os.chdir(request["cwd"])
        os.umask(int(request["umask"]))
        os.environ.clear()
        os.environ.update(request["env"])
        time.tzset()
        sys.argv = list(request["argv"])
        sys.orig_argv = list(request["orig_argv"])
        _new_stdio()
        status = _run(run, sys.argv[1:])
    except BaseException:  # noqa: BLE001 - the set-up failed: say why, as a crash would
        traceback.print_exc()
    finally:
        _exit(status)


def _run(run: Callable[[list[str]], int], args: list[str]) -> int:
    """``run(args)`` as the interpreter would end it."""
    try:
        return int(run(args) or 0)
    except SystemExit as stop:
        code = stop.code
        if code is None or isinstance(code, int):
            return int(code or 0)
        print(code, file=sys.stderr)
        return 1
    except KeyboardInterrupt:  # the interpreter ends itself by SIGINT then
        _flush()
        signal.signal(signal.SIGINT, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGINT)
        return 128 + signal.SIGINT
    except BaseException:  # noqa: BLE001 - printed as an uncaught exception is
        traceback.print_exc()
        return 1


def _new_stdio() -> None:
    """``sys.stdin``/``stdout``/``stderr`` over fds 0-2 as ``create_stdio`` makes them."""
    unbuffered = not hasattr(sys.__stdout__.buffer, "raw")  # -u, PYTHONUNBUFFERED
    made = []
    for fd, mode, name, old in ((0, "rb", "<stdin>", sys.__stdin__),
                                (1, "wb", "<stdout>", sys.__stdout__),
                                (2, "wb", "<stderr>", sys.__stderr__)):
        raw = io.FileIO(fd, mode, closefd=False)
        raw.name = name
        if fd == 0:
            buf = io.BufferedReader(raw)
        else:
            buf = raw if unbuffered else io.BufferedWriter(raw)
        line = fd == 2 or (fd == 1 and raw.isatty())
        made.append(io.TextIOWrapper(buf, encoding=old.encoding, errors=old.errors,
                                     newline="\n", line_buffering=line and not unbuffered,
                                     write_through=unbuffered and fd != 0))
    sys.stdin, sys.stdout, sys.stderr = made
    sys.__stdin__, sys.__stdout__, sys.__stderr__ = made


def _flush() -> None:
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass


def _exit(status: int) -> NoReturn:
    try:
        for thread in threading.enumerate():
            if thread is not threading.current_thread() and not thread.daemon:
                thread.join()
        atexit._run_exitfuncs()
    finally:
        _flush()
        os._exit(status)
