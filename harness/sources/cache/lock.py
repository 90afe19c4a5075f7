"""A lock file for one cache entry, safe on a folder shared between machines.

The lock is a file created with ``O_CREAT | O_EXCL`` (atomic on local file systems and on
NFSv3 and later, unlike ``fcntl`` locks, which NFS clients do not reliably honour). It holds
its owner's host, pid and start time. While the owner computes, a heartbeat thread touches
the file every ``heartbeat`` seconds; a waiter that sees neither the file's modification
time nor its content change for ``stale_after`` seconds of its own clock (so clock skew
between machines does not matter), or whose owner is a dead process on the waiter's own
host, takes the lock as stale and removes it.

Removal is a rename to a unique name then an unlink, so of several waiters that judge one
lock stale only one removes it. A live lock removed by mistake (a waiter that judged the
lock stale just before its owner's next heartbeat) costs a second computation of the same
entry, never a half-written or mixed one: entries are written by rename.
"""

from __future__ import annotations

import json
import logging
import os
import socket
import threading
import time
import uuid
from pathlib import Path

log = logging.getLogger(__name__)

#: seconds between the owner's touches of its lock file
HEARTBEAT = 5.0
#: seconds without a touch after which a waiter takes a lock as stale
STALE_AFTER = 60.0


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's live process
        return True
    return True


class EntryLock:
    """The lock of one entry: ``try_acquire`` / ``release``, and ``stale`` for waiters.

    Args:
        path: the lock file.
        heartbeat: seconds between the owner's touches (> 0).
        stale_after: seconds without a change after which the lock is stale (> heartbeat).
    """

    def __init__(self, path: Path, heartbeat: float = HEARTBEAT,
                 stale_after: float = STALE_AFTER) -> None:
        if not heartbeat > 0:
            raise ValueError(f"heartbeat must be > 0, got {heartbeat}")
        if not stale_after > heartbeat:
            raise ValueError(f"stale_after must be > heartbeat ({heartbeat}), got {stale_after}")
        self.path = Path(path)
        self.heartbeat = float(heartbeat)
        self.stale_after = float(stale_after)
        self.owner = {"host": socket.gethostname(), "pid": os.getpid(), "token": uuid.uuid4().hex}
        self._stop: threading.Event | None = None
        self._seen: tuple[object, float] | None = None  # (mtime and content, our clock)

    def try_acquire(self) -> bool:
        """Create the lock file; False when another holds it."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        try:
            fd = os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            return False
        with os.fdopen(fd, "w") as fh:
            json.dump({**self.owner, "started": time.time()}, fh)
        self._stop = threading.Event()
        threading.Thread(target=self._beat, args=(self._stop,), daemon=True,
                         name="occbench-cache-lock").start()
        return True

    def _beat(self, stop: threading.Event) -> None:
        while not stop.wait(self.heartbeat):
            try:
                os.utime(self.path)
            except OSError:  # removed as stale: the entry is still written by rename
                return

    def release(self) -> None:
        """Stop the heartbeat and remove the lock file if it is still ours."""
        if self._stop is not None:
            self._stop.set()
            self._stop = None
        if self.holder().get("token") == self.owner["token"]:
            self.path.unlink(missing_ok=True)

    def holder(self) -> dict:
        """The lock file's content ({} when there is none or it cannot be read yet)."""
        try:
            return json.loads(self.path.read_text())
        except (OSError, ValueError):
            return {}

    def stale(self) -> bool:
        """Whether the lock file (held by another) is stale; call it at each wait."""
        try:
            st = self.path.stat()
            content = self.path.read_bytes()
        except OSError:
            return False  # gone: no longer anyone's
        holder = self.holder()
        pid = holder.get("pid")
        if holder.get("host") == self.owner["host"] and isinstance(pid, int) and not _pid_alive(pid):
            return True
        now = time.monotonic()
        state = (st.st_mtime_ns, content)
        if self._seen is None or self._seen[0] != state:
            self._seen = (state, now)
            return False
        return now - self._seen[1] > self.stale_after

    def break_stale(self) -> None:
        """Remove a stale lock file (one of several waiters doing so succeeds)."""
        holder = self.holder()
        grave = self.path.with_name(f"{self.path.name}.stale.{uuid.uuid4().hex}")
        try:
            os.rename(self.path, grave)
        except OSError:
            return
        log.warning("front-end cache: removed a stale lock %s (owner %s)", self.path, holder)
        grave.unlink(missing_ok=True)
        self._seen = None
