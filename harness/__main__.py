"""``python -m harness`` and the console script ``occbench``: the commands of
``harness.commands.cli`` (without one, ``occbench run``, the Hydra app of
``harness.commands.run``).

Ctrl-C (SIGINT) and SIGTERM end the process with one line on stderr and exit status 130 or
143, never a traceback: SIGTERM raises ``harness.errors.Terminated`` in the main thread, as
SIGINT raises KeyboardInterrupt, so a run marks itself interrupted on the way out
(``harness.commands.run`` prints the line naming the run folder).
"""

from __future__ import annotations

import signal
import sys

from harness.errors import EXIT_SIGINT, EXIT_SIGTERM


def _terminate(signum: int, frame: object) -> None:
    from harness.errors import Terminated

    raise Terminated


def main() -> None:
    """Console-script entry point ``occbench`` (same as ``python -m harness``)."""
    from harness.errors import Terminated

    signal.signal(signal.SIGTERM, _terminate)
    try:
        from harness.commands.cli import main as cli

        status = cli()
    except KeyboardInterrupt:
        print("occbench: interrupted (Ctrl-C)", file=sys.stderr)
        status = EXIT_SIGINT
    except Terminated:
        print("occbench: terminated (SIGTERM)", file=sys.stderr)
        status = EXIT_SIGTERM
    raise SystemExit(status)


if __name__ == "__main__":
    main()
