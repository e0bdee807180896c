"""Comparison data: loading measured and FE-surrogate sweeps, curve families, plotting grids.

Every table here is a sweep table in the schema of :mod:`mftire.iotools.sweeps` (SI:
Fz [N], kappa [-], alpha [rad], gamma [rad], Vx [m/s], P [Pa]; channels Fx, Fy [N], Mz,
Mx, My [N·m]) with a ``source`` label per row, grouped by
:func:`mftire.segmentation.grouping.group_sweeps` over *all* sources at once, so the same
nominal load in an FE file and a rig file gets the same ``Fz_set``.

On top of the sweep kinds of ``group_sweeps`` each swept curve gets a *family*:

==================  ==============================================================
``braking``         pure longitudinal κ sweep (α = 0), Fx against κ
``cornering``       pure lateral α sweep (κ = 0), Fy, Mz, Mx against α
``combined``        κ sweep at a held α ≠ 0, Fx, Fy, Mz against κ
``combined_alpha``  α sweep at a held κ ≠ 0, Fx, Fy, Mz against α
``other``           anything else (free-rolling points, constant-slip runs)
==================  ==============================================================

and a *curve key* ``(family, Fz_set, gamma_set, P_set, Vx_set, held)`` where ``held`` is
the level of the slip held constant (α [rad] for κ sweeps, κ [-] for α sweeps).  Sweeps
of different sources with the same key are the same curve and are overlaid.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence

import numpy as np
import pandas as pd

from mftire.errors import MftireInputError
from mftire.iotools.columns import CURVE_COLUMNS, GROUPING_COLUMNS, NOT_VARIABLES
from mftire.iotools.loaders import load_sweep_files, prepare_table
from mftire.iotools.sweeps import fit_rows, read_sweep_csv
from mftire.segmentation.grouping import group_sweeps

__all__ = [
    "FAMILIES",
    "FAMILY_CHANNELS",
    "CURVE_KEYS",
    "load_comparison_data",
    "prepare_comparison_data",
    "assign_families",
    "curve_grid",
]

#: Families in plotting order.
FAMILIES: tuple[str, ...] = ("braking", "cornering", "combined", "combined_alpha")
#: Channels compared per family.
FAMILY_CHANNELS: dict[str, tuple[str, ...]] = {
    "braking": ("Fx",),
    "cornering": ("Fy", "Mz", "Mx"),
    "combined": ("Fx", "Fy", "Mz"),
    "combined_alpha": ("Fx", "Fy", "Mz"),
}
#: Columns that identify one curve (see module docstring).
CURVE_KEYS: tuple[str, ...] = ("family", "Fz_set", "gamma_set", "P_set", "Vx_set", "held")
#: Rounding of the held slip in curve keys: 0.1 deg for alpha [rad], 0.001 for kappa [-].
_HELD_ROUND_ALPHA = math.radians(0.1)
_HELD_ROUND_KAPPA = 1e-3


def _read_fe(path: str, source: str) -> pd.DataFrame:
    """One FE-surrogate CSV as a validated table (rows without a ``source`` get ``source``)."""
    if os.path.splitext(path)[1].lower() in (".tdx", ".tydex"):
        table, _ = load_sweep_files([path])
        return table
    if not os.path.exists(path):
        raise MftireInputError(f"{path}: file not found")
    df = read_sweep_csv(path, validate=False)
    if "kind" in df.columns:  # the FE campaign's own labels (braking/cornering/combined)
        df = df.rename(columns={"kind": "fe_kind"})
    table, _ = prepare_table(df, path, source=source)
    return table


def load_comparison_data(
    data: Sequence[str | os.PathLike] = (), fe: Sequence[str | os.PathLike] = ()
) -> pd.DataFrame:
    """Read measured and FE-surrogate sweep files into one grouped table.

    Parameters
    ----------
    data : sequence of path
        Measured sweeps (CSV in the sweep schema or TYDEX).  ``source`` is the file's
        own ``source`` column, else the file stem.  ``origin`` is ``"measured"``.
    fe : sequence of path
        FE-surrogate sweeps (``mftire fe campaign``'s ``sweeps.csv``).  ``source`` is the
        file's own column, else ``"fe"`` (``"fe2"``, ... for further files); its ``kind``
        column is kept as ``fe_kind``.  ``origin`` is ``"fe"``.

    Returns
    -------
    DataFrame
        See :func:`prepare_comparison_data`.
    """
    frames = []
    for path in data:
        table, _ = load_sweep_files([os.fspath(path)])
        table["origin"] = "measured"
        frames.append(table)
    for i, path in enumerate(fe):
        table = _read_fe(os.fspath(path), "fe" if i == 0 else f"fe{i + 1}")
        table["origin"] = "fe"
        frames.append(table)
    if not frames:
        raise MftireInputError("no data: give measured (--data) and/or FE (--fe) sweep files")
    return prepare_comparison_data(pd.concat(frames, ignore_index=True, sort=False))


def prepare_comparison_data(table: pd.DataFrame) -> pd.DataFrame:
    """Group a sweep table (any mix of sources) and add families and curve keys.

    Parameters
    ----------
    table : DataFrame
        Sweep table (SI) with a ``source`` column (added as ``"data"`` when absent) and
        optionally ``origin`` (``"measured"`` or ``"fe"``; default ``"measured"``, or
        ``"fe"`` when the source label starts with ``fe``).

    Returns
    -------
    DataFrame
        Copy with the :func:`~mftire.segmentation.grouping.group_sweeps` columns (``Fz_set``
        [N], ``gamma_set`` [rad], ``P_set`` [Pa], ``Vx_set`` [m/s], ``sweep_id``,
        ``kind``, ``sweep_var``, ``kappa_set``, ``alpha_set``) and ``family``, ``var``
        (swept column), ``held`` (held slip, rounded), ``curve_id``.
    """
    df = fit_rows(table).copy()  # rows kept for the diagnosis only (fit_row False) are not sweeps
    if "source" not in df.columns:
        df["source"] = "data"
    df["source"] = df["source"].astype(str)
    if "origin" not in df.columns:
        df["origin"] = np.where(df["source"].str.lower().str.startswith("fe"), "fe", "measured")
    if "phit" not in df.columns:
        df["phit"] = 0.0
    df["phit"] = df["phit"].fillna(0.0)
    derived = [*GROUPING_COLUMNS, *CURVE_COLUMNS]
    df = df.drop(columns=[c for c in derived if c in df.columns])
    df = group_sweeps(df.reset_index(drop=True))
    return assign_families(df)


def assign_families(grouped: pd.DataFrame) -> pd.DataFrame:
    """Add ``family``, ``var``, ``held`` and ``curve_id`` to a :func:`group_sweeps` table."""
    df = grouped.copy()
    kind = df["kind"].astype(str).to_numpy()
    svar = df["sweep_var"].astype(str).to_numpy()
    fam = np.full(len(df), "other", dtype=object)
    fam[(kind == "pure_longitudinal") & (svar == "kappa")] = "braking"
    fam[(kind == "pure_lateral") & (svar == "alpha")] = "cornering"
    fam[(kind == "combined") & (svar == "kappa")] = "combined"
    fam[(kind == "combined") & (svar == "alpha")] = "combined_alpha"
    df["family"] = fam
    df["var"] = np.where(svar == "alpha", "alpha", "kappa")
    a_held = np.round(df["alpha_set"].to_numpy(float) / _HELD_ROUND_ALPHA) * _HELD_ROUND_ALPHA
    k_held = np.round(df["kappa_set"].to_numpy(float) / _HELD_ROUND_KAPPA) * _HELD_ROUND_KAPPA
    held = np.where(df["var"] == "kappa", a_held, k_held)
    df["held"] = np.where(np.isfinite(held), held, 0.0) + 0.0  # + 0.0: no -0.0
    df["curve_id"] = df.groupby(list(CURVE_KEYS), sort=True).ngroup()
    return df


def curve_grid(data: pd.DataFrame, n: int = 81, families: Sequence[str] = FAMILIES) -> pd.DataFrame:
    """Smooth plotting grid: ``n`` points over the swept range of every curve.

    The range of a curve is the union over its sweeps (all sources).  The other inputs
    are the curve's set points: ``Fz = Fz_set`` [N], ``gamma = gamma_set`` [rad],
    ``Vx = Vx_set`` [m/s], ``P = P_set`` [Pa], the held slip at ``held``, ``phit = 0``.

    Returns
    -------
    DataFrame
        One row per grid point: ``curve_id``, the :data:`CURVE_KEYS`, ``var``, ``x`` (the
        swept value, rad or -), and the inputs ``Fz, kappa, alpha, gamma, Vx, P, phit``.
    """
    rows = []
    sub = data[data["family"].isin(list(families))]
    for cid, g in sub.groupby("curve_id", sort=True):
        first = g.iloc[0]
        var = str(first["var"])
        x = g[var].to_numpy(float)
        grid = np.linspace(float(np.min(x)), float(np.max(x)), n)
        held = float(first["held"])
        part = pd.DataFrame({
            "curve_id": int(cid), **{k: first[k] for k in CURVE_KEYS}, "var": var, "x": grid,
            "Fz": float(first["Fz_set"]),
            "kappa": grid if var == "kappa" else held,
            "alpha": grid if var == "alpha" else held,
            "gamma": float(first["gamma_set"]), "Vx": float(first["Vx_set"]), "P": float(first["P_set"]),
            "phit": 0.0,
        })  # fmt: skip
        for extra in _extra_variables(g):
            part[extra] = float(g[extra].median())
        rows.append(part)
    cols = ["curve_id", *CURVE_KEYS, "var", "x", "Fz", "kappa", "alpha", "gamma", "Vx", "P", "phit"]
    return pd.concat(rows, ignore_index=True) if rows else pd.DataFrame(columns=cols)


def _extra_variables(g: pd.DataFrame) -> list[str]:
    """Numeric columns that may be model-extension variables (temperature, ...), carried as medians."""
    return [c for c in g.columns if c not in NOT_VARIABLES and not str(c).startswith("fit_")
            and pd.api.types.is_numeric_dtype(g[c])]
