"""Data preparation for fitting: loading, column checks, weights, noise estimates.

The sweep table itself (schema, validation, grouping) lives in
:mod:`mftire.iotools.sweeps`; this module adds what fitting needs on top of it:

* :func:`load_sweep_files` reads CSV (sweep schema) and TYDEX ``.tdx`` files into one
  table with a ``source`` column (the file's own ``source`` column when it has one,
  else the file stem) and a ``file`` column;
* :func:`check_columns` rejects columns that look like a schema quantity under
  another name or in another unit (``FY``, ``alpha_deg``, ``Fz [kN]`` ...), naming them;
* :func:`parse_weights` / :func:`row_weights` turn ``"fe=1,measured=5"`` into per-row
  weights keyed on ``source`` (or file name);
* :func:`noise_std` estimates the measurement noise of a channel from second
  differences along each sweep (robust, MAD based).
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable, Mapping, Sequence

import numpy as np
import pandas as pd
from scipy import stats

from mftire.errors import MftireInputError
from mftire.iotools.sweeps import (
    MEASURED_COLUMNS,
    OPTIONAL_INPUT_COLUMNS,
    REQUIRED_COLUMNS,
    validate_sweeps,
)

__all__ = [
    "check_columns",
    "load_sweep_files",
    "prepare_table",
    "parse_weights",
    "row_weights",
    "noise_std",
]

_SCHEMA = set(REQUIRED_COLUMNS) | set(OPTIONAL_INPUT_COLUMNS) | set(MEASURED_COLUMNS)
_LOWER = {c.lower(): c for c in _SCHEMA}
# TYDEX channel keys and other common names of schema quantities
_OTHER_NAMES = {
    "fzw": "Fz", "fxw": "Fx", "fyw": "Fy", "mzw": "Mz", "mxw": "Mx", "myw": "My",
    "longslip": "kappa", "slipangl": "alpha", "inclangl": "gamma", "inflpres": "P", "runspeed": "Vx",
    "sa": "alpha", "sl": "kappa", "sr": "kappa", "ia": "gamma", "camber": "gamma", "slip_angle": "alpha",
    "slip_ratio": "kappa", "pressure": "P", "speed": "Vx", "load": "Fz", "v": "Vx",
}  # fmt: skip
_UNIT_RE = re.compile(r"^\s*([A-Za-z_]+?)\s*(?:[\[(]\s*([^\])]*)\s*[\])]|_(deg|rad|kn|kpa|bar|psi|pct|kmh|kph|"
                      r"percent|mm|nmm|knm|n|nm|pa|ms))\s*$", re.IGNORECASE)


def check_columns(df: pd.DataFrame, name: str = "sweep data", tydex: bool = False) -> None:
    """Raise :class:`MftireInputError` naming columns that look like a schema quantity.

    Other columns are carried through untouched; but a column such as ``FY``,
    ``SLIPANGL``, ``alpha_deg`` or ``Fz [kN]`` is almost certainly a measured quantity
    in the wrong name or unit and would silently be ignored by the fit.  With ``tydex``
    the second-choice TYDEX keys that :func:`~mftire.iotools.tydex.read_tydex` keeps
    beside the mapped channel (``FX`` next to ``FXW``) are accepted.
    """
    from mftire.iotools.tydex import TYDEX_CHANNELS

    tydex_keys = {k: col for col, keys in TYDEX_CHANNELS.items() for k in keys}
    bad: list[str] = []
    for col in df.columns:
        label = str(col)
        if label in _SCHEMA:
            continue
        if tydex and label in tydex_keys and tydex_keys[label] in df.columns:
            continue
        low = label.strip().lower()
        target = _LOWER.get(low) or _OTHER_NAMES.get(low)
        unit = None
        if target is None:
            m = _UNIT_RE.match(label)
            if m:
                stem = m.group(1).lower()
                target = _LOWER.get(stem) or _OTHER_NAMES.get(stem)
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
        from mftire.iotools.tydex import read_tydex

        df = read_tydex(path)
    else:
        from mftire.iotools.sweeps import read_sweep_csv

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


def parse_weights(spec: str | Mapping[str, float] | None) -> dict[str, float]:
    """``"fe=1,measured=5"`` -> ``{"fe": 1.0, "measured": 5.0}``.

    Raises
    ------
    MftireInputError
        On a malformed item or a negative / non-finite weight.
    """
    if spec is None or spec == "":
        return {}
    if isinstance(spec, Mapping):
        items = list(spec.items())
    else:
        items = []
        for raw in str(spec).split(","):
            if not raw.strip():
                continue
            if "=" not in raw:
                raise MftireInputError(f"--weights: {raw.strip()!r} is not SOURCE=WEIGHT (e.g. fe=1,measured=5)")
            key, value = raw.split("=", 1)
            items.append((key.strip(), value.strip()))
    out: dict[str, float] = {}
    for key, value in items:
        try:
            w = float(value)
        except (TypeError, ValueError):
            raise MftireInputError(f"--weights: weight of {key!r} is not a number: {value!r}") from None
        if not np.isfinite(w) or w < 0:
            raise MftireInputError(f"--weights: weight of {key!r} must be a finite number >= 0, got {value!r}")
        out[str(key)] = w
    return out


def row_weights(df: pd.DataFrame, weights: Mapping[str, float]) -> np.ndarray:
    """Per-row weight from ``{source or file name: weight}`` (1 where not listed).

    A key matches the ``source`` column, or the ``file`` column by base name or stem.

    Raises
    ------
    MftireInputError
        When a key matches no row (the message lists the available sources).
    """
    w = np.ones(len(df))
    if not weights:
        return w
    src = df["source"].astype(str).to_numpy() if "source" in df.columns else np.full(len(df), "")
    files = df["file"].astype(str).to_numpy() if "file" in df.columns else np.full(len(df), "")
    base = np.array([os.path.basename(f) for f in files])
    stem = np.array([os.path.splitext(b)[0] for b in base])
    for key, value in weights.items():
        hit = (src == key) | (files == key) | (base == key) | (stem == key)
        if not hit.any():
            avail = sorted(set(src) | set(base))
            raise MftireInputError(f"--weights: no data with source or file {key!r}; available: {', '.join(avail)}")
        w[hit] = value
    return w


def noise_std(y: np.ndarray, x: np.ndarray, groups: np.ndarray | None = None) -> float:
    """Robust noise standard deviation of ``y`` measured along ``x`` [unit of y].

    Within each group (sweep) points are sorted by ``x`` and the second differences
    ``y[i-1] - 2 y[i] + y[i+1]`` (variance 6σ² for white noise) are formed; σ is the
    normalised median absolute deviation of all of them divided by √6.  A smooth curve
    contributes little to second differences, gross outliers nothing (median).
    """
    y = np.asarray(y, dtype=float)
    x = np.asarray(x, dtype=float)
    if groups is None:
        groups = np.zeros(y.size, dtype=int)
    d2: list[np.ndarray] = []
    for g in np.unique(groups):
        m = groups == g
        if m.sum() < 3:
            continue
        order = np.argsort(x[m], kind="stable")
        yy = y[m][order]
        d2.append(yy[:-2] - 2.0 * yy[1:-1] + yy[2:])
    if not d2:
        return 0.0
    d = np.concatenate(d2)
    d = d[np.isfinite(d)]
    if d.size == 0:
        return 0.0
    return float(stats.median_abs_deviation(d, scale="normal") / np.sqrt(6.0))


def iter_groups(labels: np.ndarray) -> Iterable[np.ndarray]:
    """Row indices of each distinct label."""
    order = np.argsort(labels, kind="stable")
    bounds = np.flatnonzero(np.diff(labels[order])) + 1
    return np.split(order, bounds)
