"""read_mot's vectorised reading (comma-separated rows of one width, all valid) gives the
table the line-by-line reader gives; a comment line sends a file down the line-by-line path."""

from __future__ import annotations

import numpy as np
import pytest

from harness.io.mot import read_mot


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


@pytest.mark.parametrize("fields, kind", [(9, "gt"), (10, "result"), (6, "result"),
                                          (7, "any"), (10, "gt")])
def test_vectorised_reading_equals_line_by_line(tmp_path, fields, kind):
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
