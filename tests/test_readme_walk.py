"""Issue 39's acceptance, scripted: every run command the README shows composes as written,
and every mistake of the walk gets one line on stderr, ``occbench: ...``, no traceback and
no output on stdout, exit 1 (a refused input) or 2 (a command line that cannot be parsed).

The README's commands are composed in process (``compose_config``; a run would take minutes):
a sweep's comma list is taken at its first value, a placeholder path composes as any path,
and a command whose plugin (Optuna, Ray, SLURM) is not installed is skipped by name. The
mistakes run as a user runs them, one ``python -m occbench`` each.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
from hydra.errors import MissingConfigException
from occbench.config.build import compose_config

ROOT = Path(__file__).resolve().parents[1]
SUBCOMMANDS = {"detect", "eval", "sweep", "report", "bench", "fit", "cache", "server"}
# shown in the README as mistakes (or as a pattern), never as a command to run
NOT_COMMANDS = {"tracker.max_age=3"}


def readme_runs() -> list[str]:
    """The argument strings of the README's ``occbench`` run commands: code-block lines and
    inline code, comments and environment assignments removed."""
    text = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```[a-z]*\n(.*?)```", text, flags=re.DOTALL)
    lines = [ln for b in blocks for ln in b.splitlines()]
    lines += re.findall(r"`([^`\n]*occbench [^`\n]*)`", text)
    found = []
    for line in lines:
        m = re.search(r"(?:python -m )?\boccbench((?: +[^#|]*)?)(?:#.*)?$", line.strip())
        if not m or re.search(r"occbench\.[a-z]", line):
            continue
        words = shlex.split(m.group(1).strip()) if m.group(1).strip() else []
        if words[:1] == ["run"]:
            words = words[1:]
        if (words[:1] and (words[0] in SUBCOMMANDS or words[0].startswith("-")
                           and words[0] != "-m")) or "..." in words \
                or any(w.isupper() for w in words):  # a placeholder: occbench COMMAND --help
            continue
        args = " ".join(w for w in words if w != "-m")
        if args not in NOT_COMMANDS:
            found.append(args)
    return sorted(set(found))


def _first_values(words: list[str]) -> list[str]:
    """A sweep's overrides at their first value (``k=1,3,5`` -> ``k=1``; lists kept)."""
    out = []
    for w in words:
        key, _, value = w.partition("=")
        if key.startswith("hydra"):
            continue  # the launcher's and Hydra's own keys: not the job's config
        if "," in value and not value.startswith("["):
            value = value.split(",")[0]
        out.append(f"{key}={value}" if _ else w)
    return out


def test_the_walk_finds_the_readme_s_commands():
    runs = readme_runs()
    assert "" in runs and "tracker=baseline" in runs and "+experiment=pbm_table1" in runs
    assert len(runs) > 20


@pytest.mark.parametrize("args", readme_runs())
def test_every_readme_run_command_composes(args):
    try:
        cfg = compose_config(_first_values(shlex.split(args)))
    except MissingConfigException as err:  # an optional plugin's config (tune_*: Optuna)
        if str(err.missing_cfg_file).startswith("hydra/"):
            pytest.skip(f"{args}: {err.missing_cfg_file} (its plugin is not installed)")
        raise
    assert "_target_" in cfg.dataset and cfg.tracker


FAILED_RUN = "failed_run"  # a run folder with a config and no tracks/ (the run failed)
MISTAKES = [  # (arguments, exit status, the line's start) - issue 39's walk
    (["bench", "trackr=reta"], 1, "occbench: unknown key 'trackr': did you mean 'tracker'?"),
    (["bench", "dataset=cavair"], 1, "occbench: unknown dataset 'cavair': did you mean"),
    (["trackr=reta"], 1, "occbench: unknown key 'trackr': did you mean 'tracker'?"),
    (["tracker=baseline", "tracker.max_age=-1"], 1, "occbench: tracker 'baseline'"),
    (["detect", "dataset=caviar", "dataset.root=/nonexistent"], 1,
     "occbench: dataset (occbench.datasets.caviar.load_caviar): FileNotFoundError"),
    (["eval", "/nonexistent", "/nonexistent"], 1, "occbench: ground truth not found"),
    (["sweep", "/nonexistent"], 1, "occbench: sweep directory not found"),
    (["report", FAILED_RUN], 1, "occbench: "),
]


@pytest.mark.parametrize(("args", "status", "start"), MISTAKES,
                         ids=[" ".join(a) for a, _, _ in MISTAKES])
def test_a_mistake_is_one_line_and_no_traceback(args, status, start, tmp_path):
    failed = tmp_path / FAILED_RUN
    failed.mkdir()
    (failed / "config.yaml").write_text("seed: 0\n")
    argv = [str(failed) if a == FAILED_RUN else a for a in args]
    env = {k: v for k, v in os.environ.items() if k != "OCCBENCH_VERBOSE"}
    proc = subprocess.run([sys.executable, "-m", "occbench", *argv], capture_output=True,
                          check=False, text=True, cwd=tmp_path, timeout=300, env=env)
    lines = proc.stderr.splitlines()
    assert proc.returncode == status, proc.stderr[-2000:]
    assert len(lines) == 1 and lines[0].startswith(start), proc.stderr[-2000:]
    assert "Traceback" not in proc.stderr and proc.stdout == ""
