"""benchmarks/difference_figures.py and benchmarks/paper_mode_ablation.py (issue 37 item 6):
a person's matched share and a matched box's size against the person's, detections matched
one-to-one per frame; the ablation turns exactly the rules paper mode switches off back on."""

from __future__ import annotations

import importlib
from pathlib import Path

import numpy as np
import pytest
from benchmark_scripts import load

figures = load("difference_figures")
ablation = load("paper_mode_ablation")


def _mot(path: Path, rows: list[tuple]) -> str:
    path.write_text("".join(f"{f},{i},{x},{y},{w},{h},1,-1,-1,-1\n" for f, i, x, y, w, h in rows))
    return str(path)


def test_coverage_and_sizes_of_matched_boxes(tmp_path):
    gt = _mot(tmp_path / "gt.txt", [(f, 1, 10, 10, 20, 40) for f in range(1, 5)]
              + [(f, 2, 100, 10, 20, 40) for f in range(1, 5)])
    # person 1 covered in frames 1-3 by a box half as wide, centred; person 2 never
    dets = _mot(tmp_path / "det.txt", [(f, -1, 15, 10, 10, 40) for f in range(1, 4)]
                + [(f, -1, 15, 60, 10, 40) for f in range(1, 4)])
    assert figures.coverage(gt, dets) == {1: 0.75, 2: 0.0}
    assert np.allclose(figures.ratios(gt, dets), [[0.0, 0.5, 1.0]] * 3)


def test_every_figure_is_drawn(tmp_path):
    gt = _mot(tmp_path / "gt.txt", [(f, 1, 10, 10, 20, 40) for f in range(1, 5)])
    res = _mot(tmp_path / "res.txt", [(f, 7, 11, 10, 20, 40) for f in range(1, 5)])
    figures.main(["coverage", gt, f"a={res}", "--out", str(tmp_path / "c.png")])
    figures.main(["boxes", gt, f"a={res}", "--out", str(tmp_path / "b.png")])
    figures.main(["sizes", f"a={gt},{res}", "--out", str(tmp_path / "s.png")])
    assert all((tmp_path / f"{k}.png").stat().st_size > 0 for k in "cbs")
    with pytest.raises(SystemExit):
        figures.main(["coverage", gt, res, "--out", str(tmp_path / "x.png")])   # no label=


@pytest.mark.parametrize("paper, ours, module", [
    ("reta_paper", "reta", "occbench.trackers.three_hypothesis"),
    ("pbm_paper", "pbm", "occbench.trackers.layered")])
def test_the_ablation_turns_back_on_what_paper_mode_switches_off(paper, ours, module):
    adaptations = importlib.import_module(module).Adaptations
    assert set(ablation.switches(paper, ours)) == set(adaptations().changed())
    assert ablation._value({"_target_": "a.B", "frames": 3, "on": True}) == \
        "{_target_:a.B,frames:3,on:true}"
