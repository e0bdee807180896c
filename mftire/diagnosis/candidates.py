"""Candidate explanatory variables for fit residuals.

Candidates are every numeric data column that is neither a Magic Formula input or
output nor a column mftire adds itself, plus derived quantities with fixed names:

==========  =================================================================
name        definition
==========  =================================================================
Vs          slip speed Vx·sqrt(kappa² + tan² alpha) [m/s]
Vx          forward speed [m/s]
P           inflation pressure [Pa]
Fz_dev      deviation of Fz from its sweep set point [N]
sign_alpha  sign of the slip angle (left/right asymmetry) [-]
sign_kappa  sign of the slip (driving/braking asymmetry) [-]
sweep_dir   +1 while the swept slip increases, −1 while it decreases [-]
sequence    position in the test sequence (row order per source) [-]
energy      cumulative friction energy along the sequence,
            sum of (|Fx·Vsx| + |Fy·Vsy|)·dt, with dt from a ``time`` column when
            there is one, else 1 s per point [J]
==========  =================================================================
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd

from mftire.iotools.columns import NOT_VARIABLES
from mftire.iotools.sweeps import FIT_ROW  # the importer's flag: rows the fit uses (False: warm-up, ramps)
from mftire.mf.basic import slip_speed
from mftire.mf.extensions import BUILTIN_VARIABLES, identifier_name
from mftire.segmentation.grouping import group_sweeps

#: Derived candidates, in a fixed order.
DERIVED = ("Vs", "Vx", "P", "Fz_dev", "sign_alpha", "sign_kappa", "sweep_dir", "sequence", "energy")

#: Candidates odd in the slip (an asymmetry between left and right, drive and brake).  The raw residual of a
#: change symmetric in the slip (grip, stiffness, shape) is odd too, and such a candidate would stand for it
#: there: the ranking scores them along the model only, where an asymmetry is what they explain.
SIGN_CANDIDATES = ("sign_alpha", "sign_kappa")
#: Derived candidates that are functions of the MF operating point: those the evaluator itself derives from its inputs
#: (:data:`~mftire.mf.extensions.BUILTIN_VARIABLES`: the slip speed, the forward speed, the pressure, the signs of the
#: slips) and the load's deviation from its set point (the MF reads the load).  The MF models each of them itself, so
#: a residual one of them explains is a misfit of the MF's own characteristic unless a law in it predicts held-out
#: sweeps better than the model refitted without one (:func:`mftire.diagnosis.diagnose.cause_without_any_law`).
OPERATING_POINT = (*(v for v in DERIVED if v in BUILTIN_VARIABLES), "Fz_dev")

#: Columns that are never candidates: MF inputs and outputs and mftire's own labels.
EXCLUDED = NOT_VARIABLES
#: Names that look like time (used for the energy integral).
TIME_NAMES = ("time", "t", "runtime", "time_s", "et", "elapsed_time")


@dataclass(frozen=True)
class Candidate:
    """One candidate variable."""

    name: str
    values: np.ndarray
    derived: bool  #: one of :data:`DERIVED` (else a data column)
    sweep_level: bool  #: constant within every sweep


def time_column(df: pd.DataFrame) -> str | None:
    """The data's elapsed-time column (one of :data:`TIME_NAMES`), or None."""
    for c in df.columns:
        if str(c).lower() in TIME_NAMES and pd.api.types.is_numeric_dtype(df[c]):
            return str(c)
    return None


def interaction_partners(values: Mapping[str, np.ndarray], variable: str,
                         time_col: str | None) -> dict[str, np.ndarray]:
    """The candidates ``values`` (name -> values) offered as the second variable of an interaction with
    ``variable``: every other one but the elapsed time ``time_col``.  The clock orders everything a test
    programme does (loads tested in blocks, a drifting temperature): an effect whose size follows the clock
    fits the blocks one by one, has no physical reading and extrapolates on new runs (zoo seed 1171: an
    interaction of track temperature with time, Mz +135 % on new runs).  The accumulators of the test order
    (:data:`DERIVED` ``sequence``, ``energy``) are not candidates of the profiles at all."""
    return {k: v for k, v in values.items() if k not in (variable, time_col)}


def with_sweeps(df: pd.DataFrame) -> pd.DataFrame:
    """The data with sweep labels (``sweep_id``, set points, ``sweep_dir``), grouping if needed."""
    if "sweep_id" in df.columns and "Fz_set" in df.columns and "sweep_dir" in df.columns:
        return df
    return group_sweeps(df)


def derived_candidates(df: pd.DataFrame) -> dict[str, np.ndarray]:
    """The derived candidates of :data:`DERIVED` for grouped sweep data."""
    Vx = df["Vx"].to_numpy(float)
    kappa = df["kappa"].to_numpy(float)
    alpha = df["alpha"].to_numpy(float)
    out: dict[str, np.ndarray] = {}
    out["Vs"] = slip_speed(Vx, kappa, alpha)
    out["Vx"] = Vx
    out["P"] = df["P"].to_numpy(float)
    out["Fz_dev"] = df["Fz"].to_numpy(float) - df["Fz_set"].to_numpy(float)
    out["sign_alpha"] = np.sign(alpha)
    out["sign_kappa"] = np.sign(kappa)
    out["sweep_dir"] = df["sweep_dir"].to_numpy(float)
    # position in the sequence, per source when several sources are combined
    if "source" in df.columns:
        seq = df.groupby("source", sort=False).cumcount().to_numpy(float)
    else:
        seq = np.arange(len(df), dtype=float)
    out["sequence"] = seq
    # cumulative friction energy along the sequence
    Vsx = -kappa * np.abs(Vx)
    Vsy = np.tan(alpha) * np.abs(Vx)
    Fx = df["Fx"].to_numpy(float) if "Fx" in df.columns else np.zeros(len(df))
    Fy = df["Fy"].to_numpy(float) if "Fy" in df.columns else np.zeros(len(df))
    power = np.nan_to_num(np.abs(Fx * Vsx)) + np.nan_to_num(np.abs(Fy * Vsy))
    tcol = time_column(df)
    if tcol is not None:
        dt = np.diff(df[tcol].to_numpy(float), prepend=df[tcol].to_numpy(float)[0])
        dt = np.where((dt > 0) & np.isfinite(dt), dt, 0.0)
    else:
        dt = np.ones(len(df))
    if "source" in df.columns:
        energy = pd.Series(power * dt).groupby(df["source"].to_numpy(), sort=False).cumsum().to_numpy()
    else:
        energy = np.cumsum(power * dt)
    out["energy"] = energy
    return out


def _both_directions(df: pd.DataFrame) -> bool:
    """True when some kind of sweep is run in both directions (so direction is not a proxy for the kind)."""
    if "kind" not in df.columns:
        return False
    for _, g in df.groupby("kind"):
        d = g["sweep_dir"].to_numpy(float)
        if min(np.mean(d > 0), np.mean(d < 0)) >= 0.1:
            return True
    return False


#: A numbering column has at least this many distinct values ...
MIN_ID_LEVELS = 6


def numbers_things(v: np.ndarray, sweeps: np.ndarray) -> bool:
    """True when a column only numbers things (a run, sweep, segment or row number under another name):
    integer values, at least :data:`MIN_ID_LEVELS` of them, spaced by one (a count, not a measurement),
    that either never decrease along the rows or change at (nearly) every sweep.  Such a column is a
    label: on new data its values are different, and a law in it extrapolates without meaning."""
    v = np.asarray(v, float)
    ok = np.isfinite(v)
    if ok.sum() < 2 or not np.all(v[ok] == np.round(v[ok])):
        return False
    lv = np.unique(v[ok])
    if lv.size < MIN_ID_LEVELS or np.median(np.diff(lv)) != 1.0:
        return False
    if np.all(np.diff(v[ok]) >= 0):
        return True
    per_level = pd.Series(np.asarray(sweeps)[ok]).groupby(v[ok]).nunique()
    return bool(per_level.max() <= 2 and lv.size >= 0.5 * pd.unique(np.asarray(sweeps)).size)


def is_identifier(name: str, v: np.ndarray, sweeps: np.ndarray) -> bool:
    """An identifier column: named as one (:func:`mftire.mf.extensions.identifier_name`) or only numbering
    things (:func:`numbers_things`).  Never a candidate, never a law variable."""
    if str(name).lower() in TIME_NAMES:  # a clock at 1 Hz counts seconds, it does not number things
        return False
    return identifier_name(name) or numbers_things(v, sweeps)


def identifier_columns(df: pd.DataFrame) -> list[str]:
    """The data columns left out of the candidates as identifiers (:func:`is_identifier`)."""
    sweeps = df["sweep_id"].to_numpy() if "sweep_id" in df.columns else np.zeros(len(df))
    return [str(c) for c in df.columns if str(c) not in EXCLUDED and str(c) not in DERIVED
            and pd.api.types.is_numeric_dtype(df[c]) and not pd.api.types.is_bool_dtype(df[c])
            and is_identifier(str(c), df[c].to_numpy(float), sweeps)]  # fmt: skip


def candidates(df: pd.DataFrame) -> list[Candidate]:
    """All candidates for grouped sweep data: derived ones, then numeric data columns.

    Constant columns (one value) are left out: they cannot explain anything.  So are identifiers
    (:func:`is_identifier`: run, sweep, row, file numbers, any column that only numbers things), and the
    ``fit_row`` flag of imported rig data.
    """
    sweep = df["sweep_id"].to_numpy()
    out = []

    def level(v: np.ndarray) -> bool:
        s = pd.Series(v).groupby(sweep).nunique(dropna=False)
        return bool((s <= 1).all())

    for name, v in derived_candidates(df).items():
        if name in ("sign_alpha", "sign_kappa"):
            # an asymmetry needs both signs, each in at least a tenth of the rows
            if min(np.mean(v > 0), np.mean(v < 0)) < 0.1:
                continue
        if name == "sweep_dir" and not _both_directions(df):
            continue
        if np.nanstd(v) > 0:
            out.append(Candidate(name, v, True, level(v)))
    for col in df.columns:
        name = str(col)
        if name in EXCLUDED or name in DERIVED or name == FIT_ROW or not pd.api.types.is_numeric_dtype(df[col]):
            continue
        if not pd.api.types.is_bool_dtype(df[col]) and is_identifier(name, df[col].to_numpy(float), sweep):
            continue
        if pd.api.types.is_bool_dtype(df[col]):
            v = df[col].to_numpy(float)
        else:
            v = df[col].to_numpy(float)
        if np.all(np.isnan(v)) or np.nanstd(v) == 0:
            continue
        out.append(Candidate(name, v, False, level(v)))
    return out
