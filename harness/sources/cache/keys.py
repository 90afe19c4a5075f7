"""What a front-end cache entry is keyed by: everything its outputs depend on.

* the frames: a digest of the bytes they are decoded from (``frames_digest``): the image
  files of the frames in the sequence's window, or the whole video file; a synthetic
  scene's generating state (cast, background, seed and rendering settings). Decoded frames
  are never hashed. Sequences of another kind are not cached (None).
* the frame window (first frame and length: the warm-up samples frames over it);
* the detector's whole config, resolved, with the bytes of every existing file it names
  (a template, a mixture file) and of every file in every folder it names (the background
  footage's frames), and so its seeds (``calibration.line.seed``);
* the code (``code_version``): every file of ``trackers/frontend`` and the ``trackers``
  modules it imports, ``harness/sources`` and ``harness/datasets`` (decoding), and the
  versions of the libraries computing or decoding pixels. Editing a tracker does not
  change the key; editing the front end, a reader or a library version does.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import re
from functools import lru_cache
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

import numpy as np

from occbench.datasets.base import FrameWindow, Sequence
from occbench.datasets.images import ImageSequence
from occbench.datasets.synthetic.sequence import SyntheticSequence
from occbench.datasets.video import VideoSequence

ROOT = Path(__file__).resolve().parents[3]
#: source folders whose every file counts (relative to the checkout)
CODE_FOLDERS = ("trackers/frontend", "harness/sources", "harness/datasets")
#: libraries whose version counts
LIBRARIES = ("numpy", "opencv-python-headless", "opencv-python", "opencv-contrib-python",
             "numba", "scipy", "simplejpeg", "scikit-image")
FORMAT = 1  # bump when the entry's layout changes


def _update_array(h: Any, a: np.ndarray) -> None:
    a = np.ascontiguousarray(a)
    h.update(f"{a.dtype.str}{a.shape}".encode())
    h.update(a.tobytes())


def _update_value(h: Any, value: Any) -> None:
    """Feed ``value`` (arrays, dataclasses, containers, scalars) into ``h`` unambiguously."""
    if isinstance(value, np.ndarray):
        _update_array(h, value)
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        h.update(type(value).__qualname__.encode())
        for f in dataclasses.fields(value):
            h.update(f.name.encode() + b"=")
            _update_value(h, getattr(value, f.name))
    elif isinstance(value, list | tuple):
        h.update(f"[{len(value)}".encode())
        for v in value:
            _update_value(h, v)
    elif isinstance(value, dict):
        h.update(f"{{{len(value)}".encode())
        for k in sorted(value, key=str):
            h.update(repr(k).encode() + b":")
            _update_value(h, value[k])
    elif value is None or isinstance(value, bool | int | float | str | np.generic):
        h.update(repr(value).encode() + b";")
    else:
        h.update(type(value).__qualname__.encode() + b";")  # a painter etc.: its code counts


def _synthetic_state(seq: Any) -> dict[str, Any]:
    return {"cast": seq.cast, "background": seq.background, "seed": seq.seed,
            "noise": seq.noise, "gains": seq.gains, "shadows": seq.shadows is not None,
            "occluded_below": seq.occluded_below, "reflection": seq.reflection,
            "size": (seq.info.width, seq.info.height)}


def frames_digest(sequence: Sequence) -> str | None:
    """Digest of what ``sequence``'s frames in its window are decoded or rendered from, or
    None when its kind is not known here (it is then not cached)."""
    inner = sequence.inner if isinstance(sequence, FrameWindow) else sequence
    numbers = sequence.frame_numbers()
    h = hashlib.sha256(f"{type(inner).__name__} {numbers.start} {numbers.stop}".encode())
    if isinstance(inner, ImageSequence):
        if inner.paths is None:
            return None
        for k in numbers:
            h.update(inner.paths[k - 1].read_bytes())
    elif isinstance(inner, VideoSequence):
        h.update(inner.path.read_bytes())
    elif isinstance(inner, SyntheticSequence):
        _update_value(h, _synthetic_state(inner))
    else:
        return None
    return h.hexdigest()


def config_digest(config: dict[str, Any]) -> str:
    """Digest of a resolved detector config and of the bytes of every file it names, and of
    every file inside every folder it names (background footage: folders of frames)."""
    h = hashlib.sha256(json.dumps(config, sort_keys=True, default=repr).encode())
    for value in _strings(config):
        path = Path(value).expanduser()
        if len(value) >= 4096:
            continue
        files = [path] if path.is_file() else sorted(
            p for p in path.rglob("*") if p.is_file()) if path.is_dir() else []
        for f in files:  # the folder's files by their names inside it
            name = value if f == path else f"{value}/{f.relative_to(path).as_posix()}"
            h.update(name.encode() + b"\0" + f.read_bytes())
    return h.hexdigest()


def _strings(node: Any) -> list[str]:
    if isinstance(node, str):
        return [node]
    if isinstance(node, dict):
        return [s for v in node.values() for s in _strings(v)]
    if isinstance(node, list | tuple):
        return [s for v in node for s in _strings(v)]
    return []


_IMPORT = re.compile(r"^[ \t]*(?:from[ \t]+(trackers(?:\.\w+)*)[ \t]+import[ \t]+\(?([\w, \t]+)"
                     r"|import[ \t]+(trackers(?:\.\w+)*))", re.MULTILINE)


def _imported_trackers_modules(files: list[Path]) -> set[Path]:
    """The ``trackers`` module files imported (at any depth, at any indentation, so lazy
    imports count) by ``files``; a line scan, ten times faster than parsing."""
    seen: set[Path] = set()
    todo = list(files)
    while todo:
        for m in _IMPORT.finditer(todo.pop().read_text(encoding="utf-8", errors="replace")):
            module = m.group(1) or m.group(3)
            names = [module] + [f"{module}.{n.strip()}" for n in (m.group(2) or "").split(",")
                                if n.strip()]
            for name in names:
                base = ROOT / Path(*name.split("."))
                for p in (base.with_suffix(".py"), base / "__init__.py"):
                    if p.is_file() and p not in seen:
                        seen.add(p)
                        todo.append(p)
    return seen


@lru_cache(maxsize=1)
def code_version() -> str:
    """Digest of the front end's code and library versions (once per process)."""
    files = {p for d in CODE_FOLDERS for p in (ROOT / d).rglob("*")
             if p.is_file() and "__pycache__" not in p.parts}
    files |= _imported_trackers_modules([p for p in files if p.suffix == ".py"])
    h = hashlib.sha256(f"format {FORMAT}".encode())
    for p in sorted(files):
        h.update(str(p.relative_to(ROOT)).encode() + b"\0" + p.read_bytes())
    for lib in LIBRARIES:
        try:
            h.update(f"{lib} {version(lib)};".encode())
        except PackageNotFoundError:
            h.update(f"{lib} -;".encode())
    return h.hexdigest()


def entry_key(sequence: Sequence, detector: dict[str, Any]) -> str | None:
    """The key of ``sequence`` under the detector config ``detector``, or None when the
    sequence's frames cannot be fingerprinted."""
    frames = frames_digest(sequence)
    if frames is None:
        return None
    parts = {"frames": frames, "first": sequence.first_frame, "length": sequence.info.length,
             "detector": config_digest(detector), "code": code_version()}
    return hashlib.sha256(json.dumps(parts, sort_keys=True).encode()).hexdigest()[:40]
