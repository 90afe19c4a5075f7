"""PBM 2.3 head detector: colour mixtures, EM fit, head finding on drawn and rendered people."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from occbench.trackers.frontend.heads import (
    HAIR,
    SKIN,
    ColourMixtures,
    HeadDetector,
    category_likelihoods,
    fit_channel_mixture,
    fit_colour_mixtures,
    reference_samples,
)
from occbench.trackers.frontend.heads_params import HeadEllipses, HeadPixels
from occbench.trackers.geometry import iou_matrix


def test_em_recovers_a_known_two_component_mixture():
    rng = np.random.default_rng(0)
    x = np.r_[rng.normal(0.2, 0.03, 3000), rng.normal(0.7, 0.05, 1000)]
    w, m, s = fit_channel_mixture(x, k=2)
    order = np.argsort(m)
    np.testing.assert_allclose(m[order], [0.2, 0.7], atol=0.01)
    np.testing.assert_allclose(s[order], [0.03, 0.05], atol=0.01)
    np.testing.assert_allclose(w[order], [0.75, 0.25], atol=0.02)


def test_em_circular_hue_wraps_around():
    rng = np.random.default_rng(1)
    x = np.mod(rng.normal(0.0, 0.02, 2000), 1.0)  # red hue: values near 0 and near 1
    _, m, s = fit_channel_mixture(x, k=1, circular=True)
    assert min(m[0], 1 - m[0]) < 0.01 and s[0] < 0.03


def test_shipped_mixtures_load_and_classify_reference_colours():
    mix = ColourMixtures.load()
    assert set(mix.names) == set(HAIR + SKIN) and "reference" in mix.provenance
    tables = mix.tables()
    samples = reference_samples(n=50, seed=7)
    for name in ("black", "blond", "bright", "dark"):
        p = category_likelihoods(samples[name].reshape(-1, 1, 3), tables, 0.5, 0.5)[:, :, 0]
        best = np.array(mix.names)[p.argmax(axis=0)]
        assert (best == name).mean() > 0.5, name
    green = np.array([[[0, 200, 0]]], dtype=np.uint8)  # no hair or skin is saturated green
    assert category_likelihoods(green, tables, 0.5, 0.5).max() < 1.0


def test_mixtures_round_trip(tmp_path):
    mix = fit_colour_mixtures(reference_samples(n=40), k=2, provenance="test")
    mix.save(tmp_path / "m.npz")
    back = ColourMixtures.load(tmp_path / "m.npz")
    np.testing.assert_array_equal(back.means, mix.means)
    assert back.names == mix.names and back.provenance == "test"
    with pytest.raises(FileNotFoundError):
        ColourMixtures.load(tmp_path / "missing.npz")


def _draw_people(img, fg, people):
    for cx, top, h, skin, hair, shirt in people:
        hh = h / 7
        cv2.rectangle(img, (int(cx - 0.2 * h), int(top + hh)), (int(cx + 0.2 * h), int(top + h)), shirt, -1)
        cv2.rectangle(fg, (int(cx - 0.2 * h), int(top + hh)), (int(cx + 0.2 * h), int(top + h)), 1, -1)
        cv2.ellipse(img, (int(cx), int(top + hh / 2)), (int(hh * 0.4), int(hh / 2)), 0, 0, 360, skin, -1)
        cv2.ellipse(fg, (int(cx), int(top + hh / 2)), (int(hh * 0.4), int(hh / 2)), 0, 0, 360, 1, -1)
        cv2.ellipse(img, (int(cx), int(top + hh * 0.3)), (int(hh * 0.42), int(hh * 0.3)), 0, 180, 360, hair, -1)


def test_finds_drawn_heads_at_their_place():
    img = np.full((200, 300, 3), (90, 110, 100), dtype=np.uint8)
    fg = np.zeros((200, 300), dtype=np.uint8)
    # (centre x, top, height, skin BGR, hair BGR, shirt BGR): the shirts are not skin or hair
    _draw_people(img, fg, [(80, 40, 140, (130, 160, 210), (20, 25, 30), (160, 60, 40)),
                           (200, 50, 120, (60, 85, 125), (40, 60, 95), (150, 40, 40))])
    truth = np.array([[80 - 8, 40, 16, 20], [200 - 7, 50, 14, 17]], dtype=float)
    hd = HeadDetector(pixels=HeadPixels(threshold_hair=10, threshold_skin=10))
    heads = hd.detect(img, fg)
    assert len(heads) == 2
    assert (iou_matrix(truth, heads).max(axis=1) > 0.5).all()
    per_box = hd.detect(img, fg, np.array([[52, 40, 56, 140], [176, 50, 48, 120], [0, 150, 30, 30]]))
    assert (iou_matrix(truth, per_box[:2]).diagonal() > 0.5).all()
    assert np.isnan(per_box[2]).all()  # no head in an empty box
    both = hd.heads_in(img, fg, np.array([40, 40, 200, 140]), max_heads=3)
    assert len(both) == 2


def test_finds_rendered_heads():
    synthetic = pytest.importorskip("occbench.datasets.synthetic")
    seq = synthetic.load_scenario("pair_walk", length=30)
    hd = HeadDetector(pixels=HeadPixels(threshold_hair=10, threshold_skin=10))
    hits = total = 0
    for k in (5, 15, 25):
        rows = seq.gt.rows_of(k)
        visible = seq.gt.table.visibility[rows] > 0.9
        boxes, truth = seq.gt.table.boxes[rows][visible], seq.head_boxes(k)[visible]
        found = hd.detect(seq.frame(k), seq.foreground(k), boxes)
        total += len(boxes)
        ok = np.isfinite(found).all(axis=1)
        hits += int((iou_matrix(truth[ok], found[ok]).diagonal() > 0.3).sum())
    assert total >= 3 and hits >= 0.8 * total


def test_bad_arguments():
    with pytest.raises(ValueError, match=r"^heads\.pixels\.w1 "):
        HeadPixels(w1=1.5)
    with pytest.raises(ValueError, match=r"^heads\.ellipses\.min_occupancy "):
        HeadEllipses(min_occupancy=0)
    with pytest.raises(TypeError, match=r"heads.w1: moved to heads.pixels.w1"):
        HeadDetector(w1=0.4)  # a flat key before the groups (issue 36)
