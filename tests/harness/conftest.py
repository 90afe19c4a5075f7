"""Fixtures shared by the harness's tests."""

from __future__ import annotations

from pathlib import Path

import pytest
from run_scenes import write_mot_sequence


@pytest.fixture
def mot_root(tmp_path: Path) -> Path:
    """A MOT dataset folder of two sequences of two crossing people (30 and 24 frames)."""
    root = tmp_path / "data"
    write_mot_sequence(root, "cross-a", 30)
    write_mot_sequence(root, "cross-b", 24)
    return root
