"""Issue 39's acceptance, scripted: every run command the README shows composes as written,
and every mistake of the walk (the issue's frictions and faults) gets one line on stderr,
``occbench: ...``, no traceback and no output on stdout: exit 1 for a refused input (one
line), 2 for a command line that cannot be parsed (the usage, then the one line). The walk's
runs (a failing sequence, a failing sweep, the same figures in every view):
tests/test_readme_walk_runs.py.

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
LOADED = "load_video"  # the video loader's prefix: "dataset (occbench.datasets.video.load_video)"
MISTAKES = [  # (arguments, exit status, the line's start) - issue 39's walk; paths: _inputs
    (["bench", "trackr=reta"], 1, "occbench: unknown key 'trackr': did you mean 'tracker'?"),
    (["bench", "dataset=cavair"], 1, "occbench: unknown dataset 'cavair': did you mean"),
    (["trackr=reta"], 1, "occbench: unknown key 'trackr': did you mean 'tracker'?"),
    (["tracker=baseline", "tracker.max_age=-1"], 1, "occbench: tracker 'baseline'"),
    (["detect", "dataset=caviar", "dataset.root=/nonexistent"], 1,
     "occbench: dataset (occbench.datasets.caviar.load_caviar): FileNotFoundError"),
    (["dataset=video", "dataset.path=/nonexistent.mp4"], 1,
     f"occbench: dataset (occbench.datasets.video.{LOADED}): FileNotFoundError: video file "
     "not found: /nonexistent.mp4"),
    (["dataset=video", "dataset.path=uncut.mp4"], 1,  # its index cut away: FFmpeg kept quiet
     f"occbench: dataset (occbench.datasets.video.{LOADED}): FrameError: "),
    (["eval", "/nonexistent", "/nonexistent"], 1, "occbench: ground truth not found"),
    (["eval", "gt", "huge"], 1, "occbench: huge/walk.txt:2: box left must lie within +-1e+09 "
     "pixels, got 1e+308"),
    (["eval", "gt_outside", "results"], 1,
     "occbench: gt_outside/walk/gt/gt.txt:2: gt box to score lies wholly outside the 320x240"),
    (["eval", "gt", "tracks"], 1,  # an interrupted run's folders: tracks/ in place of a tracker
     "occbench: tracks holds no result file but one folder per tracker (baseline)"),
    (["sweep", "/nonexistent"], 1, "occbench: sweep directory not found"),
    (["report", FAILED_RUN], 1, "occbench: "),
]
USAGE = [  # (arguments, the last line's start): the usage, then this line, exit 2
    (["--bogus"], "occbench: unrecognized arguments: --bogus"),
    (["eval"], "occbench: eval: the following arguments are required: gt, results"),
    (["report"], "occbench: report: the following arguments are required: run_dir"),
    (["fit", "heads"], "occbench: fit heads: the following arguments are required: --out"),
    (["server", "bogus"], "occbench: server: argument action: invalid choice: 'bogus'"),
    (["cache", "--older-than", "-1"], "occbench: cache: --older-than must be >= 0"),
]


def _inputs(folder: Path) -> None:
    """The walk's inputs in ``folder``: a failed run, a gt folder of one 320x240 sequence
    ('walk') with its result, the same gt with a box wholly outside the frame, a result with
    a box 1e308 wide, a run's tracks/ folder, and an mp4 whose index was cut away."""
    failed = folder / FAILED_RUN
    failed.mkdir()
    (failed / "config.yaml").write_text("seed: 0\n")
    rows = "".join(f"{k},1,{10 + 2 * k},20,40,100,1,1,1\n" for k in range(1, 11))
    for name, gt in (("gt", rows), ("gt_outside", rows.replace("\n2,1,14,", "\n2,1,5000,"))):
        (folder / name / "walk" / "gt").mkdir(parents=True)
        (folder / name / "seqmap.txt").write_text("name\nwalk\n")
        (folder / name / "walk" / "seqinfo.ini").write_text(
            "[Sequence]\nname=walk\nimDir=img1\nframeRate=25\nseqLength=10\nimWidth=320\n"
            "imHeight=240\nimExt=.jpg\n")
        (folder / name / "walk" / "gt" / "gt.txt").write_text(gt)
    result = rows.replace(",1,1,1\n", ",1,-1,-1,-1\n")
    for name, text in (("results", result), ("huge", result.replace("\n2,1,14,", "\n2,1,1e308,")),
                       ("tracks/baseline", result)):
        (folder / name).mkdir(parents=True)
        (folder / name / "walk.txt").write_text(text)
    whole = _mp4(folder / "whole.mp4", faststart=False)  # the index (moov) at the end
    (folder / "uncut.mp4").write_bytes(whole.read_bytes()[: whole.stat().st_size * 3 // 4])


def _mp4(path: Path, faststart: bool, frames: int = 30) -> Path:
    """An MPEG-4 video of noise, 160x120, ``frames`` frames; its index first if ``faststart``."""
    import av
    import numpy as np

    options = {"movflags": "faststart"} if faststart else {}
    with av.open(str(path), "w", options=options) as box:
        stream = box.add_stream("mpeg4", rate=25)
        stream.width, stream.height, stream.pix_fmt = 160, 120, "yuv420p"
        rng = np.random.default_rng(0)
        for _ in range(frames):
            image = rng.integers(0, 255, (120, 160, 3), dtype=np.uint8)
            box.mux(stream.encode(av.VideoFrame.from_ndarray(image, format="bgr24")))
        box.mux(stream.encode())
    return path


def occbench(*argv: str, cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess:
    """``python -m occbench ARGV`` as a user runs it (not verbose), from ``cwd``."""
    env = {k: v for k, v in os.environ.items() if k != "OCCBENCH_VERBOSE"}
    return subprocess.run([sys.executable, "-m", "occbench", *argv], capture_output=True,
                          check=False, text=True, cwd=cwd, timeout=timeout, env=env)


@pytest.fixture(scope="module")
def walk_inputs(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("walk")
    _inputs(folder)
    return folder


@pytest.mark.parametrize(("args", "status", "start"), MISTAKES,
                         ids=[" ".join(a) for a, _, _ in MISTAKES])
def test_a_mistake_is_one_line_and_no_traceback(args, status, start, walk_inputs):
    proc = occbench(*args, cwd=walk_inputs)
    lines = proc.stderr.splitlines()
    assert proc.returncode == status, proc.stderr[-2000:]
    assert len(lines) == 1 and lines[0].startswith(start), proc.stderr[-2000:]
    assert "Traceback" not in proc.stderr and proc.stdout == ""


@pytest.mark.parametrize(("args", "start"), USAGE, ids=[" ".join(a) for a, _ in USAGE])
def test_a_usage_mistake_is_the_usage_then_one_line_exit_2(args, start, tmp_path):
    """A command line that cannot be parsed: the command's usage (argparse's, wrapped lines
    indented), then the one line ``occbench: COMMAND: cause``; exit 2, nothing on stdout."""
    proc = occbench(*args, cwd=tmp_path)
    lines = proc.stderr.splitlines()
    assert proc.returncode == 2, proc.stderr[-2000:]
    assert lines[0].startswith("usage: occbench") and lines[-1].startswith(start), proc.stderr
    assert all(line.startswith(" ") for line in lines[1:-1]), proc.stderr  # the usage's own
    assert "Traceback" not in proc.stderr and "error:" not in proc.stderr
    assert proc.stdout == ""
