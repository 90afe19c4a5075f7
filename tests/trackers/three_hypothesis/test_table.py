"""``table``: the people and nodes a tracker keeps between frames as column tables, and
back, equal field for field and type for type (the bench scene's state after 60 frames, with
the default rules, the paper's, and own_return's records)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from benchmark_scripts import load

from occbench.trackers.three_hypothesis import Adaptations, RetaTracker
from occbench.trackers.three_hypothesis import table
from occbench.trackers.three_hypothesis.appearance import Histogram
from occbench.trackers.three_hypothesis.state import Branch, Person

SCENE = load("bench_reta").make_scene(40, 60)


def _state(adaptations: Adaptations) -> list[Person]:
    tracker = RetaTracker(adaptations=adaptations)
    for image, detections in SCENE:
        tracker.update(image, detections)
    return tracker.memory.persons


def _same(a, b, where: str) -> None:
    """Equal values of the same types (arrays: dtype, shape and bits)."""
    assert type(a) is type(b), (where, type(a), type(b))
    if isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape, where
        assert a.tobytes() == b.tobytes(), where
    elif isinstance(a, Histogram):
        for field in ("bins", "values"):
            _same(getattr(a, field), getattr(b, field), f"{where}.q.{field}")
        assert a.size == b.size, where
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), where
        for k, (u, v) in enumerate(zip(a, b)):
            _same(u, v, f"{where}[{k}]")
    elif isinstance(a, (Person, Branch)):
        for field in dataclasses.fields(a):
            _same(getattr(a, field.name), getattr(b, field.name), f"{where}.{field.name}")
    else:
        assert a == b, (where, a, b)


@pytest.mark.parametrize("adaptations", [Adaptations(), Adaptations.paper(),
                                         Adaptations(own_return=True)],
                         ids=["reta", "reta_paper", "own_return"])
def test_the_tables_give_back_the_people_they_were_made_of(adaptations):
    persons = _state(adaptations)
    people, nodes = table.of(persons)
    back = table.persons(people, nodes)
    _same(persons, back, "persons")
    # the state exercises every column: hypotheses of each kind, hidden people, records of
    # the line (and of own_return's rho)
    assert set(nodes.kind.tolist()) == {0, 1, 2, 3}
    assert (people.id > 0).any() and (people.misses > 0).any() and people.spawned.any()
    assert (nodes.occluder >= 0).any() and (nodes.occluder < 0).any()
    assert (people.n_centres > 1).any() == adaptations.measured_hypothesis
    assert (people.n_rho > 0).any() == adaptations.own_return
    assert np.array_equal(people.public_id(), [p.public_id for p in persons])
    # rows grouped by owner, a person's rows in branch order
    assert np.all(np.diff(nodes.owner) >= 0)
    assert [table.NAMES[k] for k in nodes.kind] == [b.kind for p in persons for b in p.branches]
    # the objects made back are views of the tables' rows
    assert back[0].branches[0].x.base is nodes.x or back[0].branches[0].x.base is nodes.x.base


def test_a_tentative_track_is_id_zero_and_its_public_id_minus_its_key():
    persons = _state(Adaptations())
    persons[0].id = 0  # as a tentative track
    people, nodes = table.of(persons)
    assert people.public_id()[0] == -persons[0].key == table.persons(people, nodes)[0].public_id


def test_no_people_gives_empty_tables():
    people, nodes = table.of([])
    assert len(people) == 0 and len(nodes) == 0
    assert nodes.x.shape == (0, 8) and nodes.P.shape == (0, 8, 8) and people.Q.shape == (0, 8, 8)
    assert table.persons(people, nodes) == []
