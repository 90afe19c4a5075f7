"""MOT text files read strictly, class by class (issue 24, "Inputs misread"): every field's
range, integer-ness and finiteness, the column count of every row, huge values, encodings,
gt rows past seqLength and gt with nothing to score. Each message names file, line and what
was expected; hand-made files of two or three rows."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.io.mot import MAX_INT, MotFormatError, read_mot, read_mot_text

GT9 = "1,1,11,21,10,20,1,1,1\n"  # frame,id,left,top,w,h,conf,class,visibility (MOT16+)
GT10 = "1,1,11,21,10,20,1,-1,-1,-1\n"  # MOT15: conf then world x,y,z
RES = "1,1,11,21,10,20,0.9,-1,-1,-1\n"


def write(tmp_path, text: str | bytes, name: str = "f.txt"):
    p = tmp_path / name
    if isinstance(text, bytes):
        p.write_bytes(text)
    else:
        p.write_text(text)
    return p


# huge frames and ids: 1e20 is an integer-valued float that would wrap to -2**63 as int64
@pytest.mark.parametrize("row, kind, message", [
    ("1e20,1,1,1,5,5,1,1,1", "gt", r"frame must be a positive integer up to 2147483647, got 1000"),
    (f"{MAX_INT + 1},1,1,1,5,5,1,1,1", "gt", "frame must be a positive integer up to"),
    ("2,1e20,1,1,5,5,1,1,1", "gt", r"id must be an integer up to 2147483647 in size, got 1000"),
    ("2,-1e20,1,1,5,5,1,-1,-1,-1", "det", "id must be an integer up to"),
    ("2,1e20,1,1,5,5,1,-1,-1,-1", "result", "id must be an integer up to"),
    ("2,1,1,1,5,5,1,1e20,1", "gt", r"gt class \(column 8\) must be a positive integer"),
])
def test_huge_frames_ids_and_classes_are_errors_not_wrapped_ints(tmp_path, row, kind, message):
    first = GT9 if kind == "gt" else RES
    p = write(tmp_path, first + row + "\n")
    with pytest.raises(MotFormatError, match=rf"f\.txt:2: {message}"):
        read_mot(p, kind=kind)


def test_the_largest_accepted_frame_and_id_read_back_exactly(tmp_path):
    p = write(tmp_path, f"{MAX_INT},{MAX_INT},1,1,5,5,1,1,1\n")
    t = read_mot(p, gt=True)
    assert t.frames.tolist() == [MAX_INT] and t.ids.tolist() == [MAX_INT]


# the column count of every row: one 10-column row in a 9-column gt is not MOT15
@pytest.mark.parametrize("rows, line, message", [
    (GT9 + "2,1,12,21,10,20,1,1,1,-1\n", 2, "10 fields but line 1 has 9"),
    (GT10 + "2,1,12,21,10,20,1,1,1\n", 2, "9 fields but line 1 has 10"),
    (GT10 + "# a comment\n\n3,1,12,21,10,20,1\n", 4, "7 fields but line 1 has 10"),
    ("1,1,1,1,5,5,1,1,1,1,1\n", 1, "expected 6 to 10 fields, got 11"),
    ("1,1,1,1,5\n", 1, "expected 6 to 10 fields, got 5"),
    ("1,1,,1,5,5,1,1,1\n", 1, "field 3 is empty"),  # not silently shifted left
    ("1,1,1,1,5,5,1,1,1,,\n", 1, "field 10 is empty"),
])
def test_every_row_has_the_columns_of_the_first(tmp_path, rows, line, message):
    p = write(tmp_path, rows)
    with pytest.raises(MotFormatError, match=rf"f\.txt:{line}: {message}"):
        read_mot(p, gt=True)


def test_the_mot16_columns_are_kept_on_every_row(tmp_path):
    t = read_mot(write(tmp_path, GT9 + "2,1,12,21,10,20,1,1,0.25\n"), gt=True)
    assert t.visibility.tolist() == [1.0, 0.25] and t.classes.tolist() == [1, 1]
    t = read_mot(write(tmp_path, GT10 + "2,1,12,21,10,20,1,-1,-1,-1\n"), gt=True)
    assert np.isnan(t.visibility).all() and t.classes.tolist() == [-1, -1]


def test_separators_trailing_comma_and_whitespace(tmp_path):
    a = read_mot(write(tmp_path, "1, 1, 11, 21, 10, 20, 1, 1, 1,\n", "a.txt"), gt=True)
    b = read_mot(write(tmp_path, "1 1 11 21 10 20 1 1 1\n", "b.txt"), gt=True)
    assert np.array_equal(a.boxes, b.boxes) and a.boxes.tolist() == [[10, 20, 10, 20]]


# gt field ranges
@pytest.mark.parametrize("row, message", [
    ("2,1,1,1,5,5,0.5,1,1", r"gt conf must be 0 \(ignore\) or 1 \(score\), got 0\.5"),
    ("2,1,1,1,5,5,-1,1,1", "gt conf must be 0"),
    ("2,1,1,1,5,5,1,0,1", r"gt class \(column 8\) must be a positive integer, got 0"),
    ("2,1,1,1,5,5,1,1.5,1", r"gt class \(column 8\) must be a positive integer, got 1\.5"),
    ("2,1,1,1,5,5,1,1,1.5", r"gt visibility \(column 9\) must lie in \[0, 1\]"),
    ("2,1,1,1,5,5,1,1,-0.5", r"gt visibility \(column 9\) must lie in \[0, 1\]"),
])
def test_gt_conf_class_and_visibility_ranges(tmp_path, row, message):
    with pytest.raises(MotFormatError, match=rf"f\.txt:2: {message}"):
        read_mot(write(tmp_path, GT9 + row + "\n"), gt=True)


def test_unknown_visibility_minus_one_is_nan(tmp_path):
    t = read_mot(write(tmp_path, GT9 + "2,1,1,1,5,5,1,1,-1\n"), gt=True)
    assert np.isnan(t.visibility[1])


def test_gt_with_nothing_to_score_is_an_error(tmp_path):
    p = write(tmp_path, "1,1,1,1,5,5,0,1,1\n2,1,1,1,5,5,0,1,1\n")
    with pytest.raises(MotFormatError, match=r"f\.txt: nothing to score: none of its 2 rows"):
        read_mot(p, gt=True)
    p = write(tmp_path, "1,1,1,1,5,5,1,7,1\n2,1,1,1,5,5,1,8,1\n")  # static person, distractor
    with pytest.raises(MotFormatError, match="nothing to score"):
        read_mot(p, gt=True)
    # one scored row is enough; a result file is never checked for it
    assert len(read_mot(write(tmp_path, "1,1,1,1,5,5,0,1,1\n2,1,1,1,5,5,1,1,1\n"), gt=True)) == 2
    assert len(read_mot(write(tmp_path, "1,1,1,1,5,5,0,-1,-1,-1\n"), kind="result")) == 1


def test_rows_past_the_last_frame_are_errors_in_gt_and_results(tmp_path):
    for kind, first in (("gt", GT9), ("result", RES)):
        p = write(tmp_path, first + first.replace("1,1,", "11,1,", 1))
        with pytest.raises(MotFormatError, match=r"f\.txt:2: frame 11 is beyond the sequence's "
                                                 r"last frame 10 \(seqLength\)"):
            read_mot(p, kind=kind, last_frame=10)
        assert len(read_mot(p, kind=kind, last_frame=11)) == 2


# encodings
def test_a_utf8_byte_order_mark_is_accepted(tmp_path):
    plain = read_mot(write(tmp_path, GT9, "plain.txt"), gt=True)
    bom = read_mot(write(tmp_path, "\ufeff" + GT9, "bom.txt"), gt=True)
    assert np.array_equal(plain.boxes, bom.boxes) and bom.frames.tolist() == [1]
    assert len(read_mot_text("\ufeff" + RES, "r.txt", kind="result")) == 1


def test_bytes_that_are_not_utf8_name_the_line(tmp_path):
    p = write(tmp_path, GT9.encode() + b"2,1,1,1,5,5,1,1,1\xff\n")
    with pytest.raises(MotFormatError, match=r"f\.txt:2: not UTF-8 text"):
        read_mot(p, gt=True)


@pytest.mark.parametrize("field", ["1_0", "ten", "0x1A", "1,5"])
def test_a_field_that_is_not_a_plain_number_names_the_line(tmp_path, field):
    p = write(tmp_path, GT9 + f"2,1,{field},1,5,5,1,1,1\n")
    with pytest.raises(MotFormatError, match=r"f\.txt:2: (not a number|10 fields)"):
        read_mot(p, gt=True)


@pytest.mark.parametrize("box", ["1e308,5,40,100", "5,5,1e308,100", "5,-2e9,40,100",
                                 "5,5,40,1e10"])
@pytest.mark.parametrize("kind", ["result", "gt", "det"])
def test_absurd_box_coordinates_are_errors_naming_file_and_line(tmp_path, box, kind):
    """A box beyond +-1e9 pixels is refused (issue 39: x or width 1e308 overflowed the
    overlap code and broke the matching of the whole sequence, MOTA -0.93, exit 0)."""
    path = tmp_path / "f.txt"
    ident = "-1" if kind == "det" else "1"
    path.write_text(f"1,1,5,5,40,100,1,1,1\n2,{ident},{box},1,1,1\n")
    with pytest.raises(MotFormatError, match=r"f\.txt:2: box \w+ must lie within") as err:
        read_mot(path, kind=kind)
    assert len(str(err.value)) < 200  # 1e308 shown as 1e+308, not as its 309 digits


def test_boxes_up_to_1e9_are_read(tmp_path):
    path = tmp_path / "f.txt"
    path.write_text("1,1,-1e9,5,1e9,100,1,-1,-1,-1\n")
    assert read_mot(path, kind="result").boxes[0, 2] == 1e9
