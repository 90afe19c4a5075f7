"""The console script's fast path: hand the command to a warm server, or say it cannot.

``served(argv)`` runs before anything but the standard library is imported. It connects to
this installation's server (``socket_path``), sends the command line, the current folder,
the umask and the environment, and passes its stdin, stdout and stderr themselves
(``SCM_RIGHTS``); the server forks a preloaded child that runs the command as a cold
process would and answers with its exit status. SIGINT, SIGTERM and SIGHUP received here
go to the job's process group; Ctrl-Z (SIGTSTP) stops the job's process group and then this
process, and SIGCONT (the shell's ``fg`` or ``bg``) continues the job. ``None`` means "run
cold": the server is off (``OCCBENCH_SERVER=off``), none answers (with ``OCCBENCH_SERVER=on`` one is then started in
the background for the next command; by default, ``auto``, only ``occbench server start``
starts one), or it refused (its code is no longer the installed code: it exits, and with
``on`` a new one is started). ``occbench server ...`` itself always runs here.

Which server: one per user and per ``identity()`` - the interpreter, ``sys.path`` and the
environment variables the preloaded libraries read when they are imported - so two
checkouts, or two Python set-ups, never share one. The server checks the identity again
and the installed sources' fingerprint on every request (``occbench.server.trust``).
"""

from __future__ import annotations

import hashlib
import json
import os
import signal
import socket
import sys

ENV = "OCCBENCH_SERVER"
# on: use a server, start one when none answers; auto: use one that runs (``occbench server
# start``), never start one; off: always run cold
MODES = ("on", "auto", "off")
DEFAULT = "auto"
# read by the preloaded libraries when they are imported: a server serves only its own values
IMPORT_ENV = ("PYTHON", "LANG", "LC_", "NUMBA_", "OMP_", "OPENBLAS_", "MKL_", "GOTO",
              "VECLIB", "MPL", "OPENCV_", "KMP_", "TBB", "HYDRA_")
HEADER = 8  # bytes: the length of the JSON body that follows, in decimal, zero-padded


def mode() -> str:
    """``OCCBENCH_SERVER`` (``MODES``; unset: ``DEFAULT``); a platform without Unix
    sockets and ``SCM_RIGHTS`` (Windows) is always ``off``."""
    value = os.environ.get(ENV, "").strip().lower() or DEFAULT
    if not (hasattr(socket, "AF_UNIX") and hasattr(socket, "send_fds")):
        return "off"
    return value


def identity() -> dict:
    """What a server and its clients share: interpreter, ``sys.path``, import-time env."""
    env = {k: v for k, v in os.environ.items() if k.startswith(IMPORT_ENV)}
    return {"executable": sys.executable, "path": list(sys.path), "env": env}


def folder() -> str:
    """The user's server folder: ``$XDG_RUNTIME_DIR/occbench``, else
    ``$XDG_CACHE_HOME/occbench/server`` (``~/.cache/occbench/server``)."""
    if os.environ.get("XDG_RUNTIME_DIR"):
        return os.path.join(os.environ["XDG_RUNTIME_DIR"], "occbench")
    cache = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(cache, "occbench", "server")


def key(ident: dict) -> str:
    """16 hex digits naming the server of ``ident``."""
    text = json.dumps(ident, sort_keys=True).encode()
    return hashlib.blake2b(text, digest_size=8).hexdigest()


def socket_path(ident: dict) -> str:
    return os.path.join(folder(), key(ident) + ".sock")


def send(sock: socket.socket, message: dict, fds: list[int] = ()) -> None:
    """One request: ``HEADER`` bytes (with ``fds`` attached), then the JSON body."""
    body = json.dumps(message).encode()
    socket.send_fds(sock, [b"%0*d" % (HEADER, len(body))], list(fds))
    sock.sendall(body)


def ask(ident: dict, message: dict, timeout: float = 5.0) -> dict | None:
    """One question without fds (``status``, ``stop``) to the server of ``ident``; its
    answer, or None when none answers."""
    try:
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as sock:
            sock.settimeout(timeout)
            sock.connect(socket_path(ident))
            send(sock, message)
            line = sock.makefile("rb").readline()
    except OSError:
        return None
    return json.loads(line) if line else None


def served(argv: list[str]) -> int | None:
    """Run ``argv`` (without the program name) on the warm server: its exit status, or
    None when it must run cold here (see the module docstring)."""
    if mode() not in MODES:
        print(f"occbench: {ENV} must be one of {', '.join(MODES)}, got {mode()!r}",
              file=sys.stderr)
        return 2
    if mode() == "off" or (argv and argv[0] == "server"):
        return None
    ident = identity()
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        sock.connect(socket_path(ident))
    except OSError:
        sock.close()
        if mode() == "on":
            start_server(ident)
        return None
    request = {"op": "run", "identity": ident, "argv": [sys.argv[0], *argv],
               "orig_argv": list(getattr(sys, "orig_argv", sys.argv)), "cwd": os.getcwd(),
               "umask": _umask(), "env": dict(os.environ)}
    with sock:
        try:
            send(sock, request, [0, 1, 2])
        except OSError:
            return None
        return _wait(sock, ident)


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _wait(sock: socket.socket, ident: dict) -> int | None:
    """Forward signals to the job until the server reports its end."""
    job: list[int] = []
    pending: list[int] = []

    def forward(signum: int, frame: object) -> None:
        if job:
            try:
                os.killpg(job[0], signum)
            except OSError:
                pass
        else:
            pending.append(signum)

    def suspend(signum: object, frame: object) -> None:  # Ctrl-Z: the job stops with us
        if not job:  # its pid is on its way (the job may already be running): stop then,
            pending.append(signal.SIGTSTP)  # else we would stop and leave it running
            return
        os.killpg(job[0], signal.SIGSTOP)
        os.kill(os.getpid(), signal.SIGSTOP)  # returns when the shell continues us (fg, bg)

    def resume(signum: object, frame: object) -> None:
        if job:
            os.killpg(job[0], signal.SIGCONT)
        elif signal.SIGTSTP in pending:  # continued before the job was known: no stop
            pending.remove(signal.SIGTSTP)

    saved = {s: signal.signal(s, forward) for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)}
    saved.update({signal.SIGTSTP: signal.signal(signal.SIGTSTP, suspend),
                  signal.SIGCONT: signal.signal(signal.SIGCONT, resume)})
    try:
        for line in sock.makefile("rb"):
            answer = json.loads(line)
            if "pid" in answer:
                job.append(int(answer["pid"]))
                for signum in pending:
                    (suspend if signum == signal.SIGTSTP else forward)(signum, None)
            elif "exit" in answer:
                return int(answer["exit"])
            elif "signal" in answer:
                return _die_as(int(answer["signal"]), saved)
            elif "stale" in answer:  # it is not this code's server: it exits, we run cold
                if mode() == "on":
                    start_server(ident)
                return None
    except (OSError, ValueError):
        pass
    finally:
        for s, handler in saved.items():
            signal.signal(s, handler)
    if not job:
        return None  # the server went away before starting the job: nothing ran
    print(f"occbench: the server ended before the job (pid {job[0]}) did; its log: "
          f"{socket_path(ident)[:-5]}.log", file=sys.stderr)
    return 1


def _die_as(signum: int, saved: dict) -> int:
    """The job was killed by ``signum``: end this process the same way (the shell sees what
    it would have seen of a cold run)."""
    sys.stdout.flush()
    signal.signal(signum, signal.SIG_DFL)
    os.kill(os.getpid(), signum)
    return 128 + signum  # the signal is ignored or blocked: its conventional status


def start_server(ident: dict) -> None:
    """Start this identity's server in the background (own session, no terminal, output to
    its log); it exits at once when another one is starting or running."""
    import subprocess  # start-up: ~1.5 ms CPU, 2 % of occbench --version

    path = socket_path(ident)
    os.makedirs(os.path.dirname(path), mode=0o700, exist_ok=True)
    boot = ("import json, sys; sys.path[:] = json.loads(sys.argv[1]); "
            "from occbench.commands.server import serve; sys.exit(serve(sys.argv[2]))")
    log = os.open(path[:-5] + ".log", os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o600)
    with open(log, "ab") as log:
        subprocess.Popen([ident["executable"], "-c", boot, json.dumps(ident["path"]), path],
                         stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                         cwd="/", start_new_session=True, close_fds=True)
