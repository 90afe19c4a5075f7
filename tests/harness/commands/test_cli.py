"""The one command line (harness/commands/cli.py): dispatch of every subcommand, --version, --help,
the missing-plugin hint, and ``occbench report RUN`` writing into the run directory."""

from __future__ import annotations

import importlib.metadata
import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest

from occbench.commands import cli
from occbench.sweeps import plugins

ROOT = Path(__file__).resolve().parents[3]


def _occbench(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    """``python -m occbench ARGS`` (the console script's code) from ``cwd``."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-m", "occbench", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=120, check=False)


class _Recorder:
    def __init__(self) -> None:
        self.calls: list[tuple[str, list[str]]] = []

    def resolve(self, command: str):
        def func(argv=None):
            # a Hydra app reads sys.argv; the others take argv
            self.calls.append((command, list(sys.argv[1:]) if argv is None else list(argv)))
            return 0

        return func


@pytest.mark.parametrize("argv, command, passed", [
    (["run", "tracker=baseline", "seed=3"], "run", ["tracker=baseline", "seed=3"]),
    (["tracker=baseline", "-m", "seed=0,1"], "run", ["tracker=baseline", "-m", "seed=0,1"]),
    ([], "run", []),
    (["run", "--cfg", "job"], "run", ["--cfg", "job"]),
    (["detect", "detector=hog"], "detect", ["detector=hog"]),
    (["eval", "gt", "res", "--csv", "x.csv"], "eval", ["gt", "res", "--csv", "x.csv"]),
    (["sweep", "results/multirun/x"], "sweep", ["results/multirun/x"]),
    (["report", "results/x", "--no-video"], "report", ["results/x", "--no-video"]),
    (["bench", "dataset=caviar", "--frames", "10"], "bench", ["dataset=caviar", "--frames", "10"]),
    (["fit", "heads", "--help"], "fit", ["heads", "--help"]),
])
def test_every_subcommand_dispatches_with_its_arguments(monkeypatch, argv, command, passed):
    rec = _Recorder()
    monkeypatch.setattr(cli, "_resolve", rec.resolve)
    before = list(sys.argv)
    assert cli.main(argv) == 0
    assert rec.calls == [(command, passed)]
    assert sys.argv == before  # restored after a Hydra app


def test_every_subcommand_target_exists():
    for command, (module, attr, _, _) in cli.COMMANDS.items():
        assert callable(getattr(importlib.import_module(module), attr)), command


def test_version_and_help(capsys):
    version = importlib.metadata.version("occbench")
    assert cli.main(["--version"]) == 0
    assert capsys.readouterr().out == f"occbench {version}\n"
    assert cli.main(["run", "--version"]) == 0  # not Hydra's version
    assert capsys.readouterr().out == f"occbench {version}\n"
    assert cli.main(["--help"]) == 0
    page = capsys.readouterr().out
    assert page.startswith("usage: occbench") and len(page.splitlines()) < 40
    for command in cli.COMMANDS:
        assert f"\n  {command} " in page
    assert "occbench run --help" in page and "--cfg job" in page


def test_version_help_and_hydra_pages_from_another_directory(tmp_path):
    p = _occbench("--version", cwd=tmp_path)
    assert p.returncode == 0 and p.stdout.strip() == f"occbench {cli.version()}"
    assert "Hydra" not in p.stdout
    p = _occbench("--help", cwd=tmp_path)
    assert p.returncode == 0 and p.stdout.startswith("usage: occbench")
    p = _occbench("run", "--help", cwd=tmp_path)  # Hydra's page: every group and its choices
    assert p.returncode == 0 and "tracker: " in p.stdout and "baseline" in p.stdout
    p = _occbench("tracker=baseline", "--cfg", "job", cwd=tmp_path)
    assert p.returncode == 0 and "_target_: occbench.trackers.baseline" in p.stdout


def test_an_install_without_its_checkout_says_how_to_install(monkeypatch, tmp_path, capsys):
    """A non-editable install has no conf/ beside the package: one line naming the fix."""
    import occbench.config.paths

    monkeypatch.setattr(occbench.config.paths, "PROJECT_ROOT", tmp_path)
    assert cli.main(["tracker=baseline"]) == 2
    err = capsys.readouterr().err
    assert str(tmp_path) in err and "pip install -e" in err
    assert cli.main(["--version"]) == 0  # version and help need no checkout


def test_missing_launcher_plugin_names_the_extra(monkeypatch):
    monkeypatch.setattr(plugins, "_installed", lambda module: False)
    msgs = plugins.missing(["-m", "hydra/launcher=slurm", "tracker=baseline"])
    assert len(msgs) == 1 and "hydra-submitit-launcher" in msgs[0] and "[slurm]" in msgs[0]
    msgs = plugins.missing(["hydra/launcher=ray_cluster"])
    assert "[ray]" in msgs[0]
    msgs = plugins.missing(["+experiment=tune_reta"])  # the experiment selects the sweeper
    assert "+experiment=tune_reta" in msgs[0] and "[tune]" in msgs[0]
    assert plugins.missing(["tracker=baseline", "seed=1"]) == []
    with pytest.raises(SystemExit, match=r"pip install -e .*\[slurm\]"):
        cli.main(["-m", "hydra/launcher=slurm"])


@pytest.mark.skipif(importlib.util.find_spec("hydra_plugins.hydra_submitit_launcher") is not None,
                    reason="the slurm extra is installed here")
def test_missing_slurm_plugin_exits_with_the_hint(tmp_path):
    p = _occbench("-m", "hydra/launcher=slurm", "tracker=baseline", cwd=tmp_path)
    assert p.returncode == 1
    assert "[slurm]" in p.stderr and "Traceback" not in p.stderr


def test_report_writes_into_the_run_directory(tmp_path):
    run = tmp_path / "run"
    p = _occbench("progress=false", "tracker=baseline", "dataset.length=20",
                  "dataset.scenarios=[crossing]", "dataset.width=160", "dataset.height=120",
                  f"hydra.run.dir={run}", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    p = _occbench("report", str(run), cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert (run / "report" / "crossing.mp4").stat().st_size > 0
    assert (run / "report" / "crossing_sheet.png").stat().st_size > 0
    assert list((run / "plots").glob("trajectory_crossing_*.png"))


def test_report_of_a_folder_that_is_no_run(tmp_path, capsys):
    assert cli.main(["report", str(tmp_path)]) == 1
    assert "config.yaml" in capsys.readouterr().err


class _Stream:
    def __init__(self, tty: bool) -> None:
        self.tty = tty

    def isatty(self) -> bool:
        return self.tty

    def write(self, text: str) -> int:
        return len(text)

    def flush(self) -> None:
        pass


def test_progress_bars_only_on_a_terminal_and_never_in_a_multirun():
    from occbench.progress import bars_wanted, progress_factory

    assert bars_wanted(True, False, _Stream(True))
    assert not bars_wanted(True, False, _Stream(False))  # a file or a pipe: no redraws
    assert not bars_wanted(True, True, _Stream(True))  # a sweep job (joblib, Ray, SLURM)
    assert not bars_wanted(False, False, _Stream(True))
    assert progress_factory(True, False, _Stream(False)) is not None  # log lines instead
    assert progress_factory(True, True, _Stream(False)) is not None  # a sweep job: likewise
    bar = progress_factory(True, False, _Stream(True))(total=3, desc="s")
    bar.update(1)
    bar.close()


@pytest.mark.parametrize("argv, prefix", [
    (["--bogus"], "occbench: unrecognized arguments: --bogus"),
    (["run", "--bogus"], "occbench: unrecognized arguments: --bogus"),
    (["detect", "--bogus"], "occbench: detect: unrecognized arguments: --bogus"),
    (["eval"], "occbench: eval: the following arguments are required"),
    (["sweep"], "occbench: sweep: the following arguments are required"),
    (["report"], "occbench: report: the following arguments are required"),
    (["bench", "--bogus"], "occbench: bench: unrecognized arguments"),
    (["cache", "--older-than", "-1"], "occbench: cache: --older-than must be >= 0"),
    (["server", "bogus"], "occbench: server: argument action: invalid choice"),
    (["fit"], "occbench: fit: which model to fit is required"),
    (["fit", "bogus"], "occbench: fit: unknown model 'bogus'"),
    (["fit", "heads", "--bogus"], "occbench: fit heads: "),
])
def test_every_usage_mistake_is_the_usage_line_and_one_occbench_line_exit_2(argv, prefix, capsys):
    """1 is a refused input, 2 a usage mistake: the usage line, then ``occbench: ...``
    (argparse's own form was ``occbench eval: error: ...``)."""
    try:
        status = cli.main(argv)
    except SystemExit as stop:
        status = stop.code
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2
    assert err[0].startswith("usage: occbench") and err[-1].startswith(prefix)
    assert not any("error:" in line or "Traceback" in line for line in err)
