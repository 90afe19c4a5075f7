"""``python -m harness`` and the console script ``occbench``: the commands of
``harness.commands.cli`` (without one, ``occbench run``, the Hydra app of
``harness.commands.run``)."""

from __future__ import annotations


def main() -> None:
    """Console-script entry point ``occbench`` (same as ``python -m harness``)."""
    from harness.commands.cli import main as cli

    raise SystemExit(cli())


if __name__ == "__main__":
    main()
