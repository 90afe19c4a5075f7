"""Synthetic people: drawing (the appearance is ``occbench.datasets.synthetic.appearance``).

A person is drawn inside its box (xywh, pixels, 0-based top-left) from parts, in the
proportions of PBM 2.1 (head = 1/7 of the height): a head (skin-tone face and a hair cap,
hair at the back of the head when seen from the side, only hair when seen from behind), a
neck, a torso in the shirt colour with shading and a pattern (plain, stripes, open jacket,
chest logo), two arms (sleeves, hands in skin colour) and two legs (trousers, knees, shoes)
that swing with the walking phase. Every part lies inside the box, so the box is the
person's full (amodal) box.

Drawing uses OpenCV primitives with 3 fractional bits (sub-pixel positions) and no
anti-aliasing, and draws the same primitives into an optional int32 label image with the
person's id, so the label image is an exact segmentation of the drawn colours.

Horizontal positions are in "body units": a box of width ``w`` spans body units
[-0.2, 0.2]; vertical positions ``v`` are fractions of the box height from its top.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from occbench.datasets.synthetic.appearance import Appearance

SHIFT = 3
_S = 1 << SHIFT

def _scaled(c, f: float) -> tuple[float, float, float]:
    return (min(c[0] * f, 255.0), min(c[1] * f, 255.0), min(c[2] * f, 255.0))


# head ellipse (body units / height fractions): centre v, half width, half height
_HEAD_V, _HEAD_RA, _HEAD_RV = 0.068, 0.056, 0.066


def head_box(box: np.ndarray, facing: float = 0.0) -> np.ndarray:
    """(4,) xywh box of the head (hair included) of a person drawn in ``box``."""
    x, y, w, h = (float(v) for v in box)
    sx = w / 0.4
    cx = x + w / 2 + 0.006 * facing * sx
    return np.array(
        [cx - _HEAD_RA * sx, y + (_HEAD_V - _HEAD_RV) * h, 2 * _HEAD_RA * sx, 2 * _HEAD_RV * h]
    )


class _Pen:
    """Records primitives in body units, then draws them all (``flush``) in colour into
    ``img`` and as ``value`` into ``label``.

    Points of all primitives are converted to fixed-point pixels in one vectorised step;
    rounding is ``floor(x * 8 + 0.5)`` in image coordinates, then the integer ``origin`` is
    subtracted, so a person drawn into a crop gets exactly the pixels it gets in the image.
    """

    __slots__ = ("cmds", "cx", "h", "img", "label", "ox", "oy", "pts", "sx", "value", "y0")

    def __init__(self, img, label, value, box, origin=(0, 0)) -> None:
        x, y, w, h = (float(v) for v in box)
        self.img, self.label, self.value = img, label, int(value)
        self.cx, self.y0, self.sx, self.h = x + w / 2.0, y, w / 0.4, h
        self.ox, self.oy = int(origin[0]) * _S, int(origin[1]) * _S
        self.pts: list[float] = []
        self.cmds: list[tuple] = []

    def poly(self, pts, colour) -> None:
        self.cmds.append((0, len(self.pts) // 2, len(pts), colour))
        for a, v in pts:
            self.pts += (a, v)

    def limb(self, a0, v0, r0, a1, v1, r1, colour) -> None:
        """A tapered segment from (a0, v0) to (a1, v1) with half widths r0, r1 (body units)."""
        dx, dy = (a1 - a0) * self.sx, (v1 - v0) * self.h
        n = math.hypot(dx, dy) or 1.0
        # unit normal in pixels, converted back to body units (widths scale with sx)
        nxa, nyv = -dy / n, dx / n * self.sx / self.h
        self.poly(
            (
                (a0 + nxa * r0, v0 + nyv * r0),
                (a1 + nxa * r1, v1 + nyv * r1),
                (a1 - nxa * r1, v1 - nyv * r1),
                (a0 - nxa * r0, v0 - nyv * r0),
            ),
            colour,
        )

    def ellipse(self, a, v, ra, rv, colour, start: float = 0.0, end: float = 360.0) -> None:
        axes = (max(int(ra * self.sx * _S + 0.5), 1), max(int(rv * self.h * _S + 0.5), 1))
        self.cmds.append((1, len(self.pts) // 2, axes, colour, start, end))
        self.pts += (a, v)

    def dot(self, a, v, radius: int, colour) -> None:
        """A small disc drawn in colour only (a detail inside already labelled pixels)."""
        self.cmds.append((2, len(self.pts) // 2, radius, colour))
        self.pts += (a, v)

    def flush(self) -> None:
        if not self.cmds:
            return
        q = np.array(self.pts).reshape(-1, 2)
        q *= (self.sx * _S, self.h * _S)
        q += (self.cx * _S + 0.5, self.y0 * _S + 0.5)
        q = np.floor(q).astype(np.int32)
        q -= (self.ox, self.oy)
        ql = q.tolist()
        img, label, value = self.img, self.label, self.value
        fill, ellipse, line8 = cv2.fillConvexPoly, cv2.ellipse, cv2.LINE_8
        for cmd in self.cmds:
            kind, i = cmd[0], cmd[1]
            if kind == 0:
                p = q[i : i + cmd[2]]
                if img is not None:
                    fill(img, p, cmd[3], line8, SHIFT)
                if label is not None:
                    fill(label, p, value, line8, SHIFT)
            elif kind == 1:
                c = ql[i]
                if img is not None:
                    ellipse(img, c, cmd[2], 0, cmd[4], cmd[5], cmd[3], -1, line8, SHIFT)
                if label is not None:
                    ellipse(label, c, cmd[2], 0, cmd[4], cmd[5], value, -1, line8, SHIFT)
            elif img is not None:
                cv2.circle(img, ql[i], cmd[2], cmd[3], -1, line8, SHIFT)
        self.cmds.clear()
        self.pts.clear()


def draw_person(
    img: np.ndarray | None,
    label: np.ndarray | None,
    value: int,
    box: np.ndarray,
    app: Appearance,
    phase: float = 0.0,
    facing: float = 0.0,
    away: bool = False,
    swing: float = 1.0,
    origin: tuple[int, int] = (0, 0),
) -> None:
    """Draw one person into ``img`` ((H, W, 3) uint8 BGR) and/or ``label`` ((H, W) int32).

    Args:
        value: label value written into ``label`` (the gt id).
        box: (4,) xywh amodal box, pixels; the person fills it.
        app: appearance.
        phase: walking phase, radians (one period = one stride of both legs).
        facing: lateral walking direction in [-1, 1] (-1 left, +1 right, 0 toward or away
            from the camera); a side view is narrower and the face turns that way.
        away: seen from behind (hair, no face) when walking away from the camera.
        swing: amplitude of the arm and leg swing in [0, 1] (0 standing still).
        origin: integer (x, y) of the targets' top-left pixel in image coordinates (draw
            into a crop of the image; pixels are the same as when drawn into the image).
    """
    pen = _Pen(img, label, value, box, origin)
    side = abs(facing)
    dirn = 1.0 if facing >= 0 else -1.0
    tw = 1.0 - 0.2 * side  # torso width factor (side view narrower)
    s = math.sin(phase) * swing
    c = math.cos(phase) * swing
    _legs(pen, app, side, dirn, s, c)
    # pelvis
    pen.poly(
        [(-0.092 * tw, 0.44), (0.092 * tw, 0.44), (0.088 * tw, 0.56), (-0.088 * tw, 0.56)],
        app.trousers,
    )
    behind_first = side > 0.4  # the arm behind the torso in side views, drawn first
    if behind_first:
        _arm(pen, app, -dirn, 0.75, side, dirn, tw, s)

    # --- long hair behind the shoulders (front view)
    if app.long_hair and not away:
        pen.poly([(-0.06, 0.07), (0.06, 0.07), (0.065, 0.2), (-0.065, 0.2)], app.hair)
    _torso(pen, app, tw, facing, away)
    _head(pen, app, img is not None, facing, side, dirn, away)

    # --- arms in front (both in front views, the near one in side views)
    if behind_first:
        _arm(pen, app, dirn, 1.0, side, dirn, tw, s)
    else:
        _arm(pen, app, -1.0, 0.95, side, dirn, tw, s)
        _arm(pen, app, 1.0, 0.95, side, dirn, tw, s)
    pen.flush()


def _legs(pen: _Pen, app: Appearance, side: float, dirn: float, s: float, c: float) -> None:
    """Both legs, hip -> knee -> ankle, the leg behind drawn first and darker."""
    trousers = app.trousers
    stride = 0.11 * max(side, 0.25)
    legs = []
    for k in (-1.0, 1.0):
        hip_a = k * 0.045 * (1.0 - 0.7 * side)  # hips overlap in a side view
        foot_a = hip_a + k * dirn * stride * s
        # the leg swinging forward (k * c > 0) bends its knee forward and lifts its foot
        knee_a = 0.5 * (hip_a + foot_a) + dirn * 0.025 * side * max(k * c, 0.0)
        lift = 0.025 * max(k * c, 0.0) * side
        legs.append((hip_a, knee_a, foot_a, lift, k))
    legs.sort(key=lambda leg: leg[4] * s * dirn)  # the leg moving back is behind
    for i, (hip_a, knee_a, foot_a, lift, _) in enumerate(legs):
        col = _scaled(trousers, 0.82) if i == 0 else trousers
        pen.limb(hip_a, 0.5, 0.045, knee_a, 0.73, 0.035, col)
        pen.limb(knee_a, 0.73, 0.035, foot_a, 0.95 - lift, 0.027, col)
        pen.ellipse(knee_a, 0.73, 0.035, 0.012, col)
        pen.ellipse(foot_a + 0.012 * dirn * side, 0.968 - lift, 0.036, 0.022, app.shoes)


def _arm(pen: _Pen, app: Appearance, k: float, colour_scale: float, side: float, dirn: float,
         tw: float, s: float) -> None:
    """The arm on side ``k`` (-1 left, +1 right): sleeve, forearm, hand."""
    shirt, skin = app.shirt, app.skin
    sh_a = k * 0.11 * tw * (1.0 - 0.7 * side)  # shoulders overlap in a side view
    swing_a = -k * dirn * 0.1 * s * max(side, 0.3) if side > 0.4 else 0.0
    elbow_a = sh_a + k * 0.012 * (1 - side) + 0.5 * swing_a
    hand_a = sh_a + k * 0.02 * (1 - side) + swing_a + dirn * 0.02 * side * abs(s)
    hand_a = max(min(hand_a, 0.17), -0.17)
    sleeve = _scaled(shirt, 0.88 * colour_scale)
    pen.ellipse(sh_a, 0.2, 0.035, 0.03, sleeve)
    pen.limb(sh_a, 0.19, 0.034, elbow_a, 0.33, 0.03, sleeve)
    fore = _scaled(skin, colour_scale) if app.short_sleeves else sleeve
    pen.limb(elbow_a, 0.33, 0.03, hand_a, 0.44, 0.024, fore)
    pen.ellipse(hand_a, 0.455, 0.024, 0.02, _scaled(skin, colour_scale))


def _torso(pen: _Pen, app: Appearance, tw: float, facing: float, away: bool) -> None:
    """The torso with shading, its pattern and the belt."""
    shirt, trousers = app.shirt, app.trousers
    pen.poly(
        [
            (-0.045, 0.15),
            (0.045, 0.15),
            (0.11 * tw, 0.168),
            (0.125 * tw, 0.21),
            (0.097 * tw, 0.46),
            (-0.097 * tw, 0.46),
            (-0.125 * tw, 0.21),
            (-0.11 * tw, 0.168),
        ],
        shirt,
    )
    pen.poly(
        [
            (0.04 * tw, 0.16),
            (0.11 * tw, 0.168),
            (0.125 * tw, 0.21),
            (0.097 * tw, 0.46),
            (0.04 * tw, 0.46),
        ],
        _scaled(shirt, 0.85),
    )
    if app.pattern == "stripes":
        for v in (0.22, 0.27, 0.32, 0.37, 0.42):
            half = (0.125 + (0.097 - 0.125) * (v - 0.21) / 0.25) * tw - 0.004
            pen.poly([(-half, v), (half, v), (half, v + 0.018), (-half, v + 0.018)], app.accent)
    elif app.pattern == "jacket" and not away:
        o = 0.012 * facing
        pen.poly(
            [(o - 0.03, 0.155), (o + 0.03, 0.155), (o + 0.018, 0.46), (o - 0.018, 0.46)], app.accent
        )
    elif app.pattern == "logo" and not away:
        o = 0.02 * facing
        pen.poly(
            [(o - 0.04, 0.23), (o + 0.04, 0.23), (o + 0.04, 0.29), (o - 0.04, 0.29)], app.accent
        )
    pen.poly(
        [(-0.097 * tw, 0.445), (0.097 * tw, 0.445), (0.096 * tw, 0.465), (-0.096 * tw, 0.465)],
        _scaled(trousers, 0.5),
    )  # belt


def _head(pen: _Pen, app: Appearance, colour: bool, facing: float, side: float, dirn: float,
          away: bool) -> None:
    """Neck and head: hair cap, face, fringe and eyes (on large heads, in colour only), or
    only hair seen from behind."""
    skin, hair = app.skin, app.hair
    pen.poly([(-0.024, 0.12), (0.024, 0.12), (0.026, 0.165), (-0.026, 0.165)], _scaled(skin, 0.85))
    hx = 0.006 * facing
    pen.ellipse(hx, _HEAD_V, _HEAD_RA, _HEAD_RV, hair)
    if not away:
        fx = hx + 0.016 * facing
        pen.ellipse(fx, _HEAD_V + 0.012, _HEAD_RA * (0.82 - 0.12 * side), _HEAD_RV * 0.8, skin)
        # hair fringe over the forehead
        pen.ellipse(
            hx - 0.004 * facing, _HEAD_V - 0.018, _HEAD_RA * 0.92, _HEAD_RV * 0.5, hair, 180, 360
        )
        if pen.h >= 120 and colour:  # eyes on large heads only
            for e in (-0.018, 0.018) if side < 0.5 else (0.02 * dirn,):
                pen.dot(
                    fx + e * (1 - 0.4 * side),
                    _HEAD_V + 0.004,
                    max(int(0.005 * pen.h * _S), _S),
                    (30, 30, 30),
                )
    elif app.long_hair:
        pen.poly([(-0.055, 0.07), (0.055, 0.07), (0.06, 0.21), (-0.06, 0.21)], hair)


def _shadow_kernel() -> np.ndarray:
    n = 64
    yy, xx = np.mgrid[-1 : 1 : n * 1j, -1 : 1 : n * 1j]
    r2 = xx**2 + yy**2
    dark = 0.5 * np.exp(-2.5 * r2) * (r2 < 1)
    return dark.astype(np.float32)


class ShadowPainter:
    """Soft elliptic cast shadows on the floor under a person's feet."""

    def __init__(self, strength: float = 1.0) -> None:
        self.kernel = _shadow_kernel() * float(strength)

    def paint(self, img: np.ndarray, box: np.ndarray, offset: float = 0.15) -> None:
        """Darken an ellipse under the feet of a person drawn in ``box`` (xywh) in place;
        ``offset`` shifts it sideways (fraction of the box width) away from the light."""
        x, y, w, h = (float(v) for v in box)
        ax, ay = 0.75 * w, 0.05 * h
        cx, cy = x + w / 2 + offset * w, y + 0.975 * h
        x0, x1 = math.floor(cx - ax), math.ceil(cx + ax)
        y0, y1 = math.floor(cy - ay), math.ceil(cy + ay)
        H, W = img.shape[:2]
        if x1 <= 0 or y1 <= 0 or x0 >= W or y0 >= H or x1 - x0 < 2 or y1 - y0 < 2:
            return
        k = cv2.resize(self.kernel, (x1 - x0, y1 - y0), interpolation=cv2.INTER_LINEAR)
        cx0, cy0, cx1, cy1 = max(x0, 0), max(y0, 0), min(x1, W), min(y1, H)
        k = k[cy0 - y0 : cy1 - y0, cx0 - x0 : cx1 - x0]
        keep = cv2.merge([1.0 - k] * 3)
        roi = img[cy0:cy1, cx0:cx1]
        roi[:] = cv2.multiply(roi, keep, dtype=cv2.CV_8U)
