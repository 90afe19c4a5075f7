"""``occbench server [status | stop | start [--foreground]]``: the warm server for single runs.

``occbench server start`` starts one in the background (its own session, no terminal, its
log beside its socket); with ``OCCBENCH_SERVER=on`` the first ``occbench`` command that finds
none starts one too, and runs itself cold. Later commands are forked from it, already
imported and warmed up (a run reaches its first frame in about a quarter of the cold time:
``benchmarks/bench_startup.py``). It exits after 15 minutes without a request, when the
installed code changes (it is then never used: ``occbench.server.trust``), or on ``occbench
server stop``. ``OCCBENCH_SERVER=off`` runs every command cold; the default, ``auto``, uses
a server that runs and never starts one.
One server per user, interpreter, ``sys.path`` and import-time environment: each checkout
has its own.

``serve(path)`` is the server process's own entry point (``occbench.server.client``
starts it); what it preloads: the default run's config composed once (Hydra, OmegaConf and
their parsers warmed up), then ``occbench.pipeline.warmup.preload`` of that run (the app's
imports, the scoring, the plots, the trackers' compiled kernels).
"""

from __future__ import annotations

import argparse
import fcntl
import os
import sys
import time
from collections.abc import Sequence

from occbench.commands.cli import run
from occbench.config.build import compose_config
from occbench.pipeline.warmup import preload as warm, preload_spec
from occbench.server import client
from occbench.server.serve import Server, lock_path

PROG = "occbench server"


def preload() -> None:
    """Warm this process up for the commands it will fork: see the module docstring."""
    warm(preload_spec(compose_config([])))  # tracker=all: every tracker by its name


def serve(path: str) -> int:
    """Run the server of this process's identity on ``path`` until it exits."""
    return Server(path, run, preload).serve()


def starting(path: str) -> bool:
    """Whether a server of this socket ``path`` holds its lock but does not answer yet: it is
    preloading (``occbench.server.serve``: the lock is taken first, the socket last)."""
    try:
        lock = os.open(lock_path(path), os.O_RDWR)
    except OSError:
        return False
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        return True
    finally:
        os.close(lock)  # closing releases a lock taken here: a server starting waits for it
    return False


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    parser.add_argument("action", nargs="?", default="status", choices=["status", "stop", "start"])
    parser.add_argument("--foreground", action="store_true",
                        help="start: serve in this process (its log on stderr) until it exits")
    args = parser.parse_args(argv)
    ident = client.identity()
    path = client.socket_path(ident)
    answer = client.ask(ident, {"op": "status"})
    if answer is None and starting(path):  # not yet listening: "none running" would be wrong
        print(f"{PROG}: starting (preloading, it answers in a few seconds; log "
              f"{path[:-5]}.log)" + ("; ask again to stop it" if args.action == "stop" else ""))
        return 0 if args.action == "start" else 3  # status 0 only once it answers
    if args.action == "start":
        if answer is not None:
            print(f"{PROG}: already running (pid {answer['pid']}, {path})")
            return 0
        if args.foreground:
            return serve(path)
        client.start_server(ident)
        print(f"{PROG}: starting in the background ({path}; log {path[:-5]}.log)")
        return 0
    if answer is None:
        print(f"{PROG}: none running for this installation ({path}); "
              f"OCCBENCH_SERVER={client.mode()}")
        return 0 if args.action == "stop" else 3
    if args.action == "stop":
        client.ask(ident, {"op": "stop"})
        print(f"{PROG}: pid {answer['pid']} stops (jobs still running finish first)")
        return 0
    started = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(answer["started"]))
    print(f"{PROG}: pid {answer['pid']}, started {started}, {answer['served']} job(s) served, "
          f"{answer['running']} running, idle {answer['idle']:.0f} s of "
          f"{answer['idle_limit']:.0f}\n  socket {path}\n  log {path[:-5]}.log\n  "
          + (f"stale: {answer['stale']}" if answer["stale"] else "code unchanged since start")
          + "\n  " + ", ".join(f"{k} {v}" for k, v in answer["versions"].items())
          + f"\n  OCCBENCH_SERVER={client.mode()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
