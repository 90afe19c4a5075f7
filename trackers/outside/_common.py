"""Helpers shared by the outside-tracker adapters: guarded imports, id renumbering, boxes."""

from __future__ import annotations

import importlib
from types import ModuleType

import numpy as np
from occbench.trackers.common.checks import unit

EXTRA = "outside"
# libraries whose metadata pins numpy<2 / old scipy but whose code runs on numpy 2: they
# cannot be in the extra (pip would downgrade numpy, OpenCV and pandas) and are installed
# without their pinned dependencies
NO_DEPS = "norfair==2.3.0 ocsort==0.0.2"


class MissingLibrary(ImportError):
    """An outside tracker's optional library is not installed (the message says how to
    install it). A run of a tracker group (``tracker=everyone``) skips such a tracker.

    Attributes:
        module: the import name that failed, e.g. ``"norfair"``.
        command: the shell command that installs the set the library belongs to (the
            outside extra, or BoxMOT's), for a one-line summary of several missing ones.
    """

    def __init__(self, message: str, module: str = "", command: str = "") -> None:
        super().__init__(message)
        self.module, self.command = module, command


OUTSIDE_COMMAND = (f'pip install -e ".[{EXTRA}]" --config-settings editable_mode=strict && '
                   f'pip install --no-deps {NO_DEPS}')


def require(module: str, install: str, tracker: str,
            command: str = OUTSIDE_COMMAND) -> ModuleType:
    """Import ``module`` or raise an ImportError saying how to install it.

    Args:
        module: import name, e.g. ``"norfair"``.
        install: pip arguments that install it, e.g. ``"--no-deps norfair==2.3.0"``.
        tracker: adapter class name, for the message.
        command: the command installing the set ``module`` belongs to
            (``MissingLibrary.command``; default: the outside extra).
    """
    try:
        return importlib.import_module(module)
    except ImportError as err:
        raise MissingLibrary(
            f"{tracker} needs the outside library '{module}', which is not installed. "
            f"Install the outside trackers: {OUTSIDE_COMMAND}; or this one alone: pip "
            f"install {install} (import failed with: {err})", module, command
        ) from err


class IdMap:
    """Library identity (any hashable) -> our positive int id, 1, 2, ... in order of first use."""

    def __init__(self) -> None:
        self._ids: dict = {}

    def __call__(self, key) -> int:
        if key not in self._ids:
            self._ids[key] = len(self._ids) + 1
        return self._ids[key]


def xywh_to_xyxy(boxes: np.ndarray) -> np.ndarray:
    """(N, 4) xywh -> (N, 4) x1, y1, x2, y2 (same 0-based pixel frame)."""
    boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    return np.column_stack([boxes[:, :2], boxes[:, :2] + boxes[:, 2:]])


def xyxy_to_xywh(box) -> np.ndarray:
    """(4,) x1, y1, x2, y2 -> (4,) float64 xywh."""
    x1, y1, x2, y2 = (float(v) for v in np.asarray(box).reshape(-1)[:4])
    return np.array([x1, y1, x2 - x1, y2 - y1])


def check_min_score(min_score: float) -> float:
    unit("", min_score=min_score)
    return float(min_score)
