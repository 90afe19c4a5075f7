"""Picture of an active-basis template: its Gabor elements as oriented bars.

``python -m occbench.fit.active_basis_figure [--template T.npz] [--out docs/img/active_basis.png]``
draws the template (default: the shipped one) three times: alone (bar thickness and colour
by lambda_i, the element's weight), over a rendered person and over a rendered background
patch of a synthetic scene (seed 3, never used for learning), each titled with its score
(the log-likelihood ratio, eq. 22). Elements are drawn at their learnt positions; on the
patches, at each element's own best shift and turn (the deformed template).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.cm import ScalarMappable
from matplotlib.colors import Normalize

from occbench.datasets.synthetic import load_scenario
from occbench.fit.active_basis import load
from occbench.report.figures import save_figure
from occbench.trackers.frontend.active_basis import ActiveBasis, crop_patch, shift_offsets


def deformed(template: ActiveBasis, patch: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each element's best shifted position (rows, cols) and turned orientation on ``patch``
    (the argmax of the max map, eq. 25), template-box coordinates."""
    t = template
    k, p = t.bank.ksize // 2, t.pad
    K = t.bank.kernels()
    off = shift_offsets(t.bank, t.b1)
    rows, cols, ors = [], [], []
    for y, x, a in zip(t.rows, t.cols, t.orient):
        best = (-1.0, y, x, a)
        for dy, dx in off[a]:
            yy, xx = y + dy + p, x + dx + p
            win = patch[yy - k : yy + k + 1, xx - k : xx + k + 1]
            for d in range(-t.b2, t.b2 + 1):
                b = (a + d) % t.bank.n_orient
                e = float((win * K[b, 0]).sum() ** 2 + (win * K[b, 1]).sum() ** 2)
                if e > best[0]:
                    best = (e, y + dy, x + dx, b)
        rows.append(best[1]), cols.append(best[2]), ors.append(best[3])
    return np.asarray(rows), np.asarray(cols), np.asarray(ors)


def _bars(ax, template: ActiveBasis, rows, cols, orient, colour=None) -> None:
    t = template
    half = 0.75 * t.bank.sigma / t.bank.gamma  # half-length of an element: its envelope along the edge
    cmap = plt.get_cmap("viridis")
    lo, hi = float(t.lam.min()), float(t.lam.max())
    for y, x, a, lam in zip(rows, cols, orient, t.lam):
        theta = t.bank.angles[a] + np.pi / 2  # the edge runs across the Gabor's oscillation
        dx, dy = half * np.cos(theta), half * np.sin(theta)
        w = (lam - lo) / max(hi - lo, 1e-9)
        ax.plot([x - dx, x + dx], [y - dy, y + dy], lw=1.0 + 2.5 * w, solid_capstyle="round",
                color=colour or cmap(w))


def draw(template: ActiveBasis, person: np.ndarray, background: np.ndarray, path: str | Path) -> Path:
    """Write the three-panel picture; ``person`` and ``background`` are template patches."""
    matplotlib.use("Agg")

    t = template
    H, W = t.size
    p = t.pad
    fig, axes = plt.subplots(1, 3, figsize=(9.0, 5.6))
    ax = axes[0]
    ax.add_patch(plt.Rectangle((-0.5, -0.5), W, H, fill=False, ec="0.6", ls="--"))
    _bars(ax, t, t.rows, t.cols, t.orient)
    ax.set_title(f"{t.n} Gabor elements\n{H}x{W} px, {t.bank.n_orient} orientations", fontsize=9)
    sm = ScalarMappable(norm=Normalize(float(t.lam.min()), float(t.lam.max())), cmap="viridis")
    fig.colorbar(sm, ax=ax, fraction=0.08, pad=0.02, label="lambda_i (weight, eq. 16)")
    for ax, patch, name in ((axes[1], person, "rendered person"), (axes[2], background, "rendered background")):
        ax.imshow(patch[p : p + H, p : p + W], cmap="gray", vmin=0, vmax=255, extent=(-0.5, W - 0.5, H - 0.5, -0.5))
        r, c, o = deformed(t, patch)
        _bars(ax, t, r, c, o, colour="tab:red")
        ax.set_title(f"{name}\nscore {t.score(patch):.1f} (log-likelihood ratio)", fontsize=9)
    for ax in axes:
        ax.set_xlim(-2.5, W + 1.5)
        ax.set_ylim(H + 1.5, -2.5)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
    axes[1].plot([], [], color="tab:red", lw=2, label="elements at their best shift and turn")
    axes[1].legend(loc="lower center", bbox_to_anchor=(1.05, -0.16), fontsize=8, frameon=False)
    fig.suptitle("Active-basis person template (Wu et al. 2010; Reta 3.1): sum-max score = "
                 "sum_i lambda_i max h(r) - log Z", fontsize=9)
    return save_figure(fig, path)


def example_patches(template: ActiveBasis, seed: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """A rendered person (the first fully visible, isolated one of the ``crossing`` scene)
    and a background patch of the same size beside it in the first frame without people there."""
    seq = load_scenario("crossing", seed=seed, width=384, height=288)
    for k in seq.frame_numbers():
        rows = seq.gt.rows_of(k)
        boxes = seq.gt.table.boxes[rows]
        for j, r in enumerate(rows):
            x, _y, w, h = boxes[j]
            lab = seq.foreground(k)
            ys, xs = np.nonzero(lab == seq.gt.table.ids[r])
            if h < 60 or x < 1 or x + w > 383 or len(ys) == 0 or seq.gt.table.visibility[r] < 0.99:
                continue
            tight = (xs.min(), ys.min(), xs.max() - xs.min() + 1, ys.max() - ys.min() + 1)
            frame = seq.frame(k)
            person = crop_patch(frame, tight, template.size, template.pad)
            bx = (8.0, tight[1], tight[2], tight[3]) if tight[0] > 384 / 2 else (384 - 8.0 - tight[2], *tight[1:])
            background = crop_patch(seq.background, bx, template.size, template.pad)
            return person, background
    raise ValueError("no isolated, fully visible person found")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m occbench.fit.active_basis_figure", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--template", type=Path, default=None, help="template .npz (default: shipped)")
    ap.add_argument("--out", type=Path, default=Path("docs/img/active_basis.png"))
    args = ap.parse_args(argv)
    t = load(args.template)
    person, background = example_patches(t)
    print(draw(t, person, background, args.out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
