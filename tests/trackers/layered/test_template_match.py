"""``adaptations.pyramid_template`` (``template_match.PyramidMatch``): PBM 4.1's head template
matched at half resolution, then at full resolution around that best; the exact match
(``ExactMatch``) is ``search.match_head_template``."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.params import MatchParams, PruneParams
from occbench.trackers.layered.search import match_head_template
from occbench.trackers.layered.selection import MultipleResponsePruning
from occbench.trackers.layered.template_match import ExactMatch, PyramidMatch


def _frame(seed: int = 0) -> np.ndarray:
    """A smooth textured BGR frame (blobs a few pixels wide, as heads and clothes are)."""
    import cv2

    rng = np.random.default_rng(seed)
    small = rng.integers(0, 256, (60, 80, 3), dtype=np.uint8)
    return cv2.resize(small, (640, 480), interpolation=cv2.INTER_CUBIC)


def test_pyramid_finds_the_exact_matchs_corner_and_its_full_resolution_score():
    frame = _frame()
    rng = np.random.default_rng(1)
    for _ in range(20):
        x, y = int(rng.integers(60, 540)), int(rng.integers(60, 380))
        template = frame[y:y + 12, x:x + 30].copy()
        centre = (x + int(rng.integers(-6, 7)), y + int(rng.integers(-6, 7)))
        exact_tl, exact = ExactMatch()(frame, template, centre, 30.0)
        tl, corr = PyramidMatch()(frame, template, centre, 30.0)
        assert tl.tolist() == exact_tl.tolist() == [x, y]
        assert abs(corr - exact) < 1e-4 and corr > 0.99


def test_pyramid_matches_small_windows_and_templates_exactly():
    frame = _frame(2)
    template = frame[100:106, 200:230].copy()  # 6 rows: under MIN_SIDE
    for args in (((195, 98), 12.0), ((420, 300), 40.0)):
        assert [v.tolist() if isinstance(v, np.ndarray) else v for v in PyramidMatch()(frame, template, *args)] == \
               [v.tolist() if isinstance(v, np.ndarray) else v for v in match_head_template(frame, template, *args)]
    template = frame[100:112, 200:230].copy()  # a window of 9 x 9 positions: under MIN_POSITIONS
    tl, corr = PyramidMatch()(frame, template, (197, 97), 4.0)
    ref_tl, ref = match_head_template(frame, template, (197, 97), 4.0)
    assert tl.tolist() == ref_tl.tolist() and corr == ref
    tl, corr = PyramidMatch()(frame, template, (700.0, 10.0), 3.0)  # off the image
    assert tl.tolist() == [700.0, 10.0] and corr == -1.0


def test_pyramid_template_is_an_adaptation_off_by_default_and_in_paper_mode():
    assert not Adaptations().pyramid_template and not Adaptations.paper().pyramid_template
    pick = {on: type(MultipleResponsePruning(MatchParams(), PruneParams(),
                                             Adaptations(pyramid_template=on)).matcher)
            for on in (False, True)}
    assert pick == {False: ExactMatch, True: PyramidMatch}


def test_large_head_pyramid_matches_narrow_templates_exactly_and_wide_ones_coarse_to_fine():
    frame = _frame(3)
    matcher = PyramidMatch(min_width=30)
    rng = np.random.default_rng(4)
    told = {True: False, False: False}  # a case on each side where the two matches differ
    for width, exact_expected in ((24, True), (30, True), (31, False), (48, False)):
        x, y = int(rng.integers(60, 500)), int(rng.integers(60, 380))
        template = frame[y:y + 12, x:x + width].copy()
        centre, radius = (x + 3, y - 4), 30.0
        tl, corr = matcher(frame, template, centre, radius)
        exact = match_head_template(frame, template, centre, radius)
        pyramid = PyramidMatch()(frame, template, centre, radius)
        want = exact if exact_expected else pyramid
        assert tl.tolist() == want[0].tolist() and corr == want[1]
        told[exact_expected] |= (exact[0].tolist(), exact[1]) != (pyramid[0].tolist(), pyramid[1])
    assert told == {True: True, False: True}


def test_large_head_pyramid_is_an_adaptation_off_by_default_and_in_paper_mode():
    assert Adaptations().large_head_pyramid == 0 == Adaptations.paper().large_head_pyramid
    def build(**kw):
        return MultipleResponsePruning(MatchParams(), PruneParams(), Adaptations(**kw)).matcher

    assert type(build()) is ExactMatch
    wide = build(large_head_pyramid=48)
    assert type(wide) is PyramidMatch and wide.min_width == 48
    both = build(pyramid_template=True, large_head_pyramid=48)
    assert type(both) is PyramidMatch and both.min_width == 0
    with pytest.raises(ValueError, match="large_head_pyramid"):
        Adaptations(large_head_pyramid=-1)


def test_large_head_peaks_refines_the_coarse_levels_next_peaks_too():
    """Two copies of a 16 x 50 head: B with a pixel checkerboard (gone at half resolution,
    so the coarse best) and A with a ramp (the exact best). One refined peak keeps B, three
    find A; one peak is pyramid_template's match, bit for bit."""
    frame = _frame(6)
    template = frame[200:216, 300:350].copy()
    yy, xx = np.mgrid[0:16, 0:50]
    scene = frame.copy()
    checker = (((yy + xx) % 2) * 2 - 1)[..., None] * 60.0
    scene[100:116, 100:150] = np.clip(template + checker, 0, 255).astype(np.uint8)
    ramp = (xx[..., None] - 25) * 1.6
    scene[100:116, 160:210] = np.clip(template + ramp, 0, 255).astype(np.uint8)
    exact_tl, exact = match_head_template(scene, template, (130, 100), 45.0)
    one_tl, one = PyramidMatch(min_width=48, peaks=1)(scene, template, (130, 100), 45.0)
    three_tl, three = PyramidMatch(min_width=48, peaks=3)(scene, template, (130, 100), 45.0)
    assert exact_tl.tolist() == three_tl.tolist() == [160, 100] and one_tl.tolist() == [100, 100]
    assert abs(three - exact) < 1e-4 and one < 0.5
    plain_tl, plain = PyramidMatch()(scene, template, (130, 100), 45.0)
    assert plain_tl.tolist() == one_tl.tolist() and plain == one
    assert Adaptations().large_head_peaks == 1 == Adaptations.paper().large_head_peaks
    chosen = MultipleResponsePruning(MatchParams(), PruneParams(),
                                     Adaptations(large_head_pyramid=48, large_head_peaks=3)).matcher
    assert (chosen.min_width, chosen.peaks) == (48, 3)
    with pytest.raises(ValueError, match="large_head_peaks"):
        Adaptations(large_head_peaks=0)
