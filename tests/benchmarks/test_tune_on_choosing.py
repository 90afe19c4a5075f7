"""benchmarks/tune_on_choosing.py with a tiny budget: two trials of motpy on one short
synthetic scene (a stand-in for the choosing sets), the defaults first, the best written as a
config whose comments say where it came from."""

from __future__ import annotations

import pandas as pd
import pytest
from benchmark_scripts import load
from omegaconf import OmegaConf

pytest.importorskip("optuna")
pytest.importorskip("motpy")

tuner = load("tune_on_choosing")

G = tuner.G
TINY = G.EvalSet("tiny", G.TUNING, ("dataset=synthetic", "dataset.scenarios=[crossing]",
                                    "dataset.length=20", "detector=noisy_gt"), (0,))


def test_two_trials_defaults_first_and_the_best_written_with_its_provenance(tmp_path):
    studies, table = tuner.tune(["motpy"], [TINY], trials=2, startup=1, out=tmp_path)
    assert list(table["trial"]) == [0, 1]
    defaults = OmegaConf.load(G.CONF / "tracker" / "motpy.yaml")
    first = table.iloc[0]
    for key in tuner.space("motpy"):  # trial 0 is motpy's defaults
        assert first[key] == defaults[key.removeprefix("tracker.")], key
    assert first["objective"] == pytest.approx(first["tiny"])  # one set: its IDF1
    assert pd.read_csv(tmp_path / "trials.csv")["trial"].tolist() == [0, 1]
    assert not (tmp_path / "batch0" / "tiny" / "seed0" / "report.html").exists()  # scores only
    (path,) = tuner.write_configs(tmp_path, [TINY], 1, folder=tmp_path)
    assert path.name == "motpy_tuned_real.yaml"
    text = path.read_text()
    assert "best of 2 trials" in text and "commit" in text and "tiny" in text
    node = OmegaConf.create(text)
    best = studies["motpy"].best_trial
    assert list(node.defaults) == ["motpy", "_self_"]
    for key, value in best.params.items():  # exactly the trial's values, read back from csv
        assert node[key.removeprefix("tracker.")] == value
        assert type(node[key.removeprefix("tracker.")]) is type(value)
    assert best.value == pytest.approx(table["objective"].max())



def _fake_batch(batch, sets, out, data_root):
    """A stand-in for the harness runs: IDF1 a smooth function of the trial's parameters."""
    def idf1(p):
        return 1 - abs(p["tracker.min_iou"] - 0.3) - p["tracker.q_var_pos"] / 1e3

    return pd.DataFrame([{"label": label, "set": s.name, "IDF1": idf1(p)}
                         for label, (name, p) in batch.items() for s in sets])


def test_a_longer_study_in_batches_begins_with_the_shorter_study(tmp_path, monkeypatch):
    # --trials 40 --batches 6 24 holds the 16-trial study: both budgets from one run
    monkeypatch.setattr(tuner, "run_batch", _fake_batch)
    _, short = tuner.tune(["motpy"], [TINY], trials=4, startup=2, out=tmp_path / "a")
    _, long = tuner.tune(["motpy"], [TINY], trials=7, startup=2, out=tmp_path / "b",
                         batches=[2, 3])
    pd.testing.assert_frame_equal(short, long.iloc[:4])
    assert tuner.best_within(long, "motpy", 4)["objective"] == short["objective"].max()
    assert tuner.batch_sizes(16, 10) == [10, 6]
    with pytest.raises(SystemExit, match="do not make 40 trials"):
        tuner.batch_sizes(40, 10, [6, 20])


def _scored_batch(batch, sets, out, data_root):
    """A stand-in for the harness runs of any tracker: IDF1 a function of the trial's values."""
    return pd.DataFrame([{"label": label, "set": s.name,
                          "IDF1": sum(float(v) for v in p.values()) % 1.0}
                         for label, (name, p) in batch.items() for s in sets])


@pytest.mark.parametrize("name,paper", [("reta", "reta_paper"), ("pbm", "pbm_paper")])
def test_ours_tuned_row_differs_from_its_defaults_only_in_the_tuned_keys(
        name, paper, tmp_path, monkeypatch):
    """Ours get the outside trackers' study: the written ``<name>_tuned_real`` keeps every
    adaptation (every key but the searched ones) of ``<name>.yaml``, is one of ours with a
    colour no shipped tracker has, and the paper mode takes nothing from it."""
    from occbench.config.meta import shipped

    monkeypatch.setattr(tuner, "run_batch", _scored_batch)
    tuner.tune([name], [TINY], trials=3, startup=2, out=tmp_path)
    (path,) = tuner.write_configs(tmp_path, [TINY], 2, folder=tmp_path)
    node = OmegaConf.create(path.read_text())
    assert list(node.defaults) == [name, "_self_"]
    parent = G.compose([f"tracker={name}"]).tracker
    tuned = OmegaConf.merge(parent, {k: v for k, v in node.items() if k != "defaults"})
    keys = [k.removeprefix("tracker.") for k in tuner.space(name)]
    for key in keys:  # only the searched keys are set, to the best trial's values
        assert OmegaConf.select(tuned, key) == OmegaConf.select(node, key), key
    for key in keys:
        OmegaConf.update(tuned, key, OmegaConf.select(parent, key))
    assert tuned.adaptations == parent.adaptations
    assert OmegaConf.to_container(tuned.meta) != OmegaConf.to_container(parent.meta)
    tuned.meta = parent.meta
    assert tuned == parent  # nothing else differs
    assert node.meta.role == "ours" and node.meta.style == shipped(name).style
    colours = {shipped(p.stem).colour.lower() for p in (G.CONF / "tracker").glob("*.yaml")
               if p.stem != f"{name}{tuner.SUFFIX}" and shipped(p.stem) is not None}
    assert node.meta.colour.lower() not in colours
    assert list(OmegaConf.load(G.CONF / "tracker" / f"{paper}.yaml").defaults) == [name, "_self_"]
