"""``adaptations.fold_twins`` (``stacked.FoldTwins``): a younger target standing on an older
one's box for N frames, never found with it but in turn with it, and without foreground of its
own, is ended when the older one is found; a pair found together once, a younger target never
found (a person hidden behind), a younger box holding a person of its own, or a frame without a
mask keep both (``stacked.KeepStacked``: the paper's life cycle)."""

from types import SimpleNamespace

import numpy as np

from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.rules import LastBox, build_rules
from occbench.trackers.layered.stacked import FoldTwins, KeepStacked, own_foreground

BOX = [40.0, 20.0, 20.0, 60.0]  # xywh of the one person both targets stand on


def _mask(*boxes) -> np.ndarray:
    fg = np.zeros((120, 160), dtype=bool)
    for x, y, w, h in boxes:
        fg[int(y):int(y + h), int(x):int(x + w)] = True
    return fg


def _pair(found_old: bool, found_young: bool, young=BOX) -> SimpleNamespace:
    """Targets id 2 (older) and id 5 (younger), both confirmed, at their boxes."""
    dof = np.array([[*BOX[:2], 0.0, 0.0, *BOX[2:]], [*young[:2], 0.0, 0.0, *young[2:]]])
    return SimpleNamespace(id=np.array([5, 2]), dof=dof[::-1].copy(),
                           confirmed=np.array([True, True]),
                           misses=np.array([0 if found_young else 1, 0 if found_old else 1]))


def _fold(rule, frames, fg, young=BOX) -> list[list[bool]]:
    """Per frame, the (2,) folded flags (rows: the younger id 5, then the older id 2)."""
    runs: dict = {}
    return [rule.folded(_pair(old, new, young), LastBox(), fg, 5, runs).tolist()
            for old, new in frames]


TURNS = [(True, False), (False, True), (True, False), (False, True), (True, False)]


def test_twins_taking_one_detection_in_turn_fold_into_the_older():
    got = _fold(FoldTwins(3, 0.1), TURNS, _mask(BOX))
    # evidence 1, 2 frames: kept; 3rd frame, the older found: the younger (row 0) ends
    assert got[:2] == [[False, False]] * 2
    assert got[2] == [True, False]
    # with 4 frames the 3rd is too early and the 4th has the younger found: the 5th folds
    assert _fold(FoldTwins(4, 0.1), TURNS, _mask(BOX))[2:] == [[False, False], [False, False],
                                                              [True, False]]


def test_two_people_are_kept():
    fg = _mask(BOX)
    # found together once: the run restarts, never reaching 3 frames
    together = [(True, False), (False, True), (True, True), (True, False), (False, True)]
    assert not np.any(_fold(FoldTwins(3, 0.1), together, fg))
    # a younger box (IoU 0.6 with the older) holding a person of its own beside the older
    young = [45.0, 20.0, 20.0, 60.0]
    assert own_foreground(np.array(young), np.array(BOX), _mask(BOX, young)) > 0.2
    assert not np.any(_fold(FoldTwins(3, 0.1), TURNS, _mask(BOX, young), young))
    assert np.any(_fold(FoldTwins(3, 0.1), TURNS, _mask(BOX), young))  # ... but not alone
    # a person wholly hidden behind the older one's: never found while covered, kept
    hidden = [(True, False)] * 6
    assert not np.any(_fold(FoldTwins(3, 0.1), hidden, fg))
    # no mask: no evidence of the last half, both kept
    assert not np.any(_fold(FoldTwins(3, 0.1), TURNS, None))


def test_paper_and_the_default_keep_every_target():
    assert not np.any(_fold(KeepStacked(), TURNS, _mask(BOX)))
    paper = Adaptations.paper()
    assert isinstance(build_rules(paper).twins, KeepStacked)
    assert isinstance(build_rules(Adaptations()).twins, KeepStacked)  # off until measured
    on = Adaptations(fold_twins=3, fold_twins_own=0.1)
    assert isinstance(build_rules(on).twins, FoldTwins)
    assert {"fold_twins", "fold_twins_own"} <= set(on.changed()) and paper.changed() == []
