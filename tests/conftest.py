"""Suite-wide: the front-end cache (``OCCBENCH_CACHE``) of a test session is a fresh
temporary folder, never the user's own cache; no ``occbench`` a test runs uses or starts a
warm server (``OCCBENCH_SERVER=off``; ``tests/harness/server`` starts and stops its own)."""

from __future__ import annotations

import pytest

from occbench.config import register


def pytest_configure(config):
    """Every composition of the session finds the project's resolvers and launcher."""
    register()


@pytest.fixture(autouse=True, scope="session")
def _session_cache(tmp_path_factory):
    mp = pytest.MonkeyPatch()
    mp.setenv("OCCBENCH_CACHE", str(tmp_path_factory.mktemp("occbench_cache")))
    mp.setenv("OCCBENCH_SERVER", "off")
    yield
    mp.undo()
