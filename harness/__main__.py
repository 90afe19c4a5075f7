"""``python -m harness`` and the console script ``occbench``: the commands of
``harness.commands.cli``.

The fast path first: when this installation's warm server (``harness.server``; ``occbench
server start``, or ``OCCBENCH_SERVER=on``) answers, the command goes to it and this process
only waits for its exit status, forwarding Ctrl-C; otherwise (no server, another code,
``OCCBENCH_SERVER=off``) it runs here, cold (``harness.commands.cli.run``). Nothing but the standard library is imported
before that choice.
"""

from __future__ import annotations

import sys


def main() -> None:
    """Console-script entry point ``occbench`` (same as ``python -m harness``)."""
    from harness.server.client import served

    status = served(sys.argv[1:])
    if status is None:
        from harness.commands.cli import run

        status = run(sys.argv[1:])
    raise SystemExit(status)


if __name__ == "__main__":
    main()
