"""pbm's ``adaptations.merge_stacked`` (``rules.MergeStacked``): two targets on one person
taking its one detection in turn are merged; a person hidden behind another is not."""

from types import SimpleNamespace

import numpy as np

from trackers.layered.params import Adaptations
from trackers.layered.rules import KeepStacked, MergeStacked, build_rules

BOX = np.array([100.0, 50.0, 40.0, 100.0])


def _run(found_seq, hits=(10, 4), frames=3):
    """Two targets (ids 1, 2) reported at the same box; found_seq: per frame (found 1,
    found 2). Returns the frame (0-based) and the row the rule ended, or None."""
    rule = MergeStacked(frames)
    boxes = np.vstack([BOX, BOX + [2.0, 1.0, 0.0, 0.0]])
    for k, (f1, f2) in enumerate(found_seq):
        targets = SimpleNamespace(id=np.array([1, 2]), hits=np.array(hits),
                                  misses=np.array([0 if f1 else 1, 0 if f2 else 1]))
        end = rule.ended(targets, boxes, np.array([0, 1]))
        if len(end):
            return k, end.tolist()
    return None


def test_one_detection_taken_in_turn_is_merged_into_the_longer_record():
    # frames 0-2: the detection goes to 1, then 2, then 1: at min_hits (3) frames, 2 ends
    assert _run([(True, False), (False, True), (True, False)]) == (2, [1])
    # the target with more matches is kept whichever is found now
    assert _run([(True, False), (False, True), (False, True)], hits=(3, 9)) == (2, [0])


def test_person_hidden_behind_another_is_never_ended():
    # the one in front takes its detection every frame; the hidden one is never found
    assert _run([(True, False)] * 20) is None


def test_two_people_found_together_once_are_never_merged():
    seq = [(True, True), (True, False), (False, True), (True, False), (False, True)] * 3
    assert _run(seq) is None


def test_boxes_apart_are_never_merged():
    rule = MergeStacked(3)
    boxes = np.vstack([BOX, BOX + [30.0, 0.0, 0.0, 0.0]])  # IoU 0.14
    for k in range(6):
        targets = SimpleNamespace(id=np.array([1, 2]), hits=np.array([5, 5]),
                                  misses=np.array([k % 2, 1 - k % 2]))
        assert not len(rule.ended(targets, boxes, np.array([0, 1])))


def test_off_by_default_and_in_paper_mode():
    assert isinstance(build_rules(Adaptations(), 3).stacked, KeepStacked)
    assert isinstance(build_rules(Adaptations(merge_stacked=True), 3).stacked, MergeStacked)
