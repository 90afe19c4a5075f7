"""``occbench fit <what> [options]``: fit a model from annotated sequences.

Each subcommand lives in its own module ``occbench.fit.<what>`` exposing ``main(argv)``.
"""

from __future__ import annotations

import importlib
import sys

COMMANDS = {
    "pbm": "feature-difference models of the PBM tracker (PBM 2.2)",
    "heads": "hair and skin colour mixtures of the head detector (PBM 2.3)",
    "silhouette": "mean person silhouette template of the silhouette detector (Reta 3.1)",
    "active_basis": "active-basis (Gabor elements) person template of the shape verifier (Reta 3.1)",
}


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    usage = "usage: occbench fit {" + ",".join(COMMANDS) + "} [options]"
    if argv and argv[0] in ("-h", "--help"):
        print(usage + "\n" + "\n".join(f"  {name:<13} {what}" for name, what in COMMANDS.items()))
        return 0
    if not argv or argv[0] not in COMMANDS:  # a usage mistake: as argparse's (cli.usage_error)
        what = f"unknown model {argv[0]!r}" if argv else "which model to fit is required"
        print(f"{usage}\noccbench: fit: {what} (choose from {', '.join(COMMANDS)})",
              file=sys.stderr)
        return 2
    module = importlib.import_module(f"occbench.fit.{argv[0]}")
    return int(module.main(argv[1:]) or 0)


if __name__ == "__main__":
    raise SystemExit(main())
