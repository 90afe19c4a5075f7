"""How a synthetic person looks: skin, hair and clothes colours and patterns, drawn at random
(``random_appearance``) or near-identical to another (``similar_appearance``).
``occbench.datasets.synthetic.people`` draws a person with them."""

from __future__ import annotations

from dataclasses import dataclass, replace

import cv2
import numpy as np

#: skin tones (BGR) of the head detector's categories (PBM 2.3): bright, standard, dark
SKIN = {"bright": (190, 205, 238), "standard": (135, 165, 212), "dark": (55, 80, 118)}
#: hair colours (BGR): black, brown, blond, red (PBM 2.3) and grey
HAIR = {
    "black": (22, 22, 28),
    "brown": (30, 52, 88),
    "blond": (105, 175, 212),
    "red": (35, 70, 160),
    "grey": (150, 150, 155),
}
#: trouser colours (BGR)
TROUSERS = (
    (130, 80, 40),
    (35, 35, 38),
    (105, 105, 110),
    (110, 155, 175),
    (40, 60, 90),
    (85, 45, 30),
    (60, 90, 70),
)
PATTERNS = ("plain", "stripes", "jacket", "logo")


@dataclass(frozen=True)
class Appearance:
    """How one person looks. Colours are BGR floats in [0, 255].

    Attributes:
        skin, hair, shirt, trousers, shoes: part colours.
        accent: second colour of the shirt pattern (stripes, inner shirt, logo).
        pattern: one of ``PATTERNS``.
        long_hair: hair falls to the shoulders.
        short_sleeves: forearms in skin colour.
        height_m: body height in metres (sets the image size in world scenarios).
        build: box width / box height (0.36 slim .. 0.44 broad).
        skin_kind, hair_kind: category names (for the head detector's fit command).
    """

    skin: tuple[float, float, float]
    hair: tuple[float, float, float]
    shirt: tuple[float, float, float]
    accent: tuple[float, float, float]
    trousers: tuple[float, float, float]
    shoes: tuple[float, float, float]
    pattern: str = "plain"
    long_hair: bool = False
    short_sleeves: bool = False
    height_m: float = 1.75
    build: float = 0.4
    skin_kind: str = "standard"
    hair_kind: str = "black"


def _jitter(rng: np.random.Generator, colour, amount: float) -> tuple[float, float, float]:
    c = np.clip(np.asarray(colour, float) + rng.uniform(-amount, amount, 3), 0, 255)
    return (float(c[0]), float(c[1]), float(c[2]))


def _hsv(h: float, s: float, v: float) -> tuple[float, float, float]:
    px = np.array([[[h * 360.0, s, v]]], np.float32)  # float HSV: H in degrees, S, V in [0, 1]
    b, g, r = cv2.cvtColor(px, cv2.COLOR_HSV2BGR)[0, 0] * 255.0
    return (float(b), float(g), float(r))


def random_appearance(rng: np.random.Generator) -> Appearance:
    """A random person (every draw from ``rng``)."""
    skin_kind = str(rng.choice(list(SKIN)))
    hair_kind = str(rng.choice(list(HAIR), p=[0.35, 0.3, 0.17, 0.1, 0.08]))
    shirt = _hsv(rng.random(), rng.uniform(0.25, 0.9), rng.uniform(0.35, 0.95))
    accent_v = rng.uniform(0.15, 0.95)
    accent = _hsv(rng.random(), rng.uniform(0.0, 0.8), accent_v)
    return Appearance(
        skin=_jitter(rng, SKIN[skin_kind], 12),
        hair=_jitter(rng, HAIR[hair_kind], 10),
        shirt=shirt,
        accent=accent,
        trousers=_jitter(rng, TROUSERS[int(rng.integers(len(TROUSERS)))], 12),
        shoes=_jitter(rng, (30, 30, 35), 15),
        pattern=str(rng.choice(PATTERNS, p=[0.4, 0.25, 0.2, 0.15])),
        long_hair=bool(rng.random() < 0.3),
        short_sleeves=bool(rng.random() < 0.35),
        height_m=float(rng.uniform(1.62, 1.88)),
        build=float(rng.uniform(0.37, 0.43)),
        skin_kind=skin_kind,
        hair_kind=hair_kind,
    )


def similar_appearance(
    app: Appearance, rng: np.random.Generator, amount: float = 6.0
) -> Appearance:
    """A near-identical copy of ``app`` (every colour jittered by at most ``amount`` levels)."""
    return replace(
        app,
        skin=_jitter(rng, app.skin, amount),
        hair=_jitter(rng, app.hair, amount),
        shirt=_jitter(rng, app.shirt, amount),
        accent=_jitter(rng, app.accent, amount),
        trousers=_jitter(rng, app.trousers, amount),
        shoes=_jitter(rng, app.shoes, amount),
        height_m=float(app.height_m + rng.uniform(-0.03, 0.03)),
    )
