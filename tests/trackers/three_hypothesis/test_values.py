"""Reta's Alg. 1 steps pass values (issue 36 item 2): every step's result is frozen, the
tracker mixes nothing in, and update calls the steps in Alg. 1's order."""

from __future__ import annotations

import ast
import dataclasses
import inspect

import pytest

from occbench.trackers.three_hypothesis import RetaTracker, tracker, values


def _step_values() -> list[type]:
    return [obj for _, obj in inspect.getmembers(values, inspect.isclass)
            if obj.__module__ == values.__name__]


def test_every_step_value_is_frozen():
    found = _step_values()
    assert {c.__name__ for c in found} >= {"Measurements", "Predictions", "Occlusions", "Match",
                                           "Matching", "DepthOrder", "Updated", "Continuation"}
    for cls in found:
        if dataclasses.is_dataclass(cls):
            assert cls.__dataclass_params__.frozen, cls.__name__
            value = cls(*[None] * len(dataclasses.fields(cls)))
            with pytest.raises(dataclasses.FrozenInstanceError):
                setattr(value, dataclasses.fields(cls)[0].name, None)
        else:  # a NamedTuple
            assert issubclass(cls, tuple) and hasattr(cls, "_fields"), cls.__name__
            with pytest.raises(AttributeError):
                setattr(cls(*[0] * len(cls._fields)), cls._fields[0], 1)


def test_the_tracker_mixes_nothing_in():
    assert RetaTracker.__bases__ == (object,)


def test_update_calls_the_steps_of_algorithm_1_in_order():
    body = next(n for n in ast.walk(ast.parse(inspect.getsource(tracker)))
                if isinstance(n, ast.FunctionDef) and n.name == "update")
    calls = sorted((n for n in ast.walk(body)
                    if isinstance(n, ast.Call) and isinstance(n.func, ast.Name)),
                   key=lambda n: (n.lineno, n.col_offset))
    called = [n.func.id for n in calls]
    steps = ["measure", "predict", "occlusions", "max_similarity", "sort_occlusions",
             "update_matched", "continue_unmatched", "prune", "start_tracks", "outputs"]
    assert [name for name in called if name in steps] == steps
