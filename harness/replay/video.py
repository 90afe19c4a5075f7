"""Annotated video and contact sheets: every tracker's output drawn its own way, side by side.

The result files hold only the scored boxes; the drawings need every output of every frame
(hypotheses, tentative tracks, ellipses, part rectangles), so ``render`` runs the trackers
again, exactly as the runner does (same detection source, same foreground, each tracker its
own copy of the inputs: the tracks are the ones of the run with the same config and seed),
and draws each frame as one panel per tracker (``occbench.report.draw``; a tracker that exposes
its tracking graph, Reta et al.'s, is drawn by ``occbench.report.graph.draw_graph``: solid,
dashed and grey ellipses with the edges from the previous frame), ground truth thin white
underneath when asked.

Outputs: an H.264 MP4 (``H264Writer``: the ffmpeg that imageio-ffmpeg ships, libx264,
yuv420p, avc1 in the container, so browsers play it) of the panels, and a contact sheet: a
PNG grid with one row per chosen frame and one column per tracker. Each panel's title is in
a band above its picture; both outputs end with a legend of the marks
(``occbench.report.draw.legend``).

Command line (config overrides as for ``python -m occbench``, or the config of a finished run)::

    python -m occbench.replay.video --sequence stop_behind --out stop_behind.mp4 \\
        --sheet stop_behind.png -- dataset=synthetic dataset.scenarios=[stop_behind]
    python -m occbench.replay.video --run results/2026-01-01/12-00-00 --sequence crossing

With ``--run`` and neither ``--out`` nor ``--sheet``, both are written into the run directory:
``report/<sequence>.mp4`` and ``report/<sequence>_sheet.png``.
"""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import cv2
import imageio_ffmpeg
import numpy as np
import yaml

from occbench.datasets.base import Sequence as DataSequence
from occbench.pipeline.bank import TrackerBank, start_trackers
from occbench.config.build import (
    build_source,
    build_tracker,
    compose_config,
    load_sequences,
    tracker_choice,
    tracker_configs,
)
from occbench.config.meta import metas
from occbench.errors import REFUSED, refusal
from occbench.pipeline.loop import frames, no_progress
from occbench.progress import log_to_stderr, progress_factory
from occbench.report.draw import draw_tracks, grid, legend, with_legend
from occbench.report.graph import draw_graph
from occbench.sources.base import DetectionSource
from occbench.trackers.protocol import KeepsGraph
from occbench.trackers.records import Track

log = logging.getLogger(__name__)


class H264Writer:
    """Writes BGR frames into an H.264 MP4 (libx264, yuv420p, ``+faststart``) through the
    ffmpeg binary that imageio-ffmpeg ships; odd frame sizes are padded with one black row
    or column (yuv420p needs even sizes).

    Args:
        path: the MP4 to write.
        fps: frames per second.
        size: (width, height) of every frame.
        crf: x264 constant rate factor (lower = better; 18 is visually lossless).
    """

    def __init__(self, path: str | Path, fps: float, size: tuple[int, int], crf: int = 18) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        w, h = int(size[0]), int(size[1])
        if w <= 0 or h <= 0:
            raise ValueError(f"size must be positive, got {size}")
        self.size = (w, h)
        self._pad = (h % 2, w % 2)
        self._gen = imageio_ffmpeg.write_frames(
            str(self.path), (w + self._pad[1], h + self._pad[0]), fps=float(fps),
            codec="libx264", pix_fmt_in="bgr24", pix_fmt_out="yuv420p", macro_block_size=1,
            ffmpeg_log_level="error",
            output_params=["-crf", str(int(crf)), "-preset", "medium", "-threads", "1",
                           "-movflags", "+faststart"])
        self._gen.send(None)  # start ffmpeg

    def write(self, image: np.ndarray) -> None:
        """Append one (H, W, 3) uint8 BGR frame of the writer's size."""
        if image.shape[:2] != (self.size[1], self.size[0]):
            raise ValueError(f"{self.path}: frame of shape {image.shape}, the video is "
                             f"{self.size[0]}x{self.size[1]}")
        if any(self._pad):
            image = cv2.copyMakeBorder(image, 0, self._pad[0], 0, self._pad[1],
                                       cv2.BORDER_CONSTANT, value=0)
        self._gen.send(np.ascontiguousarray(image))

    def release(self) -> None:
        """Finish the file (ffmpeg writes the index)."""
        self._gen.close()


def track_frames(trackers: Mapping[str, Any], sequence: DataSequence, source: DetectionSource,
                 foreground: str = "auto", background: Mapping[str, Any] | None = None,
                 last: int | None = None) -> Iterable[tuple[int, np.ndarray | None,
                                                           dict[str, list[Track]]]]:
    """Yield ``(k, frame, {tracker: tracks})`` for frames up to ``last`` (default: all),
    running every tracker on the frame loop of the runner (``occbench.pipeline.loop.frames``)
    through a ``TrackerBank``, each on its own copy of the frame, the detections and the
    foreground (a lone tracker on the inputs themselves).

    Raises:
        RuntimeError: a tracker failed (its error, with the frame, in the message).
    """
    loop = frames(sequence, source, foreground, background, last)
    for t in trackers.values():
        t.reset()
    start_trackers(trackers, sequence)
    bank = TrackerBank(trackers)
    for step in loop:
        out = bank.step(step.index, step.image, step.detections, step.foreground)
        if len(out) < len(trackers):
            failed = next(n for n, o in bank.outputs.items() if o.error is not None)
            raise RuntimeError(f"tracker {failed} failed on {sequence.info.name}, "
                               f"{bank.outputs[failed].error}")
        yield step.index, step.image, out


class _GraphDrawing:
    """Draws a tracker that exposes its tracking graph (``graph_snapshot()``, Reta et al.)
    with ``occbench.report.graph.draw_graph``; ``step()`` must be called after every frame so
    that edges join each node to its predecessor of the previous frame."""

    def __init__(self, tracker: Any, draw_graph: Any) -> None:
        self.tracker, self.draw_graph = tracker, draw_graph
        self.previous: dict | None = None
        self.current: dict | None = None

    @classmethod
    def of(cls, tracker: Any) -> _GraphDrawing | None:
        if not isinstance(tracker, KeepsGraph):
            return None
        return cls(tracker, draw_graph)

    def step(self) -> None:
        self.previous, self.current = self.current, self.tracker.graph_snapshot()

    def draw(self, base: np.ndarray) -> np.ndarray:
        return self.draw_graph(base, self.current or {}, self.previous)


def _gt_of(sequence: DataSequence, k: int) -> tuple[np.ndarray, np.ndarray] | None:
    if sequence.gt is None:
        return None
    rows = sequence.gt.rows_of(k)
    t = sequence.gt.table
    return t.boxes[rows], t.ids[rows]


def _blank(sequence: DataSequence) -> np.ndarray:
    return np.full((sequence.info.height, sequence.info.width, 3), 40, np.uint8)


def _panel(name: str, style: str, k: int, base: np.ndarray, tracks: list[Track],
           graph: _GraphDrawing | None, gt: tuple[np.ndarray, np.ndarray] | None,
           scale: float) -> np.ndarray:
    """Tracker ``name``'s panel of frame ``k``: its own graph drawing when it keeps one
    (Reta Figs. 3-5), else its tracks drawn its way; resized by ``scale``."""
    if graph is not None:
        p = draw_tracks(graph.draw(base), [], "boxes", gt, f"{name}  frame {k}")
    else:
        p = draw_tracks(base, tracks, style, gt, f"{name}  frame {k}")
    if scale != 1.0:
        p = cv2.resize(p, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
    return p


def _window(sequence: DataSequence, frames: tuple[int, int] | None, sheet: bool,
            sheet_frames: Sequence[int] | None) -> tuple[int, int, set[int]]:
    """(first, last) of the video and the sheet's frames (default: 6 evenly spaced over
    the video's when there is a sheet), checked against the sequence's frame numbers."""
    numbers = sequence.frame_numbers()
    lo, hi = numbers[0], numbers[-1]
    first, last = frames or (lo, hi)
    if not lo <= first <= last <= hi:
        raise ValueError(f"frames must satisfy {lo} <= first <= last <= {hi} (the sequence's "
                         f"frame numbers), got {(first, last)}")
    if sheet and sheet_frames is None:
        sheet_frames = sorted({int(v) for v in np.linspace(first, last, 6).round()})
    wanted = set(sheet_frames or [])
    bad = sorted(f for f in wanted if not lo <= f <= hi)
    if bad:
        raise ValueError(f"sheet_frames outside {lo}..{hi}: {bad}")
    return first, last, wanted


def render(trackers: Mapping[str, Any], sequence: DataSequence, source: DetectionSource,
           video: str | Path | None = None, sheet: str | Path | None = None,
           sheet_frames: Sequence[int] | None = None, show_gt: bool = True,
           frames: tuple[int, int] | None = None, columns: int | None = None,
           scale: float = 1.0, foreground: str = "auto",
           background: Mapping[str, Any] | None = None,
           progress: Callable[..., Any] | None = None,
           styles: Mapping[str, str] | None = None) -> dict[str, Path]:
    """Run the trackers on ``sequence`` and write the annotated video and/or contact sheet.

    Args:
        trackers: name -> freshly built tracker (drawn in this order, styled by name when the
            ``styles`` gives one, else by the tracks' ``extra`` data).
        sequence, source: the data and the detection source (as for the runner).
        video: MP4 path, or None for no video.
        sheet: PNG path of the contact sheet, or None.
        sheet_frames: frame numbers of the sheet's rows (default: 6 evenly spaced frames
            of the rendered range).
        show_gt: draw the ground truth (thin white boxes) under each tracker's output.
        frames: (first, last) frame numbers written to the video (default: all of the
            sequence's ``frame_numbers()``, e.g. 151..295 for a ``dataset.frames`` window).
        columns: panels per row in a video frame (default: all side by side).
        scale: resize factor of each panel.
        progress: progress-bar factory (``occbench.progress.progress_factory``): a bar over
            the frames tracked; None shows nothing.
        styles: name -> drawing style (the ``style`` of the tracker's ``meta:`` block,
            ``occbench.config.meta``); a tracker without one is drawn by its tracks' data.
    Returns:
        {"video": path, "sheet": path} for what was written.
    """
    if not trackers:
        raise ValueError("render: no trackers")
    lo = sequence.frame_numbers()[0]
    first, last, wanted = _window(sequence, frames, sheet is not None, sheet_frames)
    end = max([last, *wanted])
    graphs = {name: _GraphDrawing.of(t) for name, t in trackers.items()}
    styles = {n: (styles or {}).get(n, "auto") for n in trackers}
    items = legend(list(styles.values()), show_gt,
                   any(g is not None for g in graphs.values()))
    writer = None
    rows: dict[int, list[np.ndarray]] = {}
    written: dict[str, Path] = {}
    bar = (progress or no_progress)(total=end - lo + 1,
                                    desc=f"drawing {sequence.info.name}")
    try:
        for k, frame, tracks in track_frames(trackers, sequence, source, foreground, background,
                                             end):
            bar.update(1)
            for g in graphs.values():
                if g is not None:
                    g.step()
            if not (first <= k <= last or k in wanted):
                continue
            base = frame if frame is not None else _blank(sequence)
            gt = _gt_of(sequence, k) if show_gt else None
            panels = [_panel(name, styles[name], k, base, out, graphs[name], gt, scale)
                      for name, out in tracks.items()]
            if k in wanted:
                rows[k] = panels
            if video is not None and first <= k <= last:
                image = with_legend(grid(panels, columns), items)
                if writer is None:
                    Path(video).parent.mkdir(parents=True, exist_ok=True)
                    fps = sequence.info.fps or 25.0
                    writer = H264Writer(video, fps, (image.shape[1], image.shape[0]))
                writer.write(image)
    finally:
        bar.close()
        if writer is not None:
            writer.release()
            written["video"] = Path(video)
    if sheet is not None:
        sheet_img = with_legend(grid([p for k in sorted(rows) for p in rows[k]], len(trackers)),
                                items)
        Path(sheet).parent.mkdir(parents=True, exist_ok=True)
        if not cv2.imwrite(str(sheet), sheet_img):
            raise OSError(f"cannot write {sheet}")
        written["sheet"] = Path(sheet)
    return written


# --------------------------------------------------------------------------- command line


def run_choice(run_dir: Path, group: str) -> str | None:
    """The config choice of ``group`` a finished run was started with (Hydra's
    ``.hydra/hydra.yaml``), None when unknown."""
    path = Path(run_dir) / ".hydra" / "hydra.yaml"
    if not path.is_file():
        return None
    body = yaml.safe_load(path.read_text()) or {}
    choice = (((body.get("hydra") or {}).get("runtime") or {}).get("choices") or {}).get(group)
    return None if choice is None else str(choice)


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m occbench.replay.video",
                                description="Annotated side-by-side video and contact sheet.")
    p.add_argument("overrides", nargs="*", help="config overrides, e.g. dataset=synthetic")
    p.add_argument("--run", type=Path, help="use the config saved in this run directory")
    p.add_argument("--sequence", help="sequence name (default: the first)")
    p.add_argument("--out", type=Path, help="MP4 to write")
    p.add_argument("--sheet", type=Path, help="contact-sheet PNG to write")
    p.add_argument("--sheet-frames", type=int, nargs="+", help="frames of the sheet's rows")
    p.add_argument("--frames", type=int, nargs=2, metavar=("FIRST", "LAST"))
    p.add_argument("--no-gt", action="store_true", help="do not draw the ground truth")
    p.add_argument("--scale", type=float, default=1.0)
    p.add_argument("--columns", type=int, default=None)
    args = p.parse_args(argv)
    log_to_stderr()
    if args.out is None and args.sheet is None and args.run is None:
        p.error("give --out and/or --sheet, or --run RUN_DIR (writes both into RUN_DIR/report/)")

    try:
        cfg = compose_config(args.overrides, args.run)
        sequences = load_sequences(cfg.dataset)
        if args.sequence:
            by_name = {s.info.name: s for s in sequences}
            if args.sequence not in by_name:
                raise ValueError(f"no sequence {args.sequence!r}; have {sorted(by_name)}")
            seq = by_name[args.sequence]
        else:
            seq = sequences[0]
        choice = tracker_choice(args.overrides)
        if choice is None and args.run is not None:
            choice = run_choice(args.run, "tracker")
        configs = tracker_configs(cfg.tracker, choice)
        trackers = {n: build_tracker(n, node) for n, node in configs.items()}
        styles = {n: m.style for n, m in metas(configs, configs).items()}
        out, sheet = args.out, args.sheet
        if out is None and sheet is None:  # --run alone: both, into the run directory
            out = args.run / "report" / f"{seq.info.name}.mp4"
            sheet = args.run / "report" / f"{seq.info.name}_sheet.png"
        written = render(trackers, seq, build_source(cfg.detector), out, sheet,
                         args.sheet_frames, not args.no_gt, tuple(args.frames) if args.frames
                         else None, args.columns, args.scale, str(cfg.get("foreground", "auto")),
                         cfg.get("background") or {}, progress_factory(), styles)
    except (OSError, ValueError, RuntimeError) as err:
        print(refusal(err), file=sys.stderr)
        return REFUSED
    for kind, path in written.items():
        print(f"{kind}: {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
