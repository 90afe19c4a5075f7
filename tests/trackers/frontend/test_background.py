"""The texture and invariant-colour background mixture (Reta 3.1) and the renderer's floor
reflections it is measured on."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.datasets.synthetic import load_scenario
from occbench.trackers.frontend.background import BackgroundModel
from occbench.trackers.frontend.background_params import MaskCleanup, PixelModel, WarmUp
from occbench.trackers.frontend.texture_colour import (
    Colour,
    ModeMatch,
    Texture,
    TextureColourMixture,
    siltp,
)


def test_siltp_is_scale_invariant_and_ignores_faint_patterns():
    rng = np.random.default_rng(0)
    g = rng.uniform(60, 200, (12, 14)).astype(np.float32)
    s = siltp(g, 0.08)
    assert set(np.unique(s)) <= {-1.0, 0.0, 1.0}
    np.testing.assert_array_equal(siltp(0.6 * g, 0.08), s)  # a cast shadow: same pattern
    flat = np.full((8, 8), 150.0, np.float32)
    flat[::2] += 5.0  # a 3% pattern, under tau
    assert not siltp(flat, 0.08).any()


def test_mixture_labels_a_shadow_127_and_an_object_255():
    rng = np.random.default_rng(1)
    bg = rng.integers(90, 160, (40, 50, 3)).astype(np.uint8)
    mix = TextureColourMixture(history=50)
    for _ in range(20):
        mix.apply(bg, 0.2)
    frame = bg.copy()
    frame[5:15, 5:15] = (bg[5:15, 5:15] * 0.6).astype(np.uint8)  # shadow: darker, same chroma
    frame[25:35, 30:45] = (20, 200, 40)  # a green object
    out = mix.apply(frame, 0.0)
    assert (out[6:14, 6:14] == 127).mean() > 0.9
    assert (out[26:34, 31:44] == 255).mean() > 0.9
    assert (out[20:24] == 0).all()
    assert mix.getBackgroundImage().shape == bg.shape


def test_mixture_arguments_validated():
    for group, kw in ((TextureColourMixture, {"modes": 0}), (ModeMatch, {"threshold": 0.0}),
                      (ModeMatch, {"background_weight": 1.0}), (Colour, {"shadow_ratio": 1.2}),
                      (Texture, {"texture_tau": 0.0}), (Colour, {"noise": -1.0})):
        (key,) = kw
        where = {ModeMatch: "matching.", Colour: "colour.", Texture: "texture."}.get(group, "")
        with pytest.raises(ValueError, match=rf"^background\.mixture\.{where}{key} "):  # its key
            group(**kw)
    with pytest.raises(TypeError, match=r"mixture.noise: moved to background.mixture.colour"):
        TextureColourMixture(noise=5.0)  # a flat key before the groups (issue 36)
    with pytest.raises(ValueError, match=r"^background\.method "):
        BackgroundModel(method="vibe")
    with pytest.raises(ValueError, match=r"^background\.model\.var_threshold .*got nan"):  # let in before
        BackgroundModel(model=PixelModel(var_threshold=float("nan")))
    with pytest.raises(ValueError, match=r"^background\.cleanup\.close_kernel "):
        BackgroundModel(cleanup=MaskCleanup(close_kernel=(3, -1)))
    with pytest.raises(TypeError, match=r"background.warmup_span: moved to background.start"):
        BackgroundModel(warmup_span="online")  # a flat key before the groups (issue 36)


def test_renderer_draws_a_mirrored_reflection_below_the_feet():
    plain = load_scenario("crossing", seed=3, width=192, height=144, length=30, noise=0.0)
    shiny = load_scenario("crossing", seed=3, width=192, height=144, length=30, noise=0.0,
                          reflection=0.4)
    k = 15
    refl = shiny.reflection_mask(k)
    assert refl.sum() > 50 and not plain.reflection_mask(k).any()
    assert not (refl & (shiny.foreground(k) > 0)).any()
    changed = np.abs(shiny.frame(k).astype(int) - plain.frame(k).astype(int)).sum(axis=2) > 0
    assert changed[refl].mean() > 0.5 and not changed[~refl].any()
    np.testing.assert_array_equal(shiny.foreground(k), plain.foreground(k))
    # below the feet: every reflection pixel lies under some person's box bottom
    rows = np.flatnonzero(refl.any(axis=1))
    boxes = shiny.gt.table.boxes[shiny.gt.rows_of(k)]
    assert rows.min() >= np.floor((boxes[:, 1] + boxes[:, 3]).min()) - 1


def test_texture_colour_removes_a_floor_reflection_and_keeps_the_person():
    """Opacity 0.6 reflections under every person: under 3% of the reflection's pixels are
    foreground (a third of MOG2's at most), and at least 95% of the people's pixels are kept."""
    seq = load_scenario("crossing", seed=11, width=192, height=144, length=40, reflection=0.6)
    res = {}
    for name, model in (("mog2", BackgroundModel()),
                        ("tc", BackgroundModel(method="texture_colour"))):
        model.warm_up_sequence(seq.info.length, seq.frame)
        fg_refl = n_refl = kept = n_person = 0
        for k in range(1, seq.info.length + 1):
            mask = model.apply(seq.frame(k))
            person, refl = seq.foreground(k) > 0, seq.reflection_mask(k)
            fg_refl += (mask & refl).sum()
            n_refl += refl.sum()
            kept += (mask & person).sum()
            n_person += person.sum()
        res[name] = (fg_refl / n_refl, kept / n_person)
    assert n_refl > 1000
    assert res["tc"][0] < 0.03 and res["tc"][0] < res["mog2"][0] / 3
    assert res["tc"][1] >= 0.95


def test_compiled_mixture_matches_the_numpy_equations():
    seq = load_scenario("crossing", seed=4, width=128, height=96, length=20, reflection=0.4)
    ref = TextureColourMixture(history=30, compiled=False)
    fast = TextureColourMixture(history=30, compiled=True)
    agree = total = 0
    for k in range(1, seq.info.length + 1):
        f = seq.frame(k)
        a, b = ref.apply(f, -1 if k > 3 else 0.3), fast.apply(f, -1 if k > 3 else 0.3)
        agree += (a == b).sum()
        total += a.size
    assert agree / total >= 0.999
    np.testing.assert_allclose(fast._w, ref._w, atol=1e-3)
    np.testing.assert_allclose(fast.getBackgroundImage(), ref.getBackgroundImage(), atol=2)


def _walker_frames(n: int, seed: int, stay_from: int | None = None) -> list[np.ndarray]:
    """n (72, 96, 3) frames of a textured floor and a bright 'person' walking right; from
    frame ``stay_from`` on (1-based) a second person stands still at the left."""
    rng = np.random.default_rng(seed)
    floor = rng.integers(60, 120, size=(72, 96, 3), dtype=np.uint8)
    out = []
    for k in range(1, n + 1):
        f = floor.copy()
        x = 4 + 2 * k
        f[20:60, x:x + 12] = (230, 200, 180)
        if stay_from is not None and k >= stay_from:
            f[10:50, 2:14] = (20, 240, 20)
        out.append(f)
    return out


@pytest.mark.parametrize("method", ["mog2", "texture_colour"])
def test_online_warm_up_never_reads_a_frame_after_the_current_one(method):
    """``warmup_span: online``: the masks of frames 1..t do not change when the frames after
    t do (here a person appears at frame 25 and stays); ``sequence`` reads them (the same
    change moves the masks of earlier frames) and says so (``uses_future_frames``)."""
    a, b = _walker_frames(40, 0), _walker_frames(40, 0, stay_from=25)
    masks = {}
    for span in ("online", "sequence"):
        for name, frames in (("a", a), ("b", b)):
            bg = BackgroundModel(method=method, start=WarmUp(warmup_frames=8, warmup_span=span))
            asked: list[int] = []

            def frame(k: int, frames=frames, asked=asked) -> np.ndarray:
                asked.append(k)
                return frames[k - 1]

            bg.warm_up_sequence(len(frames), frame)
            masks[span, name] = [bg.apply(f) for f in frames]
            if span == "online":
                assert asked == [1] and not bg.uses_future_frames
            else:
                assert max(asked) == 40 and bg.uses_future_frames
    for t in range(24):
        np.testing.assert_array_equal(masks["online", "a"][t], masks["online", "b"][t])
    assert any((masks["sequence", "a"][t] != masks["sequence", "b"][t]).any() for t in range(24))


def test_knn_builds_at_its_defaults_and_finds_a_walker():
    """method "knn" with the default ``model``: OpenCV's KNN subtractor has no background
    ratio, and setting MOG2's raised AttributeError before any frame."""
    frames = _walker_frames(40, 0)
    bg = BackgroundModel(method="knn", start=WarmUp(warmup_frames=8))
    bg.warm_up(frames[:8])
    mask = [bg.apply(f) for f in frames][-1]
    x = 4 + 2 * 39
    assert mask[25:55, x + 2:x + 10].mean() > 0.5 and mask[:, :2].sum() == 0


def test_knn_default_threshold_ignores_sensor_noise():
    """KNN's squared distance threshold is its own (OpenCV's 400), not MOG2's variance
    threshold (25, a colour distance of 5: camera noise of a few grey levels then lit most
    of a still floor)."""
    rng = np.random.default_rng(3)
    frames = [np.clip(f + rng.normal(0, 4, f.shape), 0, 255).astype(np.uint8)
              for f in _walker_frames(40, 0)]
    bg = BackgroundModel(method="knn", start=WarmUp(warmup_frames=8))
    bg.warm_up(frames[:8])
    mask = [bg.apply(f) for f in frames][-1]
    x = 4 + 2 * 39
    assert mask[25:55, x + 2:x + 10].mean() > 0.5  # the walker
    assert (mask[:, :x - 10] > 0).mean() < 0.02  # the still floor behind him


def test_online_warm_up_keeps_an_even_sample_of_the_past():
    bg = BackgroundModel(start=WarmUp(warmup_frames=4, warmup_span="online"))
    frames = _walker_frames(20, 1)
    bg.warm_up_sequence(20, lambda k: frames[k - 1])
    for f in frames[:13]:
        bg.apply(f)
    kept = [next(i for i, g in enumerate(frames) if g is s) + 1 for s in bg._sample]
    assert kept == [1, 5, 9, 13]
    with pytest.raises(ValueError, match="warmup_span"):
        BackgroundModel(start=WarmUp(warmup_span="future"))
