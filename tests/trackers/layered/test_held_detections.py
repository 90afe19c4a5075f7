"""``adaptations.held_detections``: a detection lying in a foreground blob is one more head
of the blob's region, so a blob holding a person below another (one profile peak) is a
merge, not one target grown to the blob's span (issue 35; docs/adaptations.md)."""

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


def _blob_rows(held) -> np.ndarray:
    fg, det = _stacked_people()
    cand = CandidateFinder(CandidateParams(), held=held).find(fg, det)
    assert cand.blob.sum() == 1  # the far person's head is the blob's only candidate
    assert abs(cand.head[cand.blob][0, 1] - 10) <= 2
    return cand.heads_in_region[cand.blob]


def test_a_detection_in_the_blob_counts_as_a_head_of_its_region():
    assert _blob_rows(HeldDetections(0.5)).tolist() == [2]
    assert _blob_rows(NoHeldDetections()).tolist() == [1]  # the paper's count: a lone head
    assert _blob_rows(None).tolist() == [1]


def test_a_detection_mostly_outside_the_blob_adds_no_head():
    fg, _ = _stacked_people()
    outside = Detections(boxes=np.array([[18.0, 40.0, 23.0, 71.0], [50.0, 40.0, 25.0, 71.0]]),
                         scores=np.ones(2))
    cand = CandidateFinder(CandidateParams(), held=HeldDetections(0.5)).find(fg, outside)
    assert cand.heads_in_region[cand.blob].tolist() == [2]


def test_off_in_paper_mode_and_by_default():
    assert Adaptations().held_detections is False
    assert Adaptations.paper().held_detections is False
