"""Active-basis shape model (trackers/frontend/active_basis.py): the fast sum-max score
equals the plain whole-map computation, the template prefers rendered people to rendered
background, learning is deterministic, and the verifier config composes and builds."""

from __future__ import annotations

import numpy as np
import pytest
from hydra.utils import instantiate

from occbench.datasets.synthetic import load_scenario
from occbench.fit.active_basis import collect, load, save
from occbench.config.build import compose_config
from occbench.trackers.frontend.active_basis import ActiveBasis, GaborBank, crop_patch
from occbench.trackers.frontend.active_basis_learn import learn
from occbench.trackers.frontend.detectors import SilhouetteDetector
from occbench.trackers.frontend.shape_verifier import ShapeVerifier

SIZE = (48, 20)
PAD = 2 + GaborBank().ksize // 2


@pytest.fixture(scope="module")
def scene_patches():
    """Person patches (with mirrors) and background patches of a small rendered scene."""
    seq = load_scenario("crossing", seed=11, width=384, height=288, length=40)
    return collect([seq], SIZE, PAD, step=4, min_height=30, n_background=30,
                   rng=np.random.default_rng(0), exact=True)


def test_fast_score_equals_whole_maps(scene_patches):
    people, background = scene_patches
    t = load()  # the shipped template
    rng = np.random.default_rng(1)
    for p in [*people[:4], *background[:4], (rng.random(t.patch_shape) * 255).astype(np.float32)]:
        assert t.score(p) == pytest.approx(t.score_maps(p), abs=1e-3)


def test_shipped_template_prefers_people_to_background(scene_patches):
    people, background = scene_patches
    t = load()
    sp = np.array([t.score(p) for p in people])
    sb = np.array([t.score(b) for b in background])
    assert len(sp) >= 10 and len(sb) == 30
    assert np.median(sp) > np.percentile(sb, 90)
    # one person against one background patch of its frame: the person wins in most pairs
    assert (sp[: len(sb)][:, None] > sb[None, :]).mean() > 0.8


def test_learning_is_deterministic_and_learns_a_person(scene_patches, tmp_path):
    people, background = scene_patches
    a = learn(people[::2], background[:15], size=SIZE, n_elements=8)
    b = learn(people[::2], background[:15], size=SIZE, n_elements=8)
    save(a, tmp_path / "a.npz")
    save(b, tmp_path / "b.npz")
    assert (tmp_path / "a.npz").read_bytes() == (tmp_path / "b.npz").read_bytes()
    back = load(tmp_path / "a.npz")
    assert np.array_equal(back.rows, a.rows) and np.allclose(back.lam, a.lam)
    assert (a.lam > 0).all()  # elements fire more on people than on background (eq. 16)
    # held-out people (the mirror halves) score above held-out background
    held_p = np.array([a.score(p) for p in people[1::2]])
    held_b = np.array([a.score(p) for p in background[15:]])
    assert np.median(held_p) > np.median(held_b)


def test_verifier_drops_background_boxes_and_keeps_people():
    seq = load_scenario("crossing", seed=11, width=384, height=288, length=40)
    k = 20
    frame = seq.frame(k)
    rows = seq.gt.rows_of(k)
    people = seq.gt.table.boxes[rows]
    people = people[(people[:, 3] >= 40) & (seq.gt.table.visibility[rows] > 0.95)]
    assert len(people)
    empty = np.array([[5.0, 200.0, 30.0, 72.0]])  # floor and wall, nobody there
    assert seq.foreground(k)[200:272, 5:35].sum() == 0
    v = ShapeVerifier(load(), threshold=8.0)
    boxes, _ = v(frame, np.vstack([people, empty]), np.ones(len(people) + 1))
    assert len(boxes) >= 1 and not np.any(np.all(boxes == empty[0], axis=1))


def test_crop_patch_shape_and_border():
    img = np.full((50, 60, 3), 100, np.uint8)
    p = crop_patch(img, (-10, -10, 20, 40), SIZE, PAD)  # half outside: replicated border
    assert p.shape == (SIZE[0] + 2 * PAD, SIZE[1] + 2 * PAD) and p.dtype == np.float32
    assert np.allclose(p, 100)


def test_bad_inputs_are_named(tmp_path):
    with pytest.raises(FileNotFoundError, match="nothere.npz"):
        load(tmp_path / "nothere.npz")
    with pytest.raises(ValueError, match="verifier.split_width"):
        ShapeVerifier(load(), split_width=0.5)
    with pytest.raises(ValueError, match="verifier.propose_fill"):
        ShapeVerifier(load(), propose_fill=float("nan"))
    with pytest.raises(ValueError, match="bank.ksize"):
        GaborBank(ksize=10)
    with pytest.raises(ValueError, match="bank.n_orient"):
        GaborBank(n_orient=1)
    with pytest.raises(TypeError, match="template"):
        ShapeVerifier("not a template")  # type: ignore[arg-type]
    t = load()
    with pytest.raises(ValueError, match="patch must be"):
        t.score(np.zeros((10, 10), np.float32))
    with pytest.raises(ValueError, match="outside the template box"):
        ActiveBasis(SIZE, [60], [0], [0], [1.0], [0.0])


def test_silhouette_shape_config_composes_and_builds():
    cfg = compose_config(["detector=silhouette_shape", "dataset=caviar"])
    source = instantiate(cfg.detector, _convert_="all")
    det = source.detector
    assert isinstance(det, SilhouetteDetector)
    assert isinstance(det.verifier, ShapeVerifier) and isinstance(det.verifier.template, ActiveBasis)
    plain = instantiate(compose_config(["detector=silhouette", "dataset=caviar"]).detector)
    assert plain.detector.verifier is None  # off by default


def test_propose_finds_a_person_on_unexplained_foreground():
    from occbench.trackers.geometry import iou_matrix

    seq = load_scenario("crossing", seed=11, width=384, height=288, length=40)
    k = 20
    frame, labels = seq.frame(k), seq.foreground(k)
    rows = seq.gt.rows_of(k)
    boxes = seq.gt.table.boxes[rows]
    j = int(np.argmax(boxes[:, 3] * (seq.gt.table.visibility[rows] > 0.95)))
    pid = seq.gt.table.ids[rows[j]]
    vacant = labels == pid
    ys, xs = np.nonzero(vacant)
    tight = np.array([xs.min(), ys.min(), xs.max() - xs.min() + 1, ys.max() - ys.min() + 1], float)
    v = ShapeVerifier(load(), threshold=None, propose_above=8.0)
    found, scores = v.propose(frame, vacant, lambda top: (tight[2], tight[3]))
    assert len(found) == 1 and scores[0] >= 8.0
    assert iou_matrix(found, tight[None])[0, 0] > 0.7
    # a blob of floor (no person's edges) is not proposed; nothing without propose_above
    floor = np.zeros_like(vacant)
    floor[200:272, 5:35] = True
    assert len(v.propose(frame, floor, lambda top: (30.0, 72.0))[0]) == 0
    assert len(ShapeVerifier(load()).propose(frame, vacant, lambda top: (tight[2], tight[3]))[0]) == 0


def test_silhouette_detector_with_the_verifier_runs_on_a_scene():
    cfg = compose_config(["detector=silhouette_shape", "dataset=synthetic", "dataset.scenarios=[crossing]",
                          "dataset.length=30", "dataset.width=384", "dataset.height=288",
                          "detector.detector.calibration_frames=30"])
    seq = next(iter(instantiate(cfg.dataset)))
    source = instantiate(cfg.detector, _convert_="all")
    source.start(seq)
    n = 0
    for k in (10, 20, 30):
        dets, fg = source.detect(k, seq.frame(k))
        assert dets.boxes.shape[1] == 4 and np.isfinite(dets.boxes).all()
        assert ((dets.scores >= 0) & (dets.scores <= 1)).all() and fg.shape == (288, 384)
        n += len(dets.boxes)
    assert n >= 1
