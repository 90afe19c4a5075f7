"""harness/errors.py: a block under ``signals_held`` is not cut by Ctrl-C or SIGTERM; the
signal is acted on, as it would have been, when the block ends."""

from __future__ import annotations

import os
import signal
import sys
import threading

import pytest

from occbench.errors import Terminated, signals_held


def _terminate(signum, frame):
    raise Terminated


def test_ctrl_c_inside_the_block_is_raised_after_it():
    done = []
    with pytest.raises(KeyboardInterrupt):
        with signals_held():
            os.kill(os.getpid(), signal.SIGINT)
            for _ in range(1000):  # the handler has had its chances to run here
                sum(range(10))
            done.append("block")
        done.append("after")  # not reached: raised as the block ends
    assert done == ["block"]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_sigterm_is_raised_by_the_handler_it_had(monkeypatch):
    saved = signal.signal(signal.SIGTERM, _terminate)
    try:
        done = []
        with pytest.raises(Terminated):
            with signals_held():
                os.kill(os.getpid(), signal.SIGTERM)
                for _ in range(1000):
                    sum(range(10))
                done.append("block")
        assert done == ["block"]
        assert signal.getsignal(signal.SIGTERM) is _terminate
    finally:
        signal.signal(signal.SIGTERM, saved)


def test_an_import_cut_by_ctrl_c_is_whole_under_it(tmp_path, monkeypatch):
    """What it is for: a package whose submodule is imported when Ctrl-C comes stays
    importable (without the hold, the package is left half-imported)."""
    pkg = tmp_path / "cutpkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("from . import part\nDONE = True\n")
    (pkg / "part.py").write_text("import os, signal\nos.kill(os.getpid(), signal.SIGINT)\n"
                                 "for _ in range(1000):\n    sum(range(10))\nVALUE = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    try:
        with pytest.raises(KeyboardInterrupt):
            with signals_held():
                import cutpkg
        assert sys.modules["cutpkg"].DONE and sys.modules["cutpkg.part"].VALUE == 1
    finally:
        sys.modules.pop("cutpkg", None)
        sys.modules.pop("cutpkg.part", None)


def test_outside_the_main_thread_the_block_runs_as_it_is():
    seen = []

    def body():
        with signals_held():
            seen.append(signal.getsignal(signal.SIGINT))

    t = threading.Thread(target=body)
    t.start()
    t.join()
    assert seen == [signal.default_int_handler]
