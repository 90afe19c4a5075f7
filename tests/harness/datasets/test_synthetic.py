"""The built-in synthetic scenes: determinism, ground truth from the rendered masks, real
occlusions in the occlusion presets, painting order, replay of MOT files, configs."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from occbench.datasets.synthetic import (
    DEFAULT_SCENARIOS,
    SCENARIOS,
    SyntheticSequence,
    draw_person,
    load_replay,
    load_scenario,
    load_suite,
)
from occbench.io.mot import read_mot

ROOT = Path(__file__).resolve().parents[3]
OCCLUSION_PRESETS = ("crossing", "stop_behind", "follow_occluder", "uturn_behind")


def _alone(seq: SyntheticSequence, p: int, k: int) -> np.ndarray:
    """(H, W) bool mask of cast member ``p`` drawn alone in frame ``k``."""
    lab = np.zeros((seq.info.height, seq.info.width), np.int32)
    seq._draw(p, k - 1, None, lab, 1)
    return lab > 0


@pytest.fixture(scope="module")
def crowd() -> SyntheticSequence:
    return load_scenario("crowd", seed=2, length=12, people=8, density=0.5)


def test_determinism_same_seed_same_bytes() -> None:
    a = load_suite(["crossing", "crowd"], seed=5, length=12, people=5, illumination=0.2)
    b = load_suite(["crossing", "crowd"], seed=5, length=12, people=5, illumination=0.2)
    for sa, sb in zip(a, b):
        assert sa.info == sb.info
        for k in (1, 6, 12):
            assert sa.frame(k).tobytes() == sb.frame(k).tobytes()
            assert np.array_equal(sa.foreground(k), sb.foreground(k))
        ta, tb = sa.gt.table, sb.gt.table
        for col in ("frames", "ids", "boxes", "conf", "classes", "visibility"):
            assert np.array_equal(getattr(ta, col), getattr(tb, col)), col
        assert np.array_equal(sa.head_table, sb.head_table)


def test_different_seeds_differ() -> None:
    a = load_scenario("crowd", seed=1, length=5, people=4)
    b = load_scenario("crowd", seed=2, length=5, people=4)
    assert a.frame(3).tobytes() != b.frame(3).tobytes()
    assert not np.array_equal(a.cast.boxes, b.cast.boxes)
    # the noise alone differs between seeds
    c = load_scenario("crossing", seed=1, length=5)
    d = load_scenario("crossing", seed=1, length=5)
    d.seed = 99
    assert c.frame(2).tobytes() != d.frame(2).tobytes()


def test_frame_format_random_access_and_cache(monkeypatch) -> None:
    seq = load_scenario("pair_walk", seed=0, length=20)
    f7 = seq.frame(7)
    assert f7.shape == (480, 640, 3) and f7.dtype == np.uint8
    other = load_scenario("pair_walk", seed=0, length=20)
    for k in range(1, 11):
        other.frame(k)
    assert other.frame(7).tobytes() == f7.tobytes()
    calls = []
    real = seq._render_colour
    monkeypatch.setattr(seq, "_render_colour", lambda k: calls.append(k) or real(k))
    for k in range(8, 12):
        seq.frame(k)
        seq.foreground(k)
        seq.frame(k)
    assert calls == [8, 9, 10, 11]
    lab = seq.foreground(9)
    assert lab.dtype == np.int32 and lab.shape == (480, 640)
    with pytest.raises(IndexError, match="outside 1..20"):
        seq.frame(21)
    with pytest.raises(IndexError):
        seq.frame(0)


def test_gt_columns_and_visibility_bounds(crowd) -> None:
    t = crowd.gt.table
    assert len(t) > 0
    assert (t.conf == 1).all() and (t.classes == 1).all()
    assert ((t.visibility >= 0) & (t.visibility <= 1)).all()
    assert (t.visibility < 1).any()  # a crowd has occlusions
    b = t.boxes
    assert (b[:, 0] >= 0).all() and (b[:, 1] >= 0).all()
    assert (b[:, 0] + b[:, 2] <= 640 + 1e-9).all() and (b[:, 1] + b[:, 3] <= 480 + 1e-9).all()
    assert np.array_equal(crowd.gt.occluded, t.visibility < 0.3)
    assert (np.diff(t.frames) >= 0).all()


def test_visibility_equals_label_counts(crowd) -> None:
    """Visibility = visible label pixels / pixels drawn alone, counted independently here."""
    t = crowd.gt.table
    for k in (1, 7):
        lab = crowd.foreground(k)
        for r in crowd.gt.rows_of(k):
            pid = int(t.ids[r])
            p = int(np.flatnonzero(crowd.cast.ids == pid)[0])
            alone = _alone(crowd, p, k).sum()
            assert t.visibility[r] == pytest.approx((lab == pid).sum() / alone, abs=1e-12)


def test_gt_boxes_contain_label_pixels(crowd) -> None:
    t = crowd.gt.table
    for k in (2, 9):
        lab = crowd.foreground(k)
        ids_in_gt = set(t.ids[crowd.gt.rows_of(k)].tolist())
        assert set(np.unique(lab).tolist()) - {0} <= ids_in_gt
        for r in crowd.gt.rows_of(k):
            ys, xs = np.nonzero(lab == t.ids[r])
            if len(xs) == 0:
                continue
            x, y, w, h = t.boxes[r]
            assert xs.min() >= math.floor(x) and xs.max() < math.ceil(x + w)
            assert ys.min() >= math.floor(y) and ys.max() < math.ceil(y + h)


def test_nearer_person_wins_overlaps(crowd) -> None:
    overlaps = 0
    for k in (1, 6, 12):
        lab = crowd.foreground(k)
        people = crowd._present(k - 1)
        masks = {p: _alone(crowd, p, k) for p in people}
        for i, p in enumerate(people):
            for q in people[i + 1 :]:  # q is nearer than p (painting order)
                assert crowd.cast.depth[q, k - 1] <= crowd.cast.depth[p, k - 1]
                both = masks[p] & masks[q]
                if both.any():
                    overlaps += 1
                    nearer = {int(v) for v in np.unique(lab[both])}
                    # pixels covered by both show the nearer one (or someone nearer still)
                    assert int(crowd.cast.ids[p]) not in nearer
    assert overlaps > 0


@pytest.mark.parametrize("mirror", [False, True])
@pytest.mark.parametrize("name", OCCLUSION_PRESETS)
def test_hidden_person_really_disappears(name: str, mirror: bool) -> None:
    seq = load_scenario(name, seed=7, mirror=mirror)
    t = seq.gt.table
    occluder, hidden = (t.ids == 1), (t.ids == 2)
    v = t.visibility[hidden]
    assert v.min() <= 0.01
    gone = t.frames[hidden][v <= 0.02]
    assert len(gone) >= 5, f"{name}: hidden for only {len(gone)} frames"
    # seen before and after the occlusion
    assert v[0] > 0.5 and v[-1] > 0.5
    # the occluder stays visible and is nearer while the other is hidden
    assert t.visibility[occluder].min() > 0.95
    for f in gone:
        assert seq.cast.depth[1, f - 1] > seq.cast.depth[0, f - 1]


def test_uturn_and_stop_motion_happen_while_hidden() -> None:
    seq = load_scenario("uturn_behind", seed=0, mirror=False)
    t = seq.gt.table
    hidden = t.ids == 2
    gone = t.frames[hidden][t.visibility[hidden] <= 0.02]
    x = seq.cast.boxes[1, :, 0]
    vx = np.diff(x)
    turn = int(np.argmax(np.sign(vx[:-1]) != np.sign(vx[1:]))) + 2  # first frame moving back
    assert gone.min() <= turn <= gone.max()
    stop = load_scenario("stop_behind", seed=0, mirror=False)
    t = stop.gt.table
    hidden = t.ids == 2
    gone = t.frames[hidden][t.visibility[hidden] <= 0.02]
    still = np.flatnonzero(np.abs(np.diff(stop.cast.boxes[1, :, 0])) < 1e-9) + 1
    assert len(still) >= 10 and set(still.tolist()) <= set(gone.tolist())


def test_similar_clothes_are_similar() -> None:
    seq = load_scenario("similar_clothes", seed=4)
    apps = seq.cast.appearances
    for a in apps[1:]:
        assert np.abs(np.subtract(a.shirt, apps[0].shirt)).max() <= 12
        assert np.abs(np.subtract(a.trousers, apps[0].trousers)).max() <= 12


def test_illumination_drifts() -> None:
    seq = load_scenario("illumination", seed=0, length=150, noise=0.0)
    assert seq.gains is not None
    assert seq.gains.max() - seq.gains.min() > 0.3
    m0, m1 = seq.frame(10).mean(), seq.frame(145).mean()
    assert abs(m0 - m1) > 5
    assert load_scenario("crossing", seed=0, length=5).gains is None


def test_crowd_people_and_density() -> None:
    dense = load_scenario("crowd", seed=3, length=10, people=6, density=1.0)
    sparse = load_scenario("crowd", seed=3, length=10, people=6, density=0.05)
    assert len(dense.cast.ids) == 6
    assert dense.gt.table.visibility.mean() < sparse.gt.table.visibility.mean()


def test_people_look_like_people(crowd) -> None:
    """A fully visible person fills 28-65% of its box; its head box holds skin or hair
    colours and sits at the top 1/7 of the box."""
    t = crowd.gt.table
    checked = 0
    for k in (1, 12):
        frame, lab = crowd.frame(k), crowd.foreground(k)
        heads = crowd.head_boxes(k)
        rows = crowd.gt.rows_of(k)
        assert heads.shape == (len(rows), 4)
        for j, r in enumerate(rows):
            x, y, w, h = t.boxes[r]
            if t.visibility[r] < 1 or x <= 0 or y <= 0 or x + w >= 640 or y + h >= 480:
                continue
            pid = int(t.ids[r])
            p = int(np.flatnonzero(crowd.cast.ids == pid)[0])
            fill = (lab == pid).sum() / (w * h)
            assert 0.28 < fill < 0.65
            hx, hy, hw, hh = heads[j]
            assert hy == pytest.approx(y, abs=0.01 * h) and hh == pytest.approx(h / 7.5, rel=0.15)
            assert x <= hx and hx + hw <= x + w
            r0, r1, c0, c1 = int(hy), math.ceil(hy + hh), int(hx), math.ceil(hx + hw)
            px = frame[r0:r1, c0:c1][lab[r0:r1, c0:c1] == pid].astype(float)
            app = crowd.cast.appearances[p]
            ref = np.array([app.skin, app.hair])
            d = np.abs(px[:, None, :] - ref[None] * 1.0).max(axis=2).min(axis=1)
            assert np.median(d) < 40  # noise, shading and the gain aside
            checked += 1
    assert checked > 0


def test_unknown_scenario_lists_valid_ones() -> None:
    with pytest.raises(ValueError, match="valid: crossing, stop_behind"):
        load_suite(["crossing", "nope"])
    with pytest.raises(ValueError, match="density"):
        load_scenario("crowd", density=0)
    assert set(DEFAULT_SCENARIOS) == set(SCENARIOS)


def _write_mot_dir(root: Path) -> list[str]:
    rows = [
        "1,1,11,21,40,100,1,1,1",
        "1,2,101,31,30,80,1,1,1",
        "2,1,14,21,40,100,1,1,1",
        "2,2,96,31,30,80,1,1,1",
        "3,1,17,22,40,100,1,1,1",
        "3,2,-9,31,30,80,1,1,1",  # partly outside the image: clipped
        "4,2,150,60,30,80,0,1,1",  # conf 0 copied
    ]
    (root / "gt").mkdir(parents=True)
    (root / "det").mkdir()
    (root / "gt" / "gt.txt").write_text("\n".join(rows) + "\n")
    (root / "det" / "det.txt").write_text(
        "1,-1,10,20,41,99,0.9,-1,-1,-1\n5,-1,10,20,41,99,0.8,-1,-1,-1\n"
    )
    (root / "seqinfo.ini").write_text(
        "[Sequence]\nname=tiny\nimDir=img1\nframeRate=10\nseqLength=4\nimWidth=200\nimHeight=160\n"
    )
    return rows


def test_replay_reproduces_gt_boxes(tmp_path: Path) -> None:
    _write_mot_dir(tmp_path / "tiny")
    (seq,) = load_replay(tmp_path / "tiny", seed=1, noise=0.0)
    assert (seq.info.name, seq.info.width, seq.info.height, seq.info.fps, seq.info.length) == (
        "tiny",
        200,
        160,
        10.0,
        4,
    )
    src = read_mot(tmp_path / "tiny" / "gt" / "gt.txt", gt=True)
    t = seq.gt.table
    assert np.array_equal(t.frames, src.frames) and np.array_equal(t.ids, src.ids)
    exp = src.boxes.copy()
    exp[5] = [0.0, 30.0, 20.0, 80.0]  # 0-based x = -10 clipped at the left edge
    np.testing.assert_allclose(t.boxes, exp)
    np.testing.assert_array_equal(t.conf, [1, 1, 1, 1, 1, 1, 0])
    assert ((t.visibility > 0) & (t.visibility <= 1)).all()
    assert seq.public_detections is not None and len(seq.public_detections) == 1  # frames <= 4
    lab = seq.foreground(1)
    for r in seq.gt.rows_of(1):
        ys, xs = np.nonzero(lab == t.ids[r])
        x, y, w, h = t.boxes[r]
        assert xs.min() >= math.floor(x) and xs.max() < math.ceil(x + w)
        assert ys.min() >= math.floor(y) and ys.max() < math.ceil(y + h)
    # the gt file on its own (no seqinfo: size from the boxes) and a frame limit
    (seq2,) = load_replay(tmp_path / "tiny" / "gt" / "gt.txt", max_frames=2, width=200, height=160)
    assert seq2.info.length == 2 and len(seq2.gt.table) == 4


def test_replay_missing_path_is_named(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="nowhere"):
        load_replay(tmp_path / "nowhere")


def test_draw_person_in_crop_matches_image() -> None:
    """Drawing into a crop at ``origin`` gives exactly the image's pixels (used for the
    drawn-alone pixel counts)."""
    seq = load_scenario("crossing", seed=0, length=5)
    app = seq.cast.appearances[0]
    box = np.array([-7.3, 40.6, 60.2, 150.9])
    full = np.zeros((240, 320), np.int32)
    draw_person(None, full, 1, box, app, 1.3, 0.8, False, 1.0)
    crop = np.zeros((120, 50), np.int32)
    draw_person(None, crop, 1, box, app, 1.3, 0.8, False, 1.0, origin=(3, 60))
    assert np.array_equal(full[60:180, 3:53], crop)


def test_configs_compose_and_instantiate() -> None:
    from hydra import compose, initialize_config_dir
    from hydra.utils import instantiate

    with initialize_config_dir(config_dir=str(ROOT / "conf"), version_base=None):
        cfg = compose(
            "config",
            overrides=[
                "dataset=synthetic",
                "dataset.scenarios=[crossing,crowd]",
                "dataset.length=5",
                "seed=3",
            ],
        )
        seqs = instantiate(cfg.dataset)
        assert [s.info.name for s in seqs] == ["crossing", "crowd"]
        assert seqs[0].seed == 3 and seqs[0].info.length == 5
        cfg = compose("config", overrides=["dataset=replay", "dataset.max_frames=10"])
        (rep,) = instantiate(cfg.dataset)  # the shipped PETS09-S2L1 trajectories
        assert rep.info.width == 768 and rep.info.length == 10
        assert rep.public_detections is not None and rep.public_detections.frames.max() <= 10
        assert len(rep.gt.table) > 0
