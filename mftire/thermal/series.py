"""Read the continuous series the thermal commands take: a raw rig file (``--format ttc`` or
``columns``, as ``mftire import`` reads it) or an imported series (``--format series``: the CSV
``mftire import`` writes, or any CSV in its columns, rows in time order).

Either way the result is SI in ISO W axes with temperatures in °C, keyed by ``ET`` [s].
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

import pandas as pd

from mftire.errors import MftireInputError

#: The formats :func:`read_series` takes.
FORMATS = ("ttc", "columns", "series")


def default_format(path: str | os.PathLike) -> str:
    """``series`` for a ``.csv`` (or ``.csv.gz``), else ``ttc``."""
    p = os.fspath(path).lower()
    return "series" if p.endswith(".csv") or p.endswith(".csv.gz") else "ttc"


def read_series(path: str | os.PathLike, fmt: str | None = None, *, columns: Mapping[str, Any] | None = None,
                column_map: str | os.PathLike | None = None, convention: str | None = None) -> pd.DataFrame:
    """The series at ``path`` (module docstring); ``fmt`` None: :func:`default_format`."""
    from mftire.iotools.rig import read_raw

    p = os.fspath(path)
    fmt = fmt or default_format(p)
    if not os.path.exists(p):
        raise MftireInputError(f"{p}: file not found")
    if fmt in ("ttc", "columns"):
        return read_raw(p, fmt, columns=columns, column_map=column_map, convention=convention)
    if columns or column_map:
        raise MftireInputError("a column map (--map/--columns-map) is only used with --format columns")
    if fmt == "series":
        if convention not in (None, "iso"):
            raise MftireInputError("--convention: an imported series is already in ISO axes")
        try:
            df = pd.read_csv(p)
        except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
            raise MftireInputError(f"{p}: not a readable CSV file ({exc})") from None
        df.columns = [str(c).strip() for c in df.columns]
        if "ET" not in df.columns:
            raise MftireInputError(f"{p}: no ET column; an imported series keyed by time is needed (mftire import "
                                   "without --points-per-sweep keeps it)")  # fmt: skip
        return df
    raise MftireInputError(f"--format must be one of {', '.join(FORMATS)}, not {fmt!r}")


__all__ = ["FORMATS", "default_format", "read_series"]
