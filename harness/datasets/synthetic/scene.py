"""The static scene of the synthetic renderer: a pinhole camera over a ground plane and a
textured background (tiled floor in perspective, back and side walls, a few static objects).

World coordinates are metres: ``X`` to the right, ``Y`` up from the floor, ``Z`` away from
the camera along the optical axis. The camera looks horizontally from height
``camera_height``; a floor point (X, 0, Z) projects to::

    x = cx + f * X / Z,    y = horizon + f * camera_height / Z

so a person standing farther away has a smaller image and feet higher in the image
(ground-plane perspective). The camera sits at hip height (1.3 m by default) so that a
nearer person can hide a farther one completely, head included: with the camera above the
heads, a farther person's head always shows above the nearer one's.

Image coordinates are pixels with (0, 0) the top-left pixel, x right, y down.

``defer_background`` draws a background's choices without painting it, so that a suite's
scenes load at once and each is painted when its sequence first needs it.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True)
class Camera:
    """Pinhole camera looking horizontally over the floor.

    Attributes:
        width, height: image size in pixels.
        focal: focal length in pixels.
        horizon: image row of the horizon (the vanishing line of the floor), pixels.
        camera_height: height of the optical centre above the floor, metres.
    """

    width: int
    height: int
    focal: float
    horizon: float
    camera_height: float = 1.3

    @classmethod
    def for_size(cls, width: int, height: int, camera_height: float = 1.3,
                 horizon: float = 0.42) -> Camera:
        """The camera of a ``width`` x ``height`` frame (focal = height, horizon at
        ``horizon`` x the height: 42% by default)."""
        if width < 64 or height < 64:
            raise ValueError(f"Camera: frame size must be at least 64x64, got {width}x{height}")
        return cls(int(width), int(height), float(height), float(horizon) * height, float(camera_height))

    @property
    def cx(self) -> float:
        return self.width / 2.0

    def project(self, X: np.ndarray, Y: np.ndarray, Z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Image (x, y) in pixels of world points (X, Y, Z) in metres (Z > 0)."""
        X, Y, Z = np.asarray(X, float), np.asarray(Y, float), np.asarray(Z, float)
        return self.cx + self.focal * X / Z, self.horizon + self.focal * (
            self.camera_height - Y
        ) / Z

    def scale(self, Z: np.ndarray) -> np.ndarray:
        """Pixels per metre at depth ``Z``."""
        return self.focal / np.asarray(Z, float)

    def depth_of_row(self, y: float) -> float:
        """Depth Z (m) of the floor point seen at image row ``y`` (> horizon)."""
        return self.focal * self.camera_height / (y - self.horizon)

    def half_width_at(self, Z: float) -> float:
        """Half the visible floor width (m) at depth ``Z``."""
        return Z * self.cx / self.focal

    @property
    def near_depth(self) -> float:
        """Depth of the floor at the bottom image row."""
        return self.depth_of_row(self.height)


#: depth of the back wall, m
BACK_WALL_Z = 22.0
#: X of the left side wall, m
LEFT_WALL_X = -7.5


def _poly(cam: Camera, pts: list[tuple[float, float, float]]) -> np.ndarray:
    """(N, 2) int32 image polygon (4 fractional bits) of world points."""
    a = np.asarray(pts, float)
    x, y = cam.project(a[:, 0], a[:, 1], a[:, 2])
    return np.round(np.stack([x, y], 1) * 16).astype(np.int32)


def _fill(img: np.ndarray | None, cam: Camera, pts: list[tuple[float, float, float]],
          colour) -> None:
    if img is not None:  # None: the choices are drawn, nothing painted (``defer_background``)
        cv2.fillPoly(img, [_poly(cam, pts)], tuple(float(c) for c in colour), cv2.LINE_AA, 4)


def _cuboid(
    img: np.ndarray | None,
    cam: Camera,
    x0: float,
    x1: float,
    z0: float,
    z1: float,
    h: float,
    colour: np.ndarray,
) -> None:
    """A box standing on the floor: front face, the visible side face and the top (if below
    eye level), shaded differently."""
    c = np.asarray(colour, float)
    if h < cam.camera_height:
        _fill(img, cam, [(x0, h, z0), (x1, h, z0), (x1, h, z1), (x0, h, z1)], c * 1.15)
    # side facing the camera axis
    if x1 < 0:
        _fill(img, cam, [(x1, 0, z0), (x1, 0, z1), (x1, h, z1), (x1, h, z0)], c * 0.7)
    elif x0 > 0:
        _fill(img, cam, [(x0, 0, z0), (x0, 0, z1), (x0, h, z1), (x0, h, z0)], c * 0.7)
    _fill(img, cam, [(x0, 0, z0), (x1, 0, z0), (x1, h, z0), (x0, h, z0)], c)


def render_background(cam: Camera, rng: np.random.Generator) -> np.ndarray:
    """The static background: (H, W, 3) uint8 BGR.

    A tiled floor (1 m tiles, per-tile shade jitter, grout lines converging to the vanishing
    point), a back wall with windows and a door at ``BACK_WALL_Z``, a left wall with posters,
    a few static objects (crates, a bench, planters) near the walls so that walkers pass in
    front of them, fine texture noise and a mild vignette. Every choice comes from ``rng``.
    """
    img = _background(np.zeros((cam.height, cam.width, 3), np.uint8), cam, rng)
    assert img is not None
    return img


@dataclass(frozen=True)
class DeferredBackground:
    """``render_background(cam, rng)`` painted when called, from ``state``, the generator's
    state before it (``defer_background``). ``shape``: (H, W, 3) of the image it paints."""

    cam: Camera
    state: dict

    @property
    def shape(self) -> tuple[int, int, int]:
        return self.cam.height, self.cam.width, 3

    def __call__(self) -> np.ndarray:
        bit_generator = getattr(np.random, self.state["bit_generator"])()
        bit_generator.state = self.state
        return render_background(self.cam, np.random.Generator(bit_generator))


def defer_background(cam: Camera, rng: np.random.Generator) -> DeferredBackground:
    """``render_background(cam, rng)`` left for later: ``rng`` advances exactly as the render
    would advance it (every choice drawn, nothing painted: what follows from ``rng`` is the
    same), and the returned ``DeferredBackground`` paints the same image when called."""
    deferred = DeferredBackground(cam, rng.bit_generator.state)
    _background(None, cam, rng)
    return deferred


def _background(img: np.ndarray | None, cam: Camera,
                rng: np.random.Generator) -> np.ndarray | None:
    """``render_background``'s steps on ``img`` ((H, W, 3) uint8 zeros), or, with None, the
    same draws from ``rng`` without painting."""
    wall = _back_wall_colour(img, cam, rng)
    _floor(img, cam, rng)
    _back_wall(img, cam, rng, wall)
    _left_wall(img, cam, rng, wall)
    _objects(img, cam, rng)
    return _texture(img, cam, rng)


def _extent(cam: Camera) -> tuple[float, float, float]:
    """The scene's left wall X, right floor edge X (a metre beyond the view at the back
    wall) and back wall Z, metres."""
    return LEFT_WALL_X, cam.half_width_at(BACK_WALL_Z) + 1.0, BACK_WALL_Z


def _back_wall_colour(img: np.ndarray | None, cam: Camera,
                      rng: np.random.Generator) -> np.ndarray:
    """Fill ``img`` with the back wall's colour (everything above the far floor edge) and
    the ceiling tint; the wall colour (3,) float."""
    zb = BACK_WALL_Z
    wall = rng.uniform(150, 210, 3)
    wall[rng.integers(3)] *= 0.85
    if img is None:
        return wall
    img[:] = np.clip(wall, 0, 255).astype(np.uint8)
    top_y = cam.project(0, 6.0, zb)[1]
    img[: max(int(top_y), 0)] = np.clip(wall * 0.8, 0, 255).astype(np.uint8)
    return wall


def _floor(img: np.ndarray | None, cam: Camera, rng: np.random.Generator) -> None:
    """Floor tiles (1 m, per-tile shade jitter) and grout lines."""
    xl, xr, zb = _extent(cam)
    floor_a = rng.uniform(90, 150, 3)
    floor_b = floor_a * rng.uniform(0.78, 0.9)
    zs = np.arange(max(np.floor(cam.near_depth * 0.5), 0.5), zb + 1.0, 1.0)
    xs = np.arange(np.floor(xl), np.ceil(xr) + 1.0, 1.0)
    rows = [(i, z0, min(z1, zb)) for i, (z0, z1) in enumerate(itertools.pairwise(zs))
            if z0 < min(z1, zb)]
    cols = list(enumerate(itertools.pairwise(xs)))
    shades = rng.uniform(0.94, 1.06, (len(rows), len(cols)))  # one per tile, row by row
    if img is None:
        return
    for (i, z0, z1), row_shades in zip(rows, shades, strict=True):
        for (j, (x0, x1)), shade in zip(cols, row_shades, strict=True):
            base = floor_a if (i + j) % 2 == 0 else floor_b
            col = np.clip(base * shade, 0, 255)
            _fill(img, cam, [(x0, 0, z0), (x1, 0, z0), (x1, 0, z1), (x0, 0, z1)], col)
    grout = tuple(float(v) for v in floor_b * 0.7)
    for x in xs:
        cv2.line(
            img,
            tuple(_poly(cam, [(x, 0, 0.3)])[0]),
            tuple(_poly(cam, [(x, 0, zb)])[0]),
            grout,
            1,
            cv2.LINE_AA,
            4,
        )
    for z in zs:
        if z <= zb:
            cv2.line(
                img,
                tuple(_poly(cam, [(xl, 0, z)])[0]),
                tuple(_poly(cam, [(xr + 50, 0, z)])[0]),
                grout,
                1,
                cv2.LINE_AA,
                4,
            )


def _back_wall(img: np.ndarray | None, cam: Camera, rng: np.random.Generator,
               wall: np.ndarray) -> None:
    """The back wall's skirting, windows and doors."""
    xl, xr, zb = _extent(cam)
    _fill(
        img, cam, [(xl, 0, zb), (xr + 50, 0, zb), (xr + 50, 0.15, zb), (xl, 0.15, zb)], wall * 0.5
    )
    glass = rng.uniform(120, 200, 3) * np.array([1.1, 1.0, 0.8])
    wx = xl + 1.5
    while wx < xr - 1.0:
        if rng.random() < 0.25:  # a door
            _fill(
                img,
                cam,
                [(wx, 0.15, zb), (wx + 1.2, 0.15, zb), (wx + 1.2, 2.3, zb), (wx, 2.3, zb)],
                wall * 0.45,
            )
        else:
            _fill(
                img,
                cam,
                [
                    (wx - 0.08, 0.92, zb),
                    (wx + 1.88, 0.92, zb),
                    (wx + 1.88, 2.58, zb),
                    (wx - 0.08, 2.58, zb),
                ],
                wall * 0.6,
            )
            _fill(
                img,
                cam,
                [(wx, 1.0, zb), (wx + 1.8, 1.0, zb), (wx + 1.8, 2.5, zb), (wx, 2.5, zb)],
                np.clip(glass * rng.uniform(0.9, 1.1), 0, 255),
            )
            _fill(
                img,
                cam,
                [
                    (wx + 0.87, 1.0, zb),
                    (wx + 0.93, 1.0, zb),
                    (wx + 0.93, 2.5, zb),
                    (wx + 0.87, 2.5, zb),
                ],
                wall * 0.6,
            )
        wx += rng.uniform(2.6, 3.6)


def _left_wall(img: np.ndarray | None, cam: Camera, rng: np.random.Generator,
               wall: np.ndarray) -> None:
    """The left wall (plane X = LEFT_WALL_X) and its posters."""
    xl, _, zb = _extent(cam)
    side = wall * rng.uniform(0.7, 0.85)
    zn = 0.2
    _fill(img, cam, [(xl, 0, zn), (xl, 0, zb), (xl, 8.0, zb), (xl, 8.0, zn)], side)
    _fill(img, cam, [(xl, 0, zn), (xl, 0, zb), (xl, 0.15, zb), (xl, 0.15, zn)], side * 0.55)
    z = 4.0
    while z < zb - 2.0:
        col = rng.uniform(40, 230, 3)
        _fill(img, cam, [(xl, 1.0, z), (xl, 1.0, z + 1.2), (xl, 2.2, z + 1.2), (xl, 2.2, z)], col)
        _fill(
            img,
            cam,
            [(xl, 1.15, z + 0.2), (xl, 1.15, z + 1.0), (xl, 1.5, z + 1.0), (xl, 1.5, z + 0.2)],
            255 - col,
        )
        z += rng.uniform(3.0, 5.0)


def _objects(img: np.ndarray | None, cam: Camera, rng: np.random.Generator) -> None:
    """Static objects near the walls (crates, benches, planters): people walk in front of
    them."""
    xl, _, zb = _extent(cam)
    for _ in range(int(rng.integers(3, 6))):
        zc = rng.uniform(zb - 4.0, zb - 0.6)
        half = cam.half_width_at(zc)
        xc = rng.uniform(max(xl + 0.6, -half), half)
        kind = rng.integers(3)
        if kind == 0:  # crate
            s = rng.uniform(0.5, 0.9)
            _cuboid(
                img,
                cam,
                xc - s / 2,
                xc + s / 2,
                zc,
                zc + s,
                s,
                rng.uniform(40, 140, 3) * [0.6, 0.9, 1.2],
            )
        elif kind == 1:  # bench
            col = rng.uniform(50, 120, 3)
            _cuboid(img, cam, xc - 0.9, xc + 0.9, zc, zc + 0.45, 0.45, col)
            _cuboid(img, cam, xc - 0.9, xc + 0.9, zc + 0.4, zc + 0.5, 0.9, col * 0.9)
        else:  # planter with a shrub
            _cuboid(img, cam, xc - 0.3, xc + 0.3, zc, zc + 0.6, 0.5, rng.uniform(60, 120, 3))
            cxy = cam.project(xc, 0.95, zc + 0.3)
            r = cam.scale(zc) * 0.45
            shrub = (float(rng.uniform(30, 70)), float(rng.uniform(90, 150)),
                     float(rng.uniform(30, 70)))
            if img is not None:
                cv2.ellipse(img, (int(cxy[0]), int(cxy[1])), (int(r), int(r * 1.1)), 0, 0, 360,
                            shrub, -1, cv2.LINE_AA)


def _texture(img: np.ndarray | None, cam: Camera, rng: np.random.Generator) -> np.ndarray | None:
    """``img`` with smoothed texture noise and a mild vignette, as uint8."""
    H, W = cam.height, cam.width
    noise = rng.normal(0.0, 1.0, (H // 2 + 1, W // 2 + 1)).astype(np.float32)
    if img is None:
        return None
    noise = cv2.GaussianBlur(noise, (0, 0), 0.8)
    noise = cv2.resize(noise, (W, H), interpolation=cv2.INTER_LINEAR)
    yy, xx = np.mgrid[0:H, 0:W].astype(np.float32)
    vig = 1.0 - 0.25 * (((xx - W / 2) / W) ** 2 + ((yy - H / 2) / H) ** 2)
    out = img.astype(np.float32) * vig[..., None] + 6.0 * noise[..., None]
    return np.clip(out + 0.5, 0, 255).astype(np.uint8)
