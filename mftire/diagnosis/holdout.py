"""Split sweep data by operating condition, never by random rows."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from mftire.errors import MftireInputError
from mftire.iotools.columns import SET_POINT_COLUMNS


def parse_holdout(spec: str) -> tuple[str, list[float]]:
    """Parse ``COLUMN=V1,V2,...`` (SI values)."""
    if "=" not in spec:
        raise MftireInputError(f"--holdout must look like COLUMN=VALUE[,VALUE...], got {spec!r}")
    col, _, vals = spec.partition("=")
    try:
        values = [float(v) for v in vals.split(",") if v.strip()]
    except ValueError:
        raise MftireInputError(f"--holdout {spec!r}: values must be numbers (SI units)") from None
    if not col.strip() or not values:
        raise MftireInputError(f"--holdout must look like COLUMN=VALUE[,VALUE...], got {spec!r}")
    return col.strip(), values


def holdout_mask(df: pd.DataFrame, column: str, values: Sequence[float], rel_tol: float = 0.02) -> np.ndarray:
    """Rows whose condition ``column`` is at one of ``values``.

    Fz, Vx, P and gamma are matched on their sweep set points within ``rel_tol``
    (absolute 1e-3 for gamma), other columns within ``rel_tol`` of the value.
    """
    col = SET_POINT_COLUMNS.get(column, column)
    if col not in df.columns:
        raise MftireInputError(f"--holdout: no column '{column}' in the data (have: {', '.join(map(str, df.columns))})")
    x = df[col].to_numpy(float)
    mask = np.zeros(len(df), dtype=bool)
    missing = []
    for v in values:
        tol = 1e-3 if column == "gamma" else rel_tol * max(abs(v), 1e-12)
        hit = np.abs(x - v) <= tol
        if not hit.any():
            missing.append(v)
        mask |= hit
    if missing:  # every requested level must exist, not just one of them
        levels = ", ".join(f"{u:g}" for u in np.unique(np.round(x, 6))[:12])
        raise MftireInputError(f"--holdout {column}: no rows at {', '.join(f'{v:g}' for v in missing)} "
                               f"(levels present: {levels})")
    if mask.all():
        raise MftireInputError(f"--holdout {column}={values} holds out every row; nothing is left to fit")
    return mask


def levels(df: pd.DataFrame, column: str) -> np.ndarray:
    """Sorted distinct levels of a condition (its set points for Fz, Vx, P, gamma)."""
    col = SET_POINT_COLUMNS.get(column, column)
    return np.unique(df[col].to_numpy(float))


def keeps_every_kind(kinds: np.ndarray | None, held: np.ndarray) -> bool:
    """True when holding out the rows ``held`` (a mask) leaves every kind of sweep (``kinds``, one per row; None:
    not known) in the training rows: the refitted coefficients of each channel need their own sweeps."""
    return kinds is None or set(kinds[~held]) >= set(kinds)


def _keeps_every_kind(df: pd.DataFrame, col: str, value: float) -> bool:
    """True when holding out ``col == value`` leaves every kind of sweep in the training data."""
    if "kind" not in df.columns:
        return True
    held = ~(np.abs(df[col].to_numpy(float) - value) > 1e-9 * max(abs(value), 1.0))  # NaN rows: not trained on
    return keeps_every_kind(df["kind"].to_numpy(), held)


def _mean_finite(a: np.ndarray) -> float:
    """The mean of the finite values of ``a`` (NaN when there is none, without numpy's empty-slice warning)."""
    a = a[np.isfinite(a)]
    return float(a.mean()) if a.size else float("nan")


def default_holdout(
    df: pd.DataFrame, preferred: Sequence[str] = (), misfit: np.ndarray | None = None
) -> tuple[str, list[float]]:
    """Choose a condition to hold out: an interior level of the first column with at least
    three levels, trying ``preferred`` (e.g. the top candidate) first, then load, speed,
    pressure and camber.  A level whose removal would take every sweep of one kind
    (e.g. all cornering sweeps) out of the training data is not chosen.

    The held-out condition should not be one the model fits by construction.  With
    ``misfit`` (a per-row misfit of the given model, e.g. its squared normalised
    residual) the level where the model fits worst is taken: an interior level (the
    refitted model then interpolates) when the worst interior level fits no better
    than the median level, else the worst level of all (an extrapolation, e.g. a
    pressure beyond the one the model was fitted at).  Without ``misfit``, the interior
    level nearest the middle."""
    for column in [*preferred, "Fz", "Vx", "P", "gamma"]:
        col = SET_POINT_COLUMNS.get(column, column)
        if col not in df.columns or not pd.api.types.is_numeric_dtype(df[col]):
            continue
        lv = levels(df, column)
        if len(lv) < 3:
            continue
        ok = [v for v in lv if _keeps_every_kind(df, col, v)]
        interior = [v for v in ok if lv[0] < v < lv[-1]]
        if not ok:
            continue
        if misfit is None:
            if interior:
                return column, [float(min(interior, key=lambda v: abs(v - lv[len(lv) // 2])))]
            continue
        x = df[col].to_numpy(float)
        m = np.asarray(misfit, float)
        level_misfit = {v: _mean_finite(m[np.isclose(x, v)]) for v in lv}
        median = float(np.median(list(level_misfit.values())))
        if interior and max(level_misfit[v] for v in interior) >= median:
            return column, [float(max(interior, key=level_misfit.get))]
        return column, [float(max(ok, key=level_misfit.get))]
    for column in ("Fz", "Vx", "P"):
        lv = levels(df, column)
        if len(lv) == 2:
            return column, [float(lv[-1])]
    raise MftireInputError("cannot hold out an operating condition: the data have a single load, speed and pressure")
