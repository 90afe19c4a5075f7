"""The numbers of comma-separated rows in one pass of a C reader (``read_columns``).

``occbench.io.mot`` reads a MOT file's text here first and line by line only when this gives
None. Both readers give every number exactly as Python's ``float`` parses it (correctly
rounded), so they give the same table (``tests/harness/io/test_mot.py``):

* numpy's ``loadtxt`` (its C reader calls Python's own conversion), for small texts;
* pandas' C parser, several times faster, for large ones; from pandas 3.1 its floats are
  parsed by fast_float, which rounds correctly (before, its own parser could be a unit in
  the last place off: loadtxt is used then). Small texts never import pandas (start-up).
"""

from __future__ import annotations

import csv
import io
import warnings

import numpy as np

#: texts from this many characters up go to pandas' C parser (a 300-row file is about 10 kB)
C_READER_FROM = 1 << 20
#: the first pandas whose C parser rounds every float correctly (fast_float)
PANDAS_EXACT = (3, 1)


def read_columns(text: str, c_reader_from: int | None = None) -> np.ndarray | None:
    """(R, C) float64 numbers of ``text``'s comma-separated rows, blank lines skipped.

    Args:
        text: rows of numbers separated by commas (spaces around a number allowed).
        c_reader_from: texts at least this long are read by pandas when it rounds exactly
            (None: ``C_READER_FROM``).
    Returns:
        The numbers, or None when the text is anything else (a field that is not a number,
        an empty field, rows of different widths, quotes...) or when reading it warns: the
        caller then reads it line by line and names the line.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            big = len(text) >= (C_READER_FROM if c_reader_from is None else c_reader_from)
            if big and _pandas_exact():
                return _read_pandas(text)
            return np.loadtxt(io.StringIO(text), delimiter=",", ndmin=2, dtype=np.float64)
        except (ValueError, Warning):  # pandas' ParserError is a ValueError
            return None


def _pandas_exact() -> bool:
    """Whether the installed pandas parses floats correctly rounded."""
    import pandas as pd  # start-up: pandas, ~0.25 s CPU

    version = tuple(int(p) for p in pd.__version__.split(".")[:2] if p.isdigit())
    return version >= PANDAS_EXACT


def _read_pandas(text: str) -> np.ndarray:
    import pandas as pd  # start-up: pandas, ~0.25 s CPU

    table = pd.read_csv(io.BytesIO(text.encode()), header=None, sep=",", engine="c",
                        dtype=np.float64, quoting=csv.QUOTE_NONE, na_filter=False)
    return np.ascontiguousarray(table.to_numpy(dtype=np.float64))
