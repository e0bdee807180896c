"""Import continuous rig time series into the sweep table.

Flat-track rigs deliver a continuous time series (50-100 Hz), not steady sweep points.
This module reads such files and converts them to SI and to the ISO/TYDEX W axes of the
evaluator, and writes sweep tables (:func:`write_sweeps`) and TTC-style files
(:func:`write_ttc`).  Cutting the time series into slip sweeps is sweep analysis, not
reading: :func:`mftire.segmentation.rig_segments.segment` (procedure below) and the
one-call :func:`mftire.segmentation.rig_segments.import_rig` give the sweep table of
:mod:`mftire.iotools.sweeps`, which ``mftire fit`` and ``mftire diagnose`` read unchanged.

Input formats
-------------
``ttc``
    The layout of the FSAE Tire Test Consortium run files: tab-separated, a title line,
    a channel-name line and a unit line, then one row per sample.  Channels
    ``ET V N SA IA RL RE P FX FY FZ MX MZ NFX NFY RST TSTI TSTC TSTO AMBTMP SR`` (more
    are kept), in the metric variant (s, km/h, rpm, deg, deg, cm, cm, kPa, N, N, N,
    N·m, N·m, -, -, °C x5, -) or the US variant (mph, in, psi, lbf, ft·lbf, °F).
    Units are read from the unit line and converted with the unit table of
    :mod:`mftire.iotools.sweeps`; a unit line mixing metric and US units is refused.
``columns``
    Any delimited time series with a column map (:func:`read_column_map` for the small
    TOML file, :func:`parse_map_options` for ``--map Fy=FY:N:-1``), with a unit and a
    sign per column.

Both accept gzip-compressed files (``.gz``).

Axis conventions
----------------
The evaluator uses the TYDEX W-axis system (ISO 8855 style: x forward, y left, z up),
as MFeval does.  Rig files such as the TTC ones use SAE J670 (x forward, y right,
z down).  The SAE frame is the ISO frame turned 180° about x, so every vector and
pseudo-vector component maps as (x, y, z) -> (x, -y, -z) and an angle about an axis
takes the sign of that axis:

=============  ==========  ===================  ==========================================
quantity       TTC         ISO W from SAE       note
=============  ==========  ===================  ==========================================
Fx             FX          Fx                   braking force negative in both
Fy             FY          -Fy
Fz             FZ          -Fz                  SAE files record the load as negative
Mx             MX          Mx
My             (none)      -My
Mz             MZ          -Mz
slip angle     SA          alpha = -SA          an angle about z
inclination    IA          gamma = IA           an angle about x (x is shared); files
                                                that sign it against the vehicle side
                                                need ``signs={"gamma": -1}``
slip ratio     SR          kappa = SR           same definition, Omega·Re/Vx - 1
=============  ==========  ===================  ==========================================

Sources: SAE J670 (vehicle dynamics terminology); ISO 8855; TYDEX-Format Release 1.3,
section 2.6 (C-, H- and W-axis systems); Pacejka, *Tyre and Vehicle Dynamics*, 3rd ed.,
chapter 1 (sign conventions) and section 4.3.2 (the W-axis system of the Magic
Formula).  ``convention="iso"`` takes the data unchanged.  The conversion is checked by
physical invariants that hold in any convention (``tests/test_rig_import.py``): Fz > 0
on the ground, Fy·alpha < 0 and Mz·alpha > 0 at small slip angles, Fx < 0 where
kappa < 0.

The normalised forces ``NFX``/``NFY`` (FX/FZ, FY/FZ in SAE axes) are not kept: they are
derived from the measured forces (Fx/Fz, Fy/Fz recompute them in ISO axes), and as a
data column they would hand the diagnosis the measured force as a "cause".

Segmentation (:func:`mftire.segmentation.rig_segments.segment`)
----------------------------------------------------------------
1. Each condition (Fz, P, inclination, Vx) is averaged over ``smooth_s`` and is
   *steady* where its smoothed value moves less than its tolerance within ``hold_s``.
2. The levels of each condition are the gap clusters
   (:func:`~mftire.segmentation.grouping.cluster_1d`) of its steady values; a row belongs to a
   level when it is steady and within the tolerance of the level.
3. A *segment* is a run of consecutive rows at one level of every condition.  Rows
   outside segments are dropped as load ramps or transitions (the first unsteady
   condition is named); segments shorter than ``min_segment_s`` are dropped as short
   holds; segments in which no slip is swept are dropped as free rolling.
4. Warm-up: ``warmup="auto"`` drops the first segment when its condition recurs later
   in the file (a conditioning run repeated by the measurement); a number drops the
   first ``warmup`` seconds.
5. Within a segment the swept slip (alpha or kappa) is split at its turning points
   into sweeps of one direction (``direction`` = ``increasing`` or ``decreasing``,
   ``sweep_dir`` = +1/-1), since hysteresis between directions is a real effect.
6. Optional down-sampling to ``points_per_sweep`` binned means (equal-count bins in
   time order) of every numeric column; ``row_first``/``row_last`` give the source
   rows (0-based data rows of the raw file; TTC file line = row + 4) of every point.
7. "Dropped" means left out of the sweeps, not out of the table: those rows stay, in
   time order, with ``fit_row`` False and their ``drop_reason`` (the sweep rows have
   ``fit_row`` True); a fit uses only the ``fit_row`` rows
   (:func:`mftire.iotools.sweeps.fit_rows`), the diagnosis may use all of them.

The output carries the columns of :func:`~mftire.segmentation.grouping.group_sweeps`
(``sweep_id``, ``Fz_set``, ``gamma_set``, ``P_set``, ``Vx_set``, ``kind``,
``sweep_var``, ``kappa_set``, ``alpha_set``, ``sweep_dir``, ``direction``), so the
diagnosis uses these sweeps; ``mftire fit`` regroups the rows itself.  Extra channels
keep their source names (``ET``, ``N``, ``RL``, ``RE``, ``RST``, ``TSTI``, ``TSTC``,
``TSTO``, ``AMBTMP`` ...), in SI except temperatures, which are in °C.

Bad input (missing channel, unknown or mixed units, a non-numeric or empty cell, a row
with the wrong number of fields, time going backwards) raises
:class:`~mftire.errors.MftireInputError` naming the file, line and column.
"""

from __future__ import annotations

import gzip
import io
import math
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from mftire.errors import MftireInputError
from mftire.iotools.atomic import atomic_path
from mftire.iotools.sweeps import (
    COLUMN_ALIASES,
    DIMENSIONS,
    MEASURED_COLUMNS,
    REQUIRED_COLUMNS,
    to_numbers,
    unit_factor,
    unit_offset,
)
from mftire.iotools.units import normalise_unit as _normalise_unit

__all__ = [
    "TTC_CHANNELS",
    "SAE_TO_ISO",
    "ColumnSpec",
    "read_ttc",
    "read_columns",
    "read_column_map",
    "read_raw",
    "parse_map_options",
    "to_iso",
    "column_spec",
    "write_sweeps",
    "write_ttc",
    "TTC_UNITS",
]

PathLike = str | os.PathLike[str]

#: Channels every TTC-style run file must have, in the usual order.
TTC_CHANNELS: tuple[str, ...] = ("ET", "V", "N", "SA", "IA", "RL", "RE", "P", "FX", "FY", "FZ", "MX", "MZ",
                                 "NFX", "NFY", "RST", "TSTI", "TSTC", "TSTO", "AMBTMP", "SR")  # fmt: skip
#: TTC channels that are not schema quantities, with their physical dimension (unit table of
#: :mod:`mftire.iotools.sweeps`); the schema ones (SA, SR, IA, V, P, FX, FY, FZ, MX, MZ) are
#: found through the column aliases of :mod:`mftire.iotools.sweeps`.
_TTC_EXTRA_DIMENSIONS: dict[str, str] = {
    "ET": "time", "N": "angular_speed", "RL": "length", "RE": "length", "NFX": "ratio", "NFY": "ratio",
    "RST": "temperature", "TSTI": "temperature", "TSTC": "temperature", "TSTO": "temperature",
    "AMBTMP": "temperature",
}  # fmt: skip
#: Derived channels left out of the output (see the module docstring).
_TTC_DROPPED = ("NFX", "NFY")
#: Unit tokens meaning "dimensionless" in rig files besides the unit table's (TTC writes the
#: slip-ratio unit as its definition, "SAE").
_DIMENSIONLESS_TOKENS = {"sae", "sr"}

#: Sign of each schema quantity from SAE J670 to ISO/TYDEX W axes (module docstring table).
SAE_TO_ISO: dict[str, int] = {"Fx": 1, "Fy": -1, "Fz": -1, "Mx": 1, "My": -1, "Mz": -1,
                              "alpha": -1, "gamma": 1, "kappa": 1}  # fmt: skip

# normalised US customary units (everything else dimensional counts as metric)
_US_UNITS = {"mph", "ft/s", "psi", "lb", "lbf", "ftlb", "ftlbf", "lbft", "lbfft", "lbfin", "inlbf", "in",
             "inch", "ft", "degf", "°f", "fahrenheit"}  # fmt: skip
_SYSTEM_FREE = {"angle", "ratio", "time", "angular_speed", "count"}



# ----------------------------------------------------------------------------------------
# reading
# ----------------------------------------------------------------------------------------


def _is_gzip(path: str) -> bool:
    try:
        with open(path, "rb") as fh:
            return fh.read(2) == b"\x1f\x8b"
    except OSError as exc:
        raise MftireInputError(f"{path}: cannot read ({exc.strerror or exc})") from None


def _head_lines(path: str, n: int) -> list[str]:
    """The first ``n`` lines of a (possibly gzipped) text file, without line ends."""
    opener = gzip.open if _is_gzip(path) else open
    lines: list[str] = []
    try:
        with opener(path, "rt", encoding="utf-8", errors="replace", newline="") as fh:
            for line in fh:
                lines.append(line.rstrip("\r\n"))
                if len(lines) >= n:
                    break
    except (OSError, EOFError) as exc:
        raise MftireInputError(f"{path}: cannot read ({exc})") from None
    return lines


def _read_body(path: str, sep: str, skip: int, names: list[str]) -> pd.DataFrame:
    """The data rows after ``skip`` header lines, one column per name (text kept where not numeric)."""
    try:
        df = pd.read_csv(path, sep=sep, skiprows=skip, header=None, names=names, engine="c",
                         compression="gzip" if _is_gzip(path) else None, skip_blank_lines=True,
                         skipinitialspace=True)  # fmt: skip
    except pd.errors.ParserError as exc:
        msg = str(exc)
        m = re.search(r"Expected (\d+) fields in line (\d+), saw (\d+)", msg)
        if m:
            raise MftireInputError(
                f"{path}:{m.group(2)}: row has {m.group(3)} fields, the channel line names {m.group(1)}"
            ) from None
        raise MftireInputError(f"{path}: not a readable delimited file ({msg.splitlines()[-1]})") from None
    except pd.errors.EmptyDataError:
        raise MftireInputError(f"{path}: no data rows after line {skip}") from None
    except (OSError, EOFError, UnicodeDecodeError) as exc:
        raise MftireInputError(f"{path}: cannot read ({exc})") from None
    if len(df) == 0:
        raise MftireInputError(f"{path}: no data rows after line {skip}")
    return df


def _data_line(path: str, i: int, skip: int) -> int:
    """File line (1-based) of data row ``i`` after ``skip`` header lines, counting the blank
    lines the reader skipped (the file is read again: only for an error message)."""
    opener = gzip.open if _is_gzip(path) else open
    row = -1
    try:
        with opener(path, "rt", encoding="utf-8", errors="replace", newline="") as fh:
            for lineno, line in enumerate(fh, start=1):
                if lineno > skip and line.strip("\r\n"):
                    row += 1
                    if row == i:
                        return lineno
    except (OSError, EOFError):
        pass
    return skip + 1 + i


def _numeric(path: str, df: pd.DataFrame, column: str, skip: int, allow_nan: bool = False) -> np.ndarray:
    """Column as float64; a non-numeric (or, unless ``allow_nan``, empty) cell raises naming line and column."""
    s = df[column]
    if not pd.api.types.is_numeric_dtype(s) or pd.api.types.is_bool_dtype(s):
        conv, i = to_numbers(s)
        if i is not None:
            raise MftireInputError(
                f"{path}:{_data_line(path, i, skip)}: column {column!r}: {str(s.iloc[i])!r} is not a number"
            )
        s = conv
    x = s.to_numpy(dtype=float)
    if not allow_nan:
        bad = ~np.isfinite(x)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise MftireInputError(f"{path}:{_data_line(path, i, skip)}: column {column!r}: empty or non-finite value")
    return x


def _convert(path: str, line: int, column: str, values: np.ndarray, unit: str, dimension: str) -> np.ndarray:
    """Values in ``unit`` to SI (deg C for temperatures); a bad unit raises naming line and column."""
    if dimension in ("ratio", "count") and _normalise_unit(unit) in _DIMENSIONLESS_TOKENS:
        return values
    try:
        factor = unit_factor(unit, dimension)
        offset = unit_offset(unit, dimension)
    except MftireInputError as exc:
        raise MftireInputError(f"{path}:{line}: column {column!r}: {exc}") from None
    if factor == 1.0 and offset == 0.0:
        return values
    return values * factor + offset


def _check_time(path: str, t: np.ndarray, column: str, skip: int, df: pd.DataFrame) -> None:
    back = np.flatnonzero(np.diff(t) < 0)
    if back.size:
        i = int(back[0]) + 1
        raise MftireInputError(
            f"{path}:{_data_line(path, i, skip)}: column {column!r}: time goes backwards "
            f"({t[i]:g} after {t[i - 1]:g}); the time column must be monotonic"
        )


def _no_duplicates(path: str, line: int, names: Sequence[str], what: str) -> None:
    dups = sorted({n for n in names if names.count(n) > 1 and n})
    if dups:
        raise MftireInputError(f"{path}:{line}: column {dups[0]!r} appears twice in the {what}")


def _target_of(name: str) -> str | None:
    """Schema column a rig channel name stands for, from the column aliases of the sweep schema."""
    low = name.strip().lower()
    for target, aliases in COLUMN_ALIASES.items():
        if low == target.lower() or low in aliases:
            return target
    return None


def _unit_system(unit: str, dimension: str) -> str | None:
    if dimension in _SYSTEM_FREE:
        return None
    return "US" if _normalise_unit(unit) in _US_UNITS else "metric"


def _check_mixed(path: str, line: int, units: Mapping[str, tuple[str, str]]) -> None:
    """Refuse a unit line that mixes metric and US customary units."""
    seen: dict[str, str] = {}
    for col, (unit, dim) in units.items():
        system = _unit_system(unit, dim)
        if system is None:
            continue
        other = "metric" if system == "US" else "US"
        if other in seen:
            raise MftireInputError(
                f"{path}:{line}: column {col!r}: unit {unit!r} is {system} but column {seen[other]!r} is "
                f"{other}: mixed unit systems in one file (a unit line is probably wrong)"
            )
        seen.setdefault(system, col)


def read_ttc(path: PathLike, *, convention: str = "sae", signs: Mapping[str, float] | None = None) -> pd.DataFrame:
    """Read a TTC-style run file (metric or US units, plain or gzipped) into an SI table in ISO axes.

    Parameters
    ----------
    path : path-like
        Tab-separated: title line, channel-name line, unit line, data rows.
    convention : {"sae", "iso"}
        Axis convention of the file (TTC files: SAE J670).  ``"iso"`` takes the data as
        they are.
    signs : mapping, optional
        Extra sign factors per schema column after the conversion, e.g. ``{"gamma": -1}``
        for a file that signs inclination against the vehicle side.

    Returns
    -------
    DataFrame
        One row per sample: schema columns (``Fz, kappa, alpha, gamma, Vx, P, Fx, Fy,
        Mz, Mx``) in SI and ISO W axes, extra channels under their names (SI, °C),
        ``NFX``/``NFY`` left out.  ``attrs``: ``title``, ``units_read`` (channel ->
        unit in the file), ``channel_map`` (column -> channel), ``convention``,
        ``time_column`` (``"ET"``), ``header_lines`` (3).
    """
    p = os.fspath(path)
    head = _head_lines(p, 3)
    if len(head) < 3:
        raise MftireInputError(f"{p}: {len(head)} line(s); a TTC-style file needs a title, channel and unit line")
    names = [c.strip() for c in head[1].split("\t")]
    units = [u.strip() for u in head[2].split("\t")]
    while names and names[-1] == "":  # a trailing tab
        names.pop()
    if not any(names):
        raise MftireInputError(f"{p}:2: empty channel-name line")
    _no_duplicates(p, 2, names, "channel line")
    missing = [c for c in TTC_CHANNELS if c not in names]
    if missing:
        raise MftireInputError(
            f"{p}:2: column {missing[0]!r} missing from the channel line"
            + (f" (also missing: {', '.join(missing[1:])})" if len(missing) > 1 else "")
            + f"; a TTC-style file has {' '.join(TTC_CHANNELS)}"
        )
    units = (units + [""] * len(names))[: len(names)]
    body = _read_body(p, "\t", 3, [n or f"_unnamed{i}" for i, n in enumerate(names)])
    dims: dict[str, tuple[str, str]] = {}
    targets: dict[str, str] = {}
    messages: list[str] = []
    skipped: set[str] = set()
    for name, unit in zip(names, units, strict=True):
        if not name:
            continue
        target = _target_of(name) if name not in _TTC_EXTRA_DIMENSIONS else None
        if target is not None and name not in TTC_CHANNELS:
            # e.g. a second slip channel "SL": the layout's own channel (SR) is the one used
            skipped.add(name)
            messages.append(f"channel {name} looks like {target} but is not the TTC layout's channel for it; "
                            "left out")  # fmt: skip
        elif target is not None and target in DIMENSIONS:
            targets[name] = target
            dims[name] = (unit, DIMENSIONS[target])
        elif name in _TTC_EXTRA_DIMENSIONS:
            dims[name] = (unit, _TTC_EXTRA_DIMENSIONS[name])
    _check_mixed(p, 3, dims)
    out: dict[str, np.ndarray] = {}
    cmap: dict[str, str] = {}
    for name in names:
        if not name or name in _TTC_DROPPED or name in skipped:
            continue
        required = name in TTC_CHANNELS
        x = _numeric(p, body, name, 3, allow_nan=not required)
        if name in dims:
            x = _convert(p, 3, name, x, *dims[name])
        col = targets.get(name, name)
        out[col] = x
        cmap[col] = name
    _check_time(p, out["ET"], "ET", 3, body)
    df = pd.DataFrame(out)
    df = to_iso(df, convention, signs)
    df.attrs.update({"title": head[0].strip(), "units_read": dict(zip(names, units, strict=True)),
                     "channel_map": cmap, "convention": convention, "time_column": "ET", "header_lines": 3,
                     "file": p, "messages": messages})  # fmt: skip
    return df


def to_iso(df: pd.DataFrame, convention: str, signs: Mapping[str, float] | None = None) -> pd.DataFrame:
    """Convert schema columns from ``convention`` ("sae" or "iso") to ISO W axes (in place; returns ``df``).

    SAE J670 -> ISO: see the module docstring (:data:`SAE_TO_ISO`).  ``signs`` multiplies
    columns afterwards (e.g. ``{"gamma": -1}``).
    """
    conv = str(convention).strip().lower()
    if conv not in ("sae", "iso"):
        raise MftireInputError(f"--convention must be 'sae' or 'iso', got {convention!r}")
    if conv == "sae":
        for col, sign in SAE_TO_ISO.items():
            if col in df.columns and sign != 1:
                df[col] = -df[col]
    for col, sign in (signs or {}).items():
        if col not in df.columns:
            raise MftireInputError(f"sign override for column {col!r}, which the data lack")
        df[col] = df[col] * float(sign)
    return df


@dataclass
class ColumnSpec:
    """How one output column is made from a source column: ``value = sign * raw`` in ``unit``, to SI."""

    target: str
    column: str
    unit: str | None = None
    sign: float = 1.0


def column_spec(target: str, entry: Any, where: str) -> ColumnSpec:
    if isinstance(entry, str):
        return ColumnSpec(target, entry)
    if isinstance(entry, Mapping):
        unknown = set(entry) - {"column", "unit", "sign"}
        if unknown or "column" not in entry:
            raise MftireInputError(
                f"{where}: entry {target!r} needs 'column' (and optionally 'unit', 'sign'); got {sorted(entry)}"
            )
        sign = entry.get("sign", 1.0)
        if not isinstance(sign, (int, float)) or sign == 0 or not math.isfinite(sign):
            raise MftireInputError(f"{where}: entry {target!r}: sign must be a non-zero number, got {sign!r}")
        unit = entry.get("unit")
        return ColumnSpec(target, str(entry["column"]), None if unit is None else str(unit), float(sign))
    raise MftireInputError(f"{where}: entry {target!r} must be a column name or a table, got {entry!r}")


def read_column_map(path: PathLike) -> dict[str, Any]:
    """Read a column-map TOML file for :func:`read_columns`.

    Example::

        delimiter = ","          # optional: guessed from the header line (tab, ; or ,)
        skip_lines = 0           # lines before the header line
        units_line = false       # a line of units follows the header line
        convention = "iso"       # or "sae"
        time = "t"               # time column (source name), optional

        [columns]                # output column = source column (SI, sign +1) or a table
        Fz = { column = "LOAD", unit = "kN", sign = -1 }
        alpha = { column = "SA", unit = "deg" }
        Fy = "FY"
        TSTC = { column = "tread_centre", unit = "degF" }

    Returns a dict with ``columns`` (target -> :class:`ColumnSpec`) and the options.
    """
    p = os.fspath(path)
    try:
        import tomllib  # Python >= 3.11
    except ImportError:  # pragma: no cover - Python 3.10
        raise MftireInputError(f"{p}: reading a TOML column map needs Python 3.11 (tomllib); use --map") from None
    try:
        with open(p, "rb") as fh:
            doc = tomllib.load(fh)
    except FileNotFoundError:
        raise MftireInputError(f"{p}: file not found") from None
    except tomllib.TOMLDecodeError as exc:
        raise MftireInputError(f"{p}: not valid TOML ({exc})") from None
    known = {"delimiter", "skip_lines", "units_line", "convention", "time", "columns"}
    extra = sorted(set(doc) - known)
    if extra:
        raise MftireInputError(f"{p}: unknown key(s) {', '.join(extra)}; known: {', '.join(sorted(known))}")
    cols = doc.get("columns", {})
    if not isinstance(cols, Mapping):
        raise MftireInputError(f"{p}: [columns] must be a table")
    out = {k: v for k, v in doc.items() if k != "columns"}
    out["columns"] = {t: column_spec(t, e, p) for t, e in cols.items()}
    return out


def parse_map_options(items: Sequence[str]) -> dict[str, ColumnSpec]:
    """``["Fy=FY", "Fz=LOAD:kN:-1", "alpha=SA:deg"]`` -> column specs (``TARGET=SOURCE[:UNIT[:SIGN]]``)."""
    out: dict[str, ColumnSpec] = {}
    for raw in items:
        if "=" not in raw:
            raise MftireInputError(f"--map {raw!r}: expected TARGET=SOURCE[:UNIT[:SIGN]], e.g. Fy=FY:N:-1")
        target, _, rest = raw.partition("=")
        parts = rest.split(":")
        if not target.strip() or not parts[0].strip() or len(parts) > 3:
            raise MftireInputError(f"--map {raw!r}: expected TARGET=SOURCE[:UNIT[:SIGN]], e.g. Fy=FY:N:-1")
        unit = parts[1].strip() if len(parts) > 1 and parts[1].strip() else None
        sign = 1.0
        if len(parts) > 2:
            try:
                sign = float(parts[2])
            except ValueError:
                raise MftireInputError(f"--map {raw!r}: sign {parts[2]!r} is not a number") from None
            if sign == 0 or not math.isfinite(sign):
                raise MftireInputError(f"--map {raw!r}: sign must be a non-zero number")
        out[target.strip()] = ColumnSpec(target.strip(), parts[0].strip(), unit, sign)
    return out


def _guess_delimiter(line: str) -> str:
    counts = {d: line.count(d) for d in ("\t", ";", ",")}
    best = max(counts, key=lambda d: counts[d])
    return best if counts[best] else ","


def _dimension_of(target: str, unit: str | None) -> str | None:
    """Dimension of an output column: the schema's, else the first dimension the unit belongs to."""
    if target in DIMENSIONS:
        return DIMENSIONS[target]
    if target == "time":
        return "time"
    if unit is None:
        return None
    for dim in ("temperature", "time", "length", "speed", "force", "moment", "pressure", "angle",
                "angular_speed", "ratio"):  # fmt: skip
        try:
            unit_factor(unit, dim)
        except MftireInputError:
            continue
        return dim
    return None


def read_columns(
    path: PathLike,
    columns: Mapping[str, ColumnSpec | str | Mapping],
    *,
    delimiter: str | None = None,
    skip_lines: int = 0,
    units_line: bool = False,
    convention: str = "iso",
    time: str | None = None,
) -> pd.DataFrame:
    """Read a generic delimited time series with a column map into an SI table in ISO axes.

    Parameters
    ----------
    path : path-like
        Delimited text (plain or gzipped): ``skip_lines`` lines, a header line of column
        names, optionally a line of units, then data rows.
    columns : mapping
        Output column -> :class:`ColumnSpec` (or source name, or ``{"column", "unit",
        "sign"}``).  Schema columns (``Fz, kappa, alpha, gamma, Vx, P`` required; ``Fx,
        Fy, Mz, Mx, My`` any) are converted from ``unit`` to SI (default: the unit of the
        units line, else SI); other outputs are converted when their unit names a known
        dimension (temperatures to °C).  ``value = sign * raw``, then the axis conversion.
        Unmapped source columns are kept under their own names, unconverted.
    convention : {"iso", "sae"}
        Axis convention of the mapped values.
    time : str, optional
        Source name of the time column (also accepted as the output ``time`` in
        ``columns``).  Without one, rows are taken as evenly spaced at 1 s.

    Returns
    -------
    DataFrame
        ``attrs``: ``units_read``, ``channel_map``, ``convention``, ``time_column``,
        ``header_lines``, ``file``.
    """
    p = os.fspath(path)
    specs = {t: (s if isinstance(s, ColumnSpec) else column_spec(t, s, "column map")) for t, s in columns.items()}
    head = _head_lines(p, skip_lines + 2)
    if len(head) <= skip_lines:
        raise MftireInputError(f"{p}: no header line after {skip_lines} skipped line(s)")
    sep = delimiter or _guess_delimiter(head[skip_lines])
    names = [c.strip().strip('"') for c in head[skip_lines].split(sep)]
    header_line = skip_lines + 1
    file_units: dict[str, str] = {}
    if units_line:
        if len(head) <= skip_lines + 1:
            raise MftireInputError(f"{p}:{header_line + 1}: the units line is missing")
        ulist = [u.strip().strip('"') for u in head[skip_lines + 1].split(sep)]
        file_units = dict(zip(names, ulist + [""] * len(names), strict=False))
    skip = skip_lines + (2 if units_line else 1)
    _no_duplicates(p, header_line, names, "header line")
    missing_t = [c for c in REQUIRED_COLUMNS if c not in specs]
    if missing_t:
        raise MftireInputError(
            f"column map: no source column for {', '.join(missing_t)} (give e.g. --map {missing_t[0]}=NAME[:UNIT])"
        )
    if not any(c in specs for c in MEASURED_COLUMNS):
        raise MftireInputError(f"column map: no measured channel ({', '.join(MEASURED_COLUMNS)}) is mapped")
    time_src = time or (specs["time"].column if "time" in specs else None)
    for s in [*specs.values()] + ([ColumnSpec("time", time_src)] if time_src else []):
        if s.column not in names:
            raise MftireInputError(
                f"{p}:{header_line}: column {s.column!r} (for {s.target}) missing from the header line "
                f"(have: {', '.join(n for n in names if n)})"
            )
    body = _read_body(p, sep, skip, [n or f"_unnamed{i}" for i, n in enumerate(names)])
    out: dict[str, np.ndarray] = {}
    units_read: dict[str, str] = {}
    cmap: dict[str, str] = {}
    unit_line_no = header_line + 1
    for target, s in specs.items():
        if target == "time":
            continue
        x = _numeric(p, body, s.column, skip, allow_nan=target in MEASURED_COLUMNS)
        fu = file_units.get(s.column, "")
        if s.unit is not None and fu and _normalise_unit(fu) != _normalise_unit(s.unit):
            raise MftireInputError(
                f"{p}:{unit_line_no}: column {s.column!r}: the units line says {fu!r} but the column map "
                f"says {s.unit!r} (mixed units)"
            )
        unit = s.unit if s.unit is not None else fu
        dim = _dimension_of(target, unit if unit else None)
        if dim is not None:
            if not unit and dim not in ("ratio", "count"):
                unit = {"angle": "rad", "speed": "m/s", "pressure": "Pa", "force": "N", "moment": "N.m",
                        "curvature": "1/m", "time": "s"}.get(dim, "")  # fmt: skip
            x = _convert(p, unit_line_no if fu else header_line, s.column, x, unit, dim)
        out[target] = s.sign * x
        units_read[target] = unit or ""
        cmap[target] = s.column
    tcol = None
    if time_src:
        tspec = specs.get("time", ColumnSpec("time", time_src))
        t = _numeric(p, body, time_src, skip)
        unit = tspec.unit or file_units.get(time_src, "") or "s"
        t = _convert(p, unit_line_no if units_line else header_line, time_src, t, unit, "time") * tspec.sign
        _check_time(p, t, time_src, skip, body)
        tcol = time_src if time_src not in out else "time"
        out[tcol] = t
        cmap[tcol] = time_src
        units_read[tcol] = unit
    used = {s.column for s in specs.values()} | ({time_src} if time_src else set())
    for name in names:
        if name and name not in used and name not in out:
            s = body[name]
            out[name] = pd.to_numeric(s, errors="coerce").to_numpy(float) if pd.api.types.is_numeric_dtype(s) \
                else s.to_numpy()
    df = pd.DataFrame(out)
    df = to_iso(df, convention)
    df.attrs.update({"units_read": units_read, "channel_map": cmap, "convention": convention,
                     "time_column": tcol, "header_lines": skip, "file": p})  # fmt: skip
    return df


#: Unit lines of the two TTC-style variants (the metric one as the TTC files write it).
TTC_UNITS: dict[str, dict[str, str]] = {
    "metric": {"ET": "s", "V": "kph", "N": "rpm", "SA": "deg", "IA": "deg", "RL": "cm", "RE": "cm", "P": "kPa",
               "FX": "N", "FY": "N", "FZ": "N", "MX": "N-m", "MZ": "N-m", "NFX": "-", "NFY": "-",
               "RST": "deg C", "TSTI": "deg C", "TSTC": "deg C", "TSTO": "deg C", "AMBTMP": "deg C", "SR": "-"},
    "us": {"ET": "s", "V": "mph", "N": "rpm", "SA": "deg", "IA": "deg", "RL": "in", "RE": "in", "P": "psi",
           "FX": "lbf", "FY": "lbf", "FZ": "lbf", "MX": "ft-lbf", "MZ": "ft-lbf", "NFX": "-", "NFY": "-",
           "RST": "deg F", "TSTI": "deg F", "TSTC": "deg F", "TSTO": "deg F", "AMBTMP": "deg F", "SR": "-"},
}  # fmt: skip
_TTC_DECIMALS = {"ET": 3, "SA": 4, "IA": 4, "SR": 5, "NFX": 4, "NFY": 4}


def read_raw(path: PathLike, fmt: str, *, columns: Mapping[str, Any] | None = None,
             column_map: PathLike | None = None, convention: str | None = None,
             signs: Mapping[str, float] | None = None) -> pd.DataFrame:
    """A raw rig file as a continuous series in ISO-W axes: ``fmt`` ``"ttc"`` (:func:`read_ttc`) or
    ``"columns"`` (:func:`read_columns`, the column map from ``column_map`` (TOML, :func:`read_column_map`)
    and/or ``columns``, which win).  ``convention`` defaults to SAE for TTC files and to the map's (else ISO)
    for columns; ``signs`` flips channels after the conversion."""
    p = os.fspath(path)
    if fmt == "ttc":
        if columns or column_map:
            raise MftireInputError("a column map (--map/--columns-map) is only used with --format columns")
        return read_ttc(p, convention=convention or "sae", signs=signs)
    if fmt == "columns":
        opts: dict[str, Any] = read_column_map(column_map) if column_map else {"columns": {}}
        specs = dict(opts.pop("columns"))
        specs.update({t: (s if isinstance(s, ColumnSpec) else column_spec(t, s, "--map"))
                      for t, s in (columns or {}).items()})  # fmt: skip
        conv = convention or opts.pop("convention", "iso")
        opts.pop("convention", None)
        df = read_columns(p, specs, convention=conv, **opts)
        if signs:
            to_iso(df, "iso", signs)
        return df
    raise MftireInputError(f"--format must be 'ttc' or 'columns', got {fmt!r}")


def write_ttc(raw: pd.DataFrame, path: PathLike, *, units: str = "metric", title: str = "") -> None:
    """Write TTC channels (SI, temperatures in deg C, axes as given) in the TTC-style layout, atomically.

    ``raw`` has the columns of :data:`TTC_CHANNELS` (``NFX``/``NFY`` are computed from
    FX/FZ, FY/FZ when absent); values are converted to the ``units`` variant
    (``"metric"`` or ``"us"``, :data:`TTC_UNITS`).  A path ending in ``.gz`` is gzipped
    (reproducibly: no time stamp).
    """
    if units not in TTC_UNITS:
        raise MftireInputError(f"write_ttc: units must be 'metric' or 'us', got {units!r}")
    raw = raw.copy()
    if "NFX" not in raw.columns:
        raw["NFX"] = raw["FX"] / raw["FZ"].abs().clip(lower=1.0)
    if "NFY" not in raw.columns:
        raw["NFY"] = raw["FY"] / raw["FZ"].abs().clip(lower=1.0)
    missing = [c for c in TTC_CHANNELS if c not in raw.columns]
    if missing:
        raise MftireInputError(f"write_ttc: missing channel(s) {', '.join(missing)}")
    table = TTC_UNITS[units]
    out = {}
    for c in TTC_CHANNELS:
        target = _target_of(c) if c not in _TTC_EXTRA_DIMENSIONS else None
        dim = DIMENSIONS[target] if target in DIMENSIONS else _TTC_EXTRA_DIMENSIONS[c]
        x = raw[c].to_numpy(float)
        if not (dim in ("ratio", "count") and _normalise_unit(table[c]) in _DIMENSIONLESS_TOKENS):
            x = (x - unit_offset(table[c], dim)) / unit_factor(table[c], dim)
        out[c] = np.round(x, _TTC_DECIMALS.get(c, 2))
    text = io.StringIO()
    text.write((title or "mftire TTC-style run file") + "\n")
    text.write("\t".join(TTC_CHANNELS) + "\n")
    text.write("\t".join(table[c] for c in TTC_CHANNELS) + "\n")
    pd.DataFrame(out).to_csv(text, sep="\t", header=False, index=False, lineterminator="\n")
    data = text.getvalue().encode("utf-8")
    p = os.fspath(path)
    with atomic_path(p) as tmp, open(tmp, "wb") as fh:
        if p.endswith(".gz"):
            with gzip.GzipFile(filename="", mode="wb", fileobj=fh, compresslevel=9, mtime=0) as gz:
                gz.write(data)
        else:
            fh.write(data)


def write_sweeps(table: pd.DataFrame, path: PathLike) -> None:
    """Write an imported sweep table as CSV, atomically (the folder is created if needed)."""
    folder = os.path.dirname(os.path.abspath(os.fspath(path)))
    os.makedirs(folder, exist_ok=True)
    with atomic_path(path) as tmp:
        table.to_csv(tmp, index=False, float_format="%.8g")
