"""NoisyGroundTruth and PublicDetections: exact cases, statistics, determinism, bad input."""

from __future__ import annotations

from pathlib import Path

import motmetrics
import numpy as np
import pytest
from hydra import compose, initialize_config_dir
from hydra.utils import instantiate

from occbench.datasets.base import GroundTruth, Sequence
from occbench.datasets.caviar import load_caviar
from occbench.datasets.mot import ground_truth_from_table, load_mot
from occbench.io.mot import MotTable, read_mot
from occbench.config.paths import SHIPPED_DATA
from occbench.sources.annotations import NoisyGroundTruth, PublicDetections
from occbench.trackers.geometry import clip_boxes, iou_matrix
from occbench.trackers.records import Detections, SequenceInfo

ROOT = Path(__file__).resolve().parents[3]
DATA = SHIPPED_DATA  # the sample shipped in datasets/
CAVIAR = DATA / "CAVIAR-OneLeaveShop1cor"
PETS = DATA / "trajectories" / "PETS09-S2L1"
MM_DATA = Path(motmetrics.__file__).parent / "data"


class TableSequence(Sequence):
    """A box-only sequence around a MotTable (no pixels)."""

    def __init__(self, name: str, table: MotTable | None, width: int = 640, height: int = 480,
                 length: int | None = None, occluded: np.ndarray | None = None,
                 det: MotTable | None = None) -> None:
        length = length or (int(table.frames.max()) if table is not None and len(table) else 1)
        self.info = SequenceInfo(name, width, height, 25.0, length)
        self.gt = None if table is None else GroundTruth(table, occluded)
        self.public_detections = det

    @property
    def has_pixels(self) -> bool:
        return False

    def frame(self, index: int) -> None:
        return None


def grid_table(frames: int = 50, per_row: int = 6, rows: int = 3, vis: float = np.nan) -> MotTable:
    """Well separated 30x80 people on a grid, every frame: frames * per_row * rows gt rows."""
    n = per_row * rows
    f = np.repeat(np.arange(1, frames + 1), n)
    ids = np.tile(np.arange(1, n + 1), frames)
    gx, gy = np.meshgrid(np.arange(per_row) * 100 + 20.0, np.arange(rows) * 140 + 30.0)
    xy = np.tile(np.c_[gx.ravel(), gy.ravel()], (frames, 1))
    boxes = np.c_[xy, np.full(len(f), 30.0), np.full(len(f), 80.0)]
    m = len(f)
    return MotTable(f, ids, boxes, np.ones(m), np.ones(m, dtype=np.int64), np.full(m, vis))


def sorted_rows(boxes: np.ndarray) -> np.ndarray:
    return boxes[np.lexsort(boxes.T[::-1])]


def run(source, seq: Sequence, order=None) -> dict[int, Detections]:
    source.start(seq)
    order = range(1, seq.info.length + 1) if order is None else order
    return {k: source.detect(k, None)[0] for k in order}


# ---------------------------------------------------------------- NoisyGroundTruth


@pytest.mark.parametrize("kwargs, name", [
    ({"miss_rate": 1.5}, "miss_rate"), ({"miss_rate": -0.1}, "miss_rate"),
    ({"jitter": -1}, "jitter"), ({"fp_rate": -0.5}, "fp_rate"), ({"seed": -3}, "seed"),
    ({"seed": 1.5}, "seed"), ({"min_visibility": 2}, "min_visibility"),
    ({"jitter": float("nan")}, "jitter"),
])
def test_noisy_gt_validates_arguments(kwargs, name):
    with pytest.raises(ValueError, match=name):
        NoisyGroundTruth(**kwargs)


def test_noiseless_detections_are_the_clipped_gt():
    t = MotTable(np.array([1, 1, 1, 2]), np.array([1, 2, 3, 1]),
                 np.array([[-10.0, 5, 30, 60], [600, 400, 80, 100], [100, 100, 20, 40],
                           [700, 10, 20, 40]]),  # the last lies outside the image
                 np.ones(4), np.full(4, -1), np.full(4, np.nan))
    seq = TableSequence("s", t, length=3)
    out = run(NoisyGroundTruth(), seq)
    assert np.array_equal(sorted_rows(out[1].boxes),
                          sorted_rows(np.array([[0.0, 5, 20, 60], [600, 400, 40, 80],
                                                [100, 100, 20, 40]])))
    assert out[1].scores.tolist() == [1.0, 1.0, 1.0]
    assert len(out[2]) == 0 and len(out[3]) == 0
    src = NoisyGroundTruth()
    src.start(seq)
    assert src.detect(1, None)[1] is None


def test_hidden_people_and_ignored_rows_are_not_detected():
    # visibility known: the threshold decides; NaN visibility: the occluded flag decides
    vis = np.array([1.0, 0.29, 0.3, np.nan, np.nan, 1.0])
    conf = np.array([1.0, 1, 1, 1, 1, 0])  # conf 0 = ignore
    occluded = np.array([False, False, False, True, False, False])
    t = MotTable(np.ones(6, dtype=np.int64), np.arange(1, 7),
                 np.c_[np.arange(6) * 60.0, np.full(6, 10.0), np.full(6, 30.0), np.full(6, 80.0)],
                 conf, np.ones(6, dtype=np.int64), vis)
    seq = TableSequence("v", t, occluded=occluded)
    lefts = sorted(run(NoisyGroundTruth(), seq)[1].boxes[:, 0].tolist())
    assert lefts == [0.0, 120.0, 240.0]  # rows 1, 3, 5
    lefts = sorted(run(NoisyGroundTruth(min_visibility=0.0), seq)[1].boxes[:, 0].tolist())
    assert lefts == [0.0, 60.0, 120.0, 240.0]  # the occluded label still hides row 4
    seq.gt.occluded = None
    lefts = sorted(run(NoisyGroundTruth(min_visibility=0.0), seq)[1].boxes[:, 0].tolist())
    assert lefts == [0.0, 60.0, 120.0, 180.0, 240.0]


def test_miss_rate_drops_the_expected_fraction():
    t = grid_table(frames=100)  # 1800 rows
    out = run(NoisyGroundTruth(miss_rate=0.3, seed=4), TableSequence("m", t))
    found = sum(len(d) for d in out.values())
    n, p = len(t), 0.7
    assert abs(found - n * p) < 5 * np.sqrt(n * p * (1 - p))
    assert sum(len(d) for d in run(NoisyGroundTruth(miss_rate=1.0), TableSequence("m", t)).values()) == 0


def test_jitter_has_the_requested_spread():
    t = grid_table(frames=60)
    seq = TableSequence("j", t)
    out = run(NoisyGroundTruth(jitter=0.05, seed=1), seq)
    dx, dw, dh = [], [], []
    idx = t.frame_index()
    for k, d in out.items():
        g = t.boxes[idx[k]]
        match = iou_matrix(d.boxes, g).argmax(axis=1)
        assert len(np.unique(match)) == len(g) == len(d)  # one detection per person
        gm = g[match]
        dx.append(((d.boxes[:, 0] + d.boxes[:, 2] / 2) - (gm[:, 0] + gm[:, 2] / 2)) / gm[:, 2])
        dw.append(d.boxes[:, 2] / gm[:, 2] - 1)
        dh.append(d.boxes[:, 3] / gm[:, 3] - 1)
    for v in (dx, dw, dh):
        v = np.concatenate(v)
        assert abs(v.mean()) < 0.005
        assert v.std() == pytest.approx(0.05, rel=0.1)


def test_false_positives_are_poisson_and_person_sized():
    t = grid_table(frames=400, per_row=1, rows=1)
    seq = TableSequence("f", t)
    out = run(NoisyGroundTruth(fp_rate=1.5, seed=2), seq)
    counts = np.array([int((d.scores < 1).sum()) for d in out.values()])
    assert abs(counts.mean() - 1.5) < 5 * np.sqrt(1.5 / len(counts))
    assert counts.var() == pytest.approx(1.5, rel=0.25)  # Poisson: variance = mean
    fp = np.concatenate([d.boxes[d.scores < 1] for d in out.values()])
    scores = np.concatenate([d.scores[d.scores < 1] for d in out.values()])
    assert ((scores >= 0.3) & (scores < 0.9)).all()
    assert (fp[:, 0] >= 0).all() and (fp[:, 0] + fp[:, 2] <= 640).all()
    assert (fp[:, 1] >= 0).all() and (fp[:, 1] + fp[:, 3] <= 480).all()
    assert ((fp[:, 3] >= 0.8 * 80 - 1e-9) & (fp[:, 3] <= 1.2 * 80 + 1e-9)).all()
    assert np.allclose(fp[:, 2] / fp[:, 3], 30 / 80)
    assert fp[:, 0].std() > 100  # spread over the image, not stuck in a corner
    true = [d.boxes[d.scores == 1] for d in out.values()]
    assert all(np.array_equal(b, t.boxes[:1]) for b in true)


def test_same_seed_same_bytes_whatever_the_access_order():
    t = grid_table(frames=20)
    kw = {"miss_rate": 0.2, "jitter": 0.1, "fp_rate": 2.0, "seed": 7}
    a = run(NoisyGroundTruth(**kw), TableSequence("A", t))
    rev = run(NoisyGroundTruth(**kw), TableSequence("A", t), order=range(20, 0, -1))
    src = NoisyGroundTruth(**kw)  # another sequence visited first, frames shuffled
    run(src, TableSequence("B", t))
    shuffled = run(src, TableSequence("A", t), order=np.random.default_rng(0).permutation(20) + 1)
    for k in range(1, 21):
        for other in (rev, shuffled):
            assert a[k].boxes.tobytes() == other[k].boxes.tobytes()
            assert a[k].scores.tobytes() == other[k].scores.tobytes()
    b = run(NoisyGroundTruth(**kw), TableSequence("B", t))
    c = run(NoisyGroundTruth(**{**kw, "seed": 8}), TableSequence("A", t))
    assert a[1].boxes.tobytes() != b[1].boxes.tobytes()  # seeded per sequence name
    assert a[1].boxes.tobytes() != c[1].boxes.tobytes()


def test_output_order_does_not_reveal_identities():
    t = grid_table(frames=10)
    out = run(NoisyGroundTruth(), TableSequence("o", t))
    orders = {tuple(np.lexsort(d.boxes.T[::-1])) for d in out.values()}
    assert len(orders) > 1


def test_noisy_gt_needs_gt_and_start():
    with pytest.raises(ValueError, match="'nogt' has no ground truth"):
        NoisyGroundTruth().start(TableSequence("nogt", None))
    with pytest.raises(RuntimeError, match="before start"):
        NoisyGroundTruth().detect(1, None)


def test_noiseless_on_caviar_skips_only_occluded_people():
    (seq,) = load_caviar(CAVIAR)
    out = run(NoisyGroundTruth(), seq)
    assert sum(len(d) for d in out.values()) == 1401 - 22
    t = seq.gt.table
    for k, d in out.items():
        rows = seq.gt.rows_of(k)
        rows = rows[~seq.gt.occluded[rows]]
        want = clip_boxes(t.boxes[rows], 384, 288)
        assert np.array_equal(sorted_rows(d.boxes), sorted_rows(want))


@pytest.mark.skipif(not (MM_DATA / "TUD-Stadtmitte" / "gt.txt").is_file(),
                    reason="motmetrics' bundled TUD-Stadtmitte data absent")
def test_noiseless_gt_scores_perfectly_with_motmetrics():
    gt = read_mot(MM_DATA / "TUD-Stadtmitte" / "gt.txt", gt=True)
    seq = TableSequence("TUD-Stadtmitte", gt, width=640, height=480)
    seq.gt = ground_truth_from_table(gt)
    out = run(NoisyGroundTruth(), seq)
    acc = motmetrics.MOTAccumulator(auto_id=True)
    idx = gt.frame_index()
    for k in range(1, seq.info.length + 1):
        g = gt.boxes[idx.get(k, [])]
        d = out[k].boxes
        iou = iou_matrix(clip_boxes(g, 640, 480), d)  # (motmetrics 1.4's iou_matrix needs numpy 1)
        acc.update(gt.ids[idx.get(k, [])], np.arange(len(d)), np.where(iou >= 0.5, 1 - iou, np.nan))
    s = motmetrics.metrics.create().compute(acc, metrics=["num_misses", "num_false_positives"])
    assert int(s["num_misses"].iloc[0]) == 0 and int(s["num_false_positives"].iloc[0]) == 0


# ---------------------------------------------------------------- PublicDetections


def test_public_detections_filter_by_score():
    det = MotTable(np.array([1, 1, 3]), np.full(3, -1), np.array([[1.0, 2, 3, 4], [5, 6, 7, 8],
                                                                    [9, 9, 9, 9]]),
                   np.array([0.9, 0.2, 0.6]), np.full(3, -1), np.full(3, np.nan))
    seq = TableSequence("p", None, length=3, det=det)
    out = run(PublicDetections(), seq)
    assert out[1].boxes.tolist() == [[1, 2, 3, 4], [5, 6, 7, 8]] and out[1].scores.tolist() == [0.9, 0.2]
    assert len(out[2]) == 0 and out[3].scores.tolist() == [0.6]
    out = run(PublicDetections(min_score=0.5), seq)
    assert out[1].boxes.tolist() == [[1, 2, 3, 4]] and len(out[3]) == 1
    src = PublicDetections()
    src.start(seq)
    assert src.detect(1, None)[1] is None


def test_public_detections_bad_input():
    with pytest.raises(ValueError, match="'nodet' has no public detections"):
        PublicDetections().start(TableSequence("nodet", None))
    with pytest.raises(RuntimeError, match="before start"):
        PublicDetections().detect(1, None)
    with pytest.raises(ValueError, match="min_score"):
        PublicDetections(min_score=float("nan"))


def test_public_detections_from_an_empty_det_file(tmp_path):
    seq_dir = tmp_path / "S"
    (seq_dir / "det").mkdir(parents=True)
    (seq_dir / "det" / "det.txt").write_text("")
    (seq_dir / "seqinfo.ini").write_text(
        "[Sequence]\nname=S\nframeRate=5\nseqLength=3\nimWidth=10\nimHeight=10\n")
    (seq,) = load_mot(tmp_path)
    out = run(PublicDetections(), seq)
    assert [len(d) for d in out.values()] == [0, 0, 0]


def test_public_detections_of_pets_match_the_file():
    (seq,) = load_mot(PETS)
    out = run(PublicDetections(min_score=0.9), seq)
    lines = [ln.split(",") for ln in (PETS / "det" / "det.txt").read_text().split()]
    first = np.array([[float(v) for v in ln[2:7]] for ln in lines if ln[0] == "1"])
    first = first[first[:, 4] >= 0.9]
    d = out[1]
    assert np.allclose(sorted_rows(d.boxes), sorted_rows(first[:, :4] - [1, 1, 0, 0]))
    assert sorted(d.scores.tolist()) == sorted(first[:, 4].tolist())
    assert min(s.min() for s in (o.scores for o in out.values()) if len(s)) >= 0.9


# ---------------------------------------------------------------- configs


@pytest.mark.parametrize("name, cls", [("noisy_gt", NoisyGroundTruth), ("public", PublicDetections)])
def test_detector_configs_instantiate(name, cls):
    with initialize_config_dir(config_dir=str(ROOT / "conf"), version_base=None):
        cfg = compose("config", overrides=["dataset=mot", f"detector={name}", "seed=11"])
    src = instantiate(cfg.detector)
    assert isinstance(src, cls)
    if name == "noisy_gt":
        assert (src.seed, src.miss_rate, src.jitter, src.fp_rate, src.min_visibility) == (
            11, 0.0, 0.0, 0.0, 0.3)
