"""The front-end cache: identical outputs hit or miss, one computation under a race,
unusable entries recomputed with a warning, ``off``, stale locks, ``occbench cache``."""

from __future__ import annotations

import logging
import multiprocessing
import os
import socket
import time
from pathlib import Path

import numpy as np
import pytest

from occbench.commands import cache as cache_command
from occbench.config.build import build_source, compose_config, load_sequences
from occbench.sources.cache import CachedSource, Store, cached
from occbench.sources.cache.keys import code_version, entry_key
from occbench.sources.cache.lock import EntryLock
from occbench.sources.cache.store import CorruptEntry, decode, encode

TINY = ["dataset=synthetic", "dataset.scenarios=[pair_walk]", "dataset.length=12",
        "dataset.width=320", "dataset.height=240", "detector=foreground"]


@pytest.fixture(scope="module")
def scene():
    cfg = compose_config(TINY)
    return cfg, load_sequences(cfg.dataset)[0]


def outputs(source, seq) -> list:
    """Every byte the trackers would receive from ``source`` on ``seq``."""
    source.start(seq)
    out = []
    for k in seq.frame_numbers():
        d, m = source.detect(k, seq.frame(k))
        out.append([None if a is None else (a.dtype.str, a.shape, a.tobytes())
                    for a in (d.boxes, d.scores, d.heads, d.labels, m)])
    return out


def test_hit_and_miss_equal_no_cache(scene, tmp_path, monkeypatch, caplog):
    cfg, seq = scene
    plain = outputs(build_source(cfg.detector, cache=False), seq)
    assert sum(len(o[0][2]) for o in plain) > 0  # the scene has detections
    assert any(o[4] is not None for o in plain)  # and foreground masks
    monkeypatch.setenv("OCCBENCH_CACHE", str(tmp_path))
    cold = build_source(cfg.detector)
    assert isinstance(cold, CachedSource)
    with caplog.at_level(logging.INFO, logger="occbench.sources.cache"):
        assert outputs(cold, seq) == plain
        warm = build_source(cfg.detector)
        assert outputs(warm, seq) == plain
    assert (cold.origin, warm.origin) == ("computed", "read")
    lines = [r.getMessage() for r in caplog.records if "front end of" in r.getMessage()]
    assert len(lines) == 2 and "read from the cache" in lines[1]
    assert len(list(Store(tmp_path).entries())) == 1


def test_off_runs_the_source_and_writes_nothing(scene, tmp_path, monkeypatch):
    cfg, seq = scene
    monkeypatch.setenv("OCCBENCH_CACHE", "off")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    source = build_source(cfg.detector)
    assert source.store is None
    assert outputs(source, seq) == outputs(build_source(cfg.detector, cache=False), seq)
    assert source.origin == "uncached" and not any(tmp_path.iterdir())


def test_key_follows_frames_window_and_config(scene):
    cfg, seq = scene
    from omegaconf import OmegaConf

    from occbench.datasets.base import FrameWindow

    config = OmegaConf.to_container(cfg.detector, resolve=True)
    key = entry_key(seq, config)
    assert key == entry_key(seq, config) and len(code_version()) == 64
    assert entry_key(FrameWindow(seq, 2, 12), config) != key
    changed = {**config, "detector": {**config["detector"], "min_area": 81}}
    assert entry_key(seq, changed) != key


@pytest.mark.parametrize("damage", ["truncate", "flip", "foreign"])
def test_unusable_entry_recomputed_with_one_warning(scene, tmp_path, caplog, damage):
    cfg, seq = scene
    from omegaconf import OmegaConf

    config = OmegaConf.to_container(cfg.detector, resolve=True)
    store = Store(tmp_path)
    first = CachedSource(build_source(cfg.detector, cache=False), config, store)
    want = outputs(first, seq)
    path = store.path(entry_key(seq, config))
    data = path.read_bytes()
    if damage == "truncate":
        path.write_bytes(data[: len(data) // 2])
    elif damage == "flip":
        path.write_bytes(data[:-10] + bytes([data[-10] ^ 1]) + data[-9:])
    else:  # another key's entry under this key's name
        other = store.path("0" * 40)
        store.write("0" * 40, {"sequence": "x"}, {"frames": np.zeros(0, np.int64)})
        path.write_bytes(other.read_bytes())
    again = CachedSource(build_source(cfg.detector, cache=False), config, store)
    with caplog.at_level(logging.WARNING):
        assert outputs(again, seq) == want
    warnings = [r for r in caplog.records if r.levelno == logging.WARNING
                and "unusable" in r.getMessage()]
    assert again.origin == "computed" and len(warnings) == 1
    decode(path.read_bytes(), entry_key(seq, config))  # rewritten whole


def test_decode_refuses_every_truncation():
    data = encode("k" * 40, {"sequence": "s"}, {"a": np.arange(10)})
    assert decode(data, "k" * 40).arrays["a"].tolist() == list(range(10))
    for n in (0, 5, 30, len(data) - 1):
        with pytest.raises(CorruptEntry):
            decode(data[:n], "k" * 40)


def _race(root: str, key: str, counter: str, barrier, results) -> None:
    store = Store(Path(root), heartbeat=0.2, stale_after=5.0, poll=0.05)

    def compute():
        with open(counter, "a") as fh:
            fh.write(f"{os.getpid()}\n")
        time.sleep(1.0)  # long enough for the other process to find the lock
        return {"sequence": "race"}, {"x": np.arange(1000, dtype=np.int64)}

    barrier.wait()
    entry, how = store.get_or_compute(key, compute)
    results.put((how, int(entry.arrays["x"].sum())))


def test_two_processes_racing_compute_once(tmp_path):
    ctx = multiprocessing.get_context("fork")
    barrier, results = ctx.Barrier(2), ctx.Queue()
    counter = tmp_path / "computations.txt"
    procs = [ctx.Process(target=_race, args=(str(tmp_path), "r" * 40, str(counter), barrier,
                                            results)) for _ in range(2)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(60)
    assert [p.exitcode for p in procs] == [0, 0]
    got = sorted(results.get(timeout=5) for _ in procs)
    assert got == [("computed", 499500), ("waited", 499500)]
    assert len(counter.read_text().splitlines()) == 1
    assert not list((tmp_path / "frontend").glob("*.lock"))
    assert not list((tmp_path / "frontend").glob(".*.tmp"))


def test_stale_locks_are_broken(tmp_path):
    store = Store(tmp_path, heartbeat=0.05, stale_after=0.3, poll=0.05)
    store.folder.mkdir(parents=True)
    dead = store.folder / f"{'d' * 40}.lock"  # a dead process on this host
    dead.write_text(f'{{"host": "{socket.gethostname()}", "pid": 999999999}}')
    _, how = store.get_or_compute("d" * 40, lambda: ({}, {"x": np.ones(1)}))
    assert how == "computed"
    remote = store.folder / f"{'e' * 40}.lock"  # another machine that stopped beating
    remote.write_text('{"host": "elsewhere", "pid": 1}')
    t0 = time.monotonic()
    _, how = store.get_or_compute("e" * 40, lambda: ({}, {"x": np.ones(1)}))
    assert how == "computed" and time.monotonic() - t0 >= 0.3


def test_live_lock_is_not_stale(tmp_path):
    owner = EntryLock(tmp_path / "a.lock", heartbeat=0.05, stale_after=0.3)
    assert owner.try_acquire()
    waiter = EntryLock(tmp_path / "a.lock", heartbeat=0.05, stale_after=0.3)
    assert not waiter.try_acquire()
    t0 = time.monotonic()
    while time.monotonic() - t0 < 0.8:
        assert not waiter.stale()
        time.sleep(0.05)
    owner.release()
    assert not (tmp_path / "a.lock").exists() and waiter.try_acquire()
    waiter.release()


def test_cache_command_lists_and_clears(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("OCCBENCH_CACHE", str(tmp_path))
    store = Store(tmp_path)
    store.write("a" * 40, {"sequence": "S1", "frames": [1, 9], "detector": "x.SilhouetteDetector"},
                {"x": np.ones(3)})
    store.write("b" * 40, {"sequence": "S2", "frames": [1, 5], "detector": "x.HogDetector"},
                {"x": np.ones(3)})
    assert cache_command.main([]) == 0
    out = capsys.readouterr().out
    assert "S1" in out and "SilhouetteDetector" in out and "1-9" in out and "2 entries" in out
    assert cache_command.main(["clear", "--detector", "hog"]) == 0
    assert [i.meta["sequence"] for i in store.entries()] == ["S1"]
    assert cache_command.main(["clear", "--older-than", "1"]) == 0  # written just now
    assert len(list(store.entries())) == 1
    assert cache_command.main(["clear"]) == 0
    assert list(store.entries()) == []
    monkeypatch.setenv("OCCBENCH_CACHE", "off")
    assert cache_command.main([]) == 0 and "off" in capsys.readouterr().out


def test_annotation_sources_are_not_wrapped():
    cfg = compose_config(["detector=noisy_gt"])
    assert not isinstance(build_source(cfg.detector), CachedSource)
    assert cached(object(), {}).__class__ is object


def test_detect_fills_the_cache_runs_read(scene, tmp_path, monkeypatch):
    from occbench.commands.detect import run_detection

    cfg, seq = scene
    monkeypatch.setenv("OCCBENCH_CACHE", str(tmp_path / "cache"))
    run_detection(compose_config(TINY, config_name="detect"), tmp_path / "out")
    source = build_source(cfg.detector)
    assert outputs(source, seq) == outputs(build_source(cfg.detector, cache=False), seq)
    assert source.origin == "read"


def test_unusable_cache_folder_runs_without_it(scene, tmp_path, monkeypatch, caplog):
    cfg, seq = scene
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("OCCBENCH_CACHE", str(blocker))
    source = build_source(cfg.detector)
    with caplog.at_level(logging.WARNING):
        assert outputs(source, seq) == outputs(build_source(cfg.detector, cache=False), seq)
    assert source.origin == "uncached"
    assert any("cannot be used" in r.getMessage() for r in caplog.records)


def test_front_end_failure_is_raised_not_hidden(scene, tmp_path):
    _, seq = scene

    class Broken:
        cacheable = True

        def start(self, sequence):
            raise FileNotFoundError("frame 3 missing")

    source = CachedSource(Broken(), {"_target_": "x"}, Store(tmp_path))
    with pytest.raises(FileNotFoundError, match="frame 3"):
        source.start(seq)
    assert not list((tmp_path / "frontend").glob("*.lock"))
