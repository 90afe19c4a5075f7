"""Reading a camera's other footage (occbench.sources.footage): folders of frames and videos,
clear one-line errors naming a bad path, and the front-end cache key following its bytes."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
from hydra.utils import instantiate
from omegaconf import OmegaConf

from occbench.sources.cache.keys import config_digest
from occbench.sources.footage import FootageError, camera_background
from occbench.config.build import compose_config

H, W = 48, 64


def _frames(seed: int, spot: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(6):
        f = np.full((H, W, 3), 120, np.uint8) + rng.integers(0, 3, (H, W, 3), dtype=np.uint8)
        f[10:20, spot:spot + 10] = 30  # someone standing in this clip
        out.append(f)
    return out


def _folder(root: Path, name: str, frames: list[np.ndarray], img1: bool = False) -> Path:
    folder = root / name / ("img1" if img1 else "")
    folder.mkdir(parents=True)
    for k, f in enumerate(frames, 1):
        cv2.imwrite(str(folder / f"{k:06d}.png"), f)
    return root / name


def test_folders_and_videos_pool_into_the_empty_background(tmp_path):
    a = _folder(tmp_path, "a", _frames(0, 5), img1=True)  # a MOT sequence folder
    b = _folder(tmp_path, "b", _frames(1, 25))
    video = tmp_path / "c.avi"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 25, (W, H))
    for f in _frames(2, 45):
        writer.write(f)
    writer.release()
    fp = camera_background([str(a), str(b), str(video)], frames_per_clip=4)
    assert fp.clips == 3 and fp.image.shape == (H, W, 3)
    assert "3 clip(s): a, b, c.avi" == fp.label
    assert np.abs(fp.image[10:20] - 121).max() < 8  # nobody left standing anywhere
    assert camera_background([]) is None and camera_background(None) is None


def test_bad_footage_is_one_line_naming_the_path(tmp_path):
    missing = tmp_path / "nowhere"
    with pytest.raises(FootageError, match=f"{missing}: no such file or folder"):
        camera_background([str(missing)])
    (tmp_path / "empty").mkdir()
    with pytest.raises(FootageError, match="empty: no image files"):
        camera_background([str(tmp_path / "empty")])
    bad = _folder(tmp_path, "bad", _frames(0, 5))
    (bad / "000002.png").write_bytes(b"not an image")
    with pytest.raises(FootageError, match=r"background footage .*bad.*000002\.png"):
        camera_background([str(bad)])
    small = _folder(tmp_path, "small", [f[:20, :30] for f in _frames(0, 5)])
    ok = _folder(tmp_path, "ok", _frames(0, 5))
    with pytest.raises(FootageError, match=r"different sizes: .*ok 64x48.*small 30x20"):
        camera_background([str(ok), str(small)])
    for err in (FootageError("x"),):
        assert "\n" not in str(err)


def test_the_config_builds_it_and_the_cache_key_follows_the_footage_bytes(tmp_path):
    a = _folder(tmp_path, "a", _frames(0, 5))
    cfg = compose_config(["detector=silhouette",
                          f"detector.detector.fallback.background.footage.paths=[{a}]"],
                         config_name="detect")
    bg = instantiate(cfg.detector).detector.fallback.background
    assert bg.footage is not None and bg.footage.label == "1 clip(s): a"
    node = OmegaConf.to_container(cfg.detector, resolve=True)
    key = config_digest(node)
    assert config_digest(node) == key
    f = _frames(5, 40)[0]
    cv2.imwrite(str(a / "000003.png"), f)  # one footage frame changes: another key
    assert config_digest(node) != key
    default = compose_config(["detector=silhouette"], config_name="detect")
    assert instantiate(default.detector).detector.fallback.background.footage is None


def test_a_run_with_missing_footage_stops_in_one_line_naming_it(tmp_path):
    from occbench.errors import RunError
    from occbench.config.build import build_source

    missing = tmp_path / "clip"
    cfg = compose_config(["detector=silhouette",
                          f"detector.detector.fallback.background.footage.paths=[{missing}]"],
                         config_name="detect")
    with pytest.raises(RunError, match=f"FootageError: background footage {missing}: no such") as err:
        build_source(cfg.detector, cache=False)
    assert "\n" not in str(err.value)
