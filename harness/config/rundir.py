"""Run folders that never collide: generated names, a lock per live run, no litter.

* ``${occbench.unique_dir:results/<date>/<time>}`` (the default ``hydra.run.dir`` and
  ``hydra.sweep.dir``): the resolver creates the folder atomically (``mkdir`` without
  ``exist_ok``) and, when it exists already (another run started in the same second, or an
  earlier one), takes the first free ``<folder>-2``, ``<folder>-3``, ... The choice is
  remembered per process and in the config's resolver cache (Hydra copies that cache into
  every job's config), so every later resolution in the run gives the same folder.
* ``hold(folder)``: the folder's lock (``.occbench.lock``, an ``flock`` held while the run
  lives, the owner's pid and host written in it). A second run into a folder a live run
  holds is refused in one line naming the folder and the owner; the lock goes with the
  process, so a killed run never leaves its folder locked. ``busy(folder)`` tells a library
  caller (``RunWriter``) whether another process holds it.
* ``RunFolder``, a Hydra callback (first in ``hydra.callbacks``): takes the lock of the run
  folder (or the sweep folder of a multirun) before Hydra writes anything into it, refuses a
  path that is a file or cannot be written in one line, and removes a folder it created for
  a run that failed before writing any result (no litter holding only a config and a log).
"""

from __future__ import annotations

import atexit
import fcntl
import os
import shutil
import socket
import sys
from pathlib import Path
from typing import Any

from hydra.experimental.callback import Callback
from omegaconf import DictConfig, OmegaConf

from occbench.errors import RunError

RESOLVER = "occbench.unique_dir"
LOCK_FILE = ".occbench.lock"
# a run folder holding any of these has results worth keeping, even when the run failed
RESULTS = ("metrics.csv", "tracks", "errors.txt")
_CLAIMED: dict[str, str] = {}  # resolver argument -> folder created by this process
_HELD: dict[str, int] = {}  # folder -> descriptor of its locked .occbench.lock


def unique_dir(path: str) -> str:
    """Create and return ``path``, or ``path-2``, ``path-3``, ... when it exists."""
    if path in _CLAIMED:
        return _CLAIMED[path]
    base = Path(path)
    for above in (base.parent, *base.parent.parents):
        if above.exists() and not above.is_dir():
            raise RunError(f"cannot create the run folder {base}: {above} is an existing file, "
                           "not a folder")
    try:
        base.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise RunError(f"cannot create the results folder {base.parent}: "
                       f"{err.strerror or err}") from None
    candidate, n = base, 1
    while True:
        try:
            candidate.mkdir()
            break
        except FileExistsError:
            n += 1
            candidate = base.with_name(f"{base.name}-{n}")
        except OSError as err:
            raise RunError(f"cannot create the run folder {candidate}: "
                           f"{err.strerror or err}") from None
    _CLAIMED[path] = str(candidate)
    return str(candidate)


def created_here(folder: str | Path) -> bool:
    """Whether ``unique_dir`` created ``folder`` in this process."""
    return str(folder) in _CLAIMED.values()


def _prepare(folder: Path) -> None:
    if folder.exists() and not folder.is_dir():
        raise RunError(f"run folder {folder} is an existing file, not a folder: "
                       "choose another hydra.run.dir")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise RunError(f"cannot create the run folder {folder}: {err.strerror or err} "
                       f"({err.filename or folder})") from None


def hold(folder: str | Path) -> None:
    """Lock ``folder`` for this process (created when missing) until ``release`` or exit.

    Raises:
        RunError: the folder is a file, cannot be created or written, or another live run
            holds it (its pid and host named).
    """
    folder = Path(folder).absolute()
    if str(folder) in _HELD:
        return
    _prepare(folder)
    path = folder / LOCK_FILE
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as err:
            raise RunError(f"cannot write in the run folder {folder}: "
                           f"{err.strerror or err}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            owner = _owner(fd)
            os.close(fd)
            raise RunError(f"run folder {folder} is in use by a live run ({owner}): wait "
                           "for it to end or choose another hydra.run.dir") from None
        try:  # the holder before us may have removed the file as we opened it: try again
            same = os.fstat(fd).st_ino == os.stat(path).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    os.ftruncate(fd, 0)
    os.write(fd, f"pid {os.getpid()} on {socket.gethostname()}\n".encode())
    if not _HELD:
        atexit.register(_release_all)  # a run ended by Ctrl-C or SIGTERM leaves no lock file
    _HELD[str(folder)] = fd


def _owner(fd: int) -> str:
    try:
        return os.pread(fd, 200, 0).decode(errors="replace").strip() or "owner unknown"
    except OSError:
        return "owner unknown"


def release(folder: str | Path) -> None:
    """Give up the lock ``hold`` took (the lock file is removed first, then unlocked)."""
    folder = Path(folder).absolute()
    fd = _HELD.pop(str(folder), None)
    if fd is None:
        return
    try:
        (folder / LOCK_FILE).unlink(missing_ok=True)
    except OSError:
        pass
    os.close(fd)


def _release_all() -> None:
    for folder in list(_HELD):
        release(folder)


def busy(folder: str | Path) -> str | None:
    """The owner of ``folder``'s lock when another live process holds it, else None."""
    folder = Path(folder).absolute()
    if str(folder) in _HELD:
        return None
    try:
        fd = os.open(folder / LOCK_FILE, os.O_RDONLY)
    except OSError:
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
        return _owner(fd)
    finally:
        os.close(fd)
    return None


def litter(folder: Path) -> bool:
    """Whether ``folder`` holds no result (only Hydra's files, a log, a config)."""
    return folder.is_dir() and not any((folder / name).exists() for name in RESULTS)


class RunFolder(Callback):
    """Hold the run (or sweep) folder while the run lives; see the module docstring."""

    def __init__(self) -> None:
        self.created = False

    def _start(self, config: DictConfig, key: str) -> None:
        """Resolve ``key`` (creating a generated folder) and hold the folder; a folder that
        cannot be made or held ends the run in one line (exit 1)."""
        try:
            folder = Path(str(OmegaConf.select(config, key, throw_on_missing=True)))
            self.created = created_here(folder) or not folder.exists()
            hold(folder)
        except Exception as err:  # noqa: BLE001 - the resolver's RunError comes wrapped
            cause = err
            while not isinstance(cause, RunError) and (cause.__cause__ or cause.__context__):
                cause = cause.__cause__ or cause.__context__
            print(f"occbench: {cause if isinstance(cause, RunError) else f'{key}: {err}'}",
                  file=sys.stderr)
            raise SystemExit(1) from None

    def on_run_start(self, config: DictConfig, **kwargs: Any) -> None:
        self._start(config, "hydra.run.dir")

    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        self._start(config, "hydra.sweep.dir")

    def on_run_end(self, config: DictConfig, job_return: Any = None, **kwargs: Any) -> None:
        folder = Path(str(config.hydra.run.dir))
        failed = getattr(getattr(job_return, "status", None), "name", "") == "FAILED"
        release(folder)
        if failed and self.created and litter(folder):
            shutil.rmtree(folder, ignore_errors=True)

    def on_multirun_end(self, config: DictConfig, **kwargs: Any) -> None:
        release(Path(str(config.hydra.sweep.dir)))


def register() -> None:
    """Register the resolver (once per process)."""
    if not OmegaConf.has_resolver(RESOLVER):
        OmegaConf.register_new_resolver(RESOLVER, unique_dir, use_cache=True)
