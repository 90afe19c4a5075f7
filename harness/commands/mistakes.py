"""One line for an ordinary mistake on the command line of a Hydra command (``run``,
``detect``): a key or choice that does not exist gets a "did you mean" from the config's own
keys and choices (``difflib``), a value the run refuses gets its message; the full traceback
only under ``occbench -v`` or ``OCCBENCH_VERBOSE=1``.

Hydra itself suggests ``+trackr=reta`` for a typo, which adds the key and runs with it
ignored, and wraps each error in three more lines; ``occbench.commands.cli`` lets Hydra raise
instead (``HYDRA_FULL_ERROR``) and hands the exception to ``explain`` here.
"""

from __future__ import annotations

import contextlib
import difflib
import os
import re
import sys
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any, TextIO

from occbench.errors import RunError, VERBOSE, refusal, verbose

ENV = VERBOSE
HINT = "(occbench -v ... shows the traceback)"
_OVERRIDE = re.compile(r"Could not (?:override|delete from config\.) '([^']+)'")
_MISSING = re.compile(r"Could not find '([^']+)'")


def verbose_requested(args: list[str]) -> tuple[bool, list[str]]:
    """``-v`` / ``--verbose`` before the command's arguments, or ``OCCBENCH_VERBOSE=1``; the
    arguments without the flag."""
    flags = ("-v", "--verbose")
    wanted = bool(args) and args[0] in flags
    rest = args[1:] if wanted else args
    return wanted or verbose(), rest


def _config_keys(config_name: str, overrides: Sequence[str]) -> list[str]:
    """Every dotted key of the config composed with the config group choices among
    ``overrides`` (no dotted key, no sweep, no hydra/), or [] when even that does not
    compose."""
    # start-up: hydra and omegaconf (~0.1 s CPU), not loaded for --version, --help, eval...
    from hydra import compose, initialize_config_dir
    from hydra.core.global_hydra import GlobalHydra
    from hydra.core.override_parser.overrides_parser import OverridesParser
    from omegaconf import OmegaConf

    from occbench.commands.run import CONF_DIR  # start-up: imports hydra, as above
    from occbench.config import register  # start-up: imports hydra, as above

    kept = []
    for text in overrides:
        try:
            (o,) = OverridesParser.create().parse_overrides([text])
        except Exception:  # noqa: BLE001, S112 - the bad override itself: left out
            continue
        group = o.key_or_group.lstrip("+~")
        if not (o.is_sweep_override() or "." in group or group.startswith("hydra")):
            kept.append(text)  # the choices of config groups: they shape the config
    GlobalHydra.instance().clear()
    register()
    try:
        with initialize_config_dir(CONF_DIR, version_base="1.3"):
            cfg = compose(config_name, overrides=kept)
    except Exception:  # noqa: BLE001 - fall back to the top-level names
        return []
    finally:
        GlobalHydra.instance().clear()
    out: list[str] = []

    def walk(node: Any, prefix: str) -> None:
        for key, value in node.items():
            name = f"{prefix}{key}"
            out.append(name)
            if isinstance(value, dict):
                walk(value, name + ".")

    walk(OmegaConf.to_container(cfg, resolve=False), "")
    return out


def _top_level(config_name: str) -> list[str]:
    # start-up: hydra and omegaconf (~0.1 s CPU), not loaded for --version, --help, eval...
    from omegaconf import OmegaConf

    from occbench.commands.run import CONF_DIR  # start-up: imports hydra, as above

    conf = Path(CONF_DIR)
    keys = [k for k in OmegaConf.load(conf / f"{config_name}.yaml") if k != "defaults"]
    return keys + [d.name for d in conf.iterdir() if d.is_dir()] + ["hydra"]


def suggest(word: str, known: Sequence[str]) -> str | None:
    """The closest of ``known`` to ``word`` (``difflib``): among the keys whose last part is
    close to ``word``'s last part (``max_agee`` -> ``...max_age``), else (a top-level name)
    over whole names; None when nothing is close."""
    tail = word.rsplit(".", 1)[-1]
    tails = {k: k.rsplit(".", 1)[-1] for k in known}
    near = set(difflib.get_close_matches(tail, set(tails.values()), n=3, cutoff=0.75))
    if near:
        pool = [k for k in known if tails[k] in near]
        return difflib.get_close_matches(word, pool, n=1, cutoff=0.0)[0]
    close = [] if "." in word else difflib.get_close_matches(word, known, n=1, cutoff=0.6)
    return close[0] if close else None


def explain(err: BaseException, config_name: str, overrides: Sequence[str]) -> str:
    """One line saying what is wrong with the command line (no traceback)."""
    # start-up: hydra and omegaconf (~0.1 s CPU), not loaded for --version, --help, eval...
    from hydra.errors import CompactHydraException, MissingConfigException

    text = str(err).strip()
    if isinstance(err, MissingConfigException) and _MISSING.search(text):
        path = _MISSING.search(text).group(1)
        group, _, name = path.rpartition("/")
        options = [str(o) for o in (err.options or [])]
        if group and options:
            best = suggest(name, options)
            hint = f"did you mean '{best}'? " if best else ""
            return (f"occbench: unknown {group} '{name}': {hint}(choices: "
                    f"{', '.join(sorted(options))})")
    match = _OVERRIDE.search(text)
    if match:
        key = match.group(1)
        known = _config_keys(config_name, overrides) if "." in key else []
        known = known or _top_level(config_name)
        best = suggest(key, known)
        hint = f": did you mean '{best}'?" if best else " (add a new key with +key=value)"
        return f"occbench: unknown key '{key}'{hint}"

    if isinstance(err, CompactHydraException | RunError):  # a message made to be read
        first = text.splitlines()[0] if text else type(err).__name__
        return first if first.startswith("occbench:") else f"occbench: {first}"
    return f"occbench: {type(err).__name__}: {text.splitlines()[0] if text else ''} {HINT}"


def refuse(err: object, status: int = 1) -> int:
    """Print ``occbench: <err>`` on stderr (``occbench.errors.refusal``), the one prefix of
    every mistake of every command, and return ``status`` (1: a refused input)."""
    print(refusal(err), file=sys.stderr)
    return status


class _DropLine:
    """A stderr that drops lines starting with ``prefix`` (Hydra's "Error executing job with
    overrides" line, written before the job's exception is raised to us)."""

    def __init__(self, stream: TextIO, prefix: str) -> None:
        self.stream, self.prefix = stream, prefix

    def write(self, text: str) -> int:
        if text.startswith(self.prefix):
            return len(text)
        return self.stream.write(text)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.stream, name)


@contextlib.contextmanager
def hydra_raises() -> Iterator[None]:
    """Within: Hydra raises its errors instead of printing them (``HYDRA_FULL_ERROR``), and
    its "Error executing job with overrides" line is not written."""
    saved_env, saved_err = os.environ.get("HYDRA_FULL_ERROR"), sys.stderr
    os.environ["HYDRA_FULL_ERROR"] = "1"
    sys.stderr = _DropLine(sys.stderr, "Error executing job with overrides:")
    try:
        yield
    finally:
        sys.stderr = saved_err
        if saved_env is None:
            os.environ.pop("HYDRA_FULL_ERROR", None)
        else:
            os.environ["HYDRA_FULL_ERROR"] = saved_env
