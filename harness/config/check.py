"""Typed configs: every config value checked before the first frame, the key named.

Two kinds of node make up a run's config, and both are checked here before anything runs:

* ``_target_`` nodes (``tracker``, ``detector``, ``dataset``): their schema is the
  constructor they are built by. ``check_target`` reads its signature and type hints (the
  trackers', detectors' and loaders' constructors are fully annotated) and checks each key
  against them, so ``tracker.max_age=abc`` or ``tracker.max_age=2.5`` fails as
  ``tracker.max_age: expected int, got 'abc' (str)``. Ranges are the constructors' own
  checks (they raise ``ValueError`` naming the argument), run when the harness builds each
  component once before the first frame.
* the app's own keys (``evaluation``, ``objective``, ``seed``, ``progress``, ``foreground``,
  ``graph``, ``external``): ``APP_SCHEMA`` gives each one's type and allowed range, and
  ``check_app`` checks them (``evaluation.iou_threshold=2``,
  ``objective.metric=NOTAMETRIC``, ``evaluation.table=[FOO,HOTA]`` are all rejected here).

Types are checked strictly: an int key takes no float (2.5) and no bool, a float key takes
an int, a bool key takes only true/false, a list key takes a list.
"""

from __future__ import annotations

import collections.abc as cabc
import inspect
import math
import types
import typing
from collections.abc import Callable, Mapping
from pathlib import PurePath
from typing import Any

from hydra.utils import get_object

from occbench.errors import ConfigError
from occbench.metrics import COLUMNS
from occbench.metrics.occlusion import EXTRA_COLUMNS

HYDRA_KEYS = frozenset({"_target_", "_convert_", "_recursive_", "_partial_", "_args_"})

#: the top-level ``foreground`` key's values (the frame loop's modes, ``occbench.pipeline.loop``)
FOREGROUND_MODES = ("auto", "exact", "none", "mog2")


# --------------------------------------------------------------------------- values


def _name(tp: Any) -> str:
    if tp is type(None):
        return "null"
    origin = typing.get_origin(tp)
    if origin is typing.Literal:
        return " or ".join(repr(a) for a in typing.get_args(tp))
    if origin in (typing.Union, types.UnionType):
        return " or ".join(_name(a) for a in typing.get_args(tp))
    if origin is not None:
        args = ", ".join(_name(a) for a in typing.get_args(tp))
        base = getattr(origin, "__name__", str(origin))
        return f"{base}[{args}]" if args else base
    return getattr(tp, "__name__", str(tp))


def _shown(value: Any) -> str:
    return f"{value!r} ({type(value).__name__})"


def type_error(key: str, value: Any, tp: Any) -> str | None:
    """Why ``value`` does not fit the annotation ``tp`` (a message naming ``key``), or None.

    Unknown annotations (classes, callables, arrays) are not checked.
    """
    if tp is Any or tp is inspect.Parameter.empty:
        return None
    if isinstance(value, dict) and "_target_" in value:
        return None  # a nested component: checked when it is built
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if origin in (typing.Union, types.UnionType):
        errors = [type_error(key, value, a) for a in args]
        if any(e is None for e in errors):
            return None
        return f"{key}: expected {_name(tp)}, got {_shown(value)}"
    if origin is typing.Literal:
        return None if value in args else f"{key}: expected one of {list(args)}, got {value!r}"
    if tp is type(None):
        return None if value is None else f"{key}: expected null, got {_shown(value)}"
    if tp is bool:
        return None if isinstance(value, bool) else f"{key}: expected bool, got {_shown(value)}"
    if tp is int:
        ok = isinstance(value, int) and not isinstance(value, bool)
        return None if ok else f"{key}: expected int, got {_shown(value)}"
    if tp is float:
        ok = isinstance(value, int | float) and not isinstance(value, bool)
        return None if ok else f"{key}: expected float, got {_shown(value)}"
    if tp is str:
        return None if isinstance(value, str) else f"{key}: expected str, got {_shown(value)}"
    if tp in (PurePath,) or (isinstance(tp, type) and issubclass(tp, PurePath)):
        ok = isinstance(value, str | PurePath)
        return None if ok else f"{key}: expected a path (str), got {_shown(value)}"
    if origin in (list, tuple, cabc.Sequence, cabc.MutableSequence) or tp in (list, tuple):
        if not isinstance(value, list | tuple):
            return f"{key}: expected {_name(tp)}, got {_shown(value)}"
        if origin is tuple and args and args[-1] is not Ellipsis:
            if len(value) != len(args):
                return f"{key}: expected {len(args)} values ({_name(tp)}), got {list(value)!r}"
            items = list(zip(args, value))
        else:
            items = [(args[0], v) for v in value] if args else []
        for i, (a, v) in enumerate(items):
            err = type_error(f"{key}[{i}]", v, a)
            if err is not None:
                return err
        return None
    if origin in (dict, cabc.Mapping, cabc.MutableMapping) or tp in (dict,):
        if not isinstance(value, dict):
            return f"{key}: expected a mapping, got {_shown(value)}"
        if len(args) == 2:
            for k, v in value.items():
                err = type_error(f"{key}.{k}", v, args[1])
                if err is not None:
                    return err
        return None
    return None  # a class, callable or array annotation: left to the constructor


# --------------------------------------------------------------------------- _target_ nodes


def _hints(func: Callable[..., Any]) -> dict[str, Any]:
    """Type hints of ``func``; one unresolvable annotation drops only itself."""
    try:
        return typing.get_type_hints(func)
    except Exception:  # noqa: BLE001 - a TYPE_CHECKING-only name: resolve one by one
        pass
    glob = getattr(func, "__globals__", {})
    out = {}
    for name, ann in getattr(func, "__annotations__", {}).items():
        try:
            out[name] = eval(ann, glob) if isinstance(ann, str) else ann  # noqa: S307
        except Exception:  # noqa: BLE001 - unknown: not checked
            continue
    return out


def _located(target: str) -> Any:
    """The object a nested ``_target_`` names, or None when it cannot be imported (building
    it reports that)."""
    try:
        return get_object(target)
    except Exception:  # noqa: BLE001 - reported by instantiate, with the full message
        return None


def check_target(node: Mapping[str, Any], key: str, target: Any) -> None:
    """Check the keys of a ``_target_`` config ``node`` (a plain dict, interpolations
    resolved) against the signature of ``target`` (its class or function).

    Nested ``_target_`` nodes (e.g. PBM's parameter groups) are checked against their own
    targets' signatures, named ``<key>.<argument>.<field>``.

    Raises:
        ConfigError: a key that is not an argument, or a value of the wrong type, named as
            ``<key>.<argument>``.
    """
    func = target.__init__ if inspect.isclass(target) else target
    try:
        sig = inspect.signature(target)
    except (TypeError, ValueError):
        return
    hints = _hints(func)
    params = sig.parameters
    var_kw = any(p.kind is p.VAR_KEYWORD for p in params.values())
    for arg, value in node.items():
        if arg in HYDRA_KEYS:
            continue
        where = f"{key}.{arg}"
        if arg not in params:
            if var_kw:
                continue
            names = [p for p in params if p != "self"]
            raise ConfigError(f"{where}: not an argument of {node.get('_target_')} "
                              f"(its arguments: {', '.join(names)})")
        if isinstance(value, dict) and "_target_" in value:
            nested = _located(str(value["_target_"]))
            if nested is not None:  # a parameter group or component: its own signature
                check_target(value, where, nested)
            continue
        err = type_error(where, value, hints.get(arg, inspect.Parameter.empty))
        if err is not None:
            raise ConfigError(err)


# --------------------------------------------------------------------------- the app's keys


def metric_names() -> list[str]:
    """Every column of metrics.csv besides tracker and sequence."""
    return list(dict.fromkeys([*COLUMNS, *EXTRA_COLUMNS]))


def _in_unit(v: float) -> str | None:
    return None if 0.0 < v <= 1.0 else "must lie in (0, 1]"


def _in_closed_unit(v: float) -> str | None:
    return None if 0.0 <= v <= 1.0 else "must lie in [0, 1]"


def _metrics(v: list[str]) -> str | None:
    known = metric_names()
    bad = [m for m in v if m not in known]
    return None if not bad else f"unknown metric(s) {bad}; known: {', '.join(known)}"


def _metric(v: str) -> str | None:
    return _metrics([v])


def _foreground(v: str) -> str | None:
    return None if v in FOREGROUND_MODES else f"must be one of {list(FOREGROUND_MODES)}"


def _graph_format(v: str) -> str | None:
    return None if v in ("json", "csv") else "must be json or csv"


def _non_negative(v: int) -> str | None:
    return None if v >= 0 else "must be >= 0"


# key -> (type, range check or None); a missing key keeps the default
APP_SCHEMA: dict[str, tuple[Any, Callable[[Any], str | None] | None]] = {
    "seed": (int, _non_negative),
    "progress": (bool, None),
    "report": (bool, None),
    "foreground": (str, _foreground),
    "background": (dict[str, Any], None),
    "external": (dict[str, str], None),
    "evaluation.iou_threshold": (float, _in_unit),
    "evaluation.hidden_below": (float, _in_closed_unit),
    "evaluation.table": (list[str], _metrics),
    "evaluation.plot": (list[str], _metrics),
    "objective.tracker": (str | None, None),
    "objective.metric": (str, _metric),
    "graph.export": (bool, None),
    "graph.format": (str, _graph_format),
}


def _select(cfg: Mapping[str, Any], dotted: str) -> tuple[bool, Any]:
    node: Any = cfg
    for part in dotted.split("."):
        if not isinstance(node, Mapping) or part not in node:
            return False, None
        node = node[part]
    return True, node


def check_app(cfg: Mapping[str, Any]) -> None:
    """Check the app's own keys of a composed config (a plain dict, resolved).

    Raises:
        ConfigError: the first key of the wrong type or outside its range, named with its
            value and what it takes.
    """
    for key, (tp, check) in APP_SCHEMA.items():
        found, value = _select(cfg, key)
        if not found or (value is None and key != "objective.tracker"):
            continue
        err = type_error(key, value, tp)
        if err is not None:
            raise ConfigError(err)
        if check is not None and value is not None:
            why = check(value)
            if why is not None:
                raise ConfigError(f"{key}={_plain(value)}: {why}")


def _plain(value: Any) -> str:
    if isinstance(value, float) and math.isfinite(value):
        return f"{value:g}"
    if isinstance(value, list):
        return "[" + ",".join(str(v) for v in value) + "]"
    return str(value)
