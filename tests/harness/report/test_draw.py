"""Drawing styles (harness/report/draw.py): each tracker drawn its own way, frames never
drawn on in place, the panel grid."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from occbench.report.draw import draw_tracks, grid, infer_style
from occbench.trackers.records import Track, TrackState


def _frame() -> np.ndarray:
    return np.full((120, 160, 3), 100, np.uint8)


def test_each_tracker_is_drawn_its_own_way():
    box = np.array([40.0, 20.0, 30.0, 60.0])
    plain = Track(3, box)
    ellipse = Track(4, box, extra={"ellipse": np.array([55.0, 50.0, 0.0, 15.0, 30.0])})
    hyp = Track(4, box + [30, 0, 0, 0], TrackState.HYPOTHESIS,
                extra={"ellipse": np.array([85.0, 50.0, 0.0, 15.0, 30.0]),
                       "hypothesis": "still"})
    parts = np.array([[40, 20, 30, 9], [40, 29, 15, 25], [55, 29, 15, 25], [40, 54, 15, 26],
                      [55, 54, 15, 26]], float)
    pbm = Track(5, box, extra={"parts": parts, "occluded_parts": np.array([0, 0, 0, 1, 1], bool)})
    assert infer_style([plain]) == "boxes"
    assert infer_style([ellipse]) == "ellipses" and infer_style([pbm]) == "parts"
    a = draw_tracks(_frame(), [plain], "boxes")
    b = draw_tracks(_frame(), [ellipse, hyp], "ellipses")
    c = draw_tracks(_frame(), [pbm], "parts")
    for img in (a, b, c):
        assert img.shape == (120, 160, 3) and (img != 100).any()
    # a box's corner is drawn, an ellipse leaves the box corner untouched
    assert (a[20, 40] != 100).any() and (b[20, 40] == 100).all()
    # the solid ellipse is closed, the dashed hypothesis leaves gaps along its outline
    solid = cv2.ellipse2Poly((55, 50), (15, 30), 0, 0, 360, 2)
    dashed = cv2.ellipse2Poly((85, 50), (15, 30), 0, 0, 360, 2)
    on = lambda pts: np.mean([(b[y, x] != 100).any() for x, y in pts])
    assert on(solid[10:40]) > 0.9 and on(dashed[10:40]) < 0.9
    # the part rectangles split the box: the line between torso and legs is drawn
    assert (c[54, 47] != 100).any() and (a[54, 47] == 100).all()
    # frames are never drawn on in place
    frame = _frame()
    draw_tracks(frame, [plain], gt=(box[None], np.array([1])), title="baseline")
    assert (frame == 100).all()
    with pytest.raises(ValueError, match="style"):
        draw_tracks(frame, [plain], "circles")
    g = grid([a, b, c], columns=2)
    assert g.shape == (240, 320, 3)


def test_titles_sit_above_the_picture_and_labels_do_not_overlap():
    from occbench.report.primitives import TITLE_BAND, _label

    frame = _frame()
    frame[:12] = 255  # the video's own timestamp, top rows
    titled = draw_tracks(frame, [], title="baseline  frame 7")
    assert titled.shape == (120 + TITLE_BAND, 160, 3)
    assert (titled[TITLE_BAND:] == frame).all()  # the picture whole, under the band
    # three people side by side, boxes touching: labels at the same place without placement
    tracks = [Track(i, np.array([40.0 + 2 * i, 40.0, 30.0, 60.0])) for i in (11, 12, 13)]
    taken: list = []
    img = _frame()
    for t in tracks:
        _label(img, str(t.id), (int(t.box[0]), int(t.box[1]) - 3), (255, 255, 255), taken=taken)
    assert len(taken) == 3
    for a in range(3):
        for b in range(a + 1, 3):
            p, q = taken[a], taken[b]
            assert not (p[0] < q[2] and q[0] < p[2] and p[1] < q[3] and q[1] < p[3])


def test_the_legends_name_every_mark():
    from occbench.report.draw import legend
    from occbench.report.overlays import LEGEND, draw_overlay
    from occbench.report.primitives import legend_block
    from occbench.trackers.records import Detections

    texts = " ".join(t for t, _, _ in legend(["ellipses", "parts"], gt=True, graph=True))
    for word in ("ground truth", "dashed", "tentative", "ellipse", "v/o/s", "PBM", "edge"):
        assert word in texts
    assert "ground truth" not in " ".join(t for t, _, _ in legend(["boxes"], gt=False))
    dets = Detections(np.array([[40.0, 30, 20, 50], [42.0, 31, 20, 50]]), np.array([0.9, 0.8]))
    out = draw_overlay(_frame(), np.zeros((120, 160), bool), dets, None, None)
    band = legend_block(LEGEND, 160)
    assert out.shape == (120 + band.shape[0], 160, 3) and (out[120:] == band).all()
    assert {t for t, _, _ in LEGEND} >= {"foreground (tint)", "blob", "detection, score",
                                         "ground truth", "head"}
