"""Before anything is timed: every tracker of a run runs a short scripted scene once per
process, so that compiled kernels (numba: compiled on the first use after an install,
loaded from the ``__pycache__`` cache in every new process) and lazy imports are paid for
here, not inside a timed ``update`` (``timings.csv`` measures tracking only). A warm-up
that lasts (compiling: half a minute to minutes) is announced in one log line (stderr in the
app) after ``WarmUp.first`` seconds and then says it is still going every ``WarmUp.every``
seconds (a warm run, loading its kernels in about a second, says nothing).

The scene takes a tracker through the paths a run uses: four painted people on a 240x320
frame. Two walk towards each other and merge into one foreground blob (PBM's occlusion
search), two look alike and walk side by side with touching heads (multiple responses and
head-template pruning); detections are dropped in some frames (lost targets, grown gates),
once with a bool foreground mask and once without. Each tracker is a fresh instance built
for the purpose and thrown away: the trackers of the run are built afterwards, as they
always were, and are not touched.

``preload(spec)`` does all of this ahead of a sweep's jobs, in the launcher's fork server
(``hydra_plugins.occbench_launcher``): it imports what a job imports (the app, the scoring,
the plots, the config's ``_target_`` modules) and warms the job's trackers up, so that each
job, forked from it, starts with both done.
"""

from __future__ import annotations

import importlib
import logging
import threading
import time
from contextlib import contextmanager
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from numba.core import event
from omegaconf import OmegaConf

from occbench.config.build import build_tracker, tracker_configs
from occbench.pipeline.bank import TrackerBank
from occbench.pipeline.loop import Progress, ProgressFactory, no_progress
from occbench.trackers.protocol import Tracker
from occbench.trackers.records import Detections

log = logging.getLogger(__name__)

FRAMES = 26  # the first two people meet (frame 17), overlap and part (frame 23)
ALONE_FRAMES = 6  # the first person alone: one match or none a frame
SIZE = (240, 320)
# (x at frame 0, x step per frame, y, w, h, head colour, body colour)
PEOPLE = (
    (40.0, 5.0, 60.0, 28.0, 84.0, (60, 90, 200), (200, 60, 40)),
    (240.0, -5.0, 60.0, 28.0, 84.0, (60, 90, 200), (200, 60, 40)),
    (120.0, 1.0, 140.0, 26.0, 84.0, (60, 95, 205), (150, 150, 40)),
    (138.0, 1.0, 140.0, 26.0, 84.0, (60, 95, 205), (150, 150, 40)),
)

def scene(k: int, people: tuple = PEOPLE) -> tuple[np.ndarray, np.ndarray, Detections]:
    """Frame ``k`` of the scene: BGR frame, bool person mask and the detections (some
    people missed in some frames)."""
    rng = np.random.default_rng(k)
    frame = rng.integers(90, 110, (*SIZE, 3), dtype=np.uint8)
    mask = np.zeros(SIZE, dtype=bool)
    boxes = []
    for i, (x0, step, y, w, h, head, body) in enumerate(people):
        x = x0 + step * k
        box = np.array([x, y, w, h])
        c0, r0, c1, r1 = int(x), int(y), int(x + w), int(y + h)
        frame[r0:r0 + int(h) // 7, c0:c1] = head
        frame[r0:r0 + int(h) // 21, c0 + 4:c1 - 4] = (30, 30, 40)  # hair: a textured head template
        frame[r0 + int(h) // 7:r1, c0:c1] = body
        mask[r0:r1, c0:c1] = True
        if (k + i) % 5 != 4:  # every person is missed one frame in five
            boxes.append(box)
    dets = Detections(np.array(boxes).reshape(-1, 4), np.ones(len(boxes)))
    return frame, mask, dets


STEPS = 2 * (FRAMES + ALONE_FRAMES)  # frames of warm_up's four passes (all, first person) x (mask, none)


def warm_up(tracker: Tracker, bar: Progress | None = None) -> None:
    """Run ``tracker`` over the scene with and without a foreground mask, then with the
    first person alone (one match or none a frame: numba
    compiles a separate kernel for the contiguous one-element index arrays that gives), then
    ``reset`` it: its state afterwards is as built. ``bar`` (a progress bar) advances by one
    per frame (``STEPS`` in all), so a compiling warm-up moves as each frame's kernels are
    ready rather than once a pass."""
    for people, frames in ((PEOPLE, FRAMES), (PEOPLE[:1], ALONE_FRAMES)):
        for with_mask in (True, False):
            tracker.reset()
            bank = TrackerBank({"warm-up": tracker})
            for k in range(frames):
                frame, mask, dets = scene(k, people)
                if not bank.step(k, frame, dets, mask if with_mask else None):
                    raise RuntimeError(f"warm-up failed: {bank.outputs['warm-up'].error}")
                if bar is not None:
                    bar.update(1)
    tracker.reset()


class WarmUp:
    """Warms each tracker class up once per process (numba's loaded kernels, like imports,
    are process state: a second run in the same process has nothing to load).

    ``__call__(builders)`` takes ``{name: () -> fresh tracker}`` and returns the names
    warmed up now (the others' classes already were)."""

    def __init__(self, first: float = 3.0, every: float = 15.0) -> None:
        self.done: set[str] = set()
        self.first, self.every = first, every  # seconds before the announcement, between lines

    def __call__(self, builders: dict[str, Callable[[], Tracker]],
                 announce: Callable[[str], None] | None = None,
                 progress: ProgressFactory | None = None) -> list[str]:
        todo: dict[str, Tracker] = {}
        for name, build in builders.items():
            tracker = build()
            kind = _kind(tracker)
            if kind not in self.done and kind not in map(_kind, todo.values()):
                todo[name] = tracker
        if not todo:
            return []
        compiling = threading.Event()

        def said() -> str:  # "compiles" only when numba has compiled (not loaded) a kernel
            if compiling.is_set():
                return (f"warming up {', '.join(todo)} before timing: compiling their kernels "
                        "(the first run after an install: half a minute to a few minutes; "
                        "later runs load them in about a second)")
            return f"warming up {', '.join(todo)} before timing"

        bar = (progress or no_progress)(total=STEPS * len(todo), desc="warm-up", unit="frame")
        with (heartbeat(announce, said, self.first, self.every), _closing(bar),
              _compiles(compiling)):
            for name, tracker in todo.items():
                try:
                    warm_up(tracker, bar)
                except Exception as err:  # noqa: BLE001 - the run reports a failing tracker
                    log.debug("warm-up of %s stopped: %s: %s", name, type(err).__name__, err)
                self.done.add(_kind(tracker))
        log.debug("warmed up %s", ", ".join(todo))  # hydra.verbose=[occbench.pipeline.warmup]
        return list(todo)


@contextmanager
def _closing(bar: Progress):
    try:
        yield bar
    finally:
        bar.close()


@contextmanager
def _compiles(seen: threading.Event):
    """Within: ``seen`` is set when numba compiles a kernel (its ``numba:compile`` event; a
    kernel loaded from the cache fires none)."""
    class Listener(event.Listener):
        def on_start(self, ev: Any) -> None:
            seen.set()

        def on_end(self, ev: Any) -> None:
            pass

    with event.install_listener("numba:compile", Listener()):
        yield


@contextmanager
def heartbeat(announce: Callable[[str], None] | None, said: str | Callable[[], str],
              first: float, every: float):
    """Within: ``announce(said)`` (``said()`` when callable, asked then) once the block has
    run ``first`` seconds, then a line "still ..." every ``every`` seconds (from a daemon
    thread; ``said()`` again when it has changed) until it ends; nothing said for a block
    that ends sooner."""
    if announce is None:
        yield
        return
    done = threading.Event()
    start = time.monotonic()

    def now() -> str:
        return said() if callable(said) else said

    def speak() -> None:
        if done.wait(first):
            return
        text = now()
        announce(text)
        while not done.wait(every):
            seconds = time.monotonic() - start
            if now() != text:  # learnt since (numba began compiling after the first line)
                text = now()
                announce(f"still {text} ({seconds:.0f} s)")
            else:
                announce(f"still warming up ({seconds:.0f} s)")

    thread = threading.Thread(target=speak, name="warm-up heartbeat", daemon=True)
    thread.start()
    try:
        yield
    finally:
        done.set()
        thread.join()


# what every job imports besides its config's _target_s: the app, scoring, tables, plots
JOB_MODULES = ("occbench.commands.run", "occbench.pipeline.experiment", "occbench.pipeline.summary",
               "occbench.metrics", "occbench.metrics.occlusion", "occbench.report.tables",
               "occbench.report.hota_alpha", "occbench.sweeps.gather", "occbench.sweeps.fingerprint",
               "motmetrics", "tqdm.contrib.logging")


# only this project's code is imported and built ahead of a job: a tracker of someone else's
# (a test's, a plugin's) might sleep or crash in its constructor
OURS = ("occbench.",)


def preload_spec(cfg: Any, choice: str | None = None) -> dict[str, Any]:
    """What ``preload`` imports and warms up ahead of a run of ``cfg`` (composed, its
    ``hydra`` node removed; ``choice``: its ``tracker`` choice): the modules of the project's
    ``_target_``s and the resolved configs of the project's trackers."""
    targets = config_targets(OmegaConf.to_container(cfg, resolve=False))
    return {"modules": sorted({t.rsplit(".", 1)[0] for t in targets if t.startswith(OURS)}),
            "trackers": {name: OmegaConf.to_container(node, resolve=True)
                         for name, node in tracker_configs(cfg.tracker, choice).items()
                         if str(node["_target_"]).startswith(OURS)}}


def config_targets(node: Any) -> list[str]:
    """Every ``_target_`` string in a nested container (a config as plain dicts and lists),
    nested ones included."""
    if isinstance(node, dict):
        own = [str(node["_target_"])] if "_target_" in node else []
        return own + [t for v in node.values() for t in config_targets(v)]
    if isinstance(node, list):
        return [t for v in node for t in config_targets(v)]
    return []


def preload(spec: Mapping[str, Any]) -> list[str]:
    """Import ``JOB_MODULES`` and ``spec["modules"]`` and warm up the trackers of
    ``spec["trackers"]`` (``{name: resolved _target_ config}``) once in this process (see
    ``WarmUp``); returns the trackers warmed up. Nothing here may stop the caller: a module
    that does not import or a tracker that does not build is left to the job, which reports
    it as it always does (logged here at debug level)."""
    import matplotlib  # start-up: matplotlib, ~0.08 s CPU (the server's preload)

    matplotlib.use("Agg", force=False)  # as occbench.report's plots do
    importlib.import_module("matplotlib.pyplot")
    for name in (*JOB_MODULES, *spec.get("modules", ())):
        try:
            importlib.import_module(name)
        except Exception as err:  # noqa: BLE001 - the job imports it again and says why
            log.debug("preload: %s not imported: %s: %s", name, type(err).__name__, err)

    builders = {n: (lambda n=n, node=node: build_tracker(n, node))
                for n, node in dict(spec.get("trackers", {})).items()}
    try:
        return warm_up_once(builders)
    except Exception as err:  # noqa: BLE001 - the job warms its trackers up itself
        log.debug("preload: warm-up stopped: %s: %s", type(err).__name__, err)
        return []


def _kind(tracker: Tracker) -> str:
    return f"{type(tracker).__module__}.{type(tracker).__qualname__}"


# one per process: see WarmUp
warm_up_once = WarmUp()
