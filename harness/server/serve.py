"""The warm server: one process, preloaded once, that forks a child per command.

Life cycle: ``Server.serve()`` takes the identity's lock file (a second server of the same
identity exits, once it sees the first one listening or after waiting a minute for one that
is stopping), takes the code's fingerprint (``occbench.server.trust``), runs ``preload``
(imports, compiled kernels, a config composed once), then listens on its Unix socket (mode
0600, in a 0700 folder) until ``idle`` seconds pass without a request and without a running
job, ``stop`` is asked, a request finds the code changed, or its socket file is removed
(its folder deleted): then it stops listening, answers the jobs still running, and exits.
Its own lines go to stderr (the log file its starter opened); it configures no logging, so
its children start fresh.

A request (``client.send``): ``run`` with the client's stdin, stdout and stderr attached,
``status`` or ``stop``. ``run`` is checked (identity equal, code unchanged), then forked
(``occbench.server.job``); the server answers ``{"pid": n}`` at once and
``{"exit": status}`` or ``{"signal": n}`` when the child ends. A client that goes away
before its job ends (killed) has its job's process group sent SIGTERM, as a cold run would
have ended with it. A crashing job is one child: the server goes on.
"""

from __future__ import annotations

import fcntl
import gc
import json
import os
import select
import signal
import socket
import sys
import time
from collections.abc import Callable

from occbench.server import client
from occbench.server.job import become_job
from occbench.server.trust import Fingerprint

IDLE = 15 * 60  # seconds without a request before the server exits


def say(text: str) -> None:
    """One line of the server's log."""
    print(f"{time.strftime('%Y-%m-%d %H:%M:%S')} [{os.getpid()}] {text}", file=sys.stderr,
          flush=True)


class Server:
    """``path``: the socket (its ``.lock`` and ``.log`` beside it); ``run(argv) -> status``
    runs a command in a child as a cold process would; ``preload()`` warms this process;
    ``watch``: the code's folders (``trust.Fingerprint``; default the project's)."""

    def __init__(self, path: str, run: Callable[[list[str]], int],
                 preload: Callable[[], None], idle: float = IDLE,
                 watch: list[str] | None = None) -> None:
        if not path.endswith(".sock"):
            raise ValueError(f"path must end in .sock, got {path!r}")
        if idle <= 0:
            raise ValueError(f"idle must be > 0 s, got {idle}")
        self.path, self.run, self.preload, self.idle = path, run, preload, float(idle)
        self.watch = watch
        self.identity = client.identity()
        self.jobs: dict[int, socket.socket | None] = {}  # pid -> its client (None: gone)
        self.listener: socket.socket | None = None
        self.wake: tuple[int, int] = (-1, -1)  # SIGCHLD's wake-up pipe
        self.asked = ""  # why to stop listening, set by SIGTERM's handler
        self.started, self.served, self.last = time.time(), 0, time.time()

    def serve(self) -> int:
        os.makedirs(os.path.dirname(self.path), mode=0o700, exist_ok=True)
        self.lock = _take_lock(self.path)
        if self.lock is None:
            say("another server of this identity is starting or running: exiting")
            return 0
        self.fingerprint = Fingerprint(self.watch)
        started = time.perf_counter()
        self.preload()
        gc.collect()
        gc.freeze()  # the children's collections skip what is preloaded: no copy-on-write
        say(f"preloaded in {time.perf_counter() - started:.1f} s; listening on {self.path}")
        self.listener = self._listen()
        wake_r, wake_w = self.wake = os.pipe()
        os.set_blocking(wake_w, False)
        signal.set_wakeup_fd(wake_w)
        signal.signal(signal.SIGCHLD, lambda *_: None)
        signal.signal(signal.SIGTERM, lambda *_: setattr(self, "asked", "SIGTERM"))
        try:
            self._loop(wake_r)
        finally:
            self._stop_listening("exiting")
        say(f"exited after {self.served} job(s)")
        return 0

    def _listen(self) -> socket.socket:
        if os.path.exists(self.path):
            os.unlink(self.path)  # a dead server's: we hold the lock
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        old = os.umask(0o177)
        try:
            sock.bind(self.path)  # created 0600
        finally:
            os.umask(old)
        sock.listen(16)
        self.inode = os.stat(self.path).st_ino
        return sock

    def _stop_listening(self, why: str) -> None:
        if self.listener is None:
            return
        self.listener.close()
        self.listener = None
        try:
            if os.stat(self.path).st_ino == self.inode:
                os.unlink(self.path)
        except OSError:
            pass
        say(f"stopped listening ({why}); {len(self.jobs)} job(s) still running")

    def _loop(self, wake: int) -> None:
        while self.listener is not None or self.jobs:
            if self.asked:
                self._stop_listening(self.asked)
                self.asked = ""
            watched = [wake, *(c for c in self.jobs.values() if c is not None)]
            if self.listener is not None:
                watched.append(self.listener)
            ready, _, _ = select.select(watched, [], [], 5.0)  # a signal wakes it
            if wake in ready:
                os.read(wake, 512)
                self._reap()
            if self.listener is not None and self.listener in ready:
                conn, _ = self.listener.accept()
                self._handle(conn)
            for pid, conn in list(self.jobs.items()):
                if conn in ready:  # the client went away (or spoke out of turn)
                    self._client_gone(pid, conn)
            self._reap()
            if self.listener is not None and not self._still_ours():
                self._stop_listening("its socket was removed or replaced")
            if (self.listener is not None and not self.jobs
                    and time.time() - self.last > self.idle):
                self._stop_listening(f"idle for {self.idle:.0f} s")

    def _still_ours(self) -> bool:
        try:
            return os.stat(self.path).st_ino == self.inode
        except OSError:
            return False

    def _handle(self, conn: socket.socket) -> None:
        conn.settimeout(10.0)
        fds: list[int] = []
        try:
            request, fds = _receive(conn)
        except EOFError:  # a probe (``_answers``): connected and closed
            conn.close()
            return
        except (OSError, ValueError) as err:
            say(f"bad request: {type(err).__name__}: {err}")
            for fd in fds:
                os.close(fd)
            conn.close()
            return
        op = request.get("op")
        if op == "run" and len(fds) == 3:
            self._start(conn, request, fds)
            return
        for fd in fds:
            os.close(fd)
        if op == "status":
            _answer(conn, self.status())
        elif op == "stop":
            _answer(conn, {"stopping": os.getpid()})
            self._stop_listening("asked to stop")
        else:
            _answer(conn, {"refused": f"unknown request {op!r}"})
        conn.close()

    def status(self) -> dict:
        return {"pid": os.getpid(), "started": self.started, "served": self.served,
                "running": len(self.jobs), "idle": time.time() - self.last,
                "idle_limit": self.idle, "socket": self.path,
                "stale": self.fingerprint.changed(), "versions": self.fingerprint.versions}

    def _start(self, conn: socket.socket, request: dict, fds: list[int]) -> None:
        why = ("another interpreter, sys.path or import-time environment"
               if request.get("identity") != self.identity else self.fingerprint.changed())
        if why:
            for fd in fds:
                os.close(fd)
            _answer(conn, {"stale": why})
            conn.close()
            self._stop_listening(f"stale: {why}")
            return
        sys.stderr.flush()
        pid = os.fork()
        if pid == 0:
            theirs = [self.listener, conn, *self.jobs.values()]  # closed in the child
            become_job(request, fds, [s.fileno() for s in theirs if s is not None]
                       + [self.lock, *self.wake],
                       self.run)
        for fd in fds:
            os.close(fd)
        try:
            os.setpgid(pid, pid)  # also done by the child: whichever runs first
        except OSError:
            pass
        self.jobs[pid] = conn
        say(f"job {pid}: {' '.join(request['argv'][1:])[:200]}")
        self.served += 1
        self.last = time.time()
        conn.settimeout(None)
        _answer(conn, {"pid": pid})

    def _reap(self) -> None:
        while self.jobs:
            try:
                pid, status = os.waitpid(-1, os.WNOHANG)
            except ChildProcessError:
                return
            if pid == 0:
                return
            conn = self.jobs.pop(pid, None)
            self.last = time.time()
            if conn is None:
                continue
            answer = ({"signal": os.WTERMSIG(status)} if os.WIFSIGNALED(status)
                      else {"exit": os.waitstatus_to_exitcode(status)})
            say(f"job {pid}: {answer}")
            _answer(conn, answer)
            conn.close()

    def _client_gone(self, pid: int, conn: socket.socket) -> None:
        try:
            os.killpg(pid, signal.SIGTERM)
        except OSError:
            pass
        say(f"the client of job {pid} went away: job sent SIGTERM")
        self.jobs[pid] = None
        conn.close()


def lock_path(path: str) -> str:
    """The lock file of the server whose socket is ``path`` (held for the server's life, taken
    before it preloads; its socket answers only after)."""
    return path[:-5] + ".lock"


def _take_lock(path: str, wait: float = 60.0) -> int | None:
    """The identity's lock file, held for the server's life; None when another server
    holds it and is listening, or still holds it after ``wait`` s (one stopping is waited
    for)."""
    lock = os.open(lock_path(path), os.O_RDWR | os.O_CREAT, 0o600)
    end = time.monotonic() + wait
    while True:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return lock
        except OSError:
            pass
        if time.monotonic() > end or _answers(path):
            os.close(lock)
            return None
        time.sleep(0.25)


def _answers(path: str) -> bool:
    try:
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as sock:
            sock.connect(path)
        return True
    except OSError:
        return False


def _receive(conn: socket.socket) -> tuple[dict, list[int]]:
    """One request (``client.send``): its JSON body and the fds attached to its header."""
    head, fds, _, _ = socket.recv_fds(conn, client.HEADER, 3)
    if not head:
        raise EOFError
    while len(head) < client.HEADER:
        more = conn.recv(client.HEADER - len(head))
        if not more:
            raise ValueError("the request ended early")
        head += more
    size, body = int(head), b""
    while len(body) < size:
        more = conn.recv(min(size - len(body), 1 << 16))
        if not more:
            raise ValueError("the request ended early")
        body += more
    return json.loads(body), fds


def _answer(conn: socket.socket, message: dict) -> None:
    try:
        conn.sendall(json.dumps(message).encode() + b"\n")
    except OSError:
        pass
