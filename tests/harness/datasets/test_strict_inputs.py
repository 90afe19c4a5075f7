"""Dataset folders read strictly (issue 24, "Inputs misread"): seqinfo.ini keys, gt rows past
seqLength, appearance labels, CVML numbers; hand-made folders of a few rows, no pixels."""

from __future__ import annotations

import re

import cv2
import numpy as np
import pytest

from occbench.datasets.caviar import CaviarFormatError, load_caviar, read_cvml
from occbench.datasets.images import FrameError
from occbench.datasets.mot import SeqInfoError, load_mot
from occbench.datasets.video import load_video
from occbench.io.mot import MotFormatError

N = 10
GT = "".join(f"{k},1,{10 + k},20,10,30,1,1,1\n" for k in range(1, N + 1))
INI = ("[Sequence]\nname=S\nimDir=img1\nframeRate=10\nseqLength={n}\nimWidth=64\n"
       "imHeight=48\nimExt=.jpg\n")


def mot_seq(tmp_path, gt: str = GT, ini: str | None = None, n: int = N):
    seq = tmp_path / "S"
    (seq / "gt").mkdir(parents=True)
    (seq / "gt" / "gt.txt").write_text(gt)
    (seq / "seqinfo.ini").write_text(INI.format(n=n) if ini is None else ini)
    return seq


@pytest.mark.parametrize("key, value, message", [
    ("seqLength", "10.5", "key 'seqLength' must be a positive integer"),
    ("seqLength", "1e20", "key 'seqLength' must be a positive integer"),
    ("seqLength", "99999999999", "key 'seqLength' must be a positive integer up to 2147483647"),
    ("seqLength", "0", "key 'seqLength' must be a positive integer"),
    ("imWidth", "64.0", "key 'imWidth' must be a positive integer"),
    ("imHeight", "-48", "key 'imHeight' must be a positive integer"),
    ("frameRate", "nan", "key 'frameRate' must be a positive finite number"),
    ("frameRate", "inf", "key 'frameRate' must be a positive finite number"),
    ("frameRate", "fast", "key 'frameRate' is not a number"),
])
def test_seqinfo_numbers_are_strict_and_name_the_key(tmp_path, key, value, message):
    ini = INI.format(n=N)
    start = ini.index(f"{key}=") + len(key) + 1
    ini = ini[:start] + value + ini[ini.index("\n", start):]
    seq = mot_seq(tmp_path, ini=ini)
    with pytest.raises(SeqInfoError, match=rf"{seq / 'seqinfo.ini'}: {message}"):
        load_mot(tmp_path)


def test_seqinfo_with_a_byte_order_mark_or_a_repeated_key(tmp_path):
    seq = mot_seq(tmp_path, ini="\ufeff" + INI.format(n=N))
    (s,) = load_mot(tmp_path)
    assert (s.info.name, s.info.length) == ("S", N)
    (seq / "seqinfo.ini").write_text(INI.format(n=N) + "seqLength=12\n")
    with pytest.raises(SeqInfoError, match=r"seqinfo\.ini: not an ini file: .*'seqLength'"):
        load_mot(tmp_path)


def test_gt_rows_past_seqlength_are_refused_naming_the_line(tmp_path):
    """TrackEval raises for gt frames beyond seqLength; so do we, instead of scoring rows the
    sequence does not have (FN for frames never tracked) or dropping them unseen."""
    mot_seq(tmp_path, gt=GT + "11,1,21,20,10,30,1,1,1\n")
    with pytest.raises(MotFormatError, match=rf"gt\.txt:{N + 1}: frame 11 is beyond the "
                                             rf"sequence's last frame {N} \(seqLength\)"):
        load_mot(tmp_path)


def test_without_seqlength_the_gt_sets_the_length(tmp_path):
    mot_seq(tmp_path, ini=INI.format(n=N).replace(f"seqLength={N}\n", ""))
    (s,) = load_mot(tmp_path)
    assert s.info.length == N and len(s.gt.table) == N


def test_appearance_labels_are_strict(tmp_path):
    seq = mot_seq(tmp_path)
    labels = seq / "gt" / "gt_caviar_appearance.txt"
    for text, message in (("1,1,visible\n1.0,2,visible\n", "2: frame and id must be positive"),
                          ("1,1,visible\n1,1,occluded\n", "2: frame 1, id 1 labelled twice"),
                          ("1,1e20,visible\n", "1: frame and id must be positive")):
        labels.write_text(text)
        with pytest.raises(MotFormatError, match=rf"gt_caviar_appearance\.txt:{message}"):
            load_mot(tmp_path)


CVML = """<?xml version="1.0"?>
<dataset name="tiny">
 <frame number="{n0}"><objectlist>
  <object id="{oid}"><box xc="20" yc="20" w="10" h="30"/><appearance>visible</appearance></object>
 </objectlist></frame>
 <frame number="1"><objectlist>
  <object id="0"><box xc="22" yc="20" w="10" h="30"/><appearance>visible</appearance></object>
 </objectlist></frame>
</dataset>
"""


@pytest.mark.parametrize("n0, oid, message", [
    ("1e20", "0", "<frame> number must be an integer in 0..2147483646, got '1e20'"),
    ("99999999999", "0", "<frame> number must be an integer in 0..2147483646"),
    ("-1", "0", "<frame> number must be an integer in 0..2147483646, got '-1'"),
    ("0", "2.5", "frame 0, object 2.5: needs an integer id in 0..2147483646"),
    ("0", "-3", "frame 0, object -3: needs an integer id in 0..2147483646"),
    ("1", "1", "frame 1 is listed twice"),
])
def test_cvml_numbers_are_strict(tmp_path, n0, oid, message):
    p = tmp_path / "tinygt.xml"
    p.write_text(CVML.format(n0=n0, oid=oid))
    with pytest.raises(CaviarFormatError, match=rf"tinygt\.xml: {message}"):
        read_cvml(p)


def test_cvml_frames_past_seqlength_are_refused(tmp_path):
    (tmp_path / "tinygt.xml").write_text(CVML.format(n0=0, oid=0))
    (tmp_path / "seqinfo.ini").write_text(INI.format(n=2))
    (s,) = load_caviar(tmp_path)  # CVML frames 0 and 1: sequence frames 1 and 2
    assert s.info.length == 2 and s.gt.table.frames.tolist() == [1, 2] and not s.has_pixels
    (tmp_path / "seqinfo.ini").write_text(INI.format(n=1))
    with pytest.raises(CaviarFormatError, match=r"tinygt\.xml: frame 1 \(sequence frame 2\) is "
                                                r"beyond the sequence's last frame 1"):
        load_caviar(tmp_path)


# ---------------------------------------------------------------- videos


def write_mpeg(path, n: int, size: tuple[int, int] = (96, 64), start: int = 0):
    """An MPEG-1 program stream of n frames whose grey level identifies the frame."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"PIM1"), 25.0, size)
    if not writer.isOpened():
        pytest.skip("this OpenCV build cannot write MPEG-1")
    for k in range(start, start + n):
        writer.write(np.full((size[1], size[0], 3), 8 * k % 256, dtype=np.uint8))
    writer.release()
    return path


def gt_file(path, n: int):
    path.write_text("".join(f"{k},1,10,10,20,30,1,1,1\n" for k in range(1, n + 1)))
    return path


def test_a_video_cut_short_fails_past_its_end_like_a_missing_image(tmp_path):
    full = write_mpeg(tmp_path / "full.mpg", 30)
    data = full.read_bytes()
    cut = tmp_path / "cut.mpg"
    cut.write_bytes(data[: len(data) // 3])  # the first third, as a broken download leaves it
    (seq,) = load_video(cut, gt=gt_file(tmp_path / "gt.txt", 30))
    assert seq.info.length == 30 and 0 < seq.decodable < 30  # the gt's length, not the video's
    seen = []
    with pytest.raises(FrameError, match=rf"cut\.mpg: no frame {seq.decodable + 1}: the video "
                                         rf"holds {seq.decodable} decodable frames but the "
                                         r"sequence has 30; is it cut short\?"):
        for k, _ in seq.frames():
            seen.append(k)
    assert seen == list(range(1, seq.decodable + 1))
    (whole,) = load_video(full, gt=tmp_path / "gt.txt")
    assert whole.info.length == whole.decodable == 30


def test_a_video_shorter_than_seqlength_fails_past_its_end(tmp_path):
    write_mpeg(tmp_path / "clip.mpg", 12)
    (tmp_path / "tinygt.xml").write_text(CVML.format(n0=0, oid=0))
    (tmp_path / "seqinfo.ini").write_text(INI.format(n=20))
    (seq,) = load_caviar(tmp_path)
    assert (seq.info.length, seq.decodable) == (20, 12)
    seq.frame(12)
    with pytest.raises(FrameError, match="no frame 13: the video holds 12 decodable frames"):
        seq.frame(13)
    (tmp_path / "seqinfo.ini").write_text(INI.format(n=8))  # longer video: its first 8 frames
    (seq,) = load_caviar(tmp_path)
    assert (seq.info.length, seq.decodable) == (8, 12)


def test_a_video_whose_frame_size_changes_is_refused(tmp_path):
    a = write_mpeg(tmp_path / "a.mpg", 10)
    b = write_mpeg(tmp_path / "b.mpg", 10, size=(160, 96), start=10)
    joined = tmp_path / "joined.mpg"  # MPEG-1 program streams play one after the other
    joined.write_bytes(a.read_bytes() + b.read_bytes())
    (seq,) = load_video(joined)
    assert (seq.info.width, seq.info.height) == (96, 64)
    with pytest.raises(FrameError, match=r"joined\.mpg: the frame size changes mid-stream: "
                                         r"96x64, then 160x96 from decoded frame \d+"):
        seq.frame(1)
    (one,) = load_video(a)
    assert one.refused is None and one.frame(10).shape == (64, 96, 3)


def test_replay_reads_seqinfo_and_gt_as_strictly(tmp_path):
    from occbench.datasets.synthetic import load_replay

    seq = mot_seq(tmp_path, gt=GT + "11,1,21,20,10,30,1,1,1\n")
    with pytest.raises(MotFormatError, match=rf"gt\.txt:{N + 1}: frame 11 is beyond"):
        load_replay(seq)
    ini = seq / "seqinfo.ini"
    ini.write_text(INI.format(n=N).replace(f"seqLength={N}", "seqLength=10.5"))
    with pytest.raises(SeqInfoError, match="key 'seqLength' must be a positive integer"):
        load_replay(seq)
    ini.write_text(INI.format(n=12))
    (s,) = load_replay(seq, noise=0.0)
    assert (s.info.length, s.info.width, s.info.height, s.info.fps) == (12, 64, 48, 10.0)


def test_a_video_with_rotation_metadata_is_not_a_size_change(tmp_path):
    """A portrait phone clip: OpenCV turns it (reports 64x96), its stream is 96x64 throughout."""
    import subprocess

    import imageio_ffmpeg

    plain = tmp_path / "plain.mp4"
    writer = cv2.VideoWriter(str(plain), cv2.VideoWriter_fourcc(*"mp4v"), 25.0, (96, 64))
    for k in range(6):
        writer.write(np.full((64, 96, 3), 30 * k, dtype=np.uint8))
    writer.release()
    turned = tmp_path / "turned.mp4"
    subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-display_rotation", "90",
                    "-i", str(plain), "-c", "copy", str(turned)], check=True, timeout=60)
    (seq,) = load_video(turned)
    assert seq.refused is None and seq.frame(6).shape[:2] == (seq.info.height, seq.info.width)


def test_a_truncated_mp4_names_the_frame_it_cannot_decode(tmp_path):
    """issue 39: decoding forward to a later frame through a cut mp4, the message named
    frame 1 (close() reset the position before the message was built)."""
    import av

    path = tmp_path / "whole.mp4"
    with av.open(str(path), "w", options={"movflags": "faststart"}) as box:  # index first
        stream = box.add_stream("mpeg4", rate=25)
        stream.width, stream.height, stream.pix_fmt = 160, 120, "yuv420p"
        rng = np.random.default_rng(0)
        for _ in range(60):
            image = rng.integers(0, 255, (120, 160, 3), dtype=np.uint8)
            box.mux(stream.encode(av.VideoFrame.from_ndarray(image, format="bgr24")))
        box.mux(stream.encode())
    cut = tmp_path / "cut.mp4"
    cut.write_bytes(path.read_bytes()[: len(path.read_bytes()) * 3 // 4])
    (seq,) = load_video(cut)
    assert seq.decodable == 60  # the container's count: the cut is found on decoding
    seq.frame(30)
    with pytest.raises(FrameError) as err:
        seq.frame(60)  # decoded forward from 31
    failed = int(re.search(r"cannot decode frame (\d+) of 60", str(err.value)).group(1))
    assert 31 <= failed <= 60
