"""Identifiability: which coefficients the data of a stage can determine.

A coefficient multiplies a function of the operating condition (a load increment
dfz, dfz², an inclination γ, γ², |γ|, a pressure increment dpi, dpi², a speed ...).
With one load every dfz term is a constant and cannot be told apart from the
nominal coefficient; with two loads a linear term can, a quadratic term cannot; and
so on.  :func:`data_levels` counts the distinct operating conditions of a table and
:func:`split_identified` applies the :data:`RULES` named by each coefficient's
``needs``.  Coefficients that fail a rule stay at their template value and are
reported as "not identified" with the reason.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd

from mftire.fitting.stages import Coefficient

__all__ = ["DataLevels", "data_levels", "RULES", "split_identified"]


@dataclass(frozen=True)
class DataLevels:
    """Counts of distinct operating conditions in a table (one stage's rows).

    Attributes
    ----------
    n_points : int
    loads, pressures, speeds : int
        Distinct set points of Fz, P and Vx.
    gammas : int
        Distinct inclination set points.
    abs_gammas : int
        Distinct |γ| set points (0 counts).
    nonzero_abs_gammas : int
        Distinct non-zero |γ| set points.
    gamma_negative, gamma_positive : bool
        Some set point below / above zero.
    kappa_negative, kappa_positive : bool
        At least 3 points with κ < −0.02 / κ > 0.02.
    alpha_negative, alpha_positive : bool
        At least 3 points with α < −1° / α > 1°.
    kappa_levels, alpha_levels : int
        Distinct non-zero |κ| levels (0.01 bins) / |α| levels (0.5° bins).
    kappa_range, alpha_range : float
        Spread (2–98 %) of κ [-] and α [rad].
    load_min, load_max : float
        Lowest and highest load set point [N].
    """

    n_points: int
    loads: int
    gammas: int
    abs_gammas: int
    nonzero_abs_gammas: int
    gamma_negative: bool
    gamma_positive: bool
    pressures: int
    speeds: int
    kappa_negative: bool
    kappa_positive: bool
    alpha_negative: bool
    alpha_positive: bool
    kappa_levels: int
    alpha_levels: int
    kappa_range: float
    alpha_range: float
    load_min: float = 0.0
    load_max: float = 0.0

    def to_dict(self) -> dict:
        return asdict(self)


def _distinct(values: np.ndarray, decimals: int) -> np.ndarray:
    v = values[np.isfinite(values)]
    return np.unique(np.round(v, decimals))


def data_levels(df: pd.DataFrame) -> DataLevels:
    """Count the operating conditions of ``df``.

    ``df`` is a table from :func:`mftire.segmentation.grouping.group_sweeps` (it needs the
    ``Fz_set, gamma_set, P_set, Vx_set`` columns and ``kappa``, ``alpha``).
    """
    if len(df) == 0:
        return DataLevels(0, 0, 0, 0, 0, False, False, 0, 0, False, False, False, False, 0, 0, 0.0, 0.0)
    gam = _distinct(np.degrees(df["gamma_set"].to_numpy(float)), 2)
    kappa = df["kappa"].to_numpy(float)
    alpha = df["alpha"].to_numpy(float)
    a1 = math.radians(1.0)

    def spread(x: np.ndarray) -> float:
        return float(np.subtract(*np.quantile(x, [0.98, 0.02]))) if x.size else 0.0

    k_lv = np.unique(np.round(np.abs(kappa[np.abs(kappa) > 0.01]) / 0.01))
    a_lv = np.unique(np.round(np.abs(np.degrees(alpha[np.abs(alpha) > math.radians(0.5)])) / 0.5))
    return DataLevels(
        n_points=len(df),
        loads=len(_distinct(df["Fz_set"].to_numpy(float), 0)),
        gammas=len(gam),
        abs_gammas=len(np.unique(np.abs(gam))),
        nonzero_abs_gammas=len(np.unique(np.abs(gam[gam != 0]))),
        gamma_negative=bool(np.any(gam < 0)),
        gamma_positive=bool(np.any(gam > 0)),
        pressures=len(_distinct(df["P_set"].to_numpy(float), -2)),
        speeds=len(_distinct(df["Vx_set"].to_numpy(float), 2)),
        kappa_negative=int(np.sum(kappa < -0.02)) >= 3,
        kappa_positive=int(np.sum(kappa > 0.02)) >= 3,
        alpha_negative=int(np.sum(alpha < -a1)) >= 3,
        alpha_positive=int(np.sum(alpha > a1)) >= 3,
        kappa_levels=len(k_lv),
        alpha_levels=len(a_lv),
        kappa_range=spread(kappa),
        alpha_range=spread(alpha),
        load_min=float(np.nanmin(df["Fz_set"].to_numpy(float))),
        load_max=float(np.nanmax(df["Fz_set"].to_numpy(float))),
    )


Rule = Callable[[DataLevels, Mapping[str, float]], "str | None"]


def _need(ok: bool, reason: str) -> str | None:
    return None if ok else reason


def _at_least(levels: str, n: int, what: str) -> Rule:
    """The rule: at least ``n`` distinct levels ``levels`` (a :class:`DataLevels` field) in the data."""
    return lambda lv, p: _need(getattr(lv, levels) >= n, f"needs >= {n} {what} (data: {getattr(lv, levels)})")


def _both_signs(name: str, reason: str) -> Rule:
    """The rule: values of ``name`` (``kappa``, ``alpha``, ``gamma``) of both signs in the data."""
    return lambda lv, p: _need(getattr(lv, f"{name}_negative") and getattr(lv, f"{name}_positive"), reason)


#: Least change [rad] of atan((QSX6·Fz/Fz0)²) over the data's loads for QSX5, QSX6 to count.
MX_LOAD_SPREAD = 0.05


def _mx_load_factor(lv: DataLevels, p: Mapping[str, float]) -> str | None:
    """The load factor cos(QSX5·atan((QSX6·Fz/Fz0)²)) of Mx (draft eq 49) must vary over the loads.

    When the arctangent saturates (|QSX6·Fz/Fz0| >> 1 at every load, or QSX6 ≈ 0) the factor
    is a constant that QSX4 already holds: QSX5 and QSX6 only move along a flat valley.
    """
    fz0, b = float(p.get("FNOMIN", 0.0)), float(p.get("QSX6", 0.0))
    if fz0 <= 0.0:
        return "FNOMIN <= 0"
    lo, hi = (math.atan((b * f / fz0) ** 2) for f in (lv.load_min, lv.load_max))
    return _need(abs(hi - lo) >= MX_LOAD_SPREAD,
                 f"atan((QSX6*Fz/Fz0)^2) varies by {abs(hi - lo):.3f} rad over the data's loads "
                 f"(< {MX_LOAD_SPREAD}): the Mx load factor is a constant, held by QSX4")


#: Identifiability rules: name -> function(levels, template) giving None when the rule
#: holds, else the reason the coefficient cannot be identified.
RULES: dict[str, Rule] = {
    "loads2": _at_least("loads", 2, "loads for a dfz term"),
    "loads3": _at_least("loads", 3, "loads for a dfz^2 / nonlinear load term"),
    "gamma": _at_least("gammas", 2, "cambers for a gamma term"),
    "gamma_even": lambda lv, p: _need(
        lv.abs_gammas >= 2, f"needs a non-zero camber for a gamma^2 / |gamma| term (|gamma| levels: {lv.abs_gammas})"
    ),
    "gamma_square_vs_linear": _at_least("gammas", 3, "cambers to separate gamma^2 from gamma"),
    "gamma_abs_vs_linear": _both_signs("gamma", "needs cambers of both signs to separate |gamma| from gamma"),
    "gamma_odd2_vs_linear": _at_least("nonzero_abs_gammas", 2,
                                      "distinct non-zero |gamma| to separate gamma*|gamma| from gamma"),  # fmt: skip
    "pressures2": _at_least("pressures", 2, "pressures for a dpi term"),
    "pressures3": _at_least("pressures", 3, "pressures for a dpi^2 term"),
    "speeds2": _at_least("speeds", 2, "speeds for a speed term"),
    "speeds3": _at_least("speeds", 3, "speeds for a second speed term"),
    "kappa_both_signs": _both_signs("kappa", "needs braking and driving slip (kappa of both signs)"),
    "alpha_both_signs": _both_signs("alpha", "needs slip angles of both signs"),
    "kappa_levels2": lambda lv, p: _need(lv.kappa_levels >= 2, "needs combined data at >= 2 slip ratios"),
    "alpha_levels2": lambda lv, p: _need(lv.alpha_levels >= 2, "needs combined data at >= 2 slip angles"),
    "combined": lambda lv, p: _need(lv.n_points > 0, "needs combined-slip sweeps"),
    "lateral_force": lambda lv, p: _need(
        lv.alpha_range > math.radians(2.0), "needs rows with a lateral force (slip-angle sweeps)"
    ),
    "longitudinal_force": lambda lv, p: _need(
        lv.kappa_range > 0.02, "needs rows with a longitudinal force (slip-ratio sweeps)"
    ),
    "mx_nonlinear": lambda lv, p: _need(
        float(p.get("QSX4", 0.0)) != 0.0, "nonlinear Mx term switched off in the template (QSX4 = 0)"
    ),
    "mx_load_factor": _mx_load_factor,
}


def split_identified(
    coefficients: Sequence[Coefficient], levels: DataLevels, template: Mapping[str, float]
) -> tuple[list[Coefficient], dict[str, str]]:
    """Split ``coefficients`` into identified ones and ``{key: reason}`` for the rest."""
    ok: list[Coefficient] = []
    not_ok: dict[str, str] = {}
    for c in coefficients:
        reasons = [r for r in (RULES[n](levels, template) for n in c.needs) if r]
        if reasons:
            not_ok[c.key] = "; ".join(reasons)
        else:
            ok.append(c)
    return ok, not_ok
