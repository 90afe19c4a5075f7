"""The warm server (``occbench.server``), each test with its own server in its own temporary
folder (``XDG_RUNTIME_DIR``), stopped at the end: a served command gets the client's
arguments, folder, environment, umask and stdio; the exit status comes back; Ctrl-C in the
client reaches the job; a crashing job fails alone; a changed source file makes the server
refuse (the client runs cold) and exit; a real run is byte-identical served and cold."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]

# a server whose "command" is this function and whose code is the folder argv[2]
SERVER = """
import os, sys, time
from occbench.server.serve import Server
def run(args):
    if args[0] == "crash":
        os.kill(os.getpid(), 11)
    if args[0] == "sleep":
        try:
            print("sleeping", os.getpid(), flush=True)
            time.sleep(60)
        except KeyboardInterrupt:
            print("interrupted", file=sys.stderr, flush=True)
            return 130
    line = input() if args[0] == "echo" else ""
    print(f"served {os.getpid()} {os.getcwd()} {oct(os.umask(0))} {os.environ.get('PROBE')} "
          f"{sys.stdout.isatty()} {line} {args}", flush=True)
    return int(args[1]) if len(args) > 1 else 0
sys.exit(Server(sys.argv[1], run, lambda: None, watch=[sys.argv[2]]).serve())
"""
CLIENT = """
import sys
from occbench.server import client
client.start_server = lambda ident: print("starts a server", flush=True)  # not in a test
status = client.served(sys.argv[1:])
print("cold" if status is None else f"status {status}", flush=True)
sys.exit(0 if status is None else status)
"""


def _run(cmd: list[str], **kwargs) -> subprocess.CompletedProcess:
    """A command whose exit status the test reads."""
    return subprocess.run(cmd, check=False, **kwargs)


def _env(folder: Path, **extra: str) -> dict[str, str]:
    # no empty PYTHONPATH entry: it would put the current folder on sys.path, so a client
    # in another folder would have another identity (another server)
    paths = [str(ROOT), *filter(None, os.environ.get("PYTHONPATH", "").split(os.pathsep))]
    return {**os.environ, "XDG_RUNTIME_DIR": str(folder), "OCCBENCH_SERVER": "on",
            "PYTHONPATH": os.pathsep.join(paths), **extra}


def _socket(env: dict[str, str], cwd: Path) -> Path:
    """The socket of the identity a ``python -c`` process in ``cwd`` with ``env`` has."""
    code = "from occbench.server.client import identity, socket_path; print(socket_path(identity()))"
    out = subprocess.run([sys.executable, "-c", code], env=env, cwd=cwd, capture_output=True,
                         text=True, check=True, timeout=60)
    return Path(out.stdout.strip())


def _wait_for(path: Path, proc: subprocess.Popen, timeout: float = 300) -> None:
    end = time.monotonic() + timeout
    while not path.exists():
        assert proc.poll() is None, proc.stderr.read()
        assert time.monotonic() < end, f"no server at {path}"
        time.sleep(0.1)


@pytest.fixture
def toy(tmp_path):
    """A toy server (``SERVER``) watching a folder with one source file; yields
    (client command prefix, env, cwd, watched file, server process)."""
    folder = Path(tempfile.mkdtemp(prefix="obs", dir="/tmp"))  # a socket path is short
    code = tmp_path / "code"
    code.mkdir()
    (code / "model.py").write_text("X = 1\n")
    env = _env(folder, PROBE="probe-value")
    path = _socket(env, tmp_path)
    proc = subprocess.Popen([sys.executable, "-c", SERVER, str(path), str(code)], env=env,
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    try:
        _wait_for(path, proc)
        yield [sys.executable, "-c", CLIENT], env, tmp_path, code / "model.py", proc
    finally:
        proc.kill()
        proc.wait()
        shutil.rmtree(folder, ignore_errors=True)


def test_a_served_command_runs_in_the_clients_folder_with_its_env_umask_and_stdio(toy):
    client, env, cwd, _, proc = toy
    sub = cwd / "sub"
    sub.mkdir()
    out = _run([*client, "echo", "3"], env={**env, "PROBE": "mine"}, cwd=sub,
                         input="typed\n", capture_output=True, text=True, timeout=60,
                         preexec_fn=lambda: os.umask(0o027))
    served, status = out.stdout.strip().splitlines()
    pid = int(served.split()[1])
    assert served == f"served {pid} {sub} 0o27 mine False typed ['echo', '3']"
    assert status == "status 3" and out.returncode == 3
    assert pid not in (proc.pid, os.getpid())


def test_ctrl_c_in_the_client_reaches_the_job(toy):
    client, env, cwd, _, _ = toy
    job = subprocess.Popen([*client, "sleep"], env=env, cwd=cwd, stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, text=True)
    assert job.stdout.readline().split()[0] == "sleeping"
    job.send_signal(signal.SIGINT)
    out, err = job.communicate(timeout=30)
    assert (job.returncode, out.strip(), err.strip()) == (130, "status 130", "interrupted")


def _state(pid: int) -> str:
    """The process state letter of ``pid`` (/proc/PID/stat: T stopped, S sleeping)."""
    return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]


def _wait_state(pid: int, states: str) -> str:
    end = time.monotonic() + 30
    while _state(pid) not in states and time.monotonic() < end:
        time.sleep(0.05)
    return _state(pid)


def _end(proc: subprocess.Popen, group: int | None = None) -> None:
    """No orphan, whatever the test's outcome: the job's process group (stopped or not) and
    the client are killed."""
    if group is not None:
        for sig in (signal.SIGKILL, signal.SIGCONT):
            try:
                os.killpg(group, sig)
            except OSError:
                pass
    if proc.poll() is None:
        proc.kill()
        proc.send_signal(signal.SIGCONT)
    proc.communicate(timeout=30)


@pytest.mark.skipif(not Path("/proc/self/stat").is_file(), reason="needs Linux's /proc")
def test_ctrl_z_in_the_client_stops_the_job_and_fg_continues_it(toy):
    client, env, cwd, _, _ = toy
    job = subprocess.Popen([*client, "sleep"], env=env, cwd=cwd, stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, text=True)
    pid = None
    try:
        pid = int(job.stdout.readline().split()[1])
        assert _state(pid) != "T"
        job.send_signal(signal.SIGTSTP)
        assert (_wait_state(job.pid, "T"), _wait_state(pid, "T")) == ("T", "T")
        job.send_signal(signal.SIGCONT)
        assert _wait_state(pid, "SR") in "SR" and _wait_state(job.pid, "SR") in "SR"
        job.send_signal(signal.SIGINT)
        out, err = job.communicate(timeout=30)
        assert (job.returncode, out.strip(), err.strip()) == (130, "status 130", "interrupted")
    finally:
        _end(job, pid)


# a client whose job (a sleep in its own process group) is announced by the "server" only
# after Ctrl-Z has reached the client: the race behind issue 39 item 4
EARLY_STOP = """
import json, os, signal, socket, subprocess, threading, time
from occbench.server import client
job = subprocess.Popen(["sleep", "60"], start_new_session=True)
print(job.pid, flush=True)
ours, server = socket.socketpair()
stopped = threading.Event()
def ctrl_z():
    time.sleep(0.2)
    os.kill(os.getpid(), signal.SIGTSTP)
    stopped.set()
def feed():
    stopped.wait()
    time.sleep(0.5)
    server.sendall(json.dumps({"pid": job.pid}).encode() + b"\\n")
    server.sendall(json.dumps({"exit": -job.wait()}).encode() + b"\\n")
threading.Thread(target=ctrl_z, daemon=True).start()
threading.Thread(target=feed, daemon=True).start()
print("status", client._wait(ours, {}), flush=True)
"""


@pytest.mark.skipif(not Path("/proc/self/stat").is_file(), reason="needs Linux's /proc")
def test_ctrl_z_before_the_job_is_known_stops_it_once_it_is(tmp_path):
    """Ctrl-Z reaching the client before the server's pid answer: the job must stop with the
    client (it used to stop the client alone, leaving the job running: ('T', 'S'))."""
    proc = subprocess.Popen([sys.executable, "-c", EARLY_STOP], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=_env(tmp_path))
    pid = None
    try:
        first = proc.stdout.readline()
        assert first.strip().isdigit(), proc.stderr.read()
        pid = int(first)
        assert (_wait_state(proc.pid, "T"), _wait_state(pid, "T")) == ("T", "T")
        proc.send_signal(signal.SIGCONT)  # fg
        assert _wait_state(pid, "SR") in "SR" and _wait_state(proc.pid, "SR") in "SR"
        proc.send_signal(signal.SIGTERM)  # forwarded to the job, which ends
        out, _ = proc.communicate(timeout=30)
        assert out.strip() == f"status {signal.SIGTERM}"
    finally:
        _end(proc, pid)


def test_a_crashing_job_fails_alone_and_the_server_goes_on(toy):
    client, env, cwd, _, proc = toy
    crash = _run([*client, "crash"], env=env, cwd=cwd, capture_output=True,
                           timeout=60)
    assert crash.returncode == -signal.SIGSEGV  # the client ends as the job did
    assert proc.poll() is None
    again = _run([*client, "again"], env=env, cwd=cwd, capture_output=True,
                           text=True, timeout=60)
    assert again.stdout.startswith("served") and again.returncode == 0


def test_a_changed_source_file_is_never_served_by_the_old_server(toy):
    client, env, cwd, source, proc = toy
    first = _run([*client, "x"], env=env, cwd=cwd, capture_output=True, text=True,
                           timeout=60)
    assert first.stdout.startswith("served")
    source.write_text("X = 2\n")  # same size, most likely the same time stamp
    second = _run([*client, "x"], env=env, cwd=cwd, capture_output=True,
                            text=True, timeout=60)
    assert second.stdout.split("\n")[:2] == ["starts a server", "cold"]
    assert proc.wait(timeout=60) == 0  # the stale server exits


@pytest.mark.parametrize(("mode", "says", "status"), [
    ("auto", ["cold"], 0), ("on", ["starts a server", "cold"], 0), ("off", ["cold"], 0),
    ("yes", ["status 2"], 2)])
def test_without_a_server_only_on_starts_one(tmp_path, mode, says, status):
    folder = Path(tempfile.mkdtemp(prefix="obs", dir="/tmp"))
    out = _run([sys.executable, "-c", CLIENT, "x"], env=_env(folder, OCCBENCH_SERVER=mode),
               cwd=tmp_path, capture_output=True, text=True, timeout=120)
    shutil.rmtree(folder, ignore_errors=True)
    assert (out.stdout.split(), out.returncode) == ([w for s in says for w in s.split()], status)
    assert ("must be one of on, auto, off" in out.stderr) == (mode == "yes")


def test_sigterm_stops_the_server_and_removes_its_socket(toy):
    _, env, cwd, _, proc = toy
    path = _socket(env, cwd)
    assert path.exists()
    proc.terminate()
    assert proc.wait(timeout=60) == 0 and not path.exists()


def test_server_status_and_stop_without_a_server(tmp_path):
    env = _env(Path(tempfile.mkdtemp(prefix="obs", dir="/tmp")))
    status = _run([sys.executable, "-m", "occbench", "server", "status"], env=env, cwd=tmp_path,
                  capture_output=True, text=True, timeout=120)
    stop = _run([sys.executable, "-m", "occbench", "server", "stop"], env=env, cwd=tmp_path,
                capture_output=True, text=True, timeout=120)
    shutil.rmtree(env["XDG_RUNTIME_DIR"], ignore_errors=True)
    assert status.returncode == 3 and "none running" in status.stdout
    assert stop.returncode == 0 and "none running" in stop.stdout


def _files(run_dir: Path) -> dict[str, bytes]:
    """Every file of a run folder, its own path replaced by RUN (config.yaml names it; the
    report's title names the folder: both are called ``run``)."""
    skip = ("timings.csv", ".log")
    return {str(p.relative_to(run_dir)): p.read_bytes().replace(bytes(run_dir), b"RUN")
            for p in sorted(run_dir.rglob("*"))
            if p.is_file() and ".hydra" not in p.parts and not p.name.endswith(skip)}


@pytest.mark.slow
def test_a_run_is_byte_identical_served_and_cold(tmp_path):
    """``occbench tracker=reta`` on one short scene through the project's own server and
    cold: every file of the run folder equal (times excepted: timings.csv, the log)."""
    folder = Path(tempfile.mkdtemp(prefix="obs", dir="/tmp"))
    env = _env(folder)
    occbench = [sys.executable, "-m", "occbench"]
    server = subprocess.Popen([*occbench, "server", "start", "--foreground"], env=env,
                              cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True)
    args = ["tracker=reta", "dataset.scenarios=[crossing]", "dataset.length=20",
            "progress=false"]
    runs = {}
    try:
        end = time.monotonic() + 300
        while _run([*occbench, "server", "status"], env=env, cwd=tmp_path,
                             capture_output=True, timeout=60).returncode != 0:
            assert server.poll() is None and time.monotonic() < end, server.stderr.read()
            time.sleep(0.5)
        for how, mode in (("served", "on"), ("cold", "off")):
            out = tmp_path / how / "run"
            runs[how] = _run([*occbench, *args, f"hydra.run.dir={out}"],
                                       env={**env, "OCCBENCH_SERVER": mode}, cwd=tmp_path,
                                       capture_output=True, timeout=600)
        status = _run([*occbench, "server", "status"], env=env, cwd=tmp_path,
                                capture_output=True, text=True, timeout=60)
    finally:
        _run([*occbench, "server", "stop"], env=env, cwd=tmp_path, timeout=60)
        server.wait(timeout=60)
        shutil.rmtree(folder, ignore_errors=True)
    assert [r.returncode for r in runs.values()] == [0, 0], [r.stderr for r in runs.values()]
    assert "1 job(s) served" in status.stdout
    outs = [r.stdout.replace(bytes(tmp_path / how / "run"), b"RUN") for how, r in runs.items()]
    assert outs[0] == outs[1]
    served, cold = _files(tmp_path / "served" / "run"), _files(tmp_path / "cold" / "run")
    assert sorted(served) == sorted(cold) and len(served) > 5
    assert [name for name in served if served[name] != cold[name]] == []


def test_status_says_starting_while_the_server_preloads(tmp_path, monkeypatch, capsys):
    """Between ``start`` and listening the server holds its lock and does not answer: status
    says it is starting (issue 39 item 10: it said "none running" for a few seconds)."""
    import fcntl

    from occbench.commands import server as command
    from occbench.server import client

    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    path = client.socket_path(client.identity())
    os.makedirs(os.path.dirname(path), exist_ok=True)
    assert command.main(["status"]) == 3 and "none running" in capsys.readouterr().out
    lock = os.open(command.lock_path(path), os.O_RDWR | os.O_CREAT, 0o600)
    child = os.fork()
    if child == 0:  # the "server": holds the lock, never listens
        fcntl.flock(lock, fcntl.LOCK_EX)
        time.sleep(30)
        os._exit(0)
    try:
        end = time.monotonic() + 10
        while not command.starting(path):
            assert time.monotonic() < end
            time.sleep(0.05)
        assert command.main(["status"]) == 3  # 0 only once it answers (scripts wait on it)
        out = capsys.readouterr().out
        assert "starting" in out and "none running" not in out
    finally:
        os.kill(child, signal.SIGKILL)
        os.waitpid(child, 0)
        os.close(lock)
    assert not command.starting(path)
