"""Small cv2-drawn scenes with exact answers for the PBM tests and benchmark.

A person is drawn in its xywh box: a head disc (hair on top, skin below) in the top 1/7,
a shirt with arms down to 55% of the height, two trouser legs below. People are painted
far to near (larger ``depth`` first); a static occluder (a low wall) can be painted over
them. Every scene returns frames, exact label images (pixel = person id, 0 elsewhere,
wall pixels 0), amodal ground-truth boxes and per-frame detections of the people whose
visible fraction is at least ``min_visible``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from occbench.trackers.layered.feature_models import FeatureModels, FoldedMixture
from occbench.trackers.layered.parts import FEATURES, N_PARTS, PartFeatures
from occbench.trackers.records import Detections


@dataclass
class Person:
    id: int
    boxes: np.ndarray  # (L, 4) xywh, NaN rows where absent
    shirt: tuple[int, int, int]
    pants: tuple[int, int, int]
    skin: tuple[int, int, int] = (120, 160, 210)
    hair: tuple[int, int, int] = (30, 30, 40)
    depth: float = 1.0  # larger = farther


@dataclass
class Scene:
    width: int
    height: int
    people: list[Person]
    walls: list[tuple[int, int, int, int]] = field(default_factory=list)  # x, y, w, h
    wall_colour: tuple[int, int, int] = (90, 140, 90)
    seed: int = 0

    @property
    def length(self) -> int:
        return len(self.people[0].boxes)

    def background(self) -> np.ndarray:
        rng = np.random.default_rng(self.seed)
        y = np.linspace(150, 200, self.height)[:, None, None]
        bg = np.broadcast_to(y, (self.height, self.width, 3)).astype(np.float64)
        bg = bg + rng.normal(0, 4, bg.shape)
        return np.clip(bg, 0, 255).astype(np.uint8)

    def render(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Frame k (0-based): (H, W, 3) uint8 BGR and (H, W) int32 label image."""
        rng = np.random.default_rng(self.seed * 100003 + k)
        img = self.background().copy()
        lab = np.zeros((self.height, self.width), np.int32)
        for p in sorted(self.people, key=lambda q: -q.depth):
            b = p.boxes[k]
            if np.isnan(b).any():
                continue
            draw_person(img, lab, p, b)
        for x, y, w, h in self.walls:
            img[y:y + h, x:x + w] = self.wall_colour
            lab[y:y + h, x:x + w] = 0
        noise = rng.normal(0, 3, img.shape)
        img = np.clip(img + noise, 0, 255).astype(np.uint8)
        return img, lab

    def gt(self, k: int) -> dict[int, np.ndarray]:
        return {p.id: p.boxes[k] for p in self.people if not np.isnan(p.boxes[k]).any()}

    def visible_fraction(self, k: int, lab: np.ndarray) -> dict[int, float]:
        out = {}
        for p in self.people:
            b = p.boxes[k]
            if np.isnan(b).any():
                continue
            alone = np.zeros_like(lab)
            draw_person(None, alone, p, b)
            n = (alone == p.id).sum()
            out[p.id] = float((lab == p.id).sum() / n) if n else 0.0
        return out

    def detections(self, k: int, lab: np.ndarray, min_visible: float = 0.5,
                   hidden: set[int] | None = None) -> Detections:
        """Exact amodal boxes of people at least ``min_visible`` visible (``hidden`` ids
        are left out regardless)."""
        vis = self.visible_fraction(k, lab)
        boxes = [self.people_by_id[i].boxes[k] for i, v in vis.items()
                 if v >= min_visible and not (hidden and i in hidden)]
        return Detections(np.array(boxes).reshape(-1, 4), np.ones(len(boxes)))

    @property
    def people_by_id(self) -> dict[int, Person]:
        return {p.id: p for p in self.people}


def draw_person(img: np.ndarray | None, lab: np.ndarray, p: Person, box: np.ndarray) -> None:
    x, y, w, h = (float(v) for v in box)

    def rect(x0, y0, x1, y1, colour):
        r0, r1 = round(y0), round(y1)
        c0, c1 = round(x0), round(x1)
        r0, c0 = max(r0, 0), max(c0, 0)
        if r1 <= r0 or c1 <= c0:
            return
        if img is not None:
            img[r0:r1, c0:c1] = colour
        lab[r0:r1, c0:c1] = p.id

    hh = h / 7.0
    cx = x + w / 2
    # head: hair cap over skin face
    rx = max(round(0.22 * w), 2)
    ry = max(round(hh / 2), 2)
    centre = (round(cx), round(y + hh / 2))
    m = np.zeros(lab.shape, np.uint8)
    cv2.ellipse(m, centre, (rx, ry), 0, 0, 360, 1, -1)
    sel = m.astype(bool)
    if img is not None:
        img[sel] = p.skin
        top = sel.copy()
        top[round(y + hh * 0.4):] = False
        img[top] = p.hair
    lab[sel] = p.id
    # neck + shirt with arms
    rect(cx - 0.1 * w, y + hh * 0.9, cx + 0.1 * w, y + hh * 1.1, p.skin)
    rect(x + 0.12 * w, y + hh * 1.05, x + 0.88 * w, y + 0.55 * h, p.shirt)
    rect(x, y + hh * 1.2, x + 0.12 * w, y + 0.5 * h, p.shirt)
    rect(x + 0.88 * w, y + hh * 1.2, x + w, y + 0.5 * h, p.shirt)
    # legs
    rect(x + 0.15 * w, y + 0.55 * h, x + 0.47 * w, y + h, p.pants)
    rect(x + 0.53 * w, y + 0.55 * h, x + 0.85 * w, y + h, p.pants)


def two_heads_blob() -> np.ndarray:
    """(100, 80) bool foreground of two touching people in one blob: the left one's head
    top row 5, centre column 19.5; the right one's head top row 12, centre column 54.5."""
    mask = np.zeros((100, 80), bool)
    mask[20:100, 5:35] = True  # left body
    mask[5:20, 14:26] = True  # its head, top row 5, centre column 19.5
    mask[28:100, 35:75] = True  # right body (touching: one blob)
    mask[12:28, 48:62] = True  # its head, top row 12
    return mask


def walk(length: int, start: tuple[float, float], velocity, size: tuple[float, float],
         turn_at: int | None = None, present: tuple[int, int] | None = None) -> np.ndarray:
    """(L, 4) boxes of a walk from ``start`` (top-left) with per-frame velocity (vx, vy);
    the velocity flips at ``turn_at``; NaN outside ``present`` = (first, last) frame."""
    v = np.tile(np.asarray(velocity, dtype=np.float64), (length, 1))
    if turn_at is not None:
        v[turn_at:] *= -1
    pos = np.asarray(start, dtype=np.float64) + np.vstack([[0, 0], np.cumsum(v[:-1], axis=0)])
    boxes = np.column_stack([pos, np.tile(size, (length, 1))])
    if present is not None:
        boxes[: present[0]] = np.nan
        boxes[present[1] + 1:] = np.nan
    return boxes


def uturn_behind(length: int = 90) -> tuple[Scene, set[int]]:
    """Person 1 walks right behind the standing person 2, turns back while hidden and
    walks out the way it came. Returns the scene and the id that u-turns."""
    a = walk(length, (60, 80), (2.0, 0.0), (24, 84), turn_at=45)
    b = walk(length, (130, 60), (0.0, 0.0), (46, 120))
    people = [
        Person(1, a, shirt=(40, 40, 200), pants=(90, 60, 30), depth=2.0),
        Person(2, b, shirt=(200, 120, 40), pants=(40, 40, 40), hair=(20, 60, 120), depth=1.0),
    ]
    return Scene(320, 240, people, seed=1), {1}


def merge_pair(length: int = 80) -> Scene:
    """Two people of different heights walk towards each other, stand shoulder to
    shoulder (one foreground blob) and walk apart again."""
    a = np.full((length, 4), np.nan)
    b = np.full((length, 4), np.nan)
    for k in range(length):
        t = min(k, 30) - max(k - 50, 0)  # approach 30 frames, stay 20, separate
        a[k] = (40 + 2.0 * t, 70, 30, 100)
        b[k] = (190 - 2.0 * t, 60, 32, 112)
    people = [
        Person(1, a, shirt=(30, 30, 190), pants=(100, 70, 30), depth=1.5),
        Person(2, b, shirt=(40, 170, 40), pants=(50, 50, 50), hair=(30, 90, 150), depth=1.0),
    ]
    return Scene(300, 220, people, seed=2)


def legs_behind_wall(length: int = 70) -> tuple[Scene, tuple[int, int]]:
    """One person walks right behind a low wall that hides the legs. Returns the scene
    and the frame range (first, last) during which the legs are completely hidden."""
    a = walk(length, (20, 60), (3.0, 0.0), (30, 105))
    wall = (110, 112, 110, 60)
    people = [Person(1, a, shirt=(50, 50, 200), pants=(140, 90, 20), depth=1.0)]
    # legs span x + 0.15w .. x + 0.85w; hidden when inside the wall columns
    xs = a[:, 0]
    hidden = np.nonzero((xs + 0.15 * 30 >= wall[0]) & (xs + 0.85 * 30 <= wall[0] + wall[2]))[0]
    return Scene(260, 200, people, walls=[wall], seed=3), (int(hidden[0]), int(hidden[-1]))


# ------------------------------------------------- random inputs of the PBM kernel tests


def random_models(rng: np.random.Generator) -> FeatureModels:
    """Half-normals, 2-component mixtures (one with a zero mean) and 3-component mixtures
    (so the padded arrays have zero-weight slots)."""
    models = {}
    for f in FEATURES:
        row = []
        for j in range(N_PARTS):
            kind = (FEATURES.index(f) + j) % 3
            if kind == 0:
                row.append(FoldedMixture([1.0], [0.0], [rng.uniform(0.01, 0.5)]))
            elif kind == 1:
                w = rng.uniform(0.2, 0.8)
                row.append(FoldedMixture([w, 1 - w], [0.0, rng.uniform(0.01, 0.5)],
                                         rng.uniform(0.005, 0.3, 2)))
            else:
                w = rng.dirichlet(np.ones(3))
                row.append(FoldedMixture(w, rng.uniform(0.0, 0.5, 3), rng.uniform(0.01, 0.3, 3)))
        models[f] = row
    return FeatureModels(models)


def random_features(rng: np.random.Generator, n: int, bins: int = 4) -> PartFeatures:
    """n boxes' part features: sparse joint histograms, some parts empty (area 0, zero
    histograms), some part rectangles disjoint or touching."""
    nb = bins**3
    xy = rng.uniform(0, 60, (n, N_PARTS, 2))
    wh = rng.uniform(0.5, 30, (n, N_PARTS, 2))
    wh[rng.random((n, N_PARTS)) < 0.05, 0] = 0.0  # a degenerate part rectangle
    area = rng.uniform(0, 1, (n, N_PARTS))
    area[rng.random((n, N_PARTS)) < 0.15] = 0.0
    hists = []
    for _ in range(2):
        h = rng.random((n, N_PARTS, nb)) * (rng.random((n, N_PARTS, nb)) < 0.2)
        h[area <= 0] = 0.0
        s = h.sum(-1, keepdims=True)
        hists.append(np.divide(h, s, out=np.zeros_like(h), where=s > 0))
    return PartFeatures(np.concatenate([xy, wh], axis=2), area, rng.uniform(0, 3, (n, N_PARTS)),
                        hists[0], hists[1], rng.uniform(0, 80, (n, N_PARTS, 2)),
                        rng.uniform(0.5, 100, n))


def unit_models() -> FeatureModels:
    """Half-normal models with sigma 1 for every feature and part."""
    return FeatureModels({f: [FoldedMixture([1.0], [0.0], [1.0])] * N_PARTS for f in FEATURES})


def pace_change_hidden(overrides: list[str], missed: set[int], reported_from: int = 0
                       ) -> tuple[list[float], list[float]]:
    """A person (a 12 x 40 box of colour in a 200 x 120 image) walking right at 1 px a frame
    for 14 frames, then at 5 px a frame, for 22 frames, undetected at the frames ``missed``,
    tracked by pbm with the config ``overrides``; the x of its hidden (OCCLUDED) reports
    from frame ``reported_from`` on, and the person's x at the missed frames from then."""
    from occbench.config.build import build_tracker, compose_config
    from occbench.trackers.records import TrackState

    tracker = build_tracker("pbm", compose_config(["tracker=pbm", *overrides]).tracker)
    x, hidden, truth = 20.0, [], []
    for k in range(22):
        x += 1.0 if k < 14 else 5.0
        frame = np.full((120, 200, 3), 90, dtype=np.uint8)
        frame[40:80, int(x):int(x) + 12] = (30, 60, 200)
        box = np.zeros((0, 4)) if k in missed else np.array([[x, 40.0, 12, 40]])
        out = tracker.update(frame, Detections(box, np.ones(len(box))))
        if k >= reported_from:
            hidden += [t.box[0] for t in out if t.state == TrackState.OCCLUDED]
            truth += [x] if k in missed else []
    return hidden, truth
