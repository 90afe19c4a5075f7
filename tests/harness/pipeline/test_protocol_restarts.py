"""PBM's single-target protocol with the colour comparators' loss rule: a person hidden
behind an occluder is lost by its follower, which restarts on the person's return under a
new reported id, and PBM Table 1's columns count it (over-segmentation, IDs per track)."""

import numpy as np
import pytest

from occbench.datasets.base import GroundTruth, Sequence
from occbench.io.mot import MotTable
from occbench.metrics.paper import paper_metrics
from occbench.pipeline.protocols import run_single_target
from occbench.trackers.comparators import ColourParticleFilter, MeanShiftTracker, NeverLost, SimilarityBelow
from occbench.trackers.records import Detections, SequenceInfo

W, H, N = 200, 120, 30
HIDDEN = range(11, 21)  # 1-based frames on which the red person is behind a grey occluder


def _box(k: int) -> np.ndarray:
    return np.array([20 + 3 * k, 40, 16, 32], dtype=np.float64)


class _Hidden(Sequence):
    """One red person walking right on grey noise, hidden on HIDDEN (labelled throughout)."""

    def __init__(self) -> None:
        self.info = SequenceInfo("hidden", W, H, 25.0, N)
        ks = np.arange(1, N + 1)
        self.gt = GroundTruth(MotTable(ks, np.ones(N, np.int64), np.array([_box(k) for k in ks]),
                                       np.ones(N), np.full(N, -1), np.full(N, np.nan)))

    def frame(self, index: int) -> np.ndarray:
        img = np.random.default_rng(index).integers(90, 110, (H, W, 3), dtype=np.uint8)
        if index not in HIDDEN:
            x, y, w, h = _box(index).astype(int)
            img[y:y + h, x:x + w] = (30, 30, 200)
        return img


class _Visible:
    """Detections: the person's box when it is not hidden."""

    def start(self, sequence) -> None:
        pass

    def detect(self, index, frame):
        if index in HIDDEN:
            return Detections.empty(), None
        return Detections(_box(index)[None], np.ones(1)), None


@pytest.mark.parametrize("make", [MeanShiftTracker, ColourParticleFilter])
def test_a_lost_follower_restarts_under_a_new_id(make):
    builders = {"lost": lambda: make(max_targets=1, loss=SimilarityBelow(0.8, 3)),
                "never": lambda: make(max_targets=1, loss=NeverLost())}
    out = run_single_target(builders, _Hidden(), _Visible(), foreground="none")
    lost, never = out["lost"].table, out["never"].table
    assert set(never.ids.tolist()) == {1} and len(never.frames) == N
    first = lost.frames[lost.ids == 1]
    assert first.min() == 1 and first.max() == HIDDEN.start + 1  # lost on its 3rd miss
    restart = lost.frames[lost.ids == 2]
    assert restart.min() == HIDDEN.stop and restart.max() == N  # back on its return
    assert set(lost.ids.tolist()) == {1, 2}
    m = paper_metrics(_Hidden().gt.table, lost)
    assert m["PBM_Over"] == 1 and m["PBM_IDs/traj"] == 2


@pytest.mark.parametrize("experiment", ["pbm_table1", "pbm_segmentation"])
def test_the_tables_build_mean_shift_with_its_loss_rule_and_the_filter_with_the_old_one(
        experiment):
    from occbench.config.build import build_tracker, compose_config
    from occbench.trackers.comparators import AnyDetection, MostSimilar

    cfg = compose_config([f"+experiment={experiment}"])
    ms = build_tracker("meanshift", cfg.tracker.meanshift)
    pf = build_tracker("particle_filter", cfg.tracker.particle_filter)
    assert (ms.max_targets, ms.loss, ms.restart) == (1, SimilarityBelow(0.8, 5), MostSimilar(0.8))
    assert (pf.max_targets, pf.loss, pf.restart) == (1, SimilarityBelow(0.5, 11), AnyDetection())
