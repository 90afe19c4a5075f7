"""Hypothesis 1's velocity (occbench.trackers.three_hypothesis.measured_line): M's, or the
line through the last measured centres when it has predicted them better; hand cases."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from occbench.trackers.three_hypothesis import Adaptations
from occbench.trackers.three_hypothesis.appearance import EllipseHistogrammer
from occbench.trackers.three_hypothesis._kernels import line_misses
from occbench.trackers.three_hypothesis.measured_line import (FilterVelocity, MeasuredLine, _line,
                                                             _lines, _squares)
from occbench.trackers.three_hypothesis.rules import build_rules


def _walker(rule, predicted_vx: float):
    """A person measured at xc = 10 + 3 t (t = 1..6, boxes 10 x 20) while M predicts each
    centre with velocity ``predicted_vx`` from the previous one."""
    person = SimpleNamespace(centres=[], line_errors=[0.0, 0.0])
    for t in range(1, 7):
        xc = 10.0 + 3 * t
        predicted = np.array([xc - 3 + predicted_vx, 10.0, 10, 20, predicted_vx, 0, 0, 0])
        rule.record([person], t, np.array([[xc - 5, 0.0, 10, 20]]), predicted[None])
    return person


def test_hypothesis_1_takes_the_measured_line_when_it_predicted_better():
    rule = MeasuredLine(window=4)
    x_prev = np.array([28.0, 10.0, 10, 20, 1.0, 0, 0, 0])  # M's estimate at t = 6, lagging
    x_pred = x_prev + np.array([1.0, 0, 0, 0, 0, 0, 0, 0])
    lagging = _walker(rule, 1.0)  # M predicts 1 px/frame, the person walks 3
    assert len(lagging.centres) == 4 and lagging.line_errors[1] < lagging.line_errors[0]
    x = rule.start(lagging, x_prev, x_pred)
    assert np.allclose(x[[0, 4]], [31.0, 3.0]) and np.allclose(x[2:4], x_pred[2:4])
    exact = _walker(rule, 3.0)  # M predicts exactly: its velocity stays
    assert rule.start(exact, x_prev, x_pred) is x_pred
    assert FilterVelocity().start(lagging, x_prev, x_pred) is x_pred
    h = EllipseHistogrammer()
    assert isinstance(build_rules(Adaptations.paper(), h).line, FilterVelocity)
    assert build_rules(Adaptations(measured_hypothesis=True), h).line == MeasuredLine(8, 2.0, True)


def test_the_line_is_taken_only_where_it_differs_from_m_beyond_its_error():
    """``measured_hypothesis_sigmas``: a standing person measured with 1 px jitter (M
    predicting velocity 0) draws through its last 8 centres a line of slope 0.18 px/frame,
    standard error 0.10: it predicted the jitter better than M by chance (0.0198 against
    0.0200), and moved its hypothesis anyway (sigmas 0); within two standard errors of M's
    velocity it is not taken. The lagging walker's
    line (exact, standard error 0) is taken at any sigmas."""
    rule, guarded = MeasuredLine(window=8), MeasuredLine(window=8, sigmas=2.0)
    standing = SimpleNamespace(centres=[], line_errors=[0.0, 0.0])
    jitter = [0.0, 0.0, 0.0, 1.0, -1.0, 1.0, 1.0, 0.0, 1.0, 1.0, 1.0, 1.0]
    for t, dx in enumerate(jitter, start=1):
        rule.record([standing], t, np.array([[45.0 + dx, 0.0, 10, 20]]),
                    np.array([[50.0, 10.0, 10, 20, 0, 0, 0, 0]]))
    x_prev = np.array([50.0, 10.0, 10, 20, 0, 0, 0, 0])
    x_pred = x_prev.copy()
    assert standing.line_errors[1] < standing.line_errors[0]  # the line won by chance
    moved = rule.start(standing, x_prev, x_pred)
    assert moved is not x_pred and np.isclose(moved[4], 0.17857, atol=1e-4)
    assert guarded.start(standing, x_prev, x_pred) is x_pred
    lagging = _walker(MeasuredLine(window=4), 1.0)
    x_prev, x_pred = (np.array([28.0 + k, 10.0, 10, 20, 1.0, 0, 0, 0]) for k in (0, 1))
    walker = MeasuredLine(window=4, sigmas=2.0).start(lagging, x_prev, x_pred)
    assert np.allclose(walker[[0, 4]], [31.0, 3.0])
    h = EllipseHistogrammer()
    built = build_rules(Adaptations(measured_hypothesis=True, measured_hypothesis_sigmas=2), h)
    assert built.line == MeasuredLine(8, 2.0, True)
    assert Adaptations().measured_hypothesis and Adaptations().measured_hypothesis_sigmas == 2.0
    assert "measured_hypothesis_sigmas" not in Adaptations.paper().changed()


def _record_one(window: int, person, frame: int, box: np.ndarray, predicted: np.ndarray) -> None:
    """The plain definition of ``MeasuredLine.record`` for one person (scalars, ``_line``)."""
    cx, cy = box[0] + box[2] / 2, box[1] + box[3] / 2
    if len(person.centres) >= 3:
        t0, x0, y0, vx, vy = _line(person.centres)
        h2 = max(float(box[3]), 1.0) ** 2
        person.line_errors[0] += ((predicted[0] - cx) ** 2 + (predicted[1] - cy) ** 2) / h2
        person.line_errors[1] += ((x0 + vx * (frame - t0) - cx) ** 2
                                  + (y0 + vy * (frame - t0) - cy) ** 2) / h2
        (f1, x1, y1), (f2, x2, y2) = person.centres[-2:]  # the last step's prediction
        k = (frame - f2) / max(f2 - f1, 1)
        dx, dy = x2 + (x2 - x1) * k - cx, y2 + (y2 - y1) * k - cy
        person.step_error += (dx * dx + dy * dy) / max(float(box[3]), 1.0) ** 2
    person.centres.append((frame, cx, cy))
    del person.centres[:-window]


def test_record_of_a_frame_equals_the_plain_definition_bit_for_bit():
    """People of every history length (0 to the window, windows below, at and above numpy's
    8-term summation block), boxes under 1 px high, measured for 29 frames (some frames
    skipped: steps over gaps), with and without ``step``: the errors and centres equal the
    plain per-person definition's bit for bit (enough squares that a * a
    for pow(a, 2) would differ somewhere)."""
    rng = np.random.default_rng(3)
    for window, step in ((4, True), (8, False), (8, True), (11, True), (20, False)):
        rule = MeasuredLine(window=window, step=step)
        ours = [SimpleNamespace(centres=[], line_errors=[0.0, 0.0], step_error=0.0)
                for _ in range(60)]
        plain = [SimpleNamespace(centres=[], line_errors=[0.0, 0.0], step_error=0.0)
                 for _ in range(60)]
        for frame in range(1, 30):
            k = np.flatnonzero(rng.random(60) < 0.7)
            boxes = rng.uniform(0, 300, (len(k), 4)) * rng.choice([1.0, 0.001], (len(k), 1))
            predicted = rng.uniform(0, 300, (len(k), 8))
            rule.record([ours[r] for r in k], frame, boxes, predicted)
            for j, r in enumerate(k):
                _record_one(window, plain[r], frame, boxes[j], predicted[j])
        for a, b in zip(ours, plain):
            assert a.centres == b.centres and a.line_errors == b.line_errors
            assert a.step_error == (b.step_error if step else 0.0)
        assert any(b.step_error > 0 for b in plain)


def test_squares_round_as_the_scalar_power_does():
    """``_squares`` gives Python's ``v ** 2`` (the C library's pow) for every value; a * a
    differs from it in about one value of a thousand."""
    a = np.random.default_rng(4).normal(0, 100, 20_000)
    assert _squares(a).tolist() == [v ** 2 for v in a.tolist()]


def test_a_person_who_has_just_turned_keeps_its_last_step():
    """``measured_step``: a person walks left at 3 px/frame (t = 1..6), turns and walks right
    at 3 (t = 7..9); M's velocity catches up slowly (-3, -3, -1, +1) and the line through the
    last 8 centres still points left. The last step has predicted the measurements best (one
    miss, at the turn), so hypothesis 1 at the first miss moves right from the last measured
    centre; without the rule it keeps M's prediction (the line did worse than M)."""
    centres = [50.0 - 3 * t for t in range(1, 7)] + [32.0 + 3 * k for k in (1, 2, 3)]
    m_velocity = [-3.0] * 7 + [-1.0, 1.0]

    def walked(rule):
        person = SimpleNamespace(centres=[], line_errors=[0.0, 0.0], step_error=0.0)
        for t, (xc, v) in enumerate(zip(centres, m_velocity), start=1):
            previous = centres[t - 2] if t > 1 else xc
            predicted = np.array([previous + v, 10.0, 10, 20, v, 0, 0, 0])
            rule.record([person], t, np.array([[xc - 5, 0.0, 10, 20]]), predicted[None])
        return person

    x_prev = np.array([40.0, 10.0, 10, 20, 1.0, 0, 0, 0])  # M's estimate at t = 9, lagging
    x_pred = x_prev + np.array([1.0, 0, 0, 0, 0, 0, 0, 0])
    with_step = MeasuredLine(window=8, sigmas=2.0, step=True)
    person = walked(with_step)
    assert person.step_error < min(person.line_errors)
    assert person.line_errors[1] > person.line_errors[0]  # the line lags more than M
    x = with_step.start(person, x_prev, x_pred)
    assert np.allclose(x[[0, 1, 4, 5]], [44.0, 10.0, 3.0, 0.0])
    assert np.allclose(x[2:4], x_pred[2:4])
    without = MeasuredLine(window=8, sigmas=2.0)
    assert without.start(walked(without), x_prev, x_pred) is x_pred
    h = EllipseHistogrammer()
    assert build_rules(Adaptations(measured_step=True), h).line == MeasuredLine(8, 2.0, True)
    assert Adaptations().measured_step and "measured_step" not in Adaptations.paper().changed()


def test_compiled_lines_equal_numpy_lines_bit_for_bit():
    """``_kernels.line_misses`` against ``_lines`` (numpy's reductions) for histories of 3
    to 20 rows (numpy sums below 8 terms one by one, 8 and more in eight running sums) and
    of 130 and 300 (its halving beyond 128), with negative zeros and equal frames' ties."""
    rng = np.random.default_rng(5)
    for n in [*range(3, 21), 130, 300]:
        G = 7
        hist = np.stack([np.sort(rng.uniform(0, 500, (G, n)), axis=1),
                         rng.normal(0, 300, (G, n)), rng.normal(0, 300, (G, n))], axis=2)
        hist[0, :, 1:] = -0.0
        hist[1, : n // 2, 0] = hist[1, 0, 0]  # repeated frames
        frame = float(hist[:, -1, 0].max() + 1)
        cx, cy = rng.normal(0, 300, G), rng.normal(0, 300, G)
        t0, x0, y0, vx, vy = _lines(hist)
        want = np.stack([x0 + vx * (frame - t0) - cx, y0 + vy * (frame - t0) - cy])
        got = np.empty((4, G))  # rows 2-3: the last step's misses (the record test's)
        line_misses(hist.reshape(-1, 3), np.full(G, n), frame, cx, cy, got)
        assert got[:2].tobytes() == want.tobytes(), n


def test_a_merged_measurement_stays_out_of_the_line():
    """``merged_line``: the walker (xc = 10 + 3 t, M lagging at 1 px/frame) is matched at
    t = 7 and 8 to measurements merged over a hidden partner standing at xc 30 (own share
    below 1, centre 30): they stay out of its centres and records, and at its first miss
    (t = 9) hypothesis 1 starts on the line through its own centres at t = 9, 10 + 27 = 37;
    without the rule the merged centres bend the line and it starts from the dragged
    estimate."""
    def walk(rule):
        person = SimpleNamespace(centres=[], line_errors=[0.0, 0.0], step_error=0.0,
                                 merged_at=-1)
        for t in range(1, 9):
            xc = 10.0 + 3 * t if t <= 6 else 30.0
            predicted = np.array([xc - 3 + 1.0, 10.0, 10, 20, 1.0, 0, 0, 0])
            rule.record([person], t, np.array([[xc - 5, 0.0, 10, 20]]), predicted[None],
                        np.array([1.0 if t <= 6 else 0.4]))
        return person
    x_prev = np.array([30.0, 10.0, 10, 20, 1.0, 0, 0, 0])  # dragged onto the partner
    x_pred = x_prev + np.array([1.0, 0, 0, 0, 0, 0, 0, 0])
    own = MeasuredLine(window=4, own_only=True)
    person = walk(own)
    assert [c[0] for c in person.centres] == [3, 4, 5, 6] and person.merged_at == 8
    assert np.allclose(own.start(person, x_prev, x_pred)[[0, 4]], [37.0, 3.0])
    every = MeasuredLine(window=4)
    assert [c[0] for c in walk(every).centres] == [5, 6, 7, 8]
    assert not np.isclose(every.start(walk(every), x_prev, x_pred)[0], 37.0)
    assert own.uses_shares and not every.uses_shares
    h = EllipseHistogrammer()
    assert build_rules(Adaptations(merged_line=True), h).line == MeasuredLine(8, 2.0, True, True)
    assert "merged_line" not in Adaptations().changed() + Adaptations.paper().changed()


def test_a_merged_measurement_is_one_pulled_towards_the_partner():
    """``merged_line_shift``: the walker (xc = 10 + 3 t, width 10) beside a hidden partner
    whose predicted centre stands at xc 40 holds share 0.6 of its boxes at t = 5 and 6. At
    t = 5 its own box lies on its line (a person's own box beside a hidden neighbour): kept.
    At t = 6 the box is fitted over the pair, 5 px (half its width) towards the partner: left
    out. Without the shift (``merged_line`` alone) both are left out."""
    def walk(rule):
        person = SimpleNamespace(centres=[], line_errors=[0.0, 0.0], step_error=0.0,
                                 merged_at=-1)
        for t in range(1, 7):
            xc = 10.0 + 3 * t + (5.0 if t == 6 else 0.0)
            rule.record([person], t, np.array([[xc - 5, 0.0, 10, 20]]),
                        np.array([[xc, 10.0, 10, 20, 3.0, 0, 0, 0]]),
                        np.array([0.6 if t >= 5 else 1.0]), np.array([[40.0, 10.0]]))
        return person
    shifted = walk(MeasuredLine(window=8, own_only=True, shift=0.15))
    assert [c[0] for c in shifted.centres] == [1, 2, 3, 4, 5] and shifted.merged_at == 6
    assert [c[0] for c in walk(MeasuredLine(window=8, own_only=True)).centres] == [1, 2, 3, 4]
    assert MeasuredLine(8, own_only=True, shift=0.15).uses_partners
    assert not MeasuredLine(8, own_only=True).uses_partners
    h = EllipseHistogrammer()
    assert build_rules(Adaptations(merged_line=True, merged_line_shift=0.15), h).line == \
        MeasuredLine(8, 2.0, True, True, 0.15)
    assert "merged_line_shift" not in Adaptations().changed() + Adaptations.paper().changed()


def test_a_person_measured_standing_is_missed_standing():
    """``measured_still``: a person standing at xc 100 (its measured centres jitter by +-0.5
    px, no trend: the line's slope -0.04 px/frame against a standard error of 0.08), whose
    M drifts at 0.4 px/frame, is missed at t = 9: hypothesis 1 stands at its last estimate,
    velocity 0; without the rule it drifts with M. A walker at 0.5 px/frame measured as
    exactly (the slope 0.5, its error 0) keeps moving; so does a person with fewer than m
    centres."""
    def measured(xs):
        person = SimpleNamespace(centres=[], line_errors=[0.0, 0.0], step_error=0.0,
                                 merged_at=-1)
        rule = MeasuredLine(window=8, sigmas=2.0)
        for t, xc in enumerate(xs, start=1):
            rule.record([person], t, np.array([[xc - 5, 0.0, 10, 20]]),
                        np.array([[xc, 10.0, 10, 20, 0.4, 0, 0, 0]]))
        return person
    jitter = [100.5, 99.5, 100.0, 100.5, 99.5, 100.0, 100.5, 99.5]
    x_prev = np.array([100.2, 10.0, 10, 20, 0.4, 0.0, 0.1, 0.0])
    x_pred = x_prev + np.array([0.4, 0, 0.1, 0, 0, 0, 0, 0])
    still = MeasuredLine(window=8, sigmas=2.0, still=True)
    x = still.start(measured(jitter), x_prev, x_pred)
    assert np.array_equal(x[:4], x_prev[:4]) and not x[4:].any()
    assert MeasuredLine(window=8, sigmas=2.0).start(measured(jitter), x_prev, x_pred) is x_pred
    walker = [100.0 + 0.5 * t for t in range(8)]
    assert still.start(measured(walker), x_prev, x_pred)[4] != 0.0
    assert still.start(measured(jitter[:5]), x_prev, x_pred) is x_pred  # 5 < m centres
    h = EllipseHistogrammer()
    assert build_rules(Adaptations(measured_still=True), h).line == \
        MeasuredLine(8, 2.0, True, still=True)
    assert "measured_still" in Adaptations(measured_still=True).changed()
    assert "measured_still" not in Adaptations().changed() + Adaptations.paper().changed()
