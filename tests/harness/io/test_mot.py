"""read_mot's vectorised reading (comma-separated rows of one width, all valid) gives the
table the line-by-line reader gives, with either C reader of ``occbench.io.columns``; a
comment line sends a file down the line-by-line path."""

from __future__ import annotations

import numpy as np
import pytest

from occbench.io import columns
from occbench.io.columns import read_columns
from occbench.io.mot import MotFormatError, read_mot


def _rows(rng: np.random.Generator, n: int, fields: int, gt: bool = False) -> str:
    """n rows of ``fields`` comma-separated numbers with many decimals, shuffled; in gt the
    conf is a 0/1 flag (anything else is an error there)."""
    frame = rng.integers(1, 50, n)
    ident = rng.permutation(n) + 1
    box = rng.uniform(-5, 900, (n, 4))
    box[:, 2:] = np.abs(box[:, 2:]) + 0.001
    conf = rng.integers(0, 2, n) if gt else rng.uniform(0, 1, n)
    rest = [conf, rng.integers(1, 3, n), rng.uniform(0, 1, n), np.full(n, -1)]
    cols = [frame, ident, *box.T, *rest][:fields]
    return "".join(",".join(repr(float(c[i])) if c.dtype.kind == "f" else str(c[i])
                            for c in cols) + "\n" for i in range(n))


@pytest.mark.parametrize("reader", ["numpy", "pandas"])
@pytest.mark.parametrize("fields, kind", [(9, "gt"), (10, "result"), (6, "result"),
                                          (7, "any"), (10, "gt")])
def test_vectorised_reading_equals_line_by_line(tmp_path, monkeypatch, fields, kind, reader):
    if reader == "pandas":  # every text to pandas' C parser (when it rounds exactly)
        monkeypatch.setattr(columns, "C_READER_FROM", 0)
    text = _rows(np.random.default_rng(fields), 500, fields, gt=kind == "gt")
    fast, slow = tmp_path / "fast.txt", tmp_path / "slow.txt"
    fast.write_text(text)
    slow.write_text("# forces the line-by-line reader\n" + text)
    a, b = read_mot(fast, kind=kind), read_mot(slow, kind=kind)
    for name in ("frames", "ids", "boxes", "conf", "classes", "visibility"):
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and x.tobytes() == y.tobytes(), name


def test_a_bad_row_is_reported_by_line_whatever_the_path(tmp_path):
    p = tmp_path / "f.txt"
    p.write_text("1,1,1,1,5,5,1,-1,-1,-1\n2,0,1,1,5,5,1,-1,-1,-1\n")
    with pytest.raises(ValueError, match=r"f\.txt:2: id must be a positive integer"):
        read_mot(p, kind="result")


#: numbers whose correct rounding a fast parser may miss: 17+ digits, halfway cases,
#: subnormals, exponents, signs, no digit before or after the point
HARD = ["1.700000000000000177635684", "9007199254740993", "2.2250738585072011e-308",
        "0.1", "0.30000000000000004", "123456789012345678901234567890", "4.9e-324",
        "1e22", "1e23", "-0", "+1.5", ".5", "5.", "1E2", "7.0000000000000001e-1",
        "8.98846567431158e307", "2.4703282292062328e-324", "0.000000000000000195"]


@pytest.mark.parametrize("c_reader_from", [0, 10**9])  # pandas, numpy
def test_both_c_readers_round_as_python(c_reader_from):
    rng = np.random.default_rng(5)
    fields = [*HARD, *(repr(float(x)) for x in rng.uniform(-1e4, 1e4, 200)),
              *(f"{x:.2f}" for x in rng.uniform(0, 2000, 200))]
    fields += ["1"] * (-len(fields) % 6)
    text = "\n".join(",".join(fields[i:i + 6]) for i in range(0, len(fields), 6)) + "\n"
    a = read_columns(text, c_reader_from=c_reader_from)
    want = np.array([float(f) for f in fields]).reshape(-1, 6)
    assert a is not None and a.tobytes() == want.tobytes()


@pytest.mark.parametrize("c_reader_from", [0, 10**9])
@pytest.mark.parametrize("text", ["1,2,3\n4,5\n", "1,2,3\n4,5,6,7\n", "1,,3\n", '"1",2,3\n',
                                  "1,2,3,\n", "0x1A,2,3\n", "1 2 3\n", "1,2,3 4\n", "-,1,2\n",
                                  "\u0661,2,3\n"])
def test_what_is_not_plain_rows_of_numbers_goes_line_by_line(text, c_reader_from):
    assert read_columns(text, c_reader_from=c_reader_from) is None


def test_rows_in_order_and_shuffled_give_one_table(tmp_path):
    """A file already sorted by (frame, id) is not sorted again: same table as shuffled."""
    rows = _rows(np.random.default_rng(3), 400, 10).splitlines(keepends=True)
    key = [tuple(float(v) for v in r.split(",")[:2]) for r in rows]
    (tmp_path / "a.txt").write_text("".join(rows))
    (tmp_path / "b.txt").write_text("".join(r for _, r in sorted(zip(key, rows))))
    a, b = read_mot(tmp_path / "a.txt"), read_mot(tmp_path / "b.txt")
    for name in ("frames", "ids", "boxes", "conf", "classes", "visibility"):
        assert getattr(a, name).tobytes() == getattr(b, name).tobytes(), name


def test_a_frame_of_known_size_refuses_absurd_boxes_naming_the_line(tmp_path):
    """Issue 39: a box 100 frames wide, or a gt box to score wholly outside the frame, was
    read and scored (the latter as a miss every frame): refused with file and line, on the
    vectorised path (these files are plain rows) as on the line-by-line one."""
    rows = [f"{f},1,10,10,20,40,1,1,1" for f in range(1, 40)]
    path = tmp_path / "gt.txt"
    path.write_text("\n".join(rows) + "\n")
    assert len(read_mot(path, gt=True, image=(64, 48))) == 39
    cases = {"30,1,10,10,6500,40,1,1,1": "more than 100 times the 64x48 frame",
             "30,1,70,10,20,40,1,1,1": "wholly outside the 64x48 frame",
             "30,1,-30,10,20,40,1,1,1": "wholly outside"}
    for bad, why in cases.items():
        path.write_text("\n".join(rows[:29] + [bad] + rows[30:]) + "\n")
        with pytest.raises(MotFormatError, match=rf"{path}:30: .*{why}"):
            read_mot(path, gt=True, image=(64, 48))
        assert len(read_mot(path, gt=True)) == 39  # the frame unknown: nothing to check
    # a row not scored (conf 0) may lie outside; detections and results may too, not 100x
    path.write_text("\n".join(rows[:29] + ["30,2,70,10,20,40,0,1,1"] + rows[30:]) + "\n")
    assert len(read_mot(path, gt=True, image=(64, 48))) == 39
    path.write_text("\n".join([f"{f},-1,70,10,20,40,0.9" for f in range(1, 9)]
                              + ["9,-1,70,10,20,4900,0.9"]) + "\n")
    with pytest.raises(MotFormatError, match=rf"{path}:9: box 20x4900 is more than 100"):
        read_mot(path, kind="det", image=(64, 48))
    path.write_text("\n".join([f"{f},-1,70,10,20,40,0.9" for f in range(1, 9)]) + "\n")
    assert len(read_mot(path, kind="det", image=(64, 48))) == 8
