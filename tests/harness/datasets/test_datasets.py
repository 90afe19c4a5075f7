"""MOT, CAVIAR and video readers: the shipped real sample, tiny hand-made folders, bad input."""

from __future__ import annotations

import logging
import os
import pickle
import re
from pathlib import Path

import cv2
import numpy as np
import pytest
from hydra import compose, initialize_config_dir
from hydra.utils import instantiate
from omegaconf.errors import MissingMandatoryValue

import occbench.datasets.video as video_module
from occbench.datasets.base import Sequence
from occbench.datasets.caviar import CaviarFormatError, load_caviar, read_cvml
from occbench.datasets.images import FrameError, ImageSequence, read_image
from occbench.datasets.mot import SeqInfoError, load_mot
from occbench.datasets.video import VideoSequence, load_video
from occbench.io.mot import MotFormatError, read_mot
from occbench.config.paths import DATA_ENV, SHIPPED_DATA, data_root

ROOT = Path(__file__).resolve().parents[3]
CONF = ROOT / "conf"
DATA = SHIPPED_DATA  # the sample shipped in datasets/ (occbench.config.paths)
CAVIAR = DATA / "CAVIAR-OneLeaveShop1cor"
PETS = DATA / "trajectories" / "PETS09-S2L1"
TUD = DATA / "trajectories" / "TUD-Campus"

W, H, N = 64, 48, 5


# ---------------------------------------------------------------- fixtures


def make_frame(k: int) -> np.ndarray:
    """A frame whose content identifies k: uniform grey 20*k with a white square at x=4k."""
    img = np.full((H, W, 3), 20 * k, dtype=np.uint8)
    img[10:20, 4 * k:4 * k + 10] = 255
    return img


GT_ROWS = [  # frame,id,left,top,w,h,conf,class,visibility  (MOT16 style)
    "1,1,11,21,10,20,1,1,1.0",
    "1,2,31,5,8,16,1,1,0.2",
    "2,1,12,21,10,20,1,1,0.9",
    "3,1,13,21,10,20,0,8,1.0",
    "5,2,35,6,8,16,1,1,0.6",
]
DET_ROWS = ["1,-1,10.5,20.5,11,21,0.9,-1,-1,-1", "2,-1,12,22,10,19,0.4,-1,-1,-1"]


def make_mot_seq(folder: Path, ext: str = ".png", n: int = N, seqinfo: bool = True,
                 gt: list[str] | None = GT_ROWS, det: list[str] | None = DET_ROWS,
                 images: bool = True) -> Path:
    """A tiny MOTChallenge sequence folder written with cv2.imwrite."""
    folder.mkdir(parents=True)
    if images:
        (folder / "img1").mkdir()
        for k in range(1, n + 1):
            assert cv2.imwrite(str(folder / "img1" / f"{k:06d}{ext}"), make_frame(k))
    if seqinfo:
        (folder / "seqinfo.ini").write_text(
            f"[Sequence]\nname={folder.name}\nimDir=img1\nframeRate=10\nseqLength={n}\n"
            f"imWidth={W}\nimHeight={H}\nimExt={ext}\n"
        )
    if gt is not None:
        (folder / "gt").mkdir()
        (folder / "gt" / "gt.txt").write_text("\n".join(gt) + "\n")
    if det is not None:
        (folder / "det").mkdir()
        (folder / "det" / "det.txt").write_text("\n".join(det) + ("\n" if det else ""))
    return folder


def write_video(path: Path, fourcc: str, n: int = 12, fps: float = 10.0) -> Path:
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*fourcc), fps, (W, H))
    assert writer.isOpened(), f"cannot write {fourcc} video"
    for k in range(1, n + 1):
        writer.write(np.full((H, W, 3), 20 * k, dtype=np.uint8))
    writer.release()
    return path


def frame_number(img: np.ndarray) -> int:
    """Recover k from a video frame of uniform grey 20*k (robust to compression)."""
    return round(float(img.mean()) / 20)


# ---------------------------------------------------------------- MOT folders


def test_mot_png_folder_frames_gt_det(tmp_path):
    make_mot_seq(tmp_path / "SEQ-01")
    (seq,) = load_mot(tmp_path)
    assert isinstance(seq, Sequence) and isinstance(seq, ImageSequence)
    assert seq.has_pixels
    assert (seq.info.name, seq.info.width, seq.info.height, seq.info.fps, seq.info.length) == (
        "SEQ-01", W, H, 10.0, N)
    for k in range(1, N + 1):  # PNG is lossless: exact frames, 1-based
        assert np.array_equal(seq.frame(k), make_frame(k))
    assert [k for k, _ in seq.frames()] == list(range(1, N + 1))
    assert all(np.array_equal(img, make_frame(k)) for k, img in seq.frames())
    with pytest.raises(IndexError):
        seq.frame(0)
    with pytest.raises(IndexError):
        seq.frame(N + 1)
    t = seq.gt.table
    assert len(t) == 5 and t.frames.tolist() == [1, 1, 2, 3, 5]
    assert np.array_equal(t.boxes[0], [10, 20, 10, 20])  # 1-based file -> 0-based memory
    assert t.classes.tolist() == [1, 1, 1, 8, 1]
    assert np.allclose(t.visibility, [1.0, 0.2, 0.9, 1.0, 0.6])
    assert t.conf.tolist() == [1, 1, 1, 0, 1]
    assert seq.gt.occluded.tolist() == [False, True, False, False, False]  # visibility < 0.5
    assert seq.gt.labels is None
    assert len(seq.public_detections) == 2
    assert np.allclose(seq.public_detections.boxes[0], [9.5, 19.5, 11, 21])


def test_mot_jpg_folder_uses_imext_and_prefetch_matches(tmp_path):
    make_mot_seq(tmp_path / "J", ext=".jpg")
    (seq,) = load_mot(tmp_path / "J")  # a sequence folder as root
    assert seq.paths[0].name == "000001.jpg"
    for k, img in seq.frames():
        assert img.shape == (H, W, 3) and img.dtype == np.uint8
        assert np.abs(img.astype(int) - make_frame(k)).mean() < 3  # lossy JPEG
    seq0 = load_mot(tmp_path / "J", prefetch=0)[0]
    assert all(np.array_equal(a[1], b[1]) for a, b in zip(seq.frames(), seq0.frames()))


def test_mot_selects_sorted_sequences(tmp_path):
    for name in ("B", "A", "C"):
        make_mot_seq(tmp_path / name)
    (tmp_path / "notes").mkdir()  # not a sequence folder: ignored
    assert [s.info.name for s in load_mot(tmp_path)] == ["A", "B", "C"]
    assert [s.info.name for s in load_mot(tmp_path, sequences=["C", "A"])] == ["C", "A"]
    with pytest.raises(FileNotFoundError, match="D"):
        load_mot(tmp_path, sequences=["D"])


def test_mot_missing_root_names_it(tmp_path):
    with pytest.raises(FileNotFoundError, match="no_such_dataset"):
        load_mot(tmp_path / "no_such_dataset")
    (tmp_path / "empty").mkdir()
    with pytest.raises(FileNotFoundError, match="no MOT sequence folders"):
        load_mot(tmp_path / "empty")


def test_mot_without_seqinfo_infers_length_and_size(tmp_path, caplog):
    make_mot_seq(tmp_path / "S", ext=".jpg", seqinfo=False, n=4)
    with caplog.at_level(logging.WARNING):
        (seq,) = load_mot(tmp_path)
    assert (seq.info.width, seq.info.height) == (W, H)
    # 4 images, but the gt reaches frame 5: the longer wins
    assert seq.info.length == 5
    assert "no seqinfo.ini" in caplog.text and "frame size 64x48 read from 000001.jpg" in caplog.text
    with pytest.raises(FrameError, match="000005.jpg"):
        seq.frame(5)


def test_mot_without_seqinfo_or_frames_needs_a_size(tmp_path):
    make_mot_seq(tmp_path / "S", seqinfo=False, images=False)
    with pytest.raises(SeqInfoError, match="image_size"):
        load_mot(tmp_path)
    (seq,) = load_mot(tmp_path, image_size=[320, 240])
    assert (seq.info.width, seq.info.height, seq.info.length) == (320, 240, 5)
    assert not seq.has_pixels and seq.frame(1) is None
    make_mot_seq(tmp_path / "E", seqinfo=False, images=False, gt=None, det=None)
    (tmp_path / "E" / "gt").mkdir()
    with pytest.raises(SeqInfoError, match="length"):
        load_mot(tmp_path, sequences=["E"], image_size=[320, 240])


def test_mot_malformed_seqinfo_names_key(tmp_path):
    make_mot_seq(tmp_path / "S")
    ini = tmp_path / "S" / "seqinfo.ini"
    ini.write_text(ini.read_text().replace("seqLength=5", "seqLength=five"))
    with pytest.raises(SeqInfoError, match="seqLength"):
        load_mot(tmp_path)
    ini.write_text("name=S\n")
    with pytest.raises(SeqInfoError, match="seqinfo.ini"):
        load_mot(tmp_path)


def test_mot_missing_frame_raises_frame_error_naming_file(tmp_path, caplog):
    make_mot_seq(tmp_path / "S")
    (tmp_path / "S" / "img1" / "000003.png").unlink()
    with caplog.at_level(logging.WARNING):
        (seq,) = load_mot(tmp_path)
    assert "1 of 5 frame files missing" in caplog.text
    assert seq.frame(2) is not None
    with pytest.raises(FrameError, match=r"missing frame file: .*000003\.png"):
        seq.frame(3)
    seen = []
    with pytest.raises(FrameError, match="000003.png"):
        for k, _ in seq.frames():
            seen.append(k)
    assert seen == [1, 2]


def test_prefetching_reader_random_access_and_pickle(tmp_path):
    make_mot_seq(tmp_path / "S")
    (seq,) = load_mot(tmp_path, prefetch=3)
    for k in (1, 2, 3, 5, 2, 4, 1, 1, 5):  # in order, then jumps that drop queued frames
        assert np.array_equal(seq.frame(k), make_frame(k))
    seq.frame(2)
    again = pickle.loads(pickle.dumps(seq))  # a thread pool cannot be pickled: rebuilt
    assert all(np.array_equal(img, make_frame(k)) for k, img in again.frames())
    assert again._pool is None  # closed after the last frame


def test_corrupt_image_raises_frame_error_naming_file(tmp_path):
    make_mot_seq(tmp_path / "S")
    bad = tmp_path / "S" / "img1" / "000002.png"
    bad.write_bytes(b"\x89PNG not really an image")
    (seq,) = load_mot(tmp_path)
    with pytest.raises(FrameError, match=r"cannot decode .*000002\.png"):
        seq.frame(2)
    with pytest.raises(FrameError, match="000002.png"):
        read_image(bad)


def test_frame_of_wrong_size_is_an_error(tmp_path):
    make_mot_seq(tmp_path / "S")
    cv2.imwrite(str(tmp_path / "S" / "img1" / "000004.png"), np.zeros((10, 10, 3), np.uint8))
    (seq,) = load_mot(tmp_path)
    with pytest.raises(FrameError, match=r"000004\.png: frame is 10x10 but sequence 'S' is 64x48"):
        seq.frame(4)


@pytest.mark.parametrize("which", ["gt", "det"])
def test_malformed_gt_or_det_line_propagates(tmp_path, which):
    bad = "4,1,abc,2,3,4,1,1,1" + (",-1" if which == "det" else "")  # the file's 9 or 10 fields
    rows = {"gt": GT_ROWS, "det": DET_ROWS}[which] + [bad]
    make_mot_seq(tmp_path / "S", **{which: rows})
    n = len(rows)
    with pytest.raises(MotFormatError, match=rf"{which}\.txt:{n}: not a number"):
        load_mot(tmp_path)
    make_mot_seq(tmp_path / "T", **{which: ["1,2,3"]})
    with pytest.raises(MotFormatError, match=rf"{which}\.txt:1: expected 6 to 10 fields, got 3"):
        load_mot(tmp_path, sequences=["T"])


def test_nan_and_nonpositive_boxes_are_skipped_with_line(tmp_path, caplog):
    rows = GT_ROWS + ["4,3,1,1,nan,10,1,1,1", "4,4,1,1,10,0,1,1,1", "4,5,1,1,-3,10,1,1,1"]
    make_mot_seq(tmp_path / "S", gt=rows)
    with caplog.at_level(logging.WARNING):
        (seq,) = load_mot(tmp_path)
    assert len(seq.gt.table) == len(GT_ROWS)
    for line in (6, 7, 8):
        assert f"gt.txt:{line}: skipped box with NaN or non-positive size" in caplog.text


def test_empty_det_file_gives_empty_detections(tmp_path, caplog):
    make_mot_seq(tmp_path / "S", det=[])
    with caplog.at_level(logging.WARNING):
        (seq,) = load_mot(tmp_path)
    assert seq.public_detections is not None and len(seq.public_detections) == 0
    assert "empty detection file" in caplog.text


def test_appearance_labels_file_is_attached(tmp_path):
    make_mot_seq(tmp_path / "S", gt=["1,1,1,1,10,20,1,-1,-1,-1", "2,1,2,1,10,20,1,-1,-1,-1"])
    labels = tmp_path / "S" / "gt" / "gt_caviar_appearance.txt"
    labels.write_text("1,1,appear\n2,1,occluded\n")
    (seq,) = load_mot(tmp_path)
    assert seq.gt.labels.tolist() == ["appear", "occluded"]
    assert seq.gt.occluded.tolist() == [False, True]
    labels.write_text("1,1,appear\n2,1,hidden\n")
    with pytest.raises(MotFormatError, match=r"gt_caviar_appearance\.txt:2: label 'hidden'"):
        load_mot(tmp_path)


def test_pets_trajectories_are_box_only(caplog):
    with caplog.at_level(logging.WARNING):
        (seq,) = load_mot(PETS.parent, sequences=["PETS09-S2L1"])
    assert "box-only sequence" in caplog.text
    assert not seq.has_pixels and seq.frame(1) is None
    assert (seq.info.width, seq.info.height, seq.info.fps, seq.info.length) == (768, 576, 7.0, 795)
    assert len(np.unique(seq.gt.table.ids)) == 19
    first = read_mot(PETS / "det" / "det.txt")
    assert np.array_equal(seq.public_detections.boxes, first.boxes)
    assert [k for k, img in seq.frames() if img is None] == list(range(1, 796))


def test_tud_campus_without_seqinfo():
    with pytest.raises(SeqInfoError, match="TUD-Campus"):
        load_mot(DATA / "trajectories")
    seqs = load_mot(DATA / "trajectories", image_size=[640, 480])
    assert [s.info.name for s in seqs] == ["CAVIAR-OneLeaveShop2cor", "PETS09-S2L1", "TUD-Campus"]
    assert seqs[2].info.length == 71  # the last gt/det frame


# ---------------------------------------------------------------- CAVIAR


def test_caviar_xml_gives_exactly_gt_txt():
    (seq,) = load_caviar(CAVIAR)
    ref = read_mot(CAVIAR / "gt" / "gt.txt", gt=True)
    t = seq.gt.table
    assert len(t) == len(ref) == 1401
    for col in ("frames", "ids", "boxes", "conf", "classes"):
        assert np.array_equal(getattr(t, col), getattr(ref, col)), col
    assert np.array_equal(t.visibility, ref.visibility, equal_nan=True)


def test_caviar_labels_match_appearance_file():
    (seq,) = load_caviar(CAVIAR)
    expected = {}
    for line in (CAVIAR / "gt" / "gt_caviar_appearance.txt").read_text().split():
        f, i, label = line.split(",")
        expected[(int(f), int(i))] = label
    t = seq.gt.table
    got = {(int(f), int(i)): str(lab) for f, i, lab in zip(t.frames, t.ids, seq.gt.labels)}
    assert got == expected
    assert int(seq.gt.occluded.sum()) == 22
    assert np.array_equal(seq.gt.occluded, seq.gt.labels == "occluded")
    # the MOT reader of the same folder attaches the same labels
    (mot,) = load_mot(CAVIAR)
    assert np.array_equal(mot.gt.labels, seq.gt.labels)
    assert np.array_equal(mot.gt.occluded, seq.gt.occluded)


def test_caviar_frames(caplog):
    with caplog.at_level("INFO", logger="occbench.datasets.video"):
        (seq,) = load_caviar(CAVIAR)
    # issue 39 item 10: '295 frames (the container estimates 3)' read as if 3 were frames
    assert re.search(r"295 frames, counted by decoding \(its container reports \d+, an "
                     r"estimate in this format\)", caplog.text), caplog.text
    assert (seq.info.width, seq.info.height, seq.info.fps, seq.info.length) == (384, 288, 25.0, 295)
    assert isinstance(seq, VideoSequence) and seq.exact  # the shipped MPEG, counted by decoding
    assert seq.has_pixels
    img = seq.frame(295)
    assert img.shape == (288, 384, 3) and img.dtype == np.uint8 and img.std() > 10
    # the JPEG frames in the CAVIAR distribution are this decode at JPEG quality 95: their
    # mean grey level is 139.966 (frame 295) and 137.030 (frame 1)
    assert abs(img.mean() - 139.966) < 0.2
    assert abs(seq.frame(1).mean() - 137.030) < 0.2  # a jump back decodes from the start
    last = None
    for k, frame in seq.frames():
        last = (k, frame)
    assert last[0] == 295 and np.array_equal(last[1], img)


CVML = """<?xml version="1.0" encoding="UTF-8"?><dataset name="tiny">
<frame number="0"><objectlist>
  <object id="1"><orientation>90</orientation><box h="21" w="11" xc="20" yc="30"/>
    <appearance>appear</appearance></object>
  <object id="0"><box h="10" w="4" xc="50" yc="10"/><appearance>visible</appearance></object>
</objectlist>
<grouplist><group id="0"><box h="59" w="36" xc="159" yc="61"/><members>0,1</members>
  <appearance>visible</appearance></group></grouplist></frame>
<frame number="1"><objectlist/></frame>
<frame number="2"><objectlist>
  <object id="1"><box h="21" w="11" xc="22" yc="30"/><appearance>occluded</appearance></object>
</objectlist></frame>
</dataset>
"""


def test_cvml_conversion_on_a_tiny_file(tmp_path):
    path = tmp_path / "tinygt.xml"
    path.write_text(CVML)
    gt = read_cvml(path)
    t = gt.table
    assert t.frames.tolist() == [1, 1, 3] and t.ids.tolist() == [1, 2, 2]  # groups ignored
    # 0-based memory box = (xc - w/2 - 1, yc - h/2 - 1, w, h)
    assert np.array_equal(t.boxes, [[47, 4, 4, 10], [13.5, 18.5, 11, 21], [15.5, 18.5, 11, 21]])
    assert gt.labels.tolist() == ["visible", "appear", "occluded"]
    assert gt.occluded.tolist() == [False, False, True]


@pytest.mark.parametrize("bad, message", [
    (CVML.replace("</dataset>", ""), r"malformed XML at line \d+"),
    (CVML.replace('xc="22"', 'xc="abc"'), "frame 2, object 1: needs"),
    (CVML.replace("<appearance>occluded", "<appearance>hidden"), "appearance 'hidden'"),
    (CVML.replace('<object id="0">', '<object id="1">'), "frame 0, object 1: object listed twice"),
])
def test_cvml_bad_input(tmp_path, bad, message):
    path = tmp_path / "badgt.xml"
    path.write_text(bad)
    with pytest.raises(CaviarFormatError, match=message) as err:
        read_cvml(path)
    assert "badgt.xml" in str(err.value)


def test_caviar_from_video_and_xml(tmp_path):
    write_video(tmp_path / "Tiny.avi", "MJPG", n=4)
    (tmp_path / "tinygt.xml").write_text(CVML)
    (seq,) = load_caviar(tmp_path)
    assert isinstance(seq, VideoSequence)
    assert (seq.info.name, seq.info.length, seq.info.width) == (tmp_path.name, 4, W)
    assert frame_number(seq.frame(3)) == 3
    assert seq.gt.labels.tolist() == ["visible", "appear", "occluded"]


def test_caviar_from_numbered_jpegs(tmp_path):
    for n in range(3):  # the original CAVIAR JPEG naming, 0-based
        cv2.imwrite(str(tmp_path / f"Tiny{n:04d}.jpg"), make_frame(n + 1))
    (tmp_path / "tinygt.xml").write_text(CVML)
    (seq,) = load_caviar(tmp_path, name="tiny")
    assert (seq.info.name, seq.info.length, seq.info.fps) == ("tiny", 3, 25.0)
    assert np.abs(seq.frame(1).astype(int) - make_frame(1)).mean() < 3


def test_caviar_missing_paths(tmp_path):
    with pytest.raises(FileNotFoundError, match="nowhere"):
        load_caviar(tmp_path / "nowhere")
    with pytest.raises(FileNotFoundError, match="no CAVIAR XML"):
        load_caviar(tmp_path)
    with pytest.raises(FileNotFoundError, match="missing.xml"):
        load_caviar(tmp_path, xml=tmp_path / "missing.xml")


# ---------------------------------------------------------------- video


@pytest.mark.parametrize("name, fourcc", [("clip.mp4", "mp4v"), ("clip.avi", "MJPG")])
def test_video_sequential_and_random_access(tmp_path, monkeypatch, name, fourcc):
    path = write_video(tmp_path / name, fourcc, n=12)
    (seq,) = load_video(path)
    assert (seq.info.name, seq.info.width, seq.info.height, seq.info.length) == ("clip", W, H, 12)
    assert seq.info.fps == pytest.approx(10.0)
    assert seq.gt is None and seq.has_pixels
    assert [frame_number(img) for _, img in seq.frames()] == list(range(1, 13))
    for k in (5, 5, 2, 12, 1, 7, 9, 3):  # repeats, backward seeks, short forward jumps
        assert frame_number(seq.frame(k)) == k
    with pytest.raises(IndexError):
        seq.frame(13)
    monkeypatch.setattr(video_module, "GRAB_AHEAD", 0)  # every jump seeks
    for k in (4, 11, 2, 8):
        assert frame_number(seq.frame(k)) == k
    again = pickle.loads(pickle.dumps(seq))  # e.g. sent to a joblib worker
    assert frame_number(again.frame(6)) == 6


def bar_frame(k: int) -> np.ndarray:
    """96x64 frame identifying k in 0..59 by two white bars (survives MPEG compression)."""
    img = np.zeros((64, 96, 3), dtype=np.uint8)
    img[:24, (k % 12) * 8:(k % 12) * 8 + 8] = 255
    img[40:, (k // 12) * 16:(k // 12) * 16 + 16] = 255
    return img


def bar_number(img: np.ndarray) -> int:
    a = img[:24].mean(axis=(0, 2)).reshape(12, 8).mean(1).argmax()
    b = img[40:].mean(axis=(0, 2)).reshape(6, 16).mean(1).argmax()
    return int(b * 12 + a)


def test_mpeg_program_stream_is_counted_and_never_seeked(tmp_path):
    # FFmpeg estimates an MPEG-PS frame count from its duration and seeks to wrong frames
    # near the end; the reader counts by decoding and decodes forward instead
    path = tmp_path / "clip.mpg"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MPEG"), 25.0, (96, 64))
    if not writer.isOpened():
        pytest.skip("this OpenCV build cannot write MPEG-1 program streams")
    for k in range(1, 60):
        writer.write(bar_frame(k))
    writer.release()
    (seq,) = load_video(path)
    assert seq.exact and seq.info.length == 59
    assert [bar_number(img) for _, img in seq.frames()] == list(range(1, 60))
    for k in (59, 3, 58, 57, 40, 1, 59):
        assert bar_number(seq.frame(k)) == k


def test_video_with_gt_name_and_fps(tmp_path):
    path = write_video(tmp_path / "clip.avi", "MJPG", n=5)
    gt = tmp_path / "gt.txt"
    gt.write_text("\n".join(GT_ROWS) + "\n")
    (seq,) = load_video(path, gt=gt, name="walk", fps=30)
    assert (seq.info.name, seq.info.fps) == ("walk", 30.0)
    assert len(seq.gt.table) == 5 and seq.gt.occluded.tolist()[1]


def test_video_bad_input(tmp_path):
    with pytest.raises(FileNotFoundError, match="nothing.mp4"):
        load_video(tmp_path / "nothing.mp4")
    bad = tmp_path / "broken.mp4"
    bad.write_bytes(os.urandom(2048))
    with pytest.raises(FrameError, match="broken.mp4"):
        load_video(bad)
    path = write_video(tmp_path / "clip.avi", "MJPG", n=3)
    gt = tmp_path / "gt.txt"
    gt.write_text("1,1,1,1,10,10,1,1,1\n1,2,x,1,10,10,1,1,1\n")
    with pytest.raises(MotFormatError, match=r"gt\.txt:2"):
        load_video(path, gt=gt)


# ---------------------------------------------------------------- configs


def _compose(*overrides: str):
    with initialize_config_dir(config_dir=str(CONF), version_base=None):
        return compose("config", overrides=list(overrides))


def test_mot_and_video_configs_compose_and_instantiate(tmp_path):
    make_mot_seq(tmp_path / "S")
    cfg = _compose("dataset=mot")
    with pytest.raises(MissingMandatoryValue):
        instantiate(cfg.dataset)
    (seq,) = instantiate(_compose("dataset=mot", f"dataset.root={tmp_path}").dataset)
    assert seq.info.name == "S"
    path = write_video(tmp_path / "clip.avi", "MJPG", n=3)
    cfg = _compose("dataset=video")
    with pytest.raises(MissingMandatoryValue):
        instantiate(cfg.dataset)
    (seq,) = instantiate(_compose("dataset=video", f"dataset.path={path}").dataset)
    assert seq.info.length == 3


def test_caviar_config_instantiates(monkeypatch, tmp_path):
    monkeypatch.delenv(DATA_ENV, raising=False)
    monkeypatch.chdir(tmp_path)  # the data root does not depend on the current directory
    cfg = _compose("dataset=caviar")
    assert Path(cfg.dataset.root) == SHIPPED_DATA / "CAVIAR-OneLeaveShop1cor"
    (seq,) = instantiate(cfg.dataset)
    assert seq.info.name == "CAVIAR-OneLeaveShop1cor" and len(seq.gt.table) == 1401
    replay = _compose("dataset=replay")
    assert Path(replay.dataset.gt_path) == SHIPPED_DATA / "trajectories" / "PETS09-S2L1"


def test_one_variable_moves_the_data_root(monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv(DATA_ENV, "elsewhere")  # relative: against the current directory
    assert data_root() == tmp_path / "elsewhere"
    cfg = _compose("dataset=caviar")
    assert Path(cfg.dataset.root) == tmp_path / "elsewhere" / "CAVIAR-OneLeaveShop1cor"
    with pytest.raises(Exception, match="CAVIAR sequence folder not found: .*elsewhere"):
        instantiate(cfg.dataset)
    monkeypatch.setenv(DATA_ENV, "")  # empty = unset
    assert data_root() == SHIPPED_DATA
