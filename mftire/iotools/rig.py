"""Import continuous rig time series into the sweep table.

Flat-track rigs deliver a continuous time series (50-100 Hz), not steady sweep points.
This module reads such files, converts them to SI and to the ISO/TYDEX W axes of the
evaluator, cuts them into slip sweeps and writes the sweep table of
:mod:`mftire.iotools.sweeps`, so that ``mftire fit`` and ``mftire diagnose`` read the
result unchanged.

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

Segmentation (:func:`segment`)
------------------------------
1. Each condition (Fz, P, inclination, Vx) is averaged over ``smooth_s`` and is
   *steady* where its smoothed value moves less than its tolerance within ``hold_s``.
2. The levels of each condition are the gap clusters
   (:func:`~mftire.iotools.sweeps.cluster_1d`) of its steady values; a row belongs to a
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

The output carries the columns of :func:`~mftire.iotools.sweeps.group_sweeps`
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
import time as _time
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from mftire.errors import MftireInputError
from mftire.iotools.atomic import atomic_path
from mftire.iotools.sweeps import (
    _ALIASES,
    DIMENSIONS,
    MEASURED_COLUMNS,
    REQUIRED_COLUMNS,
    _set_point,
    cluster_1d,
    sweep_kind,
    unit_factor,
    unit_offset,
)
from mftire.iotools.units import normalise_unit as _normalise_unit

__all__ = [
    "TTC_CHANNELS",
    "SAE_TO_ISO",
    "ColumnSpec",
    "RigReport",
    "read_ttc",
    "read_columns",
    "read_column_map",
    "parse_map_options",
    "to_iso",
    "segment",
    "import_rig",
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

_CONDITIONS = ("Fz", "P", "gamma", "Vx")
_SET_NAMES = {"Fz": "Fz_set", "P": "P_set", "gamma": "gamma_set", "Vx": "Vx_set"}
_REASON_NAMES = {"Fz": "load ramp", "P": "pressure change", "gamma": "inclination change", "Vx": "speed change"}


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
        conv = pd.to_numeric(s, errors="coerce")
        bad = conv.isna() & s.notna()
        if bad.any():
            i = int(np.flatnonzero(bad.to_numpy())[0])
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
    for target, aliases in _ALIASES.items():
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


def _spec_from(target: str, entry: Any, where: str) -> ColumnSpec:
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
    out["columns"] = {t: _spec_from(t, e, p) for t, e in cols.items()}
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
    specs = {t: (s if isinstance(s, ColumnSpec) else _spec_from(t, s, "column map")) for t, s in columns.items()}
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
                unit = {"angle": "rad", "speed": "m/s", "pressure": "Pa", "force": "N", "moment": "Nm",
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


# ----------------------------------------------------------------------------------------
# segmentation
# ----------------------------------------------------------------------------------------


@dataclass
class RigReport:
    """What :func:`segment` (and :func:`import_rig`) did."""

    file: str = ""
    n_rows: int = 0
    duration_s: float = 0.0
    sample_rate_hz: float = 0.0
    convention: str = ""
    units_read: dict[str, str] = field(default_factory=dict)
    channel_map: dict[str, str] = field(default_factory=dict)
    levels: dict[str, list[float]] = field(default_factory=dict)  #: levels found per condition (SI)
    rows_kept: int = 0
    dropped: dict[str, int] = field(default_factory=dict)  #: rows dropped per reason
    segments: list[dict[str, Any]] = field(default_factory=list)  #: one entry per segment, kept or dropped
    n_sweeps: int = 0
    n_points: int = 0
    directions: dict[str, int] = field(default_factory=dict)  #: sweeps per direction
    messages: list[str] = field(default_factory=list)
    seconds: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        """Plain-dict copy (JSON serialisable)."""
        return asdict(self)

    def __str__(self) -> str:
        return self.text()

    def text(self, max_listed: int = 20) -> str:
        """Human-readable summary, listing at most ``max_listed`` dropped segments."""
        lines = [f"{self.file}: {self.n_rows} rows, {self.duration_s:.1f} s at {self.sample_rate_hz:.4g} Hz, "
                 f"{self.convention.upper()} axes -> ISO W"]
        for c, lv in self.levels.items():
            shown = ", ".join(_fmt_level(c, v) for v in lv)
            lines.append(f"  {c} levels: {shown}")
        kept = sum(1 for s in self.segments if s["status"] == "kept")
        lines.append(f"  {kept} of {len(self.segments)} segments kept, {self.rows_kept} rows in "
                     f"{self.n_sweeps} sweeps ({', '.join(f'{n} {d}' for d, n in self.directions.items())}) "
                     f"-> {self.n_points} points")
        for reason, n in sorted(self.dropped.items(), key=lambda kv: -kv[1]):
            lines.append(f"  dropped {n} rows ({n / max(self.n_rows, 1):.1%}): {reason}")
        dropped = [s for s in self.segments if s["status"] != "kept"]
        for s in dropped[:max_listed]:
            lines.append(f"    t = {s['t_start']:.2f}-{s['t_end']:.2f} s (rows {s['row_first']}-{s['row_last']}):"
                         f" {s['reason']}")
        if len(dropped) > max_listed:
            lines.append(f"    ... {len(dropped) - max_listed} more dropped segments (see the JSON report)")
        lines.extend(f"  note: {m}" for m in self.messages)
        return "\n".join(lines)


def _fmt_level(column: str, v: float) -> str:
    if column == "gamma":
        return f"{math.degrees(v):.2f} deg"
    if column == "P":
        return f"{v / 1e3:.1f} kPa"
    if column == "Vx":
        return f"{v * 3.6:.1f} km/h"
    return f"{v:.0f} N"


def _tol(column: str, level: np.ndarray, tols: Mapping[str, tuple[float, float]]) -> np.ndarray:
    rel, ab = tols[column]
    return ab + rel * np.abs(level)


def _runs(codes: np.ndarray) -> np.ndarray:
    """Run id of each element: increments wherever the code changes."""
    change = np.empty(codes.size, dtype=bool)
    if codes.size:
        change[0] = True
        change[1:] = codes[1:] != codes[:-1]
    return np.cumsum(change) - 1


def segment(
    df: pd.DataFrame,
    *,
    time: str | None = None,
    fz_tol: float = 0.05,
    p_tol: float = 0.03,
    gamma_tol: float = math.radians(0.3),
    vx_tol: float = 0.05,
    vx_abs_tol: float = 0.3,
    alpha_tol: float = math.radians(0.5),
    kappa_tol: float = 0.01,
    smooth_s: float = 0.5,
    hold_s: float = 1.0,
    min_segment_s: float = 3.0,
    min_sweep_points: int = 10,
    min_dwell_s: float = 0.3,
    warmup: str | float | None = "auto",
    points_per_sweep: int | None = None,
    name: str = "",
) -> tuple[pd.DataFrame, RigReport]:
    """Cut a continuous SI/ISO time series (from :func:`read_ttc` / :func:`read_columns`) into sweeps.

    See the module docstring for the procedure.  Tolerances: ``fz_tol``, ``p_tol`` and
    ``vx_tol`` relative [-] (``vx_abs_tol`` [m/s] added), ``gamma_tol`` and
    ``alpha_tol`` [rad], ``kappa_tol`` [-].  Times in seconds.  A sweep has at least
    ``min_sweep_points`` rows; the swept slip standing still (within a tenth of its
    tolerance over 0.1 s) for ``min_dwell_s`` or longer is a dwell, not part of a sweep.

    Returns
    -------
    (DataFrame, RigReport)
        The sweep table (schema columns, extra channels, sweep labels, ``row_first``,
        ``row_last``) and the report.
    """
    missing = [c for c in REQUIRED_COLUMNS if c not in df.columns]
    if missing:
        raise MftireInputError(f"segment: missing column(s) {', '.join(missing)}")
    n = len(df)
    if n < 3:
        raise MftireInputError(f"segment: {n} rows; a time series needs more")
    tcol = time or df.attrs.get("time_column")
    t = df[tcol].to_numpy(float) if tcol else np.arange(n, dtype=float)
    dts = np.diff(t)
    dt = float(np.median(dts[dts > 0])) if np.any(dts > 0) else 1.0
    fs = 1.0 / dt
    w_smooth = max(3, int(round(smooth_s * fs)) | 1)
    w_hold = max(3, int(round(hold_s * fs)) | 1)
    tols = {"Fz": (fz_tol, 0.0), "P": (p_tol, 0.0), "gamma": (0.0, gamma_tol), "Vx": (vx_tol, vx_abs_tol)}
    rep = RigReport(file=name or str(df.attrs.get("file", "")), n_rows=n, duration_s=float(t[-1] - t[0]),
                    sample_rate_hz=fs, convention=str(df.attrs.get("convention", "")),
                    units_read=dict(df.attrs.get("units_read", {})),
                    channel_map=dict(df.attrs.get("channel_map", {})),
                    messages=list(df.attrs.get("messages", [])))  # fmt: skip

    # 1-2: steady rows and levels of every condition
    labels = np.zeros((n, len(_CONDITIONS)), dtype=np.int64)
    first_bad = np.full(n, -1, dtype=int)  # index of the first condition not at a level
    level_values: dict[str, np.ndarray] = {}
    for j, c in enumerate(_CONDITIONS):
        x = df[c].to_numpy(float)
        sm = pd.Series(x).rolling(w_smooth, center=True, min_periods=1).mean()
        move = (sm.rolling(w_hold, center=True, min_periods=1).max()
                - sm.rolling(w_hold, center=True, min_periods=1).min()).to_numpy()  # fmt: skip
        s = sm.to_numpy()
        steady = move <= _tol(c, s, tols)
        rel, ab = tols[c]
        lab = np.full(n, -1, dtype=np.int64)
        if steady.any():
            cl = cluster_1d(s[steady], rel_tol=rel, abs_tol=ab)
            ids, counts = np.unique(cl, return_counts=True)
            big = ids[counts >= max(1, int(min_segment_s * fs * 0.5))]
            kind = "angle" if c == "gamma" else "rel"
            centres = np.array([_set_point(s[steady][cl == i], kind) for i in big])
            if centres.size:
                order = np.argsort(centres)
                centres = centres[order]
                near = np.abs(s[:, None] - centres[None, :])
                k = np.argmin(near, axis=1)
                ok = steady & (near[np.arange(n), k] <= _tol(c, centres[k], tols))
                lab[ok] = k[ok]
            level_values[c] = centres
        else:
            level_values[c] = np.array([])
        labels[:, j] = lab
        first_bad[(lab < 0) & (first_bad < 0)] = j
    rep.levels = {c: [float(v) for v in level_values[c]] for c in _CONDITIONS}

    # 3: segments = runs of one level of every condition
    in_cond = first_bad < 0
    code = np.where(in_cond, labels @ (np.int64(1000) ** np.arange(len(_CONDITIONS))), -1)
    run = _runs(code)
    reason = np.empty(n, dtype=object)
    reason[:] = ""
    not_in = ~in_cond
    for j, c in enumerate(_CONDITIONS):
        reason[not_in & (first_bad == j)] = f"{_REASON_NAMES[c]} (transition between levels)"
    run_start = np.flatnonzero(np.r_[True, run[1:] != run[:-1]])
    run_end = np.r_[run_start[1:], n]
    seg_rows: list[tuple[int, int, int]] = []  # (start, end, code) of candidate segments
    for s0, e0 in zip(run_start, run_end, strict=True):
        if code[s0] < 0:
            continue
        seg_rows.append((int(s0), int(e0), int(code[s0])))
    keep = np.zeros(n, dtype=bool)
    seg_id = np.full(n, -1, dtype=int)
    alpha = df["alpha"].to_numpy(float)
    kappa = df["kappa"].to_numpy(float)
    warm_end_t = None
    if isinstance(warmup, (int, float)) and not isinstance(warmup, bool) and warmup > 0:
        warm_end_t = t[0] + float(warmup)
    elif warmup not in (None, "auto", 0, False, "none", "off"):
        raise MftireInputError(f"warmup must be 'auto', 'none' or a number of seconds, got {warmup!r}")
    auto_warm = warmup == "auto"
    first_long = True
    for k_seg, (s0, e0, cd) in enumerate(seg_rows):
        entry: dict[str, Any] = {"row_first": s0, "row_last": e0 - 1, "t_start": float(t[s0]),
                                 "t_end": float(t[e0 - 1]), "n_rows": e0 - s0}  # fmt: skip
        for j, c in enumerate(_CONDITIONS):
            entry[c] = float(level_values[c][labels[s0, j]])
        dur = float(t[e0 - 1] - t[s0])
        why = ""
        if dur < min_segment_s:
            why = f"short hold ({dur:.1f} s < {min_segment_s:g} s)"
        elif warm_end_t is not None and t[e0 - 1] <= warm_end_t:
            why = f"warm-up (first {warmup:g} s)"
        elif auto_warm and first_long and any(c2 == cd for (_, _, c2) in seg_rows[k_seg + 1:]):
            why = "warm-up (first segment; its condition is measured again later)"
        first_long = first_long and dur < min_segment_s
        if not why:
            a_rng = float(np.subtract(*np.percentile(alpha[s0:e0], [98, 2])))
            k_rng = float(np.subtract(*np.percentile(kappa[s0:e0], [98, 2])))
            if a_rng <= 2 * alpha_tol and k_rng <= 2 * kappa_tol:
                why = "no slip sweep (free rolling or a held slip)"
        if why:
            entry.update(status="dropped", reason=why)
            reason[s0:e0] = why
        else:
            entry.update(status="kept", reason="")
            keep[s0:e0] = True
            seg_id[s0:e0] = k_seg
            if warm_end_t is not None and t[s0] < warm_end_t:
                part = t[s0:e0] < warm_end_t
                keep[s0:e0][part] = False
                reason[s0:e0][part] = f"warm-up (first {warmup:g} s)"
        rep.segments.append(entry)

    # 5: sweeps inside the kept segments, split at turning points of the swept slip
    sweep = np.full(n, -1, dtype=np.int64)
    sdir = np.zeros(n, dtype=int)
    seg_info: dict[int, dict[str, Any]] = {}
    w_dir = max(3, int(round(0.05 * fs)) | 1)
    lag = max(1, int(round(0.05 * fs)))
    min_dwell = max(min_sweep_points, int(round(min_dwell_s * fs)))
    next_id = 0
    for k_seg, entry in enumerate(rep.segments):
        if entry["status"] != "kept":
            continue
        s0, e0 = entry["row_first"], entry["row_last"] + 1
        rows = np.arange(s0, e0)[keep[s0:e0]]
        if rows.size < min_sweep_points:
            continue
        a, kp = alpha[rows], kappa[rows]
        kind = sweep_kind(kp, a, kappa_tol=kappa_tol, alpha_tol=alpha_tol)
        ra = float(np.subtract(*np.percentile(a, [98, 2]))) / alpha_tol
        rk = float(np.subtract(*np.percentile(kp, [98, 2]))) / kappa_tol
        var = "alpha" if ra >= rk else "kappa"
        x = a if var == "alpha" else kp
        tol = alpha_tol if var == "alpha" else kappa_tol
        # direction from the change of the smoothed slip over +-lag; "moving" beyond a dead band
        xs = pd.Series(x).rolling(w_dir, center=True, min_periods=1).mean().to_numpy()
        xp = np.pad(xs, lag, mode="edge")
        d = xp[2 * lag:] - xp[: -2 * lag]
        moving = np.abs(d) > 0.1 * tol
        still = _runs(moving)
        dwell = ~moving & (np.bincount(still)[still] >= min_dwell)  # the slip is held: not a sweep
        sg = np.where(moving, np.sign(d), np.nan)
        sg = pd.Series(sg).ffill().bfill().fillna(1.0).to_numpy(copy=True)
        sg[dwell] = 0.0
        r = _runs(sg)
        # short flickers near turning points: take the direction of the run before them
        cnt = np.bincount(r)
        short = (cnt[r] < min_sweep_points) & ~dwell
        if short.any() and not short.all():
            sg2 = sg.copy()
            sg2[short] = np.nan
            sg = pd.Series(sg2).ffill().bfill().to_numpy()
            r = _runs(sg)
        gx = pd.Series(x).groupby(r)
        span = (gx.max() - gx.min()).to_numpy()
        cnt = np.bincount(r)
        good = (span[r] > 2 * tol) & (cnt[r] >= min_sweep_points) & (sg != 0)
        keep[rows[dwell]] = False
        reason[rows[dwell]] = "dwell (slip held, no sweep)"
        drop_rows = rows[~good & ~dwell]
        keep[drop_rows] = False
        reason[drop_rows] = "turning point (sweep shorter than the minimum)"
        _, ids = np.unique(r[good], return_inverse=True)
        sweep[rows[good]] = ids + next_id
        sdir[rows[good]] = sg[good].astype(int)
        seg_info[k_seg] = {"kind": kind, "sweep_var": var,
                           "alpha_set": np.nan if var == "alpha" else float(np.median(a)),
                           "kappa_set": np.nan if var == "kappa" else float(np.median(kp))}  # fmt: skip
        next_id += int(ids.max()) + 1 if ids.size else 0

    kept_rows = np.flatnonzero(keep)
    for why, cnt in pd.Series(reason[~keep]).value_counts().items():
        rep.dropped[str(why) or "other"] = int(cnt)
    rep.rows_kept = int(kept_rows.size)
    if kept_rows.size == 0:
        raise MftireInputError(f"{rep.file}: no sweep found in the time series\n{rep}")

    # output table: the kept rows, with labels
    base = df.iloc[kept_rows].reset_index(drop=True)
    base["row_first"] = kept_rows
    base["row_last"] = kept_rows
    base["sweep_id"] = sweep[kept_rows]
    base["sweep_dir"] = sdir[kept_rows]
    segs = seg_id[kept_rows]
    base["_seg"] = segs
    if points_per_sweep:
        if int(points_per_sweep) < 1:
            raise MftireInputError(f"points per sweep must be >= 1, got {points_per_sweep}")
        npts = int(points_per_sweep)
        pos = base.groupby("sweep_id", sort=False).cumcount().to_numpy()
        size = base.groupby("sweep_id", sort=False)["sweep_id"].transform("size").to_numpy()
        base["_bin"] = (pos * npts) // size
        keys = ["sweep_id", "_bin"]
        num = [c for c in base.columns if c not in keys and pd.api.types.is_numeric_dtype(base[c])]
        other = [c for c in base.columns if c not in keys and c not in num]
        g = base.groupby(keys, sort=True)
        agg = g[num].mean()
        agg["row_first"] = g["row_first"].min()
        agg["row_last"] = g["row_last"].max()
        agg["sweep_dir"] = g["sweep_dir"].first()
        agg["_seg"] = g["_seg"].first()
        if other:
            agg = agg.join(g[other].first())
        base = agg.reset_index().drop(columns="_bin").sort_values("row_first", kind="stable")
        base = base.reset_index(drop=True)
    segs = base["_seg"].to_numpy()
    for c in _CONDITIONS:
        lv = np.array([rep.segments[s][c] for s in range(len(rep.segments))])
        base[_SET_NAMES[c]] = lv[segs]
    for key in ("kind", "sweep_var", "kappa_set", "alpha_set"):
        m = {s: info[key] for s, info in seg_info.items()}
        base[key] = pd.Series(segs).map(m).to_numpy()
    base["direction"] = np.where(base["sweep_dir"].to_numpy() > 0, "increasing", "decreasing")
    base = base.drop(columns="_seg")
    first = base.groupby("sweep_id", sort=False)["direction"].first()
    rep.n_sweeps = int(first.size)
    rep.directions = {str(k): int(v) for k, v in first.value_counts().items()}
    rep.n_points = len(base)
    # no attrs on the table: pandas deep-copies them on every column access, which slows every
    # later step (fit, diagnosis); the report holds what they held
    base.attrs = {}
    return base, rep


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


# ----------------------------------------------------------------------------------------
# one call and the command line
# ----------------------------------------------------------------------------------------


def import_rig(
    path: PathLike,
    fmt: str = "ttc",
    *,
    output: PathLike | None = None,
    columns: Mapping[str, ColumnSpec | str | Mapping] | None = None,
    column_map: PathLike | None = None,
    convention: str | None = None,
    signs: Mapping[str, float] | None = None,
    points_per_sweep: int | None = None,
    **segment_kw: Any,
) -> tuple[pd.DataFrame, RigReport]:
    """Read a raw rig file, convert it to SI/ISO, segment it and (with ``output``) write the sweep CSV.

    ``fmt`` is ``"ttc"`` or ``"columns"``; for ``"columns"`` the column map comes from
    ``column_map`` (TOML, :func:`read_column_map`) and/or ``columns`` (which win).
    ``convention`` defaults to SAE for TTC files and to the map's (else ISO) for columns.
    Other keywords go to :func:`segment`.
    """
    t0 = _time.perf_counter()
    p = os.fspath(path)
    if fmt == "ttc":
        if columns or column_map:
            raise MftireInputError("a column map (--map/--columns-map) is only used with --format columns")
        df = read_ttc(p, convention=convention or "sae", signs=signs)
    elif fmt == "columns":
        opts: dict[str, Any] = read_column_map(column_map) if column_map else {"columns": {}}
        specs = dict(opts.pop("columns"))
        specs.update({t: (s if isinstance(s, ColumnSpec) else _spec_from(t, s, "--map"))
                      for t, s in (columns or {}).items()})  # fmt: skip
        conv = convention or opts.pop("convention", "iso")
        opts.pop("convention", None)
        df = read_columns(p, specs, convention=conv, **opts)
        if signs:
            to_iso(df, "iso", signs)
    else:
        raise MftireInputError(f"--format must be 'ttc' or 'columns', got {fmt!r}")
    table, rep = segment(df, points_per_sweep=points_per_sweep, name=p, **segment_kw)
    rep.seconds = _time.perf_counter() - t0
    if output is not None:
        write_sweeps(table, output)
    return table, rep


def write_sweeps(table: pd.DataFrame, path: PathLike) -> None:
    """Write an imported sweep table as CSV, atomically (the folder is created if needed)."""
    folder = os.path.dirname(os.path.abspath(os.fspath(path)))
    os.makedirs(folder, exist_ok=True)
    with atomic_path(path) as tmp:
        table.to_csv(tmp, index=False, float_format="%.8g")
