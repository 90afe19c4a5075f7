"""Export and drawing of a tracker's per-frame tracking graph (Reta et al. 2015, Figs. 3-5).

A tracker that keeps a graph exposes ``graph_snapshot()`` returning
``{'frame': t, 'nodes': [record, ...], 'edges': [record, ...]}`` (see
``occbench.trackers.three_hypothesis.graph``). ``GraphRecorder`` collects the snapshots of a run and
writes them beside the tracks as CSV (``<stem>_nodes.csv`` and ``<stem>_edges.csv``) or JSON
(``<stem>.json``); ``draw_graph`` draws one frame the paper's way: solid ellipses for nodes
matched by a detection, dashed ellipses for hypotheses, light grey for tentative nodes, ids
as labels, edges as lines from the predecessor's centre (``occbench.replay.graph.record_sequence``
re-runs a tracker over a sequence to draw its graph). ``GraphExport`` is the runner's
hook (config key ``graph``): it records every graph-keeping tracker of a normal run and
writes ``tracks/<tracker>/<sequence>.graph.json`` (or ``.graph_nodes.csv`` and
``.graph_edges.csv``) beside the tracks.
"""

from __future__ import annotations

import csv
import json
import logging
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from occbench.report.primitives import _label
from occbench.trackers.protocol import KeepsGraph

log = logging.getLogger(__name__)

NODE_FIELDS = ["frame", "node", "id", "kind", "hypothesis", "xc", "yc", "phi", "rx", "ry", "vx",
               "vy", "occluder", "depth", "parent", "stage", "rho"]
EDGE_FIELDS = ["frame", "source", "target", "kind"]
GREY = (190, 190, 190)


def id_colour(track_id: int) -> tuple[int, int, int]:
    """A stable, saturated BGR colour per identity."""
    hue = int((int(track_id) * 0.618034 % 1.0) * 180)  # golden-ratio spacing of hues
    hsv = np.uint8([[[hue, 220, 230]]])
    b, g, r = cv2.cvtColor(hsv, cv2.COLOR_HSV2BGR)[0, 0]
    return int(b), int(g), int(r)


class GraphRecorder:
    """Collects graph snapshots frame by frame and writes them.

    Args:
        sequence: name written in each record (several sequences may share a file).
    """

    def __init__(self, sequence: str = "") -> None:
        self.sequence = sequence
        self.nodes: list[dict] = []
        self.edges: list[dict] = []

    def add(self, snapshot: dict, frame: int | None = None) -> None:
        """Append one snapshot; ``frame`` overrides the tracker's own frame counter."""
        for rec in snapshot.get("nodes", []):
            row = dict(rec)
            if frame is not None:
                row["frame"] = int(frame)
            self.nodes.append(row)
        for rec in snapshot.get("edges", []):
            row = dict(rec)
            if frame is not None:
                row["frame"] = int(frame)
            self.edges.append(row)

    def write(self, path: str | Path) -> list[Path]:
        """Write to ``path``: suffix ``.json`` gives one JSON file, ``.csv`` gives
        ``<stem>_nodes.csv`` and ``<stem>_edges.csv``. Returns the files written."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        if path.suffix == ".json":
            # strict JSON: a missing float (NaN, e.g. rho of an unmatched node) is null
            doc = {"sequence": self.sequence,
                   "nodes": [{k: _json_value(v) for k, v in row.items()} for row in self.nodes],
                   "edges": [{k: _json_value(v) for k, v in row.items()} for row in self.edges]}
            path.write_text(json.dumps(doc, allow_nan=False, indent=None, separators=(",", ":")))
            return [path]
        if path.suffix != ".csv":
            raise ValueError(f"graph export: {path}: suffix must be .csv or .json")
        out = []
        for name, rows, fields in (("nodes", self.nodes, NODE_FIELDS),
                                   ("edges", self.edges, EDGE_FIELDS)):
            target = path.with_name(f"{path.stem}_{name}.csv")
            with target.open("w", newline="") as fh:
                writer = csv.DictWriter(fh, fieldnames=fields, extrasaction="ignore",
                                        lineterminator="\n")
                writer.writeheader()
                for row in rows:
                    writer.writerow({k: _fmt(row.get(k, "")) for k in fields})
            out.append(target)
        log.info("graph of %d nodes, %d edges written to %s", len(self.nodes), len(self.edges),
                 ", ".join(str(p) for p in out))
        return out


GRAPH_FORMATS = ("json", "csv")


class GraphExport:
    """Graph export of a run (config key ``graph: {export, format}``).

    ``record`` is the runner's per-frame hook: after a tracker's ``update`` it adds the
    tracker's ``graph_snapshot()`` (trackers without one are skipped); ``write`` then writes
    one file per tracker for the sequence, beside its tracks:
    ``<tracks_dir>/<tracker>/<sequence>.graph.json``, or with ``format: csv``
    ``<sequence>.graph_nodes.csv`` and ``<sequence>.graph_edges.csv``.

    Args:
        tracks_dir: the run's ``tracks`` folder.
        export: record and write (False: ``hook()`` is None and ``write`` writes nothing).
        format: "json" or "csv".
    Raises:
        ValueError: an unknown format (naming the key ``graph.format``).
    """

    def __init__(self, tracks_dir: str | Path, export: bool = False, format: str = "json") -> None:
        if format not in GRAPH_FORMATS:
            raise ValueError(f"graph.format must be one of {GRAPH_FORMATS}, got {format!r}")
        self.tracks_dir = Path(tracks_dir)
        self.export = bool(export)
        self.format = format
        self._recorders: dict[str, GraphRecorder] = {}

    @classmethod
    def from_config(cls, node: Mapping[str, Any] | None, tracks_dir: str | Path) -> GraphExport:
        """Build from the ``graph`` config node (None or missing keys: defaults)."""
        node = dict(node or {})
        unknown = set(node) - {"export", "format"}
        if unknown:
            raise ValueError(f"graph: unknown key(s) {sorted(unknown)}; known: export, format")
        return cls(tracks_dir, bool(node.get("export", False)), str(node.get("format", "json")))

    def hook(self) -> Callable[[str, int, Any], None] | None:
        """Start a sequence (anything recorded and not written, e.g. of a sequence that
        failed, is dropped) and return the runner's per-frame callback
        ``(tracker_name, frame, tracker)``, or None when export is off."""
        self._recorders = {}
        return self.record if self.export else None

    def record(self, tracker_name: str, frame: int, tracker: Any) -> None:
        """Add ``tracker.graph_snapshot()`` of frame ``frame`` (1-based) to its recorder."""
        if not isinstance(tracker, KeepsGraph):
            return
        recorder = self._recorders.setdefault(tracker_name, GraphRecorder())
        recorder.add(tracker.graph_snapshot(), frame=frame)

    def write(self, sequence: str) -> list[Path]:
        """Write the recorded graphs of ``sequence`` (one file, or two for CSV, per tracker)
        and start afresh for the next sequence. Returns the files written."""
        files: list[Path] = []
        for name, recorder in self._recorders.items():
            recorder.sequence = sequence
            path = self.tracks_dir / name / f"{sequence}.graph.{self.format}"
            files += recorder.write(path)
        self._recorders = {}
        return files


def _json_value(v):
    return None if isinstance(v, float) and not np.isfinite(v) else v


def _fmt(v):
    if isinstance(v, float):
        return "nan" if np.isnan(v) else f"{v:.3f}"
    return v


def read_graph_csv(path: str | Path) -> tuple[list[dict], list[dict]]:
    """Read back ``<stem>_nodes.csv`` and ``<stem>_edges.csv`` written by ``GraphRecorder``."""
    path = Path(path)
    tables = []
    for name in ("nodes", "edges"):
        target = path.with_name(f"{path.stem}_{name}.csv")
        with target.open(newline="") as fh:
            tables.append(list(csv.DictReader(fh)))
    return tables[0], tables[1]


def _dashed_ellipse(img: np.ndarray, centre, axes, angle: float, colour, thickness: int) -> None:
    """An ellipse drawn as 24 dashes (OpenCV has no dashed line style)."""
    pts = cv2.ellipse2Poly((round(centre[0]), round(centre[1])),
                           (max(round(axes[0]), 1), max(round(axes[1]), 1)),
                           round(angle), 0, 360, 360 // 48)
    for k in range(0, len(pts) - 1, 2):
        cv2.line(img, tuple(int(v) for v in pts[k]), tuple(int(v) for v in pts[k + 1]), colour,
                 thickness, cv2.LINE_AA)


def draw_graph(frame: np.ndarray, snapshot: dict, previous: dict | None = None,
               thickness: int = 2, taken: list | None = None) -> np.ndarray:
    """Draw one frame's graph on a copy of the (H, W, 3) uint8 BGR ``frame``.

    Visible nodes: solid ellipse in the id's colour; hypothesis nodes: dashed ellipse with
    the hypothesis kind; tentative nodes: light grey; labels are ids (negative while
    tentative). When ``previous`` (the snapshot of frame t-1) is given, each edge is drawn
    as a thin line from the predecessor's centre to the node's centre. Labels are moved
    off each other (``taken``: rectangles of labels already drawn; ``primitives._label``).
    """
    taken = [] if taken is None else taken
    img = frame.copy()
    before = {n["node"]: n for n in (previous or {}).get("nodes", [])}
    for n in snapshot.get("nodes", []):
        centre = (float(n["xc"]), float(n["yc"]))
        axes = (float(n["rx"]), float(n["ry"]))
        angle = float(np.degrees(float(n["phi"])))
        kind = n["kind"]
        colour = GREY if kind == "tentative" else id_colour(int(n["id"]))
        parent = before.get(n.get("parent"))
        if parent is not None:
            cv2.line(img, (int(parent["xc"]), int(parent["yc"])), (int(centre[0]), int(centre[1])),
                     colour, 1, cv2.LINE_AA)
        if kind == "hypothesis" or (kind == "tentative" and n.get("hypothesis")):
            _dashed_ellipse(img, centre, axes, angle, colour, thickness)
        else:
            cv2.ellipse(img, ((centre[0], centre[1]), (2 * axes[0], 2 * axes[1]), angle), colour,
                        thickness, cv2.LINE_AA)
        label = str(n["id"])
        if n.get("hypothesis"):
            label += {"velocity": "v", "occluder": "o", "still": "s"}.get(n["hypothesis"], "")
        org = (int(centre[0] - axes[0]), max(int(centre[1] - axes[1]) - 4, 10))
        _label(img, label, org, colour, taken=taken)
    return img
