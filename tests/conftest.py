"""Suite-wide: the front-end cache (``OCCBENCH_CACHE``) of a test session is a fresh
temporary folder, never the user's own cache; no ``occbench`` a test runs uses or starts a
warm server (``OCCBENCH_SERVER=off``; ``tests/harness/server`` starts and stops its own);
Ctrl-C is deliverable (``pytest_configure``)."""

from __future__ import annotations

import signal

import pytest

from occbench.config import register


def pytest_configure(config):
    """Every composition of the session finds the project's resolvers and launcher. The
    tests of Ctrl-C (test_errors, test_faults, the server's) need SIGINT's usual disposition:
    a suite started as ``cmd &`` by a shell without job control (a script, ``nohup``)
    inherits SIGINT ignored, Python then installs no KeyboardInterrupt handler, and neither
    do the ``occbench`` processes the tests start (an ignored signal stays ignored across
    exec; a handler does not). Restored here, in each xdist worker too."""
    register()
    if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


@pytest.fixture(autouse=True, scope="session")
def _session_cache(tmp_path_factory):
    mp = pytest.MonkeyPatch()
    mp.setenv("OCCBENCH_CACHE", str(tmp_path_factory.mktemp("occbench_cache")))
    mp.setenv("OCCBENCH_SERVER", "off")
    yield
    mp.undo()
