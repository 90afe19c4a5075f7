"""The cache folder: entries written atomically, verified on read, one computation per key.

An entry is one file ``<root>/frontend/<key>.occ``::

    MAGIC | header length (8 bytes, little-endian) | header (JSON) | payload (.npz bytes)

The header holds the entry's ``key``, the payload's ``sha256`` and length, and ``meta``
(what ``occbench cache`` lists: sequence, detector, frames, host, ...). An entry is read
only when its magic, key, length and checksum are right and its arrays load without
pickle; anything else (truncated, corrupt, written for another key) is reported in one
warning and recomputed. Entries are written to a unique temporary name in the same folder
and renamed into place, so a reader never sees a half-written one.

``Store.get_or_compute`` is the one way in: read the entry; else take its lock
(``occbench.sources.cache.lock``) and compute it, while other processes wanting the same
key wait for the entry to appear, then read it.
"""

from __future__ import annotations

import hashlib
import io
import json
import logging
import os
import socket
import time
import uuid
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from occbench.sources.cache.lock import HEARTBEAT, STALE_AFTER, EntryLock

log = logging.getLogger(__name__)

MAGIC = b"occbench front-end cache 1\n"
SUFFIX = ".occ"
#: seconds between a waiter's looks at the entry and its lock
POLL = 0.25

Arrays = dict[str, np.ndarray]


class CorruptEntry(ValueError):
    """An entry that must not be used (the message says why)."""


@dataclass(frozen=True)
class Entry:
    """A verified entry: its ``meta`` and its arrays."""

    key: str
    meta: dict[str, Any]
    arrays: Arrays


@dataclass(frozen=True)
class EntryInfo:
    """What a listing shows of one entry file (``meta`` empty and ``problem`` set when its
    header cannot be read)."""

    path: Path
    key: str
    meta: dict[str, Any]
    size: int
    mtime: float
    problem: str | None = None


def encode(key: str, meta: dict[str, Any], arrays: Arrays) -> bytes:
    """The bytes of an entry file."""
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    payload = buf.getvalue()
    header = json.dumps({"key": key, "sha256": hashlib.sha256(payload).hexdigest(),
                         "payload_bytes": len(payload), "meta": meta}, sort_keys=True).encode()
    return MAGIC + len(header).to_bytes(8, "little") + header + payload


def _header(data: bytes) -> tuple[dict[str, Any], int]:
    """The header of entry bytes ``data`` and where its payload starts; CorruptEntry."""
    if not data.startswith(MAGIC):
        raise CorruptEntry("not an occbench front-end cache entry (wrong magic)")
    at = len(MAGIC) + 8
    if len(data) < at:
        raise CorruptEntry("truncated header")
    n = int.from_bytes(data[len(MAGIC):at], "little")
    if len(data) < at + n:
        raise CorruptEntry("truncated header")
    try:
        header = json.loads(data[at:at + n])
    except ValueError as err:
        raise CorruptEntry(f"unreadable header ({err})") from None
    if not isinstance(header, dict) or not isinstance(header.get("meta"), dict):
        raise CorruptEntry("header without meta")
    return header, at + n


def decode(data: bytes, key: str) -> Entry:
    """The entry in ``data``, verified to be ``key``'s and whole; CorruptEntry otherwise."""
    header, at = _header(data)
    if header.get("key") != key:
        raise CorruptEntry(f"written for another key ({header.get('key')!r})")
    payload = data[at:]
    if len(payload) != header.get("payload_bytes"):
        raise CorruptEntry(f"truncated: {len(payload)} of {header.get('payload_bytes')} "
                           "payload bytes")
    if hashlib.sha256(payload).hexdigest() != header.get("sha256"):
        raise CorruptEntry("checksum mismatch")
    try:
        with np.load(io.BytesIO(payload), allow_pickle=False) as npz:
            arrays = {name: npz[name] for name in npz.files}
    except Exception as err:  # noqa: BLE001 - whatever numpy says of a bad payload
        raise CorruptEntry(f"unreadable arrays ({type(err).__name__}: {err})") from None
    return Entry(key, header["meta"], arrays)


def _signature(path: Path) -> tuple[int, int, int] | None:
    """What tells one version of a file from the next (None: no file)."""
    try:
        st = path.stat()
    except FileNotFoundError:
        return None
    return st.st_mtime_ns, st.st_size, st.st_ino


class Store:
    """Entries under ``root`` (``OCCBENCH_CACHE``; see ``occbench.sources.cache.cache_root``).

    Args:
        root: the cache folder (created on first write).
        heartbeat, stale_after: the locks' timing (``EntryLock``).
        poll: seconds between a waiter's looks.
    """

    def __init__(self, root: Path, heartbeat: float = HEARTBEAT,
                 stale_after: float = STALE_AFTER, poll: float = POLL) -> None:
        self.root = Path(root)
        self.folder = self.root / "frontend"
        self.heartbeat, self.stale_after, self.poll = heartbeat, stale_after, poll

    def path(self, key: str) -> Path:
        return self.folder / f"{key}{SUFFIX}"

    def read(self, key: str, check: Callable[[Entry], None] | None = None) -> Entry | None:
        """The entry of ``key``; None when there is none, or (with one warning) when it is
        corrupt, truncated or another key's. ``check`` may raise CorruptEntry too."""
        path = self.path(key)
        try:
            data = path.read_bytes()
        except FileNotFoundError:
            return None
        try:
            entry = decode(data, key)
            if check is not None:
                check(entry)
        except CorruptEntry as err:
            log.warning("front-end cache entry %s is unusable (%s): recomputing it", path, err)
            return None
        return entry

    def write(self, key: str, meta: dict[str, Any], arrays: Arrays) -> Entry:
        """Write the entry of ``key`` atomically (temporary file, fsync, rename)."""
        data = encode(key, meta, arrays)
        self.folder.mkdir(parents=True, exist_ok=True)
        path = self.path(key)
        tmp = path.with_name(f".{path.name}.{socket.gethostname()}.{os.getpid()}."
                             f"{uuid.uuid4().hex[:8]}.tmp")
        try:
            with open(tmp, "wb") as fh:
                fh.write(data)
                fh.flush()
                os.fsync(fh.fileno())
            os.replace(tmp, path)
        finally:
            tmp.unlink(missing_ok=True)
        return Entry(key, meta, arrays)

    def get_or_compute(self, key: str, compute: Callable[[], tuple[dict[str, Any], Arrays]],
                       check: Callable[[Entry], None] | None = None) -> tuple[Entry, str]:
        """The entry of ``key`` and how it came: ``"read"`` (there already), ``"computed"``
        (here, and stored) or ``"waited"`` (computed by another process meanwhile).

        ``compute()`` returns ``(meta, arrays)``; it runs at most once here and only while
        this process holds the key's lock. Whatever it raises is raised (the lock freed).
        """
        path = self.path(key)
        seen = _signature(path)
        entry = self.read(key, check) if seen is not None else None
        if entry is not None:
            return entry, "read"
        lock = EntryLock(self.folder / f"{key}.lock", self.heartbeat, self.stale_after)
        waited = False
        while True:
            if lock.try_acquire():
                try:
                    # another may have written it between our look and our lock
                    now = _signature(path)
                    entry = self.read(key, check) if now not in (None, seen) else None
                    if entry is not None:
                        return entry, "waited"
                    meta, arrays = compute()
                    return self.write(key, meta, arrays), "computed"
                finally:
                    lock.release()
            if not waited:
                log.info("front-end cache: %s is being computed by %s; waiting for it",
                         key[:12], lock.holder() or "another process")
            waited = True
            time.sleep(self.poll)
            now = _signature(path)
            if now not in (None, seen):  # written (or rewritten) since we last read it
                seen = now
                entry = self.read(key, check)
                if entry is not None:
                    return entry, "waited"
            if lock.stale():
                lock.break_stale()

    def entries(self) -> Iterator[EntryInfo]:
        """Every entry file, in name order, with its header's meta."""
        if not self.folder.is_dir():
            return
        for path in sorted(self.folder.glob(f"*{SUFFIX}")):
            try:
                st = path.stat()
                with open(path, "rb") as fh:
                    head = fh.read(len(MAGIC) + 8)
                    n = int.from_bytes(head[len(MAGIC):], "little") if len(head) == len(MAGIC) + 8 else 0
                    header, _ = _header(head + fh.read(min(n, 1 << 20)))
                yield EntryInfo(path, str(header.get("key")), header["meta"], st.st_size,
                                st.st_mtime)
            except FileNotFoundError:
                continue  # cleared meanwhile
            except (OSError, CorruptEntry) as err:
                yield EntryInfo(path, path.stem, {}, path.stat().st_size, path.stat().st_mtime,
                                str(err))

    def remove(self, info: EntryInfo) -> None:
        info.path.unlink(missing_ok=True)
