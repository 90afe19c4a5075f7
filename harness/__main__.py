"""``python -m occbench`` and the console script ``occbench``: the commands of
``occbench.commands.cli``.

The fast path first: when this installation's warm server (``occbench.server``; ``occbench
server start``, or ``OCCBENCH_SERVER=on``) answers, the command goes to it and this process
only waits for its exit status, forwarding Ctrl-C; otherwise (no server, another code,
``OCCBENCH_SERVER=off``) it runs here, cold (``occbench.commands.cli.run``). Nothing but the standard library is imported
before that choice.
"""

from __future__ import annotations

import sys

from occbench.server.client import served


def main() -> None:
    """Console-script entry point ``occbench`` (same as ``python -m occbench``)."""
    status = served(sys.argv[1:])
    if status is None:
        # start-up: ~6 ms CPU that the served path (occbench.server.client alone) saves
        from occbench.commands.cli import run

        status = run(sys.argv[1:])
    raise SystemExit(status)


if __name__ == "__main__":
    main()
