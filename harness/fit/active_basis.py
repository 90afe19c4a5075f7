"""``occbench fit active_basis``: learn the active-basis person template (Reta 3.1).

Training people (aligned grey patches, ``occbench.trackers.frontend.active_basis.crop_patch``) come
from two sources, each optional:

* the synthetic renderer (``--synthetic-seed``, default 0, a tuning seed; 384x288 frames,
  every ``--step``-th frame of the default suite): people at least 95% visible, not
  touching another person's box nor the frame's border, at least ``--min-height`` pixels
  high, each boxed tightly by its exact label image;
* CAVIAR OneLeaveShop1cor frames 1-150 only (every ``--caviar-step``-th; the dev part; frames 151-295 are
  the untouched evaluation and are never read): gt boxes of people not marked occluded, not
  touching another box nor the frame's border.

Each patch also gives its mirror image. Background statistics q(r) pool ``--background``
random boxes (seeded; sizes and places uniform over the frames' person heights) from the
same frames. The template is learnt by the shared sketch (``active_basis_learn.learn``) and saved
as ``.npz`` (``ActiveBasis.to_arrays``). The same options give the same bytes.

The shipped ``trackers/frontend/data/active_basis.npz`` was made by
``occbench fit active_basis`` (the defaults).

``load(path)`` is how configs get a template: the harness reads the file, the detector is
handed the ``ActiveBasis``.
"""

from __future__ import annotations

import argparse
import io
import logging
from pathlib import Path

import cv2
import numpy as np
from hydra.utils import instantiate

from occbench.config.build import compose_config
from occbench.progress import log_to_stderr
from occbench.trackers.frontend.active_basis import ActiveBasis, GaborBank, crop_patch
from occbench.trackers.frontend.active_basis_learn import learn
from occbench.trackers.geometry import intersection_matrix

log = logging.getLogger(__name__)

DEFAULT_OUT = Path(__file__).resolve().parents[2] / "trackers" / "frontend" / "data" / "active_basis.npz"
DEV_FRAMES = (1, 150)  # CAVIAR OneLeaveShop1cor: frames 151-295 are the untouched evaluation


def load(path: str | Path | None = None) -> ActiveBasis:
    """The template in ``path`` (None: the shipped ``trackers/frontend/data/active_basis.npz``)."""
    path = Path(path) if path is not None else DEFAULT_OUT
    if not path.is_file():
        raise FileNotFoundError(f"active-basis template not found: {path} "
                                f"(make one with: occbench fit active_basis --out {path})")
    with np.load(path, allow_pickle=False) as a:
        try:
            return ActiveBasis.from_arrays(a)
        except (KeyError, ValueError) as e:
            raise ValueError(f"{path}: not an active-basis template ({e})") from e


def _isolated(boxes: np.ndarray, H: int, W: int, min_height: float) -> np.ndarray:
    """(N,) bool: boxes touching no other box nor the frame border, at least min_height high."""
    inter = intersection_matrix(boxes, boxes)
    np.fill_diagonal(inter, 0.0)
    x, y, w, h = boxes.T
    inside = (x >= 1) & (y >= 1) & (x + w <= W - 1) & (y + h <= H - 1)
    return inside & ~inter.any(axis=1) & (h >= min_height)


def collect(sequences, size: tuple[int, int], pad: int, step: int, min_height: float,
            n_background: int, rng: np.random.Generator, exact: bool
            ) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Person patches (with mirrors) and background patches of annotated sequences.

    ``exact``: box each person by its label image (synthetic scenes) rather than its gt box.
    """
    people: list[np.ndarray] = []
    frames: list[tuple[np.ndarray, np.ndarray]] = []  # (grey, person heights) for the background
    for seq in sequences:
        table = seq.gt.table
        for k in seq.frame_numbers():
            if (k - 1) % step:
                continue
            rows = seq.gt.rows_of(k)
            if len(rows) == 0:
                continue
            grey = cv2.cvtColor(seq.frame(k), cv2.COLOR_BGR2GRAY)
            H, W = grey.shape
            boxes = table.boxes[rows]
            ok = _isolated(boxes, H, W, min_height)
            vis = table.visibility[rows]
            ok &= ~np.isfinite(vis) | (vis >= 0.95)
            if seq.gt.occluded is not None:
                ok &= ~seq.gt.occluded[rows]
            labels = seq.foreground(k) if exact else None
            for j in np.flatnonzero(ok):
                box = boxes[j]
                if labels is not None:
                    ys, xs = np.nonzero(labels == table.ids[rows[j]])
                    if len(ys) == 0:
                        continue
                    box = np.array([xs.min(), ys.min(), xs.max() - xs.min() + 1, ys.max() - ys.min() + 1],
                                   np.float64)
                p = crop_patch(grey, box, size, pad)
                people += [p, np.ascontiguousarray(p[:, ::-1])]
            frames.append((grey, boxes[:, 3]))
    background: list[np.ndarray] = []
    if frames and n_background > 0:
        heights = np.concatenate([h for _, h in frames])
        lo, hi = max(float(np.percentile(heights, 5)), min_height), float(np.percentile(heights, 95))
        aspect = size[1] / size[0]
        for i in rng.integers(0, len(frames), n_background):
            grey = frames[int(i)][0]
            h = float(rng.uniform(lo, max(hi, lo + 1)))
            w = aspect * h
            x = float(rng.uniform(0, max(grey.shape[1] - w, 1)))
            y = float(rng.uniform(0, max(grey.shape[0] - h, 1)))
            background.append(crop_patch(grey, (x, y, w, h), size, pad))
    return people, background


def fit(synthetic_seed: int | None = 0, caviar: bool = True, step: int = 5, caviar_step: int = 1,
        min_height: float = 30.0,
        n_background: int = 300, n_elements: int = 30, size: tuple[int, int] = (48, 20),
        seed: int = 0) -> ActiveBasis:
    """Learn the template from the renderer (seed ``synthetic_seed``, None: none) and CAVIAR
    OneLeaveShop1cor frames 1-150 (``caviar``)."""
    bank = GaborBank()
    b1, b2 = 2, 1
    pad = b1 + bank.ksize // 2
    rng = np.random.default_rng(seed)
    people: list[np.ndarray] = []
    background: list[np.ndarray] = []
    sources = []
    if synthetic_seed is not None:
        sources.append(([f"seed={synthetic_seed}", "dataset=synthetic", "dataset.width=384",
                         "dataset.height=288"], True, step))
    if caviar:
        sources.append((["dataset=caviar", f"dataset.frames=[{DEV_FRAMES[0]},{DEV_FRAMES[1]}]"], False,
                        caviar_step))
    if not sources:
        raise ValueError("fit: no training source (give a synthetic seed or caviar)")
    for overrides, exact, every in sources:
        cfg = compose_config(overrides)
        seqs = list(instantiate(cfg.dataset))
        if not exact:  # refuse anything beyond the dev frames
            for s in seqs:
                last = max(s.frame_numbers())
                if last > DEV_FRAMES[1]:
                    raise ValueError(f"{s.info.name}: frames beyond {DEV_FRAMES[1]} requested ({last})")
        p, b = collect(seqs, size, pad, every, min_height, n_background, rng, exact)
        log.info("%s: %d person patches (with mirrors), %d background patches", " ".join(overrides),
                 len(p), len(b))
        people += p
        background += b
    return learn(people, background, size=size, n_elements=n_elements, bank=bank, b1=b1, b2=b2)


def save(template: ActiveBasis, out: Path) -> None:
    """Write ``template`` as .npz, byte for byte the same for the same template (no zip
    timestamps: ``np.savez`` writes fixed ones)."""
    buf = io.BytesIO()
    np.savez_compressed(buf, **template.to_arrays())
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_bytes(buf.getvalue())


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="occbench fit active_basis", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, required=True,
                    help=f"output .npz (required: the shipped one is {DEFAULT_OUT}, tracked; "
                         "name it to replace it)")
    ap.add_argument("--synthetic-seed", type=int, default=0,
                    help="renderer seed of the synthetic training people (-1: none)")
    ap.add_argument("--no-caviar", action="store_true", help="leave out CAVIAR OneLeaveShop1cor frames 1-150")
    ap.add_argument("--step", type=int, default=5, help="use every step-th synthetic frame")
    ap.add_argument("--caviar-step", type=int, default=1, help="use every step-th CAVIAR frame")
    ap.add_argument("--min-height", type=float, default=30.0, help="smallest person used, pixels")
    ap.add_argument("--background", type=int, default=300, help="random background patches for q(r)")
    ap.add_argument("--elements", type=int, default=30, help="n, Gabor elements of the template")
    ap.add_argument("--seed", type=int, default=0, help="seed of the background patches")
    args = ap.parse_args(argv)
    log_to_stderr()
    template = fit(None if args.synthetic_seed < 0 else args.synthetic_seed, not args.no_caviar,
                   args.step, args.caviar_step, args.min_height, args.background, args.elements, seed=args.seed)
    out = args.out
    save(template, out)
    log.info("wrote %s: %d elements on a %s template", out, template.n, template.size)
    return 0
