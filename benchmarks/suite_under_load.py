"""The suite under load (issue 39's acceptance): does it pass round after round while another
pytest runs beside it, and does it leave no process behind?

Each round starts a second ``python -m pytest`` (the background: the README's command,
``-n auto`` from addopts) and then, in the foreground, ``python -m pytest -n 2``, both in this
checkout, each with its own ``--basetemp`` (two sessions sharing pytest's default
``/tmp/pytest-of-USER`` number and delete each other's folders) and ``-p no:cacheprovider``.
A run passes when its junit xml exists and counts tests, no failure and no error: pytest's
exit code is recorded, never trusted alone (``-q`` in addopts hides the summary). The round
waits for the background run, then looks for orphans: this script is the child subreaper of
everything the two runs start (``prctl(PR_SET_CHILD_SUBREAPER)``), so a process a test left
behind (a server, a sweep's worker, ffmpeg, chromium, a stopped job) is reparented here
instead of to init; every such process still alive 5 s after both runs ended is reported
(pid, state, which run, its working folder, which names the test's tmp folder, and command
line), then killed by its pid so that the next round starts clean. Processes carrying the
round's marker in their environment (``SUITE_UNDER_LOAD``) are reported too, wherever they
were reparented. The 1-min load average is sampled every 10 s.

A round passes when both runs pass and no orphan is found; the rounds stop at the first
failure unless ``--keep-going``. Run it with ``nice -n 19`` on a shared machine. Each round's
logs and junit xml are kept in ``--out`` (default: a new folder in the temporary directory).

Usage: ``nice -n 19 python benchmarks/suite_under_load.py [--rounds 5] [--workers 2]
[--keep-going] [--timeout 3600] [--out DIR] [--md FILE] [-- PYTEST ARGS]``.
"""

from __future__ import annotations

import argparse
import ctypes
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MARKER = "SUITE_UNDER_LOAD"
PR_SET_CHILD_SUBREAPER = 36
GRACE = 5.0  # s after both runs ended before an orphan counts as left behind


@dataclass
class Outcome:
    """One pytest run: junit counts (``None`` when no xml was written), exit code, time."""

    name: str
    seconds: float = 0.0
    code: int | None = None
    tests: int | None = None
    failures: int = 0
    errors: int = 0
    skipped: int = 0
    failed: list[str] = field(default_factory=list)
    timed_out: bool = False

    @property
    def passed(self) -> bool:
        return (not self.timed_out and self.tests is not None and self.tests > 0
                and self.failures == 0 and self.errors == 0)

    def cell(self) -> str:
        if self.timed_out:
            return "TIMEOUT"
        if self.tests is None:
            return f"NO XML (exit {self.code})"
        ran = self.tests - self.skipped
        word = "pass" if self.passed else "FAIL"
        bad = f", {self.failures} failed, {self.errors} errors" if not self.passed else ""
        return f"{word} {ran - self.failures - self.errors}/{ran}{bad} (exit {self.code})"


def read_junit(path: Path, outcome: Outcome) -> None:
    """Fill ``outcome``'s counts from the junit xml at ``path`` (left ``None`` if absent or
    unreadable: a run that wrote no xml did not pass)."""
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError):
        return
    suites = [root] if root.tag == "testsuite" else root.findall("testsuite")
    outcome.tests = sum(int(s.get("tests", 0)) for s in suites)
    outcome.failures = sum(int(s.get("failures", 0)) for s in suites)
    outcome.errors = sum(int(s.get("errors", 0)) for s in suites)
    outcome.skipped = sum(int(s.get("skipped", 0)) for s in suites)
    for case in root.iter("testcase"):
        if case.find("failure") is not None or case.find("error") is not None:
            outcome.failed.append(f"{case.get('classname')}::{case.get('name')}")


class LoadSampler(threading.Thread):
    """The 1-min load average every ``every`` s until stopped."""

    def __init__(self, every: float = 10.0):
        super().__init__(daemon=True)
        self.every, self.samples, self.done = every, [os.getloadavg()[0]], threading.Event()

    def run(self) -> None:
        while not self.done.wait(self.every):
            self.samples.append(os.getloadavg()[0])

    def summary(self) -> str:
        s = self.samples
        return f"{min(s):.1f} / {statistics.fmean(s):.1f} / {max(s):.1f}"


def become_subreaper() -> None:
    """Orphans of every process this one starts are reparented here, not to init."""
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_CHILD_SUBREAPER) failed")


def _proc(pid: int, name: str) -> bytes:
    try:
        return Path(f"/proc/{pid}/{name}").read_bytes()
    except OSError:
        return b""


def _stat(pid: int) -> tuple[str, int] | None:
    """(state, ppid) of ``pid``, or ``None`` once it is gone."""
    text = _proc(pid, "stat").decode(errors="replace")
    if not text:
        return None
    fields = text[text.rindex(")") + 2:].split()
    return fields[0], int(fields[1])


def describe(pid: int) -> str:
    """``pid state run cwd: command line`` of a live process."""
    stat = _stat(pid)
    env = _proc(pid, "environ").split(b"\0")
    run = next((e.split(b"=", 1)[1].decode() for e in env if e.startswith(MARKER.encode() + b"=")),
               "?")
    try:
        cwd = os.readlink(f"/proc/{pid}/cwd")
    except OSError:
        cwd = "?"
    cmd = _proc(pid, "cmdline").replace(b"\0", b" ").decode(errors="replace").strip()
    return f"{pid} {stat[0] if stat else '?'} {run} cwd={cwd}: {cmd[:200]}"


def reap_zombies(keep: set[int]) -> None:
    """Wait for this process's exited orphans (not for ``keep``, the runs Popen waits for)."""
    for pid in children():
        stat = _stat(pid)
        if pid not in keep and stat and stat[0] == "Z":
            try:
                os.waitpid(pid, os.WNOHANG)
            except ChildProcessError:
                pass


def children() -> list[int]:
    """Pids whose parent is this process."""
    me = os.getpid()
    out = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            stat = _stat(int(entry))
            if stat and stat[1] == me:
                out.append(int(entry))
    return out


def marked(tag: str) -> list[int]:
    """Live pids whose environment carries ``MARKER=<tag>...`` (this round's runs' progeny)."""
    needle = f"{MARKER}={tag}:".encode()
    out = []
    for entry in os.listdir("/proc"):
        if entry.isdigit() and int(entry) != os.getpid():
            if any(e.startswith(needle) for e in _proc(int(entry), "environ").split(b"\0")):
                stat = _stat(int(entry))
                if stat and stat[0] != "Z":
                    out.append(int(entry))
    return out


def orphans(tag: str, runs: set[int]) -> list[int]:
    """Live processes the round's runs left behind: this process's children other than the
    runs, and any process carrying the round's marker."""
    reap_zombies(runs)
    found = {p for p in children() if p not in runs and (_stat(p) or ("Z",))[0] != "Z"}
    return sorted(found | set(marked(tag)))


def start(name: str, tag: str, folder: Path, extra: list[str]) -> tuple[subprocess.Popen, Path]:
    """``python -m pytest`` in ROOT with its own basetemp and junit xml, output to a log."""
    xml = folder / f"{name}.xml"
    cmd = [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-rfE",
           f"--basetemp={folder / (name + '_tmp')}", f"--junitxml={xml}", *extra]
    log = open(folder / f"{name}.log", "wb")
    env = {**os.environ, MARKER: f"{tag}:{name}"}
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT, env=env,
                            start_new_session=True)
    log.close()
    return proc, xml


def finish(runs: list[tuple[subprocess.Popen, Path, Outcome, float]], deadline: float) -> None:
    """Wait for the runs (proc, xml, outcome, start), each timed to its own end, until
    ``deadline`` (then kill the process groups left), and read their xml."""
    waiting = list(runs)
    while waiting:
        for run in list(waiting):
            proc, xml, outcome, t0 = run
            if proc.poll() is None and time.monotonic() < deadline:
                continue
            if proc.returncode is None:
                outcome.timed_out = True
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
            outcome.seconds, outcome.code = time.monotonic() - t0, proc.returncode
            read_junit(xml, outcome)
            waiting.remove(run)
        time.sleep(1)


@dataclass
class Round:
    number: int
    fg: Outcome
    bg: Outcome
    load: str
    left: list[str]

    @property
    def passed(self) -> bool:
        return self.fg.passed and self.bg.passed and not self.left


def one_round(number: int, out: Path, workers: int, timeout: float, extra: list[str]) -> Round:
    """A background pytest, then ``pytest -n workers`` in the foreground; orphans after both."""
    folder = out / f"round{number}"
    folder.mkdir(parents=True, exist_ok=True)
    tag = f"{os.getpid()}.{number}"
    sampler = LoadSampler()
    sampler.start()
    deadline = time.monotonic() + timeout
    t_bg = time.monotonic()
    bg_proc, bg_xml = start("background", tag, folder, extra)
    t_fg = time.monotonic()
    fg_proc, fg_xml = start("foreground", tag, folder, ["-n", str(workers), *extra])
    fg, bg = Outcome("foreground"), Outcome("background")
    finish([(fg_proc, fg_xml, fg, t_fg), (bg_proc, bg_xml, bg, t_bg)], deadline)
    sampler.done.set()
    time.sleep(GRACE)
    left = orphans(tag, {fg_proc.pid, bg_proc.pid})
    described = [describe(p) for p in left]
    for pid in left:  # reported above; killed by pid so the next round starts clean
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    time.sleep(0.5)
    reap_zombies({fg_proc.pid, bg_proc.pid})
    return Round(number, fg, bg, sampler.summary(), described)


def table(rounds: list[Round], workers: int) -> str:
    head = ["round", f"pytest -n {workers} (fg)", "fg min", "pytest (bg)", "bg min",
            "load 1-min min / mean / max", "orphans", "round"]
    rows = [head, ["---"] * len(head)]
    for r in rounds:
        rows.append([str(r.number), r.fg.cell(), f"{r.fg.seconds / 60:.1f}", r.bg.cell(),
                     f"{r.bg.seconds / 60:.1f}", r.load, str(len(r.left)),
                     "pass" if r.passed else "FAIL"])
    return "\n".join("| " + " | ".join(row) + " |" for row in rows)


def report(r: Round) -> None:
    print(f"round {r.number}: {'pass' if r.passed else 'FAIL'}; load {r.load}", flush=True)
    for o in (r.fg, r.bg):
        print(f"  {o.name}: {o.cell()}, {o.seconds / 60:.1f} min", flush=True)
        for name in o.failed:
            print(f"    failed: {name}", flush=True)
    for line in r.left:
        print(f"  orphan: {line}", flush=True)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--workers", type=int, default=2, help="the foreground's -n")
    parser.add_argument("--keep-going", action="store_true",
                        help="run every round even after one fails")
    parser.add_argument("--timeout", type=float, default=3600,
                        help="seconds a round may take before its runs are killed")
    parser.add_argument("--out", type=Path, help="folder for each round's logs and junit xml")
    parser.add_argument("--md", type=Path, help="also write the table to this file")
    parser.add_argument("pytest_args", nargs="*", help="after --: given to both runs")
    args = parser.parse_args(argv)
    out = args.out or Path(tempfile.mkdtemp(prefix="suite_under_load."))
    out.mkdir(parents=True, exist_ok=True)
    become_subreaper()
    print(f"suite under load: {args.rounds} rounds in {ROOT}, nice {os.nice(0)}, "
          f"logs in {out}; load {os.getloadavg()[0]:.1f}", flush=True)
    rounds: list[Round] = []
    for number in range(1, args.rounds + 1):
        rounds.append(one_round(number, out, args.workers, args.timeout, args.pytest_args))
        report(rounds[-1])
        if not rounds[-1].passed and not args.keep_going:
            break
    text = table(rounds, args.workers)
    print(text, flush=True)
    if args.md:
        args.md.write_text(text + "\n")
    passed = sum(r.passed for r in rounds)
    print(f"{passed} of {args.rounds} rounds passed", flush=True)
    return 0 if passed == args.rounds else 1


if __name__ == "__main__":
    sys.exit(main())
