"""Hydra plugins the configs can select, and the extra that installs each.

Hydra reports a launcher or sweeper whose plugin is not installed as a missing config
(``Could not find 'hydra/launcher/submitit_slurm'``), which does not say what to install.
``check_plugins(overrides)`` looks at the command line (``hydra/launcher=...``,
``hydra/sweeper=...`` and the ``override /hydra/...`` lines of the chosen ``+experiment``)
before Hydra starts and stops with the ``pip install`` line that fixes it.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Sequence
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[2]
CONF = ROOT / "conf"

# (group, choice) -> (modules that must import, pyproject extra, pip package)
PLUGINS: dict[tuple[str, str], tuple[tuple[str, ...], str, str]] = {
    ("launcher", "parallel"): (("hydra_plugins.occbench_launcher",), "", "occbench"),
    ("launcher", "processes"): (("hydra_plugins.occbench_launcher",), "", "occbench"),
    ("launcher", "joblib"): (("hydra_plugins.hydra_joblib_launcher",), "", "hydra-joblib-launcher"),
    ("launcher", "ray_cluster"): (("hydra_plugins.hydra_ray_launcher", "ray"), "ray",
                                  "hydra-ray-launcher"),
    ("launcher", "ray"): (("hydra_plugins.hydra_ray_launcher", "ray"), "ray", "hydra-ray-launcher"),
    ("launcher", "slurm"): (("hydra_plugins.hydra_submitit_launcher",), "slurm",
                            "hydra-submitit-launcher"),
    ("launcher", "submitit_slurm"): (("hydra_plugins.hydra_submitit_launcher",), "slurm",
                                     "hydra-submitit-launcher"),
    ("launcher", "submitit_local"): (("hydra_plugins.hydra_submitit_launcher",), "slurm",
                                     "hydra-submitit-launcher"),
    ("sweeper", "tune"): (("hydra_plugins.hydra_optuna_sweeper",), "tune", "hydra-optuna-sweeper"),
    ("sweeper", "optuna"): (("hydra_plugins.hydra_optuna_sweeper",), "tune",
                            "hydra-optuna-sweeper"),
}
#: the README's editable install (a lenient one is shadowed by a folder named occbench)
STRICT = "--config-settings editable_mode=strict"


class MissingPlugin(SystemExit):
    """A selected launcher or sweeper is not installed; the message says how to install it."""


def _installed(module: str) -> bool:
    try:
        return importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):
        return False


def selected(overrides: Sequence[str]) -> list[tuple[str, str, str]]:
    """``(group, choice, where)`` of every launcher or sweeper the overrides select."""
    out = []
    for o in overrides:
        key, _, value = o.partition("=")
        key = key.lstrip("+~")
        if key in ("hydra/launcher", "hydra/sweeper") and value:
            out.append((key.split("/")[1], value, o))
        elif key == "experiment" and value:
            path = CONF / "experiment" / f"{value}.yaml"
            try:
                body = yaml.safe_load(path.read_text()) or {}
            except (OSError, yaml.YAMLError):
                continue  # Hydra reports a missing or broken experiment itself
            for entry in body.get("defaults") or []:
                if not isinstance(entry, dict):
                    continue
                for k, v in entry.items():
                    group = str(k).removeprefix("override").strip().lstrip("/")
                    if group in ("hydra/launcher", "hydra/sweeper"):
                        out.append((group.split("/")[1], str(v), f"+experiment={value}"))
    return out


def missing(overrides: Sequence[str]) -> list[str]:
    """One message per selected plugin that is not installed."""
    messages = []
    for group, choice, where in selected(overrides):
        spec = PLUGINS.get((group, choice))
        if spec is None:
            continue
        modules, extra, package = spec
        absent = [m for m in modules if not _installed(m)]
        if not absent:
            continue
        how = (f'pip install -e "{ROOT}[{extra}]" {STRICT}' if extra
               else f'pip install -e "{ROOT}" {STRICT}' if package == "occbench"
               else f"pip install {package}")
        what = f"hydra/{group}={choice}"
        head = what if where == what else f"{where} (which selects {what})"
        messages.append(f"{head} needs the {package} plugin, which is not installed "
                        f"(no module {', '.join(absent)}): {how}")
    return messages


def check_plugins(overrides: Sequence[str]) -> None:
    """Raise ``MissingPlugin`` (exit status 1, the message on stderr) when a selected
    launcher or sweeper is not installed."""
    problems = missing(overrides)
    if problems:
        raise MissingPlugin("occbench: " + "\noccbench: ".join(problems))
