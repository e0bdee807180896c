"""The shared table loaders: sweep files (CSV, TYDEX) and plain numeric CSV tables.

* :func:`load_sweep_files` reads CSV (sweep schema) and TYDEX ``.tdx`` files into one
  validated table with a ``source`` column (the file's own ``source`` column when it has
  one, else the file stem) and a ``file`` column; :func:`prepare_table` does the same for
  a table already in memory.  The fitter, the comparison, the bands and the diagnosis
  all load through these.
* :func:`check_columns` rejects columns that look like a schema quantity under another
  name or in another unit (``FY``, ``alpha_deg``, ``Fz [kN]`` ...), naming them; the names
  are the column aliases of :mod:`mftire.iotools.sweeps` and the TYDEX keys, the unit
  suffixes those of :mod:`mftire.iotools.units`.
* :func:`read_numeric_csv` reads a CSV whose given columns must be finite numbers
  (``mftire evaluate``'s input).
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence

import numpy as np
import pandas as pd

from mftire.errors import MftireInputError
from mftire.iotools.sweeps import (
    COLUMN_ALIASES,
    MEASURED_COLUMNS,
    OPTIONAL_INPUT_COLUMNS,
    REQUIRED_COLUMNS,
    read_sweep_csv,
    validate_sweeps,
)
from mftire.iotools.tydex import TYDEX_CHANNELS, read_tydex
from mftire.iotools.units import is_known_unit

__all__ = ["check_columns", "load_sweep_files", "prepare_table", "read_numeric_csv"]

_SCHEMA = set(REQUIRED_COLUMNS) | set(OPTIONAL_INPUT_COLUMNS) | set(MEASURED_COLUMNS)
_LOWER = {c.lower(): c for c in _SCHEMA}
# other names of schema quantities (lower case) -> (schema column, unit they usually carry)
_OTHER_NAMES = {alias: (col, unit) for col, aliases in COLUMN_ALIASES.items() for alias, unit in aliases.items()}
# NAME [unit], NAME (unit) or NAME_unit, the suffix a unit of mftire.iotools.units
_UNIT_RE = re.compile(r"^\s*([A-Za-z_]+?)\s*(?:[\[(]\s*([^\])]*)\s*[\])]|_([A-Za-z]+))\s*$")


def check_columns(df: pd.DataFrame, name: str = "sweep data", tydex: bool = False) -> None:
    """Raise :class:`MftireInputError` naming columns that look like a schema quantity.

    Other columns are carried through untouched; but a column such as ``FY``,
    ``SLIPANGL``, ``alpha_deg`` or ``Fz [kN]`` is almost certainly a measured quantity
    in the wrong name or unit and would silently be ignored by the fit.  With ``tydex``
    the second-choice TYDEX keys that :func:`~mftire.iotools.tydex.read_tydex` keeps
    beside the mapped channel (``FX`` next to ``FXW``) are accepted.
    """
    tydex_keys = {k: col for col, keys in TYDEX_CHANNELS.items() for k in keys}
    bad: list[str] = []
    for col in df.columns:
        label = str(col)
        if label in _SCHEMA:
            continue
        if tydex and label in tydex_keys and tydex_keys[label] in df.columns:
            continue
        low = label.strip().lower()
        target, unit = (_LOWER[low], None) if low in _LOWER else _OTHER_NAMES.get(low, (None, None))
        if target is None:
            m = _UNIT_RE.match(label)
            if m and (m.group(2) is not None or is_known_unit(m.group(3))):
                stem = m.group(1).lower()
                target = _LOWER.get(stem) or _OTHER_NAMES.get(stem, (None,))[0]
                unit = m.group(2) or m.group(3)
        if target is None:
            continue
        how = f" in {unit!r}" if unit else ""
        bad.append(f"{label!r} (looks like {target}{how}; the schema wants {target!r} in SI units)")
    if bad:
        raise MftireInputError(
            f"{name}: unknown column(s) {', '.join(bad)}; rename/convert them, e.g. with "
            "mftire.iotools.sweeps.to_schema, or drop them"
        )


def _read_one(path: str) -> pd.DataFrame:
    ext = os.path.splitext(path)[1].lower()
    if ext in (".tdx", ".tydex"):
        df = read_tydex(path)
    else:
        if not os.path.exists(path):
            raise MftireInputError(f"{path}: file not found")
        df = read_sweep_csv(path, validate=False)
    return df


def prepare_table(
    df: pd.DataFrame, name: str = "sweep data", source: str | None = None, tydex: bool = False
) -> tuple[pd.DataFrame, dict]:
    """Check and clean one table for fitting.

    Returns the validated table (see :func:`mftire.iotools.sweeps.validate_sweeps`:
    rows with NaN inputs or no measured value dropped and counted) with ``source`` and
    ``file`` columns, and the validation report as a dict.
    """
    check_columns(df, name, tydex=tydex)
    src = source
    if "source" in df.columns and df["source"].notna().all():
        src = None  # keep the file's own source labels
    elif src is None:
        src = os.path.splitext(os.path.basename(name))[0]
    clean, report = validate_sweeps(df, name, source=src)
    if "file" not in clean.columns:
        clean["file"] = os.path.basename(name)
    clean["source"] = clean["source"].astype(str)
    return clean, report.to_dict()


def load_sweep_files(paths: Sequence[str | os.PathLike]) -> tuple[pd.DataFrame, list[dict]]:
    """Read sweep files (CSV in the sweep schema or TYDEX ``.tdx``) into one table.

    Returns
    -------
    table : DataFrame
        Concatenated, validated table with ``source`` and ``file`` columns.
    reports : list of dict
        One validation report per file (rows dropped for NaN, channels present ...).
    """
    if not paths:
        raise MftireInputError("no data files given")
    frames, reports = [], []
    for path in paths:
        path = os.fspath(path)
        df = _read_one(path)
        tdx = os.path.splitext(path)[1].lower() in (".tdx", ".tydex")
        clean, rep = prepare_table(df, path, tydex=tdx)
        frames.append(clean)
        reports.append(rep)
    table = pd.concat(frames, ignore_index=True, sort=False) if len(frames) > 1 else frames[0]
    table.attrs = {}
    return table.reset_index(drop=True), reports


def read_numeric_csv(path: str, required: Sequence[str], optional: Sequence[str] = ()) -> pd.DataFrame:
    """Read a CSV whose ``required`` and present ``optional`` columns must be finite numbers.

    Raises :class:`MftireInputError` naming the file, column and (1-based) data row
    of the first problem: a missing column, a non-numeric cell, a NaN or an infinity.
    """
    try:
        df = pd.read_csv(path, sep=None if path == "-" else ",", engine="python" if path == "-" else "c")
    except FileNotFoundError:
        raise MftireInputError(f"{path}: file not found") from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise MftireInputError(f"{path}: not a readable CSV file ({exc})") from None
    df.columns = [str(c).strip() for c in df.columns]
    missing = [c for c in required if c not in df.columns]
    if missing:
        raise MftireInputError(
            f"{path}: missing column(s) {', '.join(missing)} (have: {', '.join(df.columns)})"
        )
    for col in [*required, *(c for c in optional if c in df.columns)]:
        raw = df[col]
        values = pd.to_numeric(raw, errors="coerce")
        bad = values.isna() | ~np.isfinite(values.to_numpy(dtype=float, na_value=np.nan))
        if bad.any():
            i = int(np.flatnonzero(bad.to_numpy())[0])
            cell = raw.iloc[i]
            what = "empty or NaN" if pd.isna(cell) or str(cell).strip().lower() == "nan" else f"{cell!r}"
            raise MftireInputError(
                f"{path}: column '{col}', row {i + 1} (line {i + 2}): {what} is not a finite number"
            )
        df[col] = values.astype(float)
    return df
