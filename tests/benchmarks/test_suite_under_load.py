"""benchmarks/suite_under_load.py: a run passes on its junit xml alone (never on its exit
code), and a process left behind is described by the run that started it."""

from __future__ import annotations

import os
import subprocess
import sys

from benchmark_scripts import load

load = load("suite_under_load")

XML = """<?xml version="1.0" encoding="utf-8"?><testsuites><testsuite name="pytest" errors="{e}"
failures="{f}" skipped="1" tests="4"><testcase classname="tests.a" name="test_x"/>
<testcase classname="tests.a" name="test_y">{case}</testcase></testsuite></testsuites>"""


def _outcome(tmp_path, text: str | None, code: int = 0) -> load.Outcome:
    out = load.Outcome("fg", code=code)
    path = tmp_path / "run.xml"
    if text is not None:
        path.write_text(text)
    load.read_junit(path, out)
    return out


def test_a_run_passes_on_its_junit_counts_not_its_exit_code(tmp_path):
    ok = _outcome(tmp_path, XML.format(e=0, f=0, case=""), code=1)
    assert ok.passed and ok.cell() == "pass 3/3 (exit 1)"
    bad = _outcome(tmp_path, XML.format(e=0, f=1, case="<failure message='x'/>"), code=0)
    assert not bad.passed and bad.failed == ["tests.a::test_y"]
    assert bad.cell() == "FAIL 2/3, 1 failed, 0 errors (exit 0)"
    assert not _outcome(tmp_path, None, code=0).passed  # no xml: a crash, whatever the code
    assert not _outcome(tmp_path, "<testsuites", code=0).passed  # cut short


def test_a_marked_process_is_found_and_described(tmp_path):
    tag = f"test{os.getpid()}"
    proc = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"],
                            env={**os.environ, load.MARKER: f"{tag}:background"}, cwd=tmp_path)
    try:
        assert proc.pid in load.marked(tag)
        line = load.describe(proc.pid)
        assert f"{tag}:background" in line and f"cwd={tmp_path}" in line
        assert not load.marked(tag + "x")
    finally:
        proc.kill()
        proc.wait()
    assert proc.pid not in load.marked(tag)
