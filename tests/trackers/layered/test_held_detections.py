"""``adaptations.held_detections``: a foreground blob holding a detection whose head is
none of the blob's peaks (a person below another) is never one target grown to the blob's
span (``lone_growth``); its heads stay its own (issue 35; docs/adaptations.md)."""

import numpy as np

from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.candidates import CandidateFinder, HeldDetections, NoHeldDetections
from occbench.trackers.layered.params import CandidateParams
from occbench.trackers.records import Detections


def _stacked_people() -> tuple[np.ndarray, Detections]:
    """A far person (no detection) standing above a near one (detected): one blob, whose
    top profile has one peak, the far person's head."""
    fg = np.zeros((140, 80), dtype=bool)
    fg[10:60, 20:36] = True  # far person, head at row 10
    fg[40:111, 18:41] = True  # near person, its head hidden in the profile by the far one
    return fg, Detections(boxes=np.array([[18.0, 40.0, 23.0, 71.0]]), scores=np.ones(1))


def _blob(held, det: Detections | None = None) -> tuple[list, list]:
    fg, stacked = _stacked_people()
    cand = CandidateFinder(CandidateParams(), held=held).find(fg, stacked if det is None else det)
    assert cand.blob.sum() == 1  # the far person's head is the blob's only candidate
    assert abs(cand.head[cand.blob][0, 1] - 10) <= 2
    held_rows = np.zeros(len(cand), dtype=np.int64) if cand.held is None else cand.held
    return cand.heads_in_region[cand.blob].tolist(), held_rows[cand.blob].tolist()


def test_a_detection_in_the_blob_is_held_and_its_heads_stay_the_blobs_own():
    assert _blob(HeldDetections(0.5)) == ([1], [1])
    assert _blob(NoHeldDetections()) == ([1], [0])  # the paper's count: a lone head
    assert _blob(None) == ([1], [0])


def test_a_detection_mostly_outside_the_blob_is_not_held():
    two = Detections(boxes=np.array([[18.0, 40.0, 23.0, 71.0], [50.0, 40.0, 25.0, 71.0]]),
                     scores=np.ones(2))
    assert _blob(HeldDetections(0.5), two) == ([1], [1])


def test_off_in_paper_mode_and_by_default():
    assert Adaptations().held_detections is False
    assert Adaptations.paper().held_detections is False
