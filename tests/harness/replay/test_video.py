"""The annotated video and contact sheet (harness/replay/video.py)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from report_scenes import GtSource, Walk


def _legend_height(width: int) -> int:
    from occbench.report.draw import legend
    from occbench.report.primitives import legend_block

    return legend_block(legend(["boxes"], gt=True), width).shape[0]


def test_video_and_contact_sheet_side_by_side(tmp_path):
    from occbench.replay.video import render
    from occbench.trackers.baseline import BaselineTracker

    seq = Walk()
    trackers = {"baseline": BaselineTracker(min_hits=1), "other": BaselineTracker(max_age=0)}
    out = render(trackers, seq, GtSource(), tmp_path / "v.mp4", tmp_path / "s.png",
                 sheet_frames=[2, 6, 10])
    assert set(out) == {"video", "sheet"}
    cap = cv2.VideoCapture(str(out["video"]))
    n, size = 0, None
    while True:
        ok, img = cap.read()
        if not ok:
            break
        n, size = n + 1, img.shape
    cap.release()
    legend = _legend_height(320)  # the legend's rows under the panels
    assert n == 12 and size == (22 + 120 + legend, 320, 3)  # two panels side by side, titled
    data = out["video"].read_bytes()
    assert b"ftyp" in data[:32] and b"avc1" in data  # H.264 (browsers do not play mp4v)
    sheet = cv2.imread(str(out["sheet"]))
    assert sheet.shape == (3 * (22 + 120) + legend, 320, 3)  # 3 frames x 2 trackers
    with pytest.raises(ValueError, match="sheet_frames"):
        render(trackers, seq, GtSource(), sheet=tmp_path / "x.png", sheet_frames=[99])


def test_a_frame_window_is_rendered_by_its_own_frame_numbers(tmp_path):
    # dataset.frames=[5,9]: the window's frames keep their numbers 5..9, and so do the video's
    from occbench.datasets.base import window
    from occbench.replay.video import render
    from occbench.trackers.baseline import BaselineTracker

    (seq,) = window([Walk()], [5, 9])
    out = render({"baseline": BaselineTracker(min_hits=1)}, seq, GtSource(), tmp_path / "w.mp4",
                 tmp_path / "w.png")
    cap = cv2.VideoCapture(str(out["video"]))
    n = 0
    while cap.read()[0]:
        n += 1
    cap.release()
    assert n == 5
    # frames 5, 6, 7, 8, 9, each under its title band, then the legend
    assert cv2.imread(str(out["sheet"])).shape[0] == 5 * (22 + 120) + _legend_height(160)
    with pytest.raises(ValueError, match="5 <= first <= last <= 9"):
        render({"baseline": BaselineTracker()}, seq, GtSource(), tmp_path / "x.mp4",
               frames=(1, 4))


def test_h264_writer_pads_odd_sizes_and_checks_frames(tmp_path):
    from occbench.replay.video import H264Writer

    rng = np.random.default_rng(0)
    writer = H264Writer(tmp_path / "odd.mp4", 25.0, (33, 21))
    frames = [rng.integers(0, 255, (21, 33, 3), dtype=np.uint8) for _ in range(5)]
    for f in frames:
        writer.write(f)
    with pytest.raises(ValueError, match="33x21"):
        writer.write(frames[0][:, :32])
    writer.release()
    cap = cv2.VideoCapture(str(tmp_path / "odd.mp4"))
    shapes = []
    while True:
        ok, img = cap.read()
        if not ok:
            break
        shapes.append(img.shape)
    cap.release()
    assert shapes == [(22, 34, 3)] * 5  # one black row and column added
