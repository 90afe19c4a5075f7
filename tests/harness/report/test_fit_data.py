"""No paper table's test frames fitted anything it depends on (issue 37 item 2): every
``+experiment=`` with a ``paper_table`` lists the frames it scores (``test_data``) and the
data each fitted model, template and chosen default came from (``fit_data``); the ranges of
one sequence never meet unless the table says so (``fit_on_test``, printed under it), and a table whose dataset is cut to frames scores those frames."""

from __future__ import annotations

from pathlib import Path

import pytest
from omegaconf import OmegaConf

from occbench.report.paper_tables import _data_lines

CONF = Path(__file__).resolve().parents[3] / "conf"
TABLES = sorted(p.stem for p in (CONF / "experiment").glob("*.yaml")
                if "paper_table:" in p.read_text())


def _compose(name: str):
    from hydra import compose, initialize_config_dir

    from occbench.config import register

    register()
    with initialize_config_dir(config_dir=str(CONF), version_base="1.3"):
        return compose("config", overrides=[f"+experiment={name}"])


def _meet(a, b) -> bool:
    """Whether two inclusive frame ranges (None: every frame) share a frame."""
    if a is None or b is None:
        return True
    return a[0] <= b[1] and b[0] <= a[1]


def overlaps(test_data, fit_data) -> list[str]:
    return [f"{f['what']}: {f['sequence']} {f['frames']} meets the test frames {t['frames']}"
            for t in test_data for f in fit_data
            if t["sequence"] == f["sequence"] and _meet(t["frames"], f["frames"])]


def test_overlap_check_finds_a_shared_frame():
    test = [{"sequence": "A", "frames": [151, 295]}]
    assert overlaps(test, [{"what": "x", "sequence": "A", "frames": [1, 151]}])
    assert overlaps(test, [{"what": "x", "sequence": "A", "frames": None}])
    assert not overlaps(test, [{"what": "x", "sequence": "A", "frames": [1, 150]},
                               {"what": "y", "sequence": "B", "frames": [151, 295]}])


@pytest.mark.parametrize("name", TABLES)
def test_no_table_scores_a_frame_it_was_fitted_on(name):
    assert len(TABLES) >= 5
    cfg = _compose(name)
    spec = OmegaConf.to_container(cfg.paper_table, resolve=False)
    assert spec.get("test_data") and spec.get("fit_data"), f"{name}: test_data / fit_data missing"
    disclosed = [e["what"] for e in spec.get("fit_on_test") or []]
    hidden = [o for o in overlaps(spec["test_data"], spec["fit_data"])
              if not any(o.startswith(f"{w}:") for w in disclosed)]
    assert hidden == [], f"{name}: fitted on its test frames without saying so"
    assert all(overlaps(spec["test_data"], [f for f in spec["fit_data"] if f["what"] == w])
               for w in disclosed), f"{name}: fit_on_test names an entry that does not overlap"
    frames = cfg.dataset.get("frames")  # the dataset config (CAVIAR part) scores these
    caviar = [t for t in spec["test_data"] if t["sequence"].startswith("CAVIAR")]
    if caviar:
        assert frames is not None and list(frames) == caviar[0]["frames"], name
    text = "\n".join(_data_lines(spec))
    assert "Test frames:" in text and "Fitting data" in text
