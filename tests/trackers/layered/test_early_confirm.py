"""``adaptations.early_confirm`` (``rules.IsolatedEarly``): a new target overlapping no other
live target is confirmed after ``hits`` matches, others after ``life_cycle.min_hits``."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.trackers.layered import Adaptations
from occbench.trackers.layered.dynamics import Gate
from occbench.trackers.layered.confirmation import InARow, IsolatedEarly
from occbench.trackers.layered.rules import build_rules
from occbench.trackers.layered.targets import Targets


def _targets(boxes, hits) -> Targets:
    tg = Targets(Gate(3.0, 0.5, 2.0, 1.15, 6.0), (0.5, 0.2, 0.5), (0.2, 0.02, 0.5), 4, 3, 4)
    tg.dof = np.array([[x, y, x + w / 2, y + h / 2, w, h] for x, y, w, h in boxes], dtype=float)
    tg.hits, tg.confirmed = np.array(hits), np.zeros(len(hits), dtype=bool)
    return tg


def test_a_lone_newcomer_is_confirmed_early_a_fragment_is_not():
    # 0: alone, second match; 1: second match inside 2's box (a fragment); 2: first match
    boxes = [(10.0, 10, 20, 60), (100.0, 10, 20, 30), (100.0, 10, 20, 60)]
    rows = np.array([0, 1, 2])
    off = _targets(boxes, [2, 2, 1])
    InARow().confirm(off, rows, 3)
    assert off.confirmed.tolist() == [False, False, False]  # three in a row needed
    on = _targets(boxes, [2, 2, 1])
    IsolatedEarly(2).confirm(on, rows, 3)
    assert on.confirmed.tolist() == [True, False, False]
    # min_hits still confirms the overlapping one in the end
    on.hits[1] = 3
    IsolatedEarly(2).confirm(on, rows, 3)
    assert on.confirmed.tolist() == [True, True, False]


def test_early_confirm_is_off_in_paper_mode_and_checked():
    assert build_rules(Adaptations()).confirmation == IsolatedEarly(1)  # on: at birth
    assert isinstance(build_rules(Adaptations(early_confirm=0)).confirmation, InARow)
    assert Adaptations.paper().early_confirm == 0
    with pytest.raises(ValueError, match="early_confirm"):
        Adaptations(early_confirm=-1)


def test_with_one_a_lone_newcomer_is_confirmed_at_birth():
    # 0: an older target; 1: born alone; 2 and 3: born this frame on one another
    boxes = [(10.0, 10, 20, 60), (100.0, 10, 20, 60), (200.0, 10, 20, 60), (205.0, 10, 20, 60)]
    born = np.array([1, 2, 3])
    two = _targets(boxes, [5, 1, 1, 1])
    IsolatedEarly(2).confirm_born(two, born, (640, 480))
    InARow().confirm_born(two, born, (640, 480))
    assert two.confirmed.tolist() == [False, False, False, False]  # first match: tentative
    one = _targets(boxes, [5, 1, 1, 1])
    IsolatedEarly(1).confirm_born(one, born, (640, 480))
    assert one.confirmed.tolist() == [False, True, False, False]


def test_border_birth_waits_keeps_a_newcomer_at_an_image_border_tentative():
    # 0: born at the left border (a person stepping in); 1: born inside; both alone
    boxes = [(0.0, 10, 12, 60), (100.0, 10, 20, 60)]
    born = np.array([0, 1])
    one = _targets(boxes, [1, 1])
    IsolatedEarly(1).confirm_born(one, born, (640, 480))
    assert one.confirmed.tolist() == [True, True]
    waits = _targets(boxes, [1, 1])
    IsolatedEarly(1, border_waits=True).confirm_born(waits, born, (640, 480))
    assert waits.confirmed.tolist() == [False, True]
    assert build_rules(Adaptations(border_birth_waits=True)).confirmation.border_waits
    assert Adaptations.paper().border_birth_waits is False
