"""Optuna studies of the ``tune_*`` experiments: the defaults as the first trial, and the
study drawn with Optuna's own matplotlib views.

``EnqueueDefaults`` (a Hydra callback, ``conf/config.yaml``) makes a new study's first trial
the config's own values of the searched parameters (``study.enqueue_trial``), so the tuned
result is always compared with the defaults it would replace, on the same data. The
hydra-optuna-sweeper plugin creates its study inside ``sweep()`` and offers no hook there,
and Hydra loads sweepers only from its ``hydra_plugins`` package; so, when a multirun with
that sweeper starts, the callback wraps ``optuna.create_study`` for the one call the sweeper
makes (restored at once). A resumed study (``storage``) that already has trials gets
nothing enqueued; a default outside its search range is left to the sampler.

``plot_study(sweep_dir, config)`` rebuilds the study from the job folders (each job's
``status.json``: overrides and objective; the search space from ``hydra.sweeper.params``)
and writes ``plots/optuna_*.png`` with ``optuna.visualization.matplotlib``: optimisation
history, slice, contour and (with scikit-learn) parameter importances.
"""

from __future__ import annotations

import importlib.util
import logging
import math
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from hydra.experimental.callback import Callback
from omegaconf import DictConfig, OmegaConf

from occbench.sweeps.jobs import DONE, members, parse_override, read_overrides, read_status

log = logging.getLogger(__name__)


def search_space(params: Mapping[str, Any] | None,
                 arguments: Sequence[str] = ()) -> dict[str, Any]:
    """Optuna distributions of ``hydra.sweeper.params`` plus sweep arguments, as the
    plugin builds them (``interval(a, b)``, ``int(interval(a, b))``, ``choice(...)``,
    ``range(...)``); fixed values are left out."""
    # optional: hydra-optuna-sweeper (the tune extra)
    from hydra_plugins.hydra_optuna_sweeper._impl import create_params_from_overrides

    overrides = [f"{k}={v}" for k, v in (params or {}).items()] + list(arguments)
    distributions, _ = create_params_from_overrides(overrides)
    return distributions


def _contains(distribution: Any, value: Any) -> bool:
    choices = getattr(distribution, "choices", None)
    if choices is not None:
        return value in choices
    try:
        v = float(value)
    except (TypeError, ValueError):
        return False
    return math.isfinite(v) and distribution.low <= v <= distribution.high


def defaults_of(config: DictConfig, distributions: Mapping[str, Any]) -> dict[str, Any]:
    """The config's value of each searched parameter, where it lies in the search space."""
    out = {}
    for name, dist in distributions.items():
        value = OmegaConf.select(config, name, default=None)
        if value is None or not _contains(dist, value):
            log.warning("tune: default %s=%s is not in the search space %s: not enqueued",
                        name, value, dist)
            continue
        out[name] = value
    return out


def is_optuna(config: DictConfig) -> bool:
    """Whether the multirun of ``config`` is an Optuna study (hydra-optuna-sweeper)."""
    target = OmegaConf.select(config, "hydra.sweeper._target_", default="") or ""
    return "optuna" in str(target).lower()


class EnqueueDefaults(Callback):
    """At the start of an Optuna multirun: the defaults become the new study's first trial."""

    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        if not is_optuna(config):
            return
        import optuna  # optional: optuna (the tune extra)

        params = OmegaConf.to_container(OmegaConf.select(config, "hydra.sweeper.params") or {},
                                        resolve=True)
        task = [str(o) for o in OmegaConf.select(config, "hydra.overrides.task", default=[])]
        defaults = defaults_of(config, search_space(params, task))
        if not defaults:
            return
        create_study = optuna.create_study

        def create_with_defaults(*args: Any, **kw: Any) -> Any:
            optuna.create_study = create_study  # one study per sweep: restore at once
            study = create_study(*args, **kw)
            if not study.trials:
                log.info("tune: trial 0 is the defaults %s", defaults)
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
                    study.enqueue_trial(defaults)
            return study

        optuna.create_study = create_with_defaults


def study_of(sweep_dir: str | Path, distributions: Mapping[str, Any],
             direction: str = "maximize") -> Any:
    """An in-memory Optuna study of a finished sweep: one trial per job folder, its
    parameters from the job's overrides, its value the job's objective (``status.json``);
    a failed job is a failed trial."""
    import optuna  # optional: optuna (the tune extra)
    from optuna.trial import TrialState, create_trial  # optional: optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    warnings.filterwarnings("ignore", category=optuna.exceptions.ExperimentalWarning)
    study = optuna.create_study(direction=direction)
    for d in members(sweep_dir)[0]:  # not the folders an earlier sweep left
        status = read_status(d) or {}
        overrides = status.get("overrides") or read_overrides(d)
        given = dict(parse_override(o) for o in overrides)
        params = {}
        for name, dist in distributions.items():
            if name not in given:
                break
            text = given[name]
            choices = getattr(dist, "choices", None)
            if choices is not None:
                value = next((c for c in choices if str(c) == text), None)
            else:
                value = float(text)
                if "Int" in type(dist).__name__:
                    value = int(round(value))
            if value is None:
                break
            params[name] = value
        else:
            value = status.get("objective")
            ok = status.get("status") == DONE and value is not None and math.isfinite(value)
            study.add_trial(create_trial(
                params=params, distributions=dict(distributions),
                value=float(value) if ok else None,
                state=TrialState.COMPLETE if ok else TrialState.FAIL))
    return study


def plot_study(sweep_dir: str | Path, config: DictConfig, out_dir: str | Path | None = None,
               metric: str = "objective") -> list[Path]:
    """``plots/optuna_*.png`` of the sweep's study with ``optuna.visualization.matplotlib``."""
    import matplotlib  # start-up: matplotlib, ~0.08 s CPU

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # start-up: matplotlib.pyplot, ~0.4 s CPU
    from optuna.visualization import matplotlib as views  # optional: optuna

    sweep_dir = Path(sweep_dir)
    out_dir = Path(out_dir) if out_dir is not None else sweep_dir / "plots"
    params = OmegaConf.to_container(OmegaConf.select(config, "hydra.sweeper.params") or {},
                                    resolve=True)
    direction = str(OmegaConf.select(config, "hydra.sweeper.direction", default="maximize"))
    distributions = search_space(params)
    study = study_of(sweep_dir, distributions, direction.rsplit(".", 1)[-1].lower())
    done = [t for t in study.trials if t.value is not None]
    if not done:
        log.warning("optuna plots: no finished trial in %s", sweep_dir)
        return []
    out_dir.mkdir(parents=True, exist_ok=True)
    names = list(distributions)
    # optimisation history, objective against each parameter, and (two or more parameters)
    # the first two parameters' contour and, where scikit-learn is installed (Optuna 2's
    # fANOVA needs it), the parameter importances
    wanted = [("history", lambda: views.plot_optimization_history(study, target_name=metric)),
              ("slice", lambda: views.plot_slice(study, target_name=metric))]
    if len(names) >= 2 and len(done) >= 2:
        wanted.append(("contour", lambda: views.plot_contour(study, params=names[:2],
                                                             target_name=metric)))
        if importlib.util.find_spec("sklearn") is not None:
            wanted.append(("importances", lambda: views.plot_param_importances(
                study, target_name=metric)))
    written = []
    for name, draw in wanted:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # Optuna's "experimental" and layout notices
            try:
                result = draw()
                axes = result.ravel()[0] if hasattr(result, "ravel") else result
                fig = axes.get_figure()
                fig.set_size_inches(max(6.4, 3.2 * len(names)) if name == "slice" else 6.4,
                                    4.4)
                fig.tight_layout()
                path = out_dir / f"optuna_{name}.png"
                fig.savefig(path, dpi=90)
            except Exception as err:  # noqa: BLE001 - one view must not cost the others
                log.warning("optuna %s plot failed: %s: %s", name, type(err).__name__, err)
                continue
            finally:
                plt.close("all")
        written.append(path)
    return written
