"""Who may start a PBM target (occbench.trackers.layered.starts): every free candidate, or only the
hand-initialised one of the single-target protocol (PBM 3)."""

from __future__ import annotations

import numpy as np
import pbm_scenes as S

from occbench.trackers.layered import GivenTargetOnly, PBMTracker
from occbench.trackers.records import Detections


def _two_walkers() -> S.Scene:
    L = 20
    return S.Scene(320, 240, [
        S.Person(1, S.walk(L, (30, 60), (2.0, 0.0), (30, 105)), shirt=(40, 40, 200),
                 pants=(90, 60, 30)),
        S.Person(2, S.walk(L, (220, 60), (-1.0, 0.0), (32, 110)), shirt=(40, 170, 40),
                 pants=(50, 50, 50), hair=(30, 90, 150)),
    ], seed=5)


def _ids(tracker: PBMTracker, scene: S.Scene, first_only: int | None) -> set[int]:
    """Ids reported over the scene; on frame 0 the only detection is person ``first_only``'s
    box when given (the protocol's hand initialisation), else every person's."""
    ids: set[int] = set()
    for k in range(scene.length):
        img, lab = scene.render(k)
        det = scene.detections(k, lab)
        if k == 0 and first_only is not None:
            det = Detections(scene.gt(k)[first_only][None], np.ones(1))
        ids |= {t.id for t in tracker.update(img, det, lab) if t.state.reported}
    return ids


def test_given_target_only_follows_the_one_started_target_and_starts_no_other():
    scene = _two_walkers()
    tracker = PBMTracker(starts=GivenTargetOnly())
    assert _ids(tracker, scene, first_only=2) == {1}
    assert len(tracker.targets) == 1
    # the one target is person 2: its last box overlaps person 2's, not person 1's
    box = tracker.targets.boxes[0]
    last = scene.gt(scene.length - 1)
    assert abs(box[0] - last[2][0]) < 8 and abs(box[0] - last[1][0]) > 50


def test_default_starts_every_person_in_view():
    scene = _two_walkers()
    assert _ids(PBMTracker(), scene, first_only=2) == {1, 2}
    assert GivenTargetOnly().may_start(1, 0) and not GivenTargetOnly().may_start(1, 1)
    assert not GivenTargetOnly().may_start(2, 0)
