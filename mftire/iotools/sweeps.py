"""The sweep table: one pandas DataFrame format for all slip-sweep data.

Every loader in mftire (CSV, TYDEX, simulation output) ends in the same table:

======== ====== ==================================================
column   unit   meaning
======== ====== ==================================================
Fz       N      vertical load (positive in compression)
kappa    -      longitudinal slip (fraction, not %)
alpha    rad    slip angle
gamma    rad    inclination (camber) angle
Vx       m/s    forward speed of the wheel centre
P        Pa     inflation pressure
phit     1/m    turn slip (optional, 0 when absent)
Fx, Fy   N      measured forces (any subset)
Mx,My,Mz N·m    measured moments (any subset)
======== ====== ==================================================

Any other column (run id, time, temperature, file, ...) is carried through untouched.

Functions here are small and pure: :func:`validate_sweeps` checks a table and returns a
clean copy plus a :class:`SweepReport`; :func:`convert_to_si` and :func:`to_schema` do the
unit conversions shared with :mod:`mftire.iotools.tydex`.  Grouping rows into sweeps
(set points, sweep ids, kinds) is sweep analysis, not reading: it lives in
:mod:`mftire.segmentation.grouping`.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from mftire.errors import MftireInputError
from mftire.iotools.units import DIMENSIONS, SI_UNITS, is_known_unit, unit_factor, unit_offset

__all__ = [
    "REQUIRED_COLUMNS",
    "OPTIONAL_INPUT_COLUMNS",
    "MEASURED_COLUMNS",
    "SI_UNITS",
    "SweepReport",
    "is_known_unit",
    "unit_factor",
    "unit_offset",
    "convert_to_si",
    "convert_from_si",
    "to_schema",
    "read_sweep_csv",
    "validate_sweeps",
    "FIT_ROW",
    "fit_rows",
    "COLUMN_ALIASES",
    "to_numbers",
]

#: Operating-condition inputs every sweep table must have (SI).
REQUIRED_COLUMNS: tuple[str, ...] = ("Fz", "kappa", "alpha", "gamma", "Vx", "P")
#: Inputs that may be absent (filled with 0 where NaN).
OPTIONAL_INPUT_COLUMNS: tuple[str, ...] = ("phit",)
#: Measured channels; a table holds any subset.
MEASURED_COLUMNS: tuple[str, ...] = ("Fx", "Fy", "Mz", "Mx", "My")

#: Boolean column of imported rig tables (:func:`mftire.segmentation.rig_segments.segment`):
#: True on the rows of the sweeps a fit uses, False on rows kept only for the diagnosis
#: (warm-up, load ramps and other transitions, dwells), with their ``drop_reason``.
FIT_ROW = "fit_row"


def fit_rows(df: pd.DataFrame) -> pd.DataFrame:
    """The rows a fit (and a comparison) uses: those with ``fit_row`` True, or all rows without that column.

    A ``fit_row`` column read back from CSV holds ``True``/``False`` (bool) or text; both
    are understood.  The index is kept.
    """
    if FIT_ROW not in df.columns:
        return df
    flag = df[FIT_ROW]
    if flag.dtype != bool:
        flag = flag.astype(str).str.strip().str.lower().isin(("true", "1", "1.0", "yes"))
    return df if bool(flag.all()) else df[flag.to_numpy()]


# The unit table (names, exact SI factors, SI unit and dimension of each column) lives in
# mftire.iotools.units; re-exported here for the readers and users of the sweep table.


def convert_to_si(values: Any, unit: str | None, column: str) -> Any:
    """Convert ``values`` given in ``unit`` to the SI unit of schema ``column``.

    ``values`` may be a scalar, numpy array or pandas Series; the same type comes back.
    Example: ``convert_to_si(12.0, "deg", "alpha")`` gives 0.2094 rad.
    """
    dimension = DIMENSIONS.get(column)
    if dimension is None:
        raise MftireInputError(f"no SI unit is defined for column {column!r}")
    return values * unit_factor(unit, dimension)


def convert_from_si(values: Any, unit: str | None, column: str) -> Any:
    """Inverse of :func:`convert_to_si`: SI values of ``column`` expressed in ``unit``."""
    dimension = DIMENSIONS.get(column)
    if dimension is None:
        raise MftireInputError(f"no SI unit is defined for column {column!r}")
    return values / unit_factor(unit, dimension)


def to_schema(df: pd.DataFrame, mapping: Mapping[str, tuple[str, str]]) -> pd.DataFrame:
    """Rename and convert columns into the sweep schema.

    Parameters
    ----------
    df : DataFrame
        Input table; not modified.
    mapping : dict
        ``{source_column: (schema_column, unit)}``, e.g.
        ``{"SA": ("alpha", "deg"), "FZ": ("Fz", "N"), "P_kPa": ("P", "kPa")}``.
        A negative sign convention can be handled afterwards (``out["Fz"] *= -1``).

    Returns
    -------
    DataFrame
        Copy with the schema columns added in SI; the source columns are dropped
        unless they have the same name as their target.
    """
    out = df.copy()
    for src, (dst, unit) in mapping.items():
        if src not in out.columns:
            raise MftireInputError(f"to_schema: column {src!r} not found")
        values = pd.to_numeric(out[src], errors="raise").astype(float)
        converted = convert_to_si(values, unit, dst)
        if src != dst:
            out = out.drop(columns=[src])
        out[dst] = converted
    return out


# ----------------------------------------------------------------------------------------
# Validation
# ----------------------------------------------------------------------------------------

#: Lower-case column names that usually mean a schema quantity, with the unit they usually
#: carry (None: the same as the schema, only the name differs).  The one table of column aliases.
COLUMN_ALIASES: dict[str, dict[str, str | None]] = {
    "alpha": {"sa": "deg", "slipangle": "deg", "slip_angle": "deg", "slipangl": "deg",
              "alpha_deg": "deg", "sa_deg": "deg", "alpha_rad": None, "alfa": None},
    "kappa": {"sl": None, "sr": None, "slipratio": None, "slip_ratio": None, "longslip": None,
              "kappa_pct": "%", "kappa_percent": "%", "sl_pct": "%", "slip_pct": "%",
              "longslip_pct": "%"},
    "gamma": {"ia": "deg", "inclination": "deg", "inclangl": "deg", "camber": "deg",
              "gamma_deg": "deg", "ia_deg": "deg", "camber_deg": "deg", "gamma_rad": None},
    "Fz": {"fz": None, "fzw": None, "fz_kn": "kN", "load": None, "normal_load": None,
           "fz_n": None},
    "Vx": {"v": "km/h", "vx": None, "vx_kmh": "km/h", "v_kmh": "km/h", "speed": None,
           "runspeed": None, "velocity": None, "vx_kph": "km/h"},
    "P": {"p": None, "pressure": None, "p_kpa": "kPa", "p_bar": "bar", "p_psi": "psi",
          "inflpres": None, "ip": None},
    "phit": {"turnslip": None, "phi_t": None},
    "Fx": {"fx": None, "fxw": None, "fx_kn": "kN"},
    "Fy": {"fy": None, "fyw": None, "fy_kn": "kN"},
    "Mz": {"mz": None, "mzw": None},
    "Mx": {"mx": None, "mxw": None},
    "My": {"my": None, "myw": None},
}


def find_column(columns, column: str) -> str | None:
    """The name among ``columns`` that holds schema ``column`` in its SI unit: the column
    itself, a different letter case of it, or an alias of :data:`COLUMN_ALIASES` that differs in
    name only (``fz`` for ``Fz``, ``slip_ratio`` for ``kappa``; not ``sa``, usually in
    degrees).  None when there is none; a :class:`MftireInputError` when several match."""
    names = [str(c) for c in columns]
    if column in names:
        return column
    same_unit = {a for a, unit in COLUMN_ALIASES.get(column, {}).items() if unit is None} | {column.lower()}
    hits = [n for n in names if n.lower() in same_unit]
    if len(hits) > 1:
        raise MftireInputError(f"columns {', '.join(map(repr, hits))} all look like {column}: keep one")
    return hits[0] if hits else None


def _alias_hint(df: pd.DataFrame, column: str) -> str:
    """A sentence suggesting how an existing column could become schema ``column``."""
    aliases = COLUMN_ALIASES.get(column, {})
    for c in df.columns:
        name = str(c)
        low = name.lower()
        if low == column.lower() and name != column:
            unit = None
        elif low in aliases:
            unit = aliases[low]
        else:
            continue
        unit_txt = unit if unit is not None else SI_UNITS[column]
        note = "" if unit is not None else " (check its unit and sign convention first)"
        convert = f"convert it from {unit_txt} to {SI_UNITS[column]} and " if unit is not None else ""
        return f"; column {name!r} looks like {column}{note}: {convert}rename it {column}"
    return ""


@dataclass
class SweepReport:
    """What :func:`validate_sweeps` did to a table.

    Attributes
    ----------
    name : str
        Name of the data set (file name) used in messages.
    n_rows_in, n_rows_out : int
        Rows before and after cleaning.
    n_dropped_nan : int
        Rows dropped because a required input was NaN/inf or because every measured
        channel present was NaN.
    nan_by_column : dict
        NaN/inf count per required input column among the input rows.
    n_dropped_all_measured_nan : int
        Rows dropped because all measured channels were NaN.
    nan_in_measured : dict
        Rows kept that have NaN in *some* measured channels, per channel (the fit of that
        channel must skip them).
    n_dropped_nonpositive_fz : int
        Rows dropped with Fz <= 0 (wheel lift-off).
    measured_channels, missing_channels : list of str
        Measured channels present / absent.
    filled_defaults : dict
        Columns that were missing and filled with a constant (see ``defaults``).
    n_phit_filled : int
        NaN turn-slip values set to 0.
    messages : list of str
        Human-readable notes.
    """

    name: str
    n_rows_in: int = 0
    n_rows_out: int = 0
    n_dropped_nan: int = 0
    nan_by_column: dict[str, int] = field(default_factory=dict)
    n_dropped_all_measured_nan: int = 0
    nan_in_measured: dict[str, int] = field(default_factory=dict)
    n_dropped_nonpositive_fz: int = 0
    measured_channels: list[str] = field(default_factory=list)
    missing_channels: list[str] = field(default_factory=list)
    filled_defaults: dict[str, float] = field(default_factory=dict)
    n_phit_filled: int = 0
    messages: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """Plain-dict copy (JSON serialisable)."""
        return asdict(self)

    def __str__(self) -> str:
        lines = [f"{self.name}: {self.n_rows_out} of {self.n_rows_in} rows kept"]
        if self.n_dropped_nan:
            detail = ", ".join(f"{k}: {v}" for k, v in self.nan_by_column.items() if v)
            lines.append(f"  {self.n_dropped_nan} rows dropped for NaN ({detail})")
        if self.n_dropped_nonpositive_fz:
            lines.append(f"  {self.n_dropped_nonpositive_fz} rows dropped with Fz <= 0")
        lines.append(f"  measured channels: {', '.join(self.measured_channels) or 'none'}")
        lines.extend(f"  {m}" for m in self.messages)
        return "\n".join(lines)


def to_numbers(raw: pd.Series) -> tuple[pd.Series, int | None]:
    """``raw`` as numbers (NaN where a cell is empty or not a number) and the position of the first cell that
    holds something that is not a number (None when there is none): the readers name its line in the error."""
    num = pd.to_numeric(raw, errors="coerce")
    bad = (num.isna() & raw.notna()).to_numpy()
    return num, (int(np.flatnonzero(bad)[0]) if bad.any() else None)


def _numeric_column(df: pd.DataFrame, column: str, name: str) -> pd.Series:
    """``df[column]`` as float64; raise naming the column and a bad cell if not numeric."""
    s = df[column]
    if pd.api.types.is_bool_dtype(s):
        raise MftireInputError(f"{name}: column {column!r} is boolean, expected numbers")
    if pd.api.types.is_numeric_dtype(s):
        return s.astype(float)
    conv = pd.to_numeric(s, errors="coerce")
    bad = conv.isna() & s.notna() & (s.astype(str).str.strip() != "")
    if bad.any():
        first = bad.idxmax()
        raise MftireInputError(
            f"{name}: column {column!r} is not numeric (row {first!r} holds {s[first]!r}); "
            f"{int(bad.sum())} non-numeric cell(s)"
        )
    return conv.astype(float)


def _check_si(df: pd.DataFrame, name: str, measured: Sequence[str]) -> None:
    """Raise when a schema column's magnitudes suggest a non-SI unit."""

    def robust_max(col: str) -> float:
        v = np.abs(df[col].to_numpy(dtype=float))
        v = v[np.isfinite(v)]
        return float(np.quantile(v, 0.99)) if v.size else 0.0

    def fail(col: str, why: str, fix: str) -> None:
        raise MftireInputError(f"{name}: column {col!r} does not look SI ({why}); {fix}")

    a = robust_max("alpha")
    if a > 1.5 * math.pi / 2:
        fail("alpha", f"|alpha| reaches {a:.3g}, more than 1.5*pi/2 rad",
             "it looks like degrees: convert with np.deg2rad")
    g = robust_max("gamma")
    if g > math.pi / 6:
        fail("gamma", f"|gamma| reaches {g:.3g}, more than 30 deg in rad",
             "it looks like degrees: convert with np.deg2rad")
    k = robust_max("kappa")
    if k > 2.0:
        fail("kappa", f"|kappa| reaches {k:.3g}", "it looks like percent: divide by 100")
    fz = df["Fz"].to_numpy(dtype=float)
    fz = fz[np.isfinite(fz)]
    if fz.size:
        if np.mean(fz < 0) > 0.5:
            fail("Fz", "most values are negative",
                 "mftire wants Fz > 0 in compression; flip the sign (SAE z-down data)")
        fz_max = float(np.quantile(np.abs(fz), 0.99))
        if 0 < fz_max < 50.0:
            fail("Fz", f"|Fz| only reaches {fz_max:.3g}", "it looks like kN: multiply by 1000")
    p = df["P"].to_numpy(dtype=float)
    p = p[np.isfinite(p)]
    if p.size:
        p_med = float(np.median(p))
        if p_med <= 0:
            fail("P", f"median pressure {p_med:.3g} is not positive", "give the inflation pressure in Pa")
        if p_med < 1000.0:
            guess = "bar (multiply by 1e5)" if p_med < 20 else "kPa (multiply by 1e3) or psi (x 6894.76)"
            fail("P", f"median {p_med:.3g} Pa is below 1000 Pa", f"it looks like {guess}")
    v = robust_max("Vx")
    if v > 100.0:
        fail("Vx", f"|Vx| reaches {v:.3g} m/s", "it looks like km/h: divide by 3.6")
    # signs: in ISO/TYDEX W axes Fy opposes a small slip angle and Mz follows it (pneumatic trail,
    # Pacejka 2012 §4.3.2); SAE-signed forces with ISO angles give the opposite at nearly every point
    a_all = df["alpha"].to_numpy(dtype=float)
    small = (np.abs(a_all) > 0.02) & (np.abs(a_all) < 0.1) & (np.abs(df["kappa"].to_numpy(dtype=float)) < 0.02)
    for col, want, says in (("Fy", -1.0, "opposes"), ("Mz", 1.0, "follows")):
        if col in measured and small.sum() >= 10:
            prod = np.sign(df[col].to_numpy(dtype=float)[small] * a_all[small]) * want
            prod = prod[np.isfinite(prod)]
            if prod.size >= 10 and np.mean(prod < 0) > 0.9:
                fail(col, f"at {prod.size} points of small slip angle (1 to 6 deg) {col} has the wrong sign",
                     f"in ISO/TYDEX W axes {col} {says} the slip angle; SAE-signed data? flip {col} "
                     "(or alpha) to ISO")
    # forces in kN: peak lateral/longitudinal force far below what the slip implies
    fz_med = float(np.median(np.abs(fz))) if fz.size else 0.0
    for col, slip, span in (("Fy", "alpha", 0.05), ("Fx", "kappa", 0.05)):
        if col in measured and fz_med > 0:
            s = df[slip].to_numpy(dtype=float)
            s = s[np.isfinite(s)]
            if s.size and np.ptp(s) > span:
                f_max = robust_max(col)
                if 0 < f_max < 0.01 * fz_med:
                    fail(col, f"peak |{col}| {f_max:.3g} is below 1 % of Fz {fz_med:.3g} N "
                         f"over a {slip} sweep", "it looks like kN: multiply by 1000")


def validate_sweeps(
    df: pd.DataFrame,
    name: str = "sweep data",
    *,
    source: str | None = None,
    defaults: Mapping[str, float] | None = None,
    check_units: bool = True,
) -> tuple[pd.DataFrame, SweepReport]:
    """Check a sweep table and return a clean copy with a report.

    Parameters
    ----------
    df : DataFrame
        Table in the sweep schema (see module docstring): SI columns ``Fz`` [N],
        ``kappa`` [-], ``alpha`` [rad], ``gamma`` [rad], ``Vx`` [m/s], ``P`` [Pa],
        optional ``phit`` [1/m], and any of ``Fx, Fy`` [N], ``Mz, Mx, My`` [N·m].
    name : str
        Name of the data set (e.g. the file), used in error messages and the report.
    source : str, optional
        When given, a ``source`` column with this value is added (overwriting any).
    defaults : dict, optional
        Constant values for missing input columns, e.g. ``{"kappa": 0.0, "P": 2.2e5}``
        (SI). Recorded in the report.
    check_units : bool
        Check magnitudes for signs of non-SI units (degrees, percent, kN, bar, km/h).

    Returns
    -------
    clean : DataFrame
        Copy with float64 input/measured columns; rows with NaN/inf in a required
        input, rows where every measured channel is NaN, and rows with Fz <= 0 are
        dropped; NaN ``phit`` is set to 0. The index is kept. Other columns untouched.
    report : SweepReport
        Counts of what was dropped and why.

    Raises
    ------
    MftireInputError
        Missing required column (with a hint when a similarly named column exists), a
        non-numeric column, a column that looks non-SI, or no rows left.
    """
    if not isinstance(df, pd.DataFrame):
        raise MftireInputError(f"{name}: expected a pandas DataFrame, got {type(df).__name__}")
    report = SweepReport(name=name, n_rows_in=len(df))
    dup = df.columns[df.columns.duplicated()].tolist()
    if dup:
        raise MftireInputError(f"{name}: duplicate column(s) {dup}")
    out = df.copy()
    for col, value in (defaults or {}).items():
        if col not in REQUIRED_COLUMNS + OPTIONAL_INPUT_COLUMNS:
            raise MftireInputError(f"{name}: defaults given for {col!r}, which is not an input column")
        if col not in out.columns:
            out[col] = float(value)
            report.filled_defaults[col] = float(value)

    missing = [c for c in REQUIRED_COLUMNS if c not in out.columns]
    if missing:
        hints = "".join(_alias_hint(out, c) for c in missing)
        raise MftireInputError(
            f"{name}: missing required column(s) {', '.join(missing)} "
            f"(SI units: {', '.join(f'{c} [{SI_UNITS[c]}]' for c in missing)}){hints}"
            + ("" if hints else "; an input held constant can be a column of one value")
        )
    for col in MEASURED_COLUMNS + OPTIONAL_INPUT_COLUMNS:
        if col not in out.columns:
            hint = _alias_hint(out, col)
            if hint:
                raise MftireInputError(f"{name}: no column {col!r} [{SI_UNITS[col]}]{hint}")

    measured = [c for c in MEASURED_COLUMNS if c in out.columns]
    report.measured_channels = measured
    report.missing_channels = [c for c in MEASURED_COLUMNS if c not in out.columns]
    inputs = list(REQUIRED_COLUMNS) + [c for c in OPTIONAL_INPUT_COLUMNS if c in out.columns]
    for col in inputs + measured:
        out[col] = _numeric_column(out, col, name).replace([np.inf, -np.inf], np.nan)

    if check_units:
        _check_si(out, name, measured)

    if "phit" in out.columns:
        n_fill = int(out["phit"].isna().sum())
        if n_fill:
            out["phit"] = out["phit"].fillna(0.0)
            report.n_phit_filled = n_fill
            report.messages.append(f"{n_fill} NaN phit values set to 0")

    nan_inputs = out[list(REQUIRED_COLUMNS)].isna()
    report.nan_by_column = {c: int(nan_inputs[c].sum()) for c in REQUIRED_COLUMNS}
    bad = nan_inputs.any(axis=1)
    if measured:
        all_meas_nan = out[measured].isna().all(axis=1) & ~bad
        report.n_dropped_all_measured_nan = int(all_meas_nan.sum())
        bad |= all_meas_nan
    else:
        report.messages.append("no measured channel (Fx, Fy, Mz, Mx, My) in the data")
    report.n_dropped_nan = int(bad.sum())
    out = out.loc[~bad]

    nonpos = out["Fz"] <= 0
    report.n_dropped_nonpositive_fz = int(nonpos.sum())
    out = out.loc[~nonpos]
    if measured:
        report.nan_in_measured = {c: int(out[c].isna().sum()) for c in measured}
    if report.n_dropped_nan:
        report.messages.append(f"{report.n_dropped_nan} rows with NaN dropped")
    if report.n_dropped_nonpositive_fz:
        report.messages.append(f"{report.n_dropped_nonpositive_fz} rows with Fz <= 0 dropped")
    if len(out) == 0:
        raise MftireInputError(f"{name}: no valid rows left after dropping NaN and Fz <= 0 rows")
    if source is not None:
        out["source"] = source
    report.n_rows_out = len(out)
    return out, report


def read_sweep_csv(
    path: str | os.PathLike[str],
    source: str | None = None,
    *,
    validate: bool = True,
    defaults: Mapping[str, float] | None = None,
    check_units: bool = True,
    **read_csv_kwargs: Any,
) -> pd.DataFrame:
    """Read a CSV file in the sweep schema.

    Parameters
    ----------
    path : path-like
        CSV file with a header row; lines starting with ``#`` are comments.
    source : str, optional
        Value of an added ``source`` column (e.g. ``"rig"``, ``"fe"``).
    validate : bool
        Run :func:`validate_sweeps` (default). Its report is stored as a dict in
        ``df.attrs["report"]``.
    defaults, check_units
        Passed to :func:`validate_sweeps`.
    **read_csv_kwargs
        Extra keyword arguments for :func:`pandas.read_csv`.

    Returns
    -------
    DataFrame
        The sweep table (SI).
    """
    kwargs: dict[str, Any] = {"comment": "#", "skipinitialspace": True}
    kwargs.update(read_csv_kwargs)
    try:
        df = pd.read_csv(path, **kwargs)
    except (OSError, pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise MftireInputError(f"cannot read sweep CSV {os.fspath(path)}: {exc}") from exc
    df.columns = [str(c).strip() for c in df.columns]
    if not validate:
        if source is not None:
            df["source"] = source
        return df
    clean, report = validate_sweeps(df, os.fspath(path), source=source, defaults=defaults,
                                    check_units=check_units)
    clean.attrs["report"] = report.to_dict()
    return clean
