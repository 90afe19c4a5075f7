"""Scenario presets: who walks where in the synthetic scene.

Walkers move on the floor in world coordinates (metres, see ``scene.Camera``). Keyframe
times are seconds relative to the middle of the sequence, where each preset puts its
event, so a longer sequence shows more walking before and after the event at the same
walking speeds; positions are linear between keyframes and extrapolated with the first
(last) segment's velocity before (after) them.

Occlusion presets put the hidden person three to four times farther from the camera than the
occluder, shorter and slimmer, so that its whole silhouette fits inside the occluder's
torso: visibility really drops to 0 (``tests/harness/datasets/test_synthetic.py`` checks it).

Presets (``SCENARIOS``):

- ``crossing``: two people cross in opposite directions; the far one is totally hidden.
- ``stop_behind``: the near person stops; the far one walks behind, stops while hidden,
  then walks on.
- ``follow_occluder``: the far person walks toward the camera, is hidden by a passer-by,
  walks along with the occluder (hidden) and then drops back and reappears.
- ``uturn_behind``: the far person turns back while hidden and reappears on the side it
  entered from.
- ``pair_walk``: two people walk side by side (one partly hidden by the other); a third
  crosses behind them.
- ``similar_clothes``: three people in near-identical clothes cross.
- ``illumination``: passers-by under strong global illumination drift and a dimming step.
- ``crowd``: ``people`` walkers wandering between random waypoints at ``density`` persons
  per square metre of floor.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from occbench.datasets.synthetic.appearance import (
    Appearance,
    random_appearance,
    similar_appearance,
)
from occbench.datasets.synthetic.scene import Camera
from occbench.datasets.synthetic.sequence import Cast

#: metres walked per walking cycle (two steps)
STRIDE_M = 1.4


@dataclass
class Walker:
    """A person's keyframes: times t (s, relative to the sequence middle), floor X and Z (m)."""

    app: Appearance
    t: np.ndarray
    X: np.ndarray
    Z: np.ndarray

    @classmethod
    def columns(cls, app: Appearance, t, u, Z) -> Walker:
        """Keyframes given as image columns ``u = X / Z`` (0 = image centre)."""
        t, u, Z = (np.asarray(v, float) for v in (t, u, Z))
        Z = np.broadcast_to(Z, t.shape).astype(float)
        u = np.broadcast_to(u, t.shape).astype(float)
        return cls(app, t, u * Z, Z)

    def at(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """X, Z (m) at ``times`` (s)."""
        t, X, Z = self.t, self.X, self.Z
        if len(t) == 1:
            return np.full(times.shape, X[0]), np.full(times.shape, Z[0])
        x, z = np.interp(times, t, X), np.interp(times, t, Z)
        lo, hi = times < t[0], times > t[-1]
        for mask, a, b in ((lo, 0, 1), (hi, -2, -1)):
            if mask.any():
                dt = t[b] - t[a]
                vx, vz = (X[b] - X[a]) / dt, (Z[b] - Z[a]) / dt
                ref = t[0] if a == 0 else t[-1]
                x[mask] = (X[0] if a == 0 else X[-1]) + vx * (times[mask] - ref)
                z[mask] = (Z[0] if a == 0 else Z[-1]) + vz * (times[mask] - ref)
        return x, z


def walking_poses(
    vx: np.ndarray, vz: np.ndarray, speed: np.ndarray, fps: float, phase0: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per-frame pose of walkers from their velocities.

    Args:
        vx: (P, L) lateral velocity (any unit; only its sign and share of ``speed`` matter).
        vz: (P, L) velocity away from the camera, same unit as ``vx``.
        speed: (P, L) walking speed in m/s (sets the phase advance and the swing).
        fps: frames per second.
        phase0: (P,) initial phases.
    Returns:
        phase (P, L) radians, facing (P, L) in [-1, 1], away (P, L) bool, swing (P, L) in [0, 1].
        A standing person keeps its last facing and stops swinging.
    """
    norm = np.hypot(vx, vz)
    moving = speed > 0.15
    phase = phase0[:, None] + np.cumsum(speed / fps, axis=1) * (2 * math.pi / STRIDE_M)
    facing = np.where(moving, vx / np.maximum(norm, 1e-9), np.nan)
    away = np.where(moving, (vz > 0.3 * norm) & (np.abs(facing) < 0.6), np.nan)
    for a in (facing, away):  # carry the last moving value over standing frames
        for p in range(a.shape[0]):
            row = a[p]
            ok = np.flatnonzero(np.isfinite(row))
            if len(ok) == 0:
                row[:] = 0.0
                continue
            idx = np.maximum.accumulate(np.where(np.isfinite(row), np.arange(len(row)), -1))
            idx[idx < 0] = ok[0]
            row[:] = row[idx]
    swing = np.clip(speed / 1.1, 0.0, 1.0) * moving
    return phase, facing, away.astype(bool), swing


def world_cast(
    cam: Camera, walkers: list[Walker], length: int, fps: float, rng: np.random.Generator
) -> Cast:
    """Image-space cast of ``walkers`` over ``length`` frames (ids 1..P in order)."""
    times = (np.arange(length) - (length - 1) / 2.0) / fps
    P = len(walkers)
    X = np.zeros((P, length))
    Z = np.zeros((P, length))
    for p, w in enumerate(walkers):
        X[p], Z[p] = w.at(times)
    dX = np.gradient(X, axis=1) * fps if length > 1 else np.zeros_like(X)
    dZ = np.gradient(Z, axis=1) * fps if length > 1 else np.zeros_like(Z)
    speed = np.hypot(dX, dZ)
    phase, facing, away, swing = walking_poses(dX, dZ, speed, fps, rng.uniform(0, 2 * math.pi, P))
    heights = np.array([w.app.height_m for w in walkers])[:, None]
    builds = np.array([w.app.build for w in walkers])[:, None]
    valid = Z > 0.5
    Zs = np.where(valid, Z, np.nan)
    xf, yf = cam.project(X, 0.0, Zs)
    hp = cam.focal * heights / Zs
    wp = builds * hp
    boxes = np.stack([xf - wp / 2, yf - hp, wp, hp], axis=-1)
    return Cast(
        np.arange(1, P + 1), [w.app for w in walkers], boxes, Zs, phase, facing, away, swing
    )


# ---------------------------------------------------------------------- appearances
def _occluder(rng: np.random.Generator) -> Appearance:
    return replace(
        random_appearance(rng),
        height_m=float(rng.uniform(1.83, 1.88)),
        build=float(rng.uniform(0.42, 0.44)),
    )


def _hidden(rng: np.random.Generator, base: Appearance | None = None) -> Appearance:
    app = random_appearance(rng) if base is None else similar_appearance(base, rng)
    return replace(
        app, height_m=float(rng.uniform(1.6, 1.66)), build=float(rng.uniform(0.37, 0.39))
    )


# ---------------------------------------------------------------------- presets
# Each returns the walkers; ``sign`` mirrors the scene left-right (chosen by the seed).
def _crossing(cam, rng, fps, length, people, density, sign):
    # 0.65 m/s at 3.3 m and 0.75 m/s at 12.5 m, in image columns per second
    a = Walker.columns(_occluder(rng), [-1.0, 1.0], [-0.197 * sign, 0.197 * sign], 3.3)
    b = Walker.columns(_hidden(rng), [-1.0, 1.0], [0.06 * sign, -0.06 * sign], 12.5)
    return [a, b]


def _stop_behind(cam, rng, fps, length, people, density, sign):
    s = sign
    a = Walker.columns(_occluder(rng), [-4.0, -1.2, 2.5, 5.3], [-0.55 * s, 0.0, 0.0, 0.55 * s], 3.4)
    b = Walker.columns(_hidden(rng), [-3.5, 0.0, 1.4, 4.9], [0.35 * s, 0.0, 0.0, -0.35 * s], 11.0)
    return [a, b]


def _follow_occluder(cam, rng, fps, length, people, density, sign):
    s = sign
    du = 0.147  # occluder's image speed (columns per second): 0.5 m/s at 3.4 m
    a = Walker.columns(_occluder(rng), [-1.0, 1.0], [-du * s, du * s], 3.4)
    t_meet, u_meet, t_part = -0.68, -0.1, 1.2
    u_part = du * t_part
    # walks toward the camera on column u_meet, then along with the occluder, then drops
    # back (slower, away from the camera) and reappears on the occluder's trailing side
    b = Walker.columns(
        _hidden(rng),
        [t_meet - 3.4, t_meet, t_part, t_part + 3.0],
        [u_meet * s, u_meet * s, u_part * s, (u_part + 0.03 * 3.0) * s],
        [14.0, 9.0, 9.0, 10.5],
    )
    return [a, b]


def _uturn_behind(cam, rng, fps, length, people, density, sign):
    s = sign
    a = Walker.columns(_occluder(rng), [-1.0, 1.0], [-0.118 * s, 0.118 * s], 3.4)
    u_turn = -0.01
    b = Walker.columns(
        _hidden(rng),
        [-3.0, 0.0, 3.0],
        [(u_turn + 0.126 * 3.0) * s, u_turn * s, (u_turn + 0.15 * 3.0) * s],
        9.5,
    )
    return [a, b]


def _pair_walk(cam, rng, fps, length, people, density, sign):
    s = sign
    v = 1.1 / 4.3  # columns per second of the nearer walker
    a = Walker.columns(random_appearance(rng), [-1.0, 1.0], [-v * s, v * s], 4.3)
    xa = np.array([-v, v]) * 4.3 * s
    b = Walker(random_appearance(rng), np.array([-1.0, 1.0]), xa + 0.3 * s, np.array([4.9, 4.9]))
    c = Walker.columns(random_appearance(rng), [0.5, 2.5], [0.15 * s, -0.1 * s], 9.0)
    return [a, b, c]


def _similar_clothes(cam, rng, fps, length, people, density, sign):
    s = sign
    base = random_appearance(rng)
    a = Walker.columns(
        replace(similar_appearance(base, rng), height_m=1.86, build=0.43),
        [-1.0, 1.0],
        [-0.206 * s, 0.206 * s],
        3.4,
    )
    b = Walker.columns(_hidden(rng, base), [-1.0, 1.0], [0.0857 * s, -0.0857 * s], 10.5)
    c = Walker.columns(
        similar_appearance(base, rng), [1.5, 2.5], [0.309 * s, (0.309 - 0.1667) * s], 6.0
    )
    return [a, b, c]


def _passers(
    cam: Camera, rng: np.random.Generator, fps: float, length: int, n: int, sign: float
) -> list[Walker]:
    """``n`` people crossing the view on straight lines, spread over the sequence."""
    half_t = length / (2.0 * fps)
    out = []
    for i in range(n):
        z0 = rng.uniform(4.0, 12.0)
        z1 = float(np.clip(z0 + rng.uniform(-2.5, 2.5), 3.5, 14.0))
        d = 1.0 if rng.random() < 0.5 else -1.0
        speed = rng.uniform(0.9, 1.5)
        u0, u1 = -0.75 * d, 0.75 * d
        X0, X1 = u0 * z0, u1 * z1
        dur = math.hypot(X1 - X0, z1 - z0) / speed
        # the middle of the walk falls somewhere inside the sequence
        tm = rng.uniform(-0.7, 0.7) * half_t + (i - (n - 1) / 2) * 0.1
        t0 = tm - dur / 2
        out.append(
            Walker(
                random_appearance(rng),
                np.array([t0, t0 + dur]),
                np.array([X0, X1]),
                np.array([z0, z1]),
            )
        )
    return out


def _illumination(cam, rng, fps, length, people, density, sign):
    return _passers(cam, rng, fps, length, 4, sign)


def _crowd(cam, rng, fps, length, people, density, sign):
    area = people / density
    z0 = 4.0
    depth = min(math.sqrt(area / 1.5), 14.0)
    width = area / depth
    half_t = length / (2.0 * fps) + 1.0
    out = []
    for _ in range(people):
        t = [-half_t - rng.uniform(0.0, 1.0)]
        X = [rng.uniform(-width / 2, width / 2)]
        Z = [rng.uniform(z0, z0 + depth)]
        while t[-1] < half_t:
            if rng.random() < 0.15:  # pause
                t.append(t[-1] + rng.uniform(0.5, 2.0))
                X.append(X[-1])
                Z.append(Z[-1])
                continue
            x1, z1 = rng.uniform(-width / 2, width / 2), rng.uniform(z0, z0 + depth)
            dist = math.hypot(x1 - X[-1], z1 - Z[-1])
            if dist < 0.5:
                continue
            t.append(t[-1] + dist / rng.uniform(0.8, 1.5))
            X.append(x1)
            Z.append(z1)
        out.append(Walker(random_appearance(rng), np.array(t), np.array(X), np.array(Z)))
    return out


Builder = Callable[..., list[Walker]]

#: preset name -> walker builder
SCENARIOS: dict[str, Builder] = {
    "crossing": _crossing,
    "stop_behind": _stop_behind,
    "follow_occluder": _follow_occluder,
    "uturn_behind": _uturn_behind,
    "pair_walk": _pair_walk,
    "similar_clothes": _similar_clothes,
    "illumination": _illumination,
    "crowd": _crowd,
}


def illumination_gains(
    amplitude: float, length: int, fps: float, rng: np.random.Generator, step: bool = False
) -> np.ndarray | None:
    """(L, 3) per-frame B, G, R gains: a slow drift plus a faster flicker of relative size
    ``amplitude``, a small colour-temperature drift, and with ``step`` a 30% dimming over
    half a second in the middle. None when there is nothing to apply."""
    if amplitude < 0:
        raise ValueError(f"illumination must be >= 0, got {amplitude}")
    if amplitude == 0 and not step:
        return None
    t = np.arange(length) / fps
    T1, T2, T3 = rng.uniform(6.0, 12.0), rng.uniform(1.5, 3.0), rng.uniform(4.0, 8.0)
    p1, p2, p3 = rng.uniform(0, 2 * math.pi, 3)
    base = 1.0 + amplitude * (
        0.7 * np.sin(2 * math.pi * t / T1 + p1) + 0.3 * np.sin(2 * math.pi * t / T2 + p2)
    )
    if step:
        mid = t[-1] / 2.0
        base = base * (1.0 - 0.3 * np.clip((t - mid) / 0.5, 0.0, 1.0))
    tint = 0.15 * amplitude * np.sin(2 * math.pi * t / T3 + p3)
    gains = base[:, None] * (1.0 + np.stack([tint, np.zeros_like(tint), -tint], 1))
    return np.clip(gains, 0.05, 3.0)
