"""Built-in synthetic scenes: the project's default dataset.

``load_suite(scenarios, seed, ...)`` renders one ``SyntheticSequence`` per scenario preset
(see ``occbench.datasets.synthetic.scenarios``); ``load_replay(gt_path, ...)`` draws people
along the boxes of a real MOT gt file. Both are Hydra ``_target_`` callables returning
``list[Sequence]`` (conf/dataset/synthetic.yaml, conf/dataset/replay.yaml).

Everything is seeded: the same arguments give the same frames byte for byte and the same
ground truth. Each scenario draws from its own generator
``default_rng([seed, crc32(name)])``, so a scenario looks the same whichever other
scenarios are loaded with it.

Modules: ``scene`` (camera and background), ``people`` (appearance and drawing),
``scenarios`` (presets), ``sequence`` (``SyntheticSequence``: frames, label images,
ground truth, head boxes), ``replay``.
"""

from __future__ import annotations

import logging
import zlib
from collections.abc import Sequence as Seq

import numpy as np

from occbench.datasets.base import window
from occbench.datasets.synthetic.appearance import Appearance, random_appearance
from occbench.datasets.synthetic.people import draw_person, head_box
from occbench.datasets.synthetic.replay import load_replay
from occbench.datasets.synthetic.scenarios import SCENARIOS, illumination_gains, world_cast
from occbench.datasets.synthetic.scene import Camera, defer_background, render_background
from occbench.datasets.synthetic.sequence import Cast, SyntheticSequence

log = logging.getLogger(__name__)

#: the default suite, in order
DEFAULT_SCENARIOS = (
    "crossing",
    "stop_behind",
    "follow_occluder",
    "uturn_behind",
    "pair_walk",
    "similar_clothes",
    "illumination",
    "crowd",
)

__all__ = [
    "DEFAULT_SCENARIOS",
    "SCENARIOS",
    "Appearance",
    "Camera",
    "Cast",
    "SyntheticSequence",
    "draw_person",
    "head_box",
    "load_replay",
    "load_scenario",
    "load_suite",
    "random_appearance",
    "render_background",
]


def load_scenario(
    scenario: str,
    seed: int = 0,
    width: int = 640,
    height: int = 480,
    length: int = 150,
    fps: float = 25.0,
    people: int = 10,
    density: float = 0.3,
    noise: float = 2.0,
    illumination: float = 0.0,
    shadows: bool = True,
    occluded_below: float = 0.3,
    mirror: bool | None = None,
    name: str | None = None,
    reflection: float = 0.0,
    camera_height: float = 1.3,
    horizon: float = 0.42,
) -> SyntheticSequence:
    """One synthetic sequence of preset ``scenario`` (arguments as in ``load_suite``;
    ``mirror`` forces the left-right orientation, None lets the seed choose)."""
    if scenario not in SCENARIOS:
        raise ValueError(f"unknown synthetic scenario {scenario!r}; valid: {', '.join(SCENARIOS)}")
    if length < 2:
        raise ValueError(f"length must be >= 2, got {length}")
    if people < 1:
        raise ValueError(f"people must be >= 1, got {people}")
    if density <= 0:
        raise ValueError(f"density must be > 0 (persons per square metre), got {density}")
    if fps <= 0:
        raise ValueError(f"fps must be > 0, got {fps}")
    if camera_height <= 0 or not 0.0 <= horizon < 1.0:
        raise ValueError(f"need camera_height > 0 and 0 <= horizon < 1, got {camera_height}, {horizon}")
    cam = Camera.for_size(width, height, camera_height=camera_height, horizon=horizon)
    rng = np.random.default_rng([int(seed), zlib.crc32(scenario.encode())])
    background = defer_background(cam, rng)  # painted when the sequence first needs it
    flip = bool(rng.random() < 0.5) if mirror is None else bool(mirror)
    sign = -1.0 if flip else 1.0
    walkers = SCENARIOS[scenario](cam, rng, fps, length, int(people), float(density), sign)
    cast = world_cast(cam, walkers, int(length), float(fps), rng)
    gains = illumination_gains(
        max(illumination, 0.3) if scenario == "illumination" else illumination,
        int(length),
        float(fps),
        rng,
        step=scenario == "illumination",
    )
    seq = SyntheticSequence(
        name or scenario, cast, background, fps, int(seed), noise, gains, shadows, occluded_below,
        reflection=reflection,
    )
    log.debug("built %r", seq)
    return seq


def load_suite(
    scenarios: Seq[str] = DEFAULT_SCENARIOS,
    seed: int = 0,
    width: int = 640,
    height: int = 480,
    length: int = 150,
    fps: float = 25.0,
    people: int = 10,
    density: float = 0.3,
    noise: float = 2.0,
    illumination: float = 0.0,
    shadows: bool = True,
    occluded_below: float = 0.3,
    frames: list[int] | None = None,
    reflection: float = 0.0,
    camera_height: float = 1.3,
    horizon: float = 0.42,
) -> list[SyntheticSequence]:
    """One sequence per scenario preset, named after it.

    Args:
        scenarios: preset names (``SCENARIOS``); duplicates are not allowed.
        seed: seed of everything random (appearances, background, noise, crowd paths).
        width, height: frame size, pixels.
        length: frames per sequence; each preset's event is in the middle.
        fps: frame rate (walking speeds are in m/s, so a higher rate gives smaller steps).
        people: number of people in ``crowd``.
        density: persons per square metre of floor in ``crowd``.
        noise: standard deviation of the Gaussian sensor noise, grey levels (0 = off).
        illumination: relative amplitude of the global illumination drift for every preset
            (0 = constant light); ``illumination`` uses at least 0.3 plus a dimming step.
        shadows: draw soft cast shadows.
        occluded_below: gt rows with visibility below this are flagged occluded.
        frames: [first, last] (1-based, inclusive) to run only those frames of each scene,
            numbered as in the whole scene (``occbench.datasets.base.window``); None = all.
        reflection: opacity of a mirrored floor reflection under each person (0 = none;
            ``SyntheticSequence``).
        camera_height: height of the camera above the floor, metres, and
        horizon: image row of the horizon, fraction of the frame height: the perspective.
            A person ``height_m`` tall with feet at image row y is
            height_m / camera_height * (y - horizon * height) pixels tall, linear in y.
    Raises:
        ValueError: an unknown scenario (the message lists the valid ones) or bad value.
    """
    if isinstance(scenarios, str):
        scenarios = [scenarios]
    names = [str(s) for s in scenarios]
    bad = [s for s in names if s not in SCENARIOS]
    if bad:
        raise ValueError(f"unknown synthetic scenario(s) {bad}; valid: {', '.join(SCENARIOS)}")
    if len(set(names)) != len(names):
        raise ValueError(f"scenarios must be distinct, got {names}")
    return window([
        load_scenario(
            s,
            seed,
            width,
            height,
            length,
            fps,
            people,
            density,
            noise,
            illumination,
            shadows,
            occluded_below,
            reflection=reflection,
            camera_height=camera_height,
            horizon=horizon,
        )
        for s in names
    ], frames)
