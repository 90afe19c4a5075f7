"""occbench.commands.mistakes: a config mistake on the command line is one line with a "did you
mean" from the config's own keys and choices; the traceback only under -v."""

from __future__ import annotations

import pytest

from occbench.commands.cli import main
from occbench.commands.mistakes import suggest, verbose_requested


def _one_line(capsys, *args: str) -> str:
    status = main([*args, "progress=false"])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 1
    assert len(err) == 1, err
    return err[0]


@pytest.mark.parametrize(("args", "line"), [
    (["trackr=reta"], "occbench: unknown key 'trackr': did you mean 'tracker'?"),
    (["tracker.max_age=abc"],  # tracker=all: the key is per tracker
     "occbench: unknown key 'tracker.max_age': did you mean 'tracker.baseline.max_age'?"),
    (["tracker=reta", "tracker.association.mu_gg=3"],
     ("occbench: unknown key 'tracker.association.mu_gg': did you mean "
      "'tracker.association.mu_g'?")),
    (["dataset.lenght=30"], ("occbench: unknown key 'dataset.lenght': did you mean "
                             "'dataset.length'?")),
    (["detector=silhouette", "detector.detector.matcher.min_height=0.2"],  # moved into a group
     ("occbench: unknown key 'detector.detector.matcher.min_height': did you mean "
      "'detector.detector.matcher.heights.min_height'?")),
    (["detector=silhouette", "detector.detector.calibration.min_fill=0.4"],  # issue 36 item 6
     ("occbench: unknown key 'detector.detector.calibration.min_fill': did you mean "
      "'detector.detector.calibration.people.min_fill'?")),
    (["detector=foreground", "detector.detector.background.warmup_span=online"],
     ("occbench: unknown key 'detector.detector.background.warmup_span': did you mean "
      "'detector.detector.background.start.warmup_span'?")),
    (["detector=foreground", "detector.detector.heads.threshold_hair=5"],
     ("occbench: unknown key 'detector.detector.heads.threshold_hair': did you mean "
      "'detector.detector.heads.pixels.threshold_hair'?")),
    (["detector=silhouette", "detector.detector.fallback.background.k_sigma=3"],
     ("occbench: unknown key 'detector.detector.fallback.background.k_sigma': did you mean "
      "'detector.detector.fallback.background.threshold.k_sigma'?")),
])
def test_a_typo_is_one_line_with_did_you_mean(capsys, args, line):
    assert _one_line(capsys, *args) == line


def test_an_unknown_choice_names_the_closest_and_the_choices(capsys):
    line = _one_line(capsys, "tracker=rta")
    assert line.startswith("occbench: unknown tracker 'rta': did you mean 'reta'? (choices: ")
    assert "baseline" in line


def test_a_wrong_value_is_the_runs_one_line(capsys, tmp_path):
    line = _one_line(capsys, "tracker=baseline", "tracker.max_age=abc",
                     f"hydra.run.dir={tmp_path / 'run'}")
    assert line == "occbench: tracker.max_age: expected int, got 'abc' (str)"
    assert not (tmp_path / "run").exists()  # a run refused before any result leaves no folder


def test_verbose_shows_the_traceback(capsys, monkeypatch):
    from hydra.errors import ConfigCompositionException

    with pytest.raises(ConfigCompositionException, match="trackr"):
        main(["-v", "trackr=reta"])
    monkeypatch.setenv("OCCBENCH_VERBOSE", "1")
    assert verbose_requested(["trackr=reta"]) == (True, ["trackr=reta"])
    monkeypatch.setenv("OCCBENCH_VERBOSE", "0")
    assert verbose_requested(["-v", "x=1"]) == (True, ["x=1"])
    assert verbose_requested(["x=1"]) == (False, ["x=1"])


def test_suggest_prefers_the_closest_last_part_and_says_nothing_when_far():
    known = ["tracker.baseline.max_age", "tracker.reta.max_age", "tracker._target_", "seed"]
    assert suggest("tracker.max_age", known) in known[:2]
    assert suggest("tracker.reta.max_agee", known) == "tracker.reta.max_age"
    assert suggest("tracker.flux", known) is None
    assert suggest("sed", known) == "seed"
