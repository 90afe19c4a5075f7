"""Every command speaks one language (issue 39): a mistake or a refused input is one line on
stderr starting ``occbench:`` with its cause, exit status 1, nothing on stdout, no traceback;
results go to stdout, logs to stderr."""

from __future__ import annotations

import pytest

from occbench.commands.cli import main


def _one_line(capsys, *args: str) -> str:
    status = main(list(args))
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert status == 1, captured
    assert len(err) == 1 and err[0].startswith("occbench: "), err
    assert captured.out == ""
    return err[0]


@pytest.mark.parametrize(("args", "expected"), [
    (["bench", "trackr=reta"], "occbench: unknown key 'trackr': did you mean 'tracker'?"),
    (["bench", "dataset=cavair"], "occbench: unknown dataset 'cavair': did you mean 'caviar'?"),
    (["bench", "dataset=caviar", "dataset.root=/nonexistent"],
     "CAVIAR sequence folder not found: /nonexistent"),
    (["detect", "dataset=caviar", "dataset.root=/nonexistent"],
     "CAVIAR sequence folder not found: /nonexistent"),
    (["detect", "dataset=video", "dataset.path=/nonexistent.mp4"],
     "video file not found: /nonexistent.mp4"),
    (["detect", "trackr=reta"], "occbench: unknown key 'trackr'"),
    (["eval", "/nonexistent/gt", "/nonexistent/res"],
     "occbench: ground truth not found: /nonexistent/gt"),
])
def test_a_mistake_is_one_line_naming_its_cause(capsys, args, expected):
    assert expected in _one_line(capsys, *args)


def test_report_of_a_run_without_tracks_is_one_line(capsys, tmp_path):
    """A run that failed before any tracker finished a sequence (no tracks/): one line, not
    a 20-line traceback."""
    assert "config.yaml not found" in _one_line(capsys, "report", str(tmp_path))
    (tmp_path / "config.yaml").write_text("seed: 0\n")
    (tmp_path / "errors.txt").write_text("* sequence: FrameError\n")
    line = _one_line(capsys, "report", str(tmp_path))
    assert f"{tmp_path / 'tracks'} not found" in line and "errors.txt" in line


def test_detect_writes_results_on_stdout_and_logs_on_stderr(capsys, tmp_path):
    assert main(["detect", "detector=noisy_gt", "dataset.length=8", "dataset.scenarios=[crossing]",
                 "progress=false", f"hydra.run.dir={tmp_path / 'd'}"]) == 0
    captured = capsys.readouterr()
    assert captured.out.splitlines()[0].startswith("sequence ")
    assert captured.out.splitlines()[-1] == f"results: {tmp_path / 'd'}"
    assert "INFO" not in captured.out and "crossing: 8 frames" in captured.err
