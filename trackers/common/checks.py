"""Range checks of the trackers' parameter groups, one error format for all of them:
``ValueError("<group>.<field> <rule>, got <value>")``, where ``<group>.<field>`` is the key
under ``tracker.`` (or ``detector.detector.``) in the config (``matching.match_threshold``,
``association.mu_rho``, ``calibration.people.min_fill``); a tracker without groups names the bare
key (group ""): ``iou_threshold``."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import fields
from typing import TypeVar

G = TypeVar("G")


def parameter_group(name: str, value: G | None, kind: type[G]) -> G:
    """A tracker constructor's parameter group ``name``: ``value``, or the group's defaults
    (``kind()``) when None; TypeError naming ``name`` when it is not a ``kind``."""
    if value is None:
        return kind()
    if not isinstance(value, kind):
        raise TypeError(f"{name}: expected a {kind.__name__} or None, got {value!r}")
    return value


def require(key: str, ok: bool, rule: str, value: object) -> None:
    """ValueError ``"<key> <rule>, got <value>"`` unless ``ok``."""
    if not ok:
        raise ValueError(f"{key} {rule}, got {value!r}")


def _key(group: str, name: str) -> str:
    return f"{group}.{name}" if group else name


def unit(group: str, **values: float) -> None:
    """ValueError naming ``group.name`` unless each value lies in [0, 1] (NaN does not)."""
    for name, v in values.items():
        require(_key(group, name), 0.0 <= v <= 1.0, "must lie in [0, 1]", v)


def at_least(group: str, low: float, **values: float) -> None:
    """ValueError naming ``group.name`` unless each value is >= ``low`` (NaN is not)."""
    for name, v in values.items():
        require(_key(group, name), v >= low, f"must be >= {low}", v)


def coerce(group: object, kinds: dict[str, type]) -> None:
    """Store each named field of the frozen dataclass ``group`` as ``kinds[name]`` (YAML
    gives 3 for 3.0 and a tracker compares types in its hot loop)."""
    for name, kind in kinds.items():
        object.__setattr__(group, name, kind(getattr(group, name)))


def refuse_moved(owner: str, moved: Mapping[str, object], groups: Mapping[str, type]) -> None:
    """TypeError for the first key of ``moved`` (flat keyword arguments a constructor took
    before its parameter groups): ``<owner>.<key>: moved to <owner>.<group>.<key>``, the
    group being the one of ``groups`` (name -> frozen dataclass) with that field."""
    home = {f.name: name for name, kind in groups.items() for f in fields(kind)}
    for key in moved:
        if key not in home:
            raise TypeError(f"{owner}.{key}: not a key of the {owner} (its groups: "
                            f"{', '.join(groups)})")
        raise TypeError(f"{owner}.{key}: moved to {owner}.{home[key]}.{key} (issue 36: "
                        "parameter groups)")
