"""``occbench cache``: what the front-end cache holds, and clearing it.

The cache (``occbench.sources.cache``) keeps each sequence's front-end outputs under
``OCCBENCH_CACHE`` (default ``$XDG_CACHE_HOME/occbench`` or ``~/.cache/occbench``;
``off`` disables it). Runs and ``occbench detect`` fill it.

Examples::

    occbench cache                              # entries: sequence, frames, detector, size, age
    occbench cache clear                        # remove every entry
    occbench cache clear --sequence OneLeaveShop1cor --detector Silhouette
    occbench cache clear --older-than 30        # entries older than 30 days
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence

from occbench.sources.cache import ENV, Store, cache_root
from occbench.sources.cache.store import EntryInfo


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="occbench cache", description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("action", nargs="?", choices=("list", "clear"), default="list",
                   help="list the entries (default) or remove them")
    p.add_argument("--sequence", help="only entries whose sequence name contains this")
    p.add_argument("--detector", help="only entries whose detector class contains this")
    p.add_argument("--older-than", type=float, metavar="DAYS",
                   help="only entries written more than DAYS days ago")
    return p


def _detector(info: EntryInfo) -> str:
    name = info.meta.get("detector") or info.meta.get("source") or "?"
    return str(name).rsplit(".", 1)[-1]


def _age(seconds: float) -> str:
    for unit, size in (("d", 86400), ("h", 3600), ("min", 60)):
        if seconds >= size:
            return f"{seconds / size:.1f} {unit}"
    return f"{seconds:.0f} s"


def _size(n: int) -> str:
    for unit, size in (("GB", 1 << 30), ("MB", 1 << 20), ("KB", 1 << 10)):
        if n >= size:
            return f"{n / size:.1f} {unit}"
    return f"{n} B"


def selected(infos: list[EntryInfo], sequence: str | None, detector: str | None,
             older_than: float | None, now: float) -> list[EntryInfo]:
    """The entries matching every filter given (name parts are case-insensitive)."""
    out = []
    for info in infos:
        if sequence and sequence.lower() not in str(info.meta.get("sequence", "")).lower():
            continue
        if detector and detector.lower() not in _detector(info).lower():
            continue
        if older_than is not None and now - info.mtime <= older_than * 86400:
            continue
        out.append(info)
    return out


def table(infos: list[EntryInfo], now: float) -> str:
    """One line per entry: key, sequence, frames, detector, size, age."""
    rows = [("key", "sequence", "frames", "detector", "size", "age")]
    for i in infos:
        frames = i.meta.get("frames")
        span = f"{frames[0]}-{frames[1]}" if isinstance(frames, list) and len(frames) == 2 else "?"
        rows.append((i.key[:12], str(i.meta.get("sequence", f"(unreadable: {i.problem})")),
                     span, _detector(i), _size(i.size), _age(now - i.mtime)))
    widths = [max(len(r[c]) for r in rows) for c in range(len(rows[0]))]
    return "\n".join("  ".join(v.ljust(w) for v, w in zip(r, widths)).rstrip() for r in rows)


def main(argv: Sequence[str] | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.older_than is not None and args.older_than < 0:
        parser.error(f"--older-than must be >= 0, got {args.older_than}")
    root = cache_root()
    if root is None:
        print(f"the front-end cache is off ({ENV}=off)")
        return 0
    store, now = Store(root), time.time()
    infos = selected(list(store.entries()), args.sequence, args.detector, args.older_than, now)
    if args.action == "clear":
        for info in infos:
            store.remove(info)
        print(f"removed {len(infos)} entr{'y' if len(infos) == 1 else 'ies'} "
              f"({_size(sum(i.size for i in infos))}) from {store.folder}")
        return 0
    print(f"front-end cache: {store.folder} ({ENV} sets it, {ENV}=off disables it)")
    if not infos:
        print("no entries")
        return 0
    print(table(infos, now))
    print(f"{len(infos)} entr{'y' if len(infos) == 1 else 'ies'}, "
          f"{_size(sum(i.size for i in infos))}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
