"""``occbench``: one command line for every tool of the harness.

``occbench COMMAND ARGS...`` hands ``ARGS`` to the command's own parser; without a command
(plain ``occbench``, or ``occbench key=value ...``, ``occbench -m ...``) the arguments go to
``run``, the Hydra app (``occbench.commands.run.app``), as they always did. ``python -m occbench``
is the same command.

Commands and where they live:

=========  ==================================  =========================================
run        ``occbench.commands.run.app``        Hydra: overrides, ``-m``, ``--cfg job``
detect     ``occbench.commands.detect.app``     Hydra (``conf/detect.yaml``)
eval       ``occbench.commands.evaluate.main``  argparse: ``GT RESULTS``
sweep      ``occbench.sweeps.gather.main``      argparse: ``SWEEP_DIR``
report     ``occbench.commands.report.main``    argparse: ``RUN_DIR``
bench      ``occbench.commands.bench.main``     argparse + overrides
fit        ``occbench.commands.fit.main``       ``pbm | heads | silhouette | active_basis``
cache      ``occbench.commands.cache.main``     argparse: ``[list | clear] [filters]``
server     ``occbench.commands.server.main``    argparse: ``status | stop | start``
=========  ==================================  =========================================
"""

from __future__ import annotations

import argparse
import importlib
import importlib.metadata
import os
import signal
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import NoReturn

from occbench.commands.mistakes import explain, hydra_raises, verbose_requested
from occbench.errors import EXIT_SIGINT, EXIT_SIGTERM, Terminated, VERBOSE

PROG = "occbench"

# name -> (module, function, one-line description, True when the function is a Hydra app)
COMMANDS: dict[str, tuple[str, str, str, bool]] = {
    "run": ("occbench.commands.run", "app",
            "run trackers on a dataset and score them (default)", True),
    "detect": ("occbench.commands.detect", "app",
               "run one detector alone: det/ files, precision, recall", True),
    "eval": ("occbench.commands.evaluate", "main",
             "score MOT result files against ground truth", False),
    "sweep": ("occbench.sweeps.gather", "main",
              "gather a multirun folder into sweep.csv, .md, plots/", False),
    "report": ("occbench.commands.report", "main",
               "annotated video, contact sheet, trajectory plot of a run", False),
    "bench": ("occbench.commands.bench", "main",
              "frames/s per stage: decode, front end, each tracker", False),
    "fit": ("occbench.commands.fit", "main",
            "refit models: pbm | heads | silhouette | active_basis", False),
    "cache": ("occbench.commands.cache", "main",
              "what the front-end cache holds (OCCBENCH_CACHE); clear it", False),
    "server": ("occbench.commands.server", "main",
               "the warm server for single runs (OCCBENCH_SERVER): status, stop, start", False),
}

USAGE = f"""\
usage: {PROG} [-v] [COMMAND] [ARGS...]
       {PROG} --version | --help

-v (or OCCBENCH_VERBOSE=1): a mistake or failure shows its full traceback, not one line.

commands (without one, the arguments go to `run`):
{{commands}}

examples:
  {PROG}                                       every built tracker on the synthetic suite
  {PROG} tracker=reta tracker.association.mu_g=40   one tracker, one parameter changed
  {PROG} +experiment=reta_table2               Reta et al.'s Table 2 on the CAVIAR corridor
  {PROG} -m tracker=baseline tracker.max_age=1,3,5 seed=0,1,2     a sweep
  {PROG} report results/<date>/<time>          video, contact sheet, trajectories of a run
  {PROG} eval GT_FOLDER RESULTS_FOLDER         score another tracker's result files
  {PROG} detect dataset=caviar detector=silhouette

`{PROG} run --help` lists every config group and its choices (Hydra's page),
`{PROG} run --cfg job` prints the composed config, `{PROG} run --hydra-help` Hydra's options,
`{PROG} COMMAND --help` each command's options. Docs: README.md.
"""


def version() -> str:
    """The installed package's version (``pyproject.toml``), else the source tree's."""
    try:
        return importlib.metadata.version("occbench")
    except importlib.metadata.PackageNotFoundError:  # run from a source tree, not installed
        import tomllib  # start-up: ~1.6 ms CPU (2 % of --version), for a source tree only

        path = Path(__file__).resolve().parents[2] / "pyproject.toml"
        return str(tomllib.loads(path.read_text())["project"]["version"])


def usage() -> str:
    width = max(len(c) for c in COMMANDS)
    lines = [f"  {name:<{width}}  {spec[2]}" for name, spec in COMMANDS.items()]
    return USAGE.format(commands="\n".join(lines))


def _resolve(command: str) -> Callable:
    module, attr, _, _ = COMMANDS[command]
    return getattr(importlib.import_module(module), attr)


def _call_hydra(app: Callable, prog: str, args: Sequence[str], config_name: str,
                verbose: bool = False) -> int:
    """Run a ``@hydra.main`` app with ``args`` as its command line (Hydra reads sys.argv); a
    config mistake or a refused run is one line on stderr and exit status 1, the traceback
    only when ``verbose`` (``occbench.commands.mistakes``)."""
    # start-up: hydra and omegaconf (~0.1 s CPU), not loaded for --version, --help, eval...
    from occbench.config import register

    register()
    saved = sys.argv
    sys.argv = [prog, *args]
    try:
        with hydra_raises():
            app()
    except Exception as err:  # noqa: BLE001 - every error ends in one line (or a traceback)
        if verbose:
            raise
        print(explain(err, config_name, args), file=sys.stderr)
        return 1
    finally:
        sys.argv = saved
    return 0


def _check_checkout() -> str | None:
    """Why this installation cannot run, or None: the configs (``conf/``) and the shipped data
    (``datasets/``) live in the project checkout, which only an editable install keeps."""
    # start-up: hydra and omegaconf (~0.1 s CPU), not loaded for --version, --help, eval...
    from occbench.config.paths import PROJECT_ROOT

    if (PROJECT_ROOT / "conf" / "config.yaml").is_file():
        return None
    return (f"{PROG}: no conf/ beside the installed package ({PROJECT_ROOT}): occbench runs from "
            "its checkout; install it with `pip install -e <checkout> --config-settings "
            "editable_mode=strict` as the README says")


def _terminate(signum: int, frame: object) -> None:
    raise Terminated


def run(argv: Sequence[str]) -> int:
    """``main(argv)`` as a process runs it (``occbench.__main__``, cold, or a served child):
    Ctrl-C (SIGINT) and SIGTERM end it with one line on stderr and exit status 130 or 143,
    never a traceback: SIGTERM raises ``occbench.errors.Terminated`` in the main thread, as
    SIGINT raises KeyboardInterrupt, so a run marks itself interrupted on the way out
    (``occbench.commands.run`` prints the line naming the run folder)."""
    signal.signal(signal.SIGTERM, _terminate)
    try:
        return main(argv)
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted (Ctrl-C)", file=sys.stderr)
        return EXIT_SIGINT
    except Terminated:
        print(f"{PROG}: terminated (SIGTERM)", file=sys.stderr)
        return EXIT_SIGTERM


def usage_error(parser: argparse.ArgumentParser, message: str) -> NoReturn:
    """Every command's usage mistake (argparse's ``error``, Hydra's parser included): the
    usage line, then one line ``occbench: COMMAND: message`` on stderr, exit status 2 (1 is
    a refused input)."""
    parser.print_usage(sys.stderr)
    command = parser.prog.removeprefix(PROG).strip()
    parser.exit(2, f"{PROG}: {command + ': ' if command else ''}{message}\n")


def main(argv: Sequence[str] | None = None) -> int:
    """The command line ``argv`` (default ``sys.argv[1:]``); returns the exit status."""
    argparse.ArgumentParser.error = usage_error  # one form for every command's parser

    verbose, args = verbose_requested(list(sys.argv[1:] if argv is None else argv))
    saved = os.environ.get(VERBOSE)
    if verbose:  # for what the command starts too (a sweep's jobs)
        os.environ[VERBOSE] = "1"
    try:
        return _dispatch(args, verbose)
    finally:
        if saved is None:
            os.environ.pop(VERBOSE, None)
        else:
            os.environ[VERBOSE] = saved


def _dispatch(args: list[str], verbose: bool) -> int:
    """``main`` after ``-v``: the command ``args`` names (``run`` without one)."""
    if args and args[0] in ("-h", "--help", "help"):
        print(usage(), end="")
        return 0
    if args and args[0] in ("-V", "--version"):
        print(f"{PROG} {version()}")
        return 0
    problem = _check_checkout()
    if problem:
        print(problem, file=sys.stderr)
        return 2
    command = "run"
    if args and args[0] in COMMANDS:
        command, args = args[0], args[1:]
    func = _resolve(command)
    if COMMANDS[command][3]:
        if "--version" in args or "-V" in args:  # Hydra's own would print Hydra's version
            print(f"{PROG} {version()}")
            return 0
        from occbench.sweeps.plugins import check_plugins  # start-up: ~11 ms CPU

        check_plugins(args)  # a missing launcher or sweeper names the extra to install
        return _call_hydra(func, f"{PROG} {command}" if command != "run" else PROG, args,
                           "detect" if command == "detect" else "config", verbose)
    try:
        return int(func(args) or 0)
    except Exception as err:  # noqa: BLE001 - every command's failure ends in one line
        if verbose:
            raise

        print(explain(err, "config", args), file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
