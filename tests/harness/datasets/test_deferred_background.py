"""A synthetic scene's background is painted when the sequence first needs it
(``scene.defer_background``), not when the suite is loaded: the same image and the same
generator stream afterwards as painting it at once, so every scene keeps its bytes."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.datasets.synthetic import load_suite, scene
from occbench.datasets.synthetic.scene import Camera, defer_background, render_background


@pytest.mark.parametrize(("seed", "size", "camera_height"),
                         [(0, (640, 480), 1.3), (7, (320, 240), 1.3), (1000, (384, 288), 2.0)])
def test_deferred_background_is_the_rendered_one_and_draws_the_same(seed, size, camera_height):
    cam = Camera.for_size(*size, camera_height=camera_height)
    now, later = np.random.default_rng([seed, 1]), np.random.default_rng([seed, 1])
    painted = render_background(cam, now)
    deferred = defer_background(cam, later)
    # what follows from the generator (the people, their paths) is unchanged
    np.testing.assert_array_equal(now.random(8), later.random(8))
    image = deferred()
    assert deferred.shape == image.shape == (size[1], size[0], 3)
    np.testing.assert_array_equal(image, painted)
    np.testing.assert_array_equal(deferred(), painted)  # the same image every time


def test_a_suite_paints_each_background_on_its_first_frame(monkeypatch):
    painted = []
    real = scene.render_background

    def counting(cam, rng):
        painted.append(cam)
        return real(cam, rng)

    monkeypatch.setattr(scene, "render_background", counting)
    seqs = load_suite(["crossing", "pair_walk", "crowd"], seed=3, length=6, people=4)
    assert painted == []  # loading paints nothing
    first = seqs[0].frame(1)
    assert len(painted) == 1 and first.shape == (480, 640, 3)
    seqs[0].frame(2)
    assert seqs[0].background is seqs[0].background and len(painted) == 1  # painted once
