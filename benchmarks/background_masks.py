"""Before/after foreground masks: MOG2 (the default) against Reta 3.1's texture and
invariant-colour mixture (``background.method=texture_colour``).

Rows: a rendered scene with floor reflections of opacity 0.6 (exact masks: the reflection's
pixels outlined), CAVIAR OneLeaveShop1cor frame 130 (the dev half, a man in white with his
reflection on the shiny floor) and frames of two unlabelled CAVIAR videos. Columns: the frame,
then each model's clean foreground (white) and the pixels it labelled shadow / explained by the
invariance and removed (red). Both models warm up on 50 frames sampled over the first 150.

Run: ``python benchmarks/background_masks.py [--out docs/img/background_before_after.png]``.
CAVIAR comes from the shipped sample (``occbench.config.paths``); the unlabelled videos from
``../shared/data/videos`` (optional material: their rows are left out without it).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from occbench.datasets.caviar import load_caviar  # noqa: E402
from occbench.datasets.synthetic import load_scenario  # noqa: E402
from occbench.datasets.video import load_video  # noqa: E402
from occbench.config.paths import data_path  # noqa: E402
from occbench.trackers.frontend.background import BackgroundModel  # noqa: E402

VIDEOS = ROOT.parent / "shared" / "data" / "videos"  # optional, not shipped
MODELS = {"MOG2": {}, "texture_colour (Reta 3.1, silhouette default)": {"method": "texture_colour"}}


def _panel(model: BackgroundModel, frame: np.ndarray) -> np.ndarray:
    raw = model.raw(frame)
    out = np.zeros_like(frame)
    out[raw == 127] = (0, 0, 230)
    out[model.clean(raw) > 0] = (255, 255, 255)
    return out


def row(seq, k: int, outline: np.ndarray | None = None) -> list[np.ndarray]:
    panels = [seq.frame(k)]
    for kw in MODELS.values():
        m = BackgroundModel(**kw)
        m.warm_up_sequence(min(seq.info.length, 150), seq.frame)
        for j in range(1, k):
            m.raw(seq.frame(j))
        panels.append(_panel(m, seq.frame(k)))
    if outline is not None:
        cnt, _ = cv2.findContours(outline.astype(np.uint8), cv2.RETR_EXTERNAL,
                                  cv2.CHAIN_APPROX_NONE)
        for p in panels[1:]:
            cv2.drawContours(p, cnt, -1, (255, 160, 0), 1)
    return panels


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "img" / "background_before_after.png")
    args = ap.parse_args()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cv2.setNumThreads(1)
    rows, titles = [], []
    syn = load_scenario("crossing", seed=11, width=384, height=288, length=40, reflection=0.6)
    rows.append(row(syn, 20, syn.reflection_mask(20)))
    titles.append("synthetic, reflection 0.6")
    caviar = data_path("CAVIAR-OneLeaveShop1cor")
    if caviar.is_dir():
        rows.append(row(load_caviar(caviar, prefetch=0)[0], 130))
        titles.append("CAVIAR frame 130 (dev half)")
    for name, k in (("CAVIAR-ShopAssistant1cor", 300), ("CAVIAR-OneStopEnter1front", 300)):
        path = VIDEOS / f"{name}.mp4"
        if path.is_file():
            rows.append(row(load_video(path)[0], k))
            titles.append(f"{name} frame {k} (unlabelled)")
    cols = ["frame", *MODELS]
    fig, axes = plt.subplots(len(rows), 3, figsize=(12, 3.0 * len(rows)), squeeze=False)
    for r, (panels, title) in enumerate(zip(rows, titles)):
        for c, img in enumerate(panels):
            ax = axes[r, c]
            ax.imshow(cv2.cvtColor(img, cv2.COLOR_BGR2RGB))
            ax.set_xticks([])
            ax.set_yticks([])
            if r == 0:
                ax.set_title(cols[c])
        axes[r, 0].set_ylabel(title, fontsize=7)
    from matplotlib.patches import Patch

    fig.legend(handles=[Patch(color="white", ec="k", label="foreground kept (after cleaning)"),
                        Patch(color=(0.9, 0, 0), label="shadow / explained by invariance: removed"),
                        Patch(color=(0, 0.63, 1), label="exact reflection pixels (synthetic)")],
               loc="lower center", ncol=3, fontsize=8)
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=80)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
