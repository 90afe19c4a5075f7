"""Suite-wide: the front-end cache (``OCCBENCH_CACHE``) of a test session is a fresh
temporary folder, never the user's own cache."""

from __future__ import annotations

import pytest


@pytest.fixture(autouse=True, scope="session")
def _session_cache(tmp_path_factory):
    mp = pytest.MonkeyPatch()
    mp.setenv("OCCBENCH_CACHE", str(tmp_path_factory.mktemp("occbench_cache")))
    yield
    mp.undo()
