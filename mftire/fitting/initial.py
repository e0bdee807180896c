"""Initial values from the data: peak, slope at zero, shape, shifts of each sweep.

For a Magic Formula curve y = D sin(C atan(B x − E (B x − atan(B x)))) + SV with
x = s + SH (Pacejka 2012 eq 4.E9 / 4.E19):

* D is the peak of |y| (after a running median against outliers);
* the slope at zero is K = B C D (eqs 4.E16, 4.E26), from a robust Theil–Sen line
  through the points near zero slip, whose intercept is y(0) ≈ K·SH + SV;
* C follows from the value far beyond the peak, ya = D sin(C π/2) (C in [1, 2]);
* E follows from the slip of the peak, where B x_m − E (B x_m − atan(B x_m)) =
  tan(π / (2C)).

Per-sweep values are combined over the loads (regression on dfz) into the nominal
coefficients (PDX1, PDX2, PKX1, PKX2, PCX1, PEX1, PVX1, ...).  Every estimate is a
proposal: :mod:`mftire.fitting.fitter` keeps it only when it lowers the stage's cost.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import stats

from mftire.mf.basic import increments

__all__ = ["SweepShape", "sweep_shape", "longitudinal_guess", "lateral_guess"]


@dataclass
class SweepShape:
    """Magic Formula shape features of one sweep (units of x and y)."""

    Fz: float  #: mean load [N]
    D: float  #: peak |y|
    x_peak: float  #: slip at the peak
    K: float  #: slope dy/dx at zero slip
    y0: float  #: value at zero slip (intercept)
    C: float  #: shape factor from the tail, NaN when the sweep does not reach far enough
    E: float  #: curvature from the peak location, NaN when not computable


def sweep_shape(x: np.ndarray, y: np.ndarray, Fz: float) -> SweepShape | None:
    """Shape features of a sweep ``y(x)`` (at least 8 points), or None."""
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    if x.size < 8 or np.ptp(x) == 0:
        return None
    order = np.argsort(x, kind="stable")
    x, y = x[order], y[order]
    ys = pd.Series(y).rolling(5, center=True, min_periods=1).median().to_numpy()
    i = int(np.argmax(np.abs(ys)))
    D, xp = float(abs(ys[i])), float(x[i])
    if D == 0:
        return None
    # the linear region: |y| below half the peak and slip between zero and the peak
    lin = (np.abs(ys) < 0.5 * D) & (np.abs(x) <= max(abs(xp), 1e-9))
    if lin.sum() < 3:
        lin = np.argsort(np.abs(x))[: min(5, x.size)]
    if np.ptp(x[lin]) > 0:
        res = stats.theilslopes(y[lin], x[lin])
        K, intercept = float(res.slope), float(res.intercept)
    else:  # the linear region's points at one slip: no slope (scipy would warn and return NaN)
        K = intercept = math.nan
    # intercept from the points closest to zero slip (less curvature bias)
    near = np.abs(x) <= 0.3 * abs(xp)
    if near.sum() >= 3:
        y0 = float(np.median(y[near] - K * x[near]))
    else:
        y0 = intercept
    C = E = math.nan
    side = np.sign(xp) if xp != 0 else 1.0
    far = x * side
    if far.max() >= 2.5 * abs(xp) > 0:
        ya = abs(float(ys[np.argmax(far)]))
        C = 2.0 - (2.0 / math.pi) * math.asin(min(max(ya / D, 0.0), 1.0))  # from ya = D sin(C pi/2)
    return SweepShape(Fz=Fz, D=D, x_peak=xp, K=K, y0=y0, C=C, E=E)


def _curvature(shape: SweepShape, C: float) -> float:
    """E from the peak location (eq 4.E9 at its maximum)."""
    if shape.K == 0 or C <= 1.0:
        return math.nan
    B = abs(shape.K) / (C * shape.D)
    xm = abs(shape.x_peak + shape.y0 / shape.K)  # peak slip measured from the zero crossing
    Bx = B * xm
    denom = Bx - math.atan(Bx)
    if denom <= 1e-9:
        return math.nan
    return (Bx - math.tan(math.pi / (2.0 * C))) / denom


def _shapes(df: pd.DataFrame, xcol: str, ycol: str) -> list[SweepShape]:
    out = []
    keys = ["Fz_set", "gamma_set", "P_set", "Vx_set"]
    for _, g in df.groupby(keys, sort=True):
        s = sweep_shape(g[xcol].to_numpy(float), g[ycol].to_numpy(float), float(g["Fz"].mean()))
        if s is not None:
            out.append(s)
    return out


def _nominal_rows(df: pd.DataFrame, p: dict) -> pd.DataFrame:
    """Rows at the camber closest to 0 and the pressure closest to NOMPRES."""
    g = df["gamma_set"].abs()
    d = df[g == g.min()]
    dp = (d["P_set"] - p["NOMPRES"]).abs()
    return d[dp == dp.min()]


def _regress(dfz: np.ndarray, v: np.ndarray, slope_default: float) -> tuple[float, float]:
    """Intercept and slope of v(dfz); slope fixed to its default with one load."""
    if np.unique(np.round(dfz, 3)).size >= 2:
        res = stats.theilslopes(v, dfz)
        return float(res.intercept), float(res.slope)
    return float(np.mean(v - slope_default * dfz)), slope_default


def _common(df: pd.DataFrame, p: dict, xcol: str, ycol: str, pre: str) -> dict[str, float]:
    """Shared guesses of the Fx and Fy stages; ``pre`` is ``"X"`` or ``"Y"``."""
    nominal = _nominal_rows(df, p)
    shapes = _shapes(nominal, xcol, ycol)
    if not shapes:
        return {}
    Fz = np.array([s.Fz for s in shapes])
    _, dfz, _ = increments(p, Fz, p["NOMPRES"])  # eqs 4.E1, 4.E2a
    lmu = p[f"LMU{pre}"]
    guess: dict[str, float] = {}
    mu = np.array([s.D for s in shapes]) / Fz / lmu
    sign_d = -1.0 if p[f"PD{pre}1"] < 0 else 1.0
    d1, d2 = _regress(dfz, mu, p[f"PD{pre}2"] * sign_d)
    if d1 > 0.05:
        guess[f"PD{pre}1"], guess[f"PD{pre}2"] = sign_d * d1, sign_d * d2
    Cs = np.array([s.C for s in shapes])
    Cs = Cs[np.isfinite(Cs)]
    C = float(np.clip(np.median(Cs), 1.05, 2.2)) if Cs.size else p[f"PC{pre}1"] * p[f"LC{pre}"]
    if Cs.size:
        guess[f"PC{pre}1"] = C / p[f"LC{pre}"]
    Es = np.array([_curvature(s, C) for s in shapes])
    Es = Es[np.isfinite(Es)]
    if Es.size:
        guess[f"PE{pre}1"] = float(np.clip(np.median(Es), -10.0, 0.9)) / p[f"LE{pre}"]
    return guess


def longitudinal_guess(df: pd.DataFrame, p: dict) -> dict[str, float]:
    """Proposals for PDX1, PDX2, PCX1, PEX1, PKX1, PKX2 and PVX1 from pure Fx(κ) sweeps."""
    guess = _common(df, p, "kappa", "Fx", "X")
    shapes = _shapes(_nominal_rows(df, p), "kappa", "Fx")
    if not shapes:
        return guess
    Fz = np.array([s.Fz for s in shapes])
    _, dfz, _ = increments(p, Fz, p["NOMPRES"])  # eqs 4.E1, 4.E2a
    K = np.array([s.K for s in shapes])
    # Kxk = Fz (PKX1 + PKX2 dfz) exp(PKX3 dfz) LKX  (eq 4.E15 at dpi = 0)
    kk = K / (Fz * np.exp(p["PKX3"] * dfz) * p["LKX"])
    k1, k2 = _regress(dfz, kk, p["PKX2"])
    if abs(k1) > 1.0:
        guess["PKX1"], guess["PKX2"] = k1, k2
    # Fx(0) ~ Kxk SHx + SVx, SVx = Fz (PVX1 + PVX2 dfz) LVX LMUX  (eqs 4.E17, 4.E18)
    SHx = (p["PHX1"] + p["PHX2"] * dfz) * p["LHX"]
    sv = (np.array([s.y0 for s in shapes]) - K * SHx) / (Fz * p["LVX"] * p["LMUX"])
    guess["PVX1"] = float(np.median(sv - p["PVX2"] * dfz))
    return guess


def lateral_guess(df: pd.DataFrame, p: dict, template_slope) -> dict[str, float]:
    """Proposals for PDY1, PDY2, PCY1, PEY1, PKY1 and PVY1 from pure Fy(α) sweeps.

    ``template_slope(Fz)`` gives the template's cornering stiffness [N/rad] at the
    nominal camber and pressure; PKY1 is scaled by the measured/template ratio (eq 4.E25
    is proportional to PKY1).
    """
    guess = _common(df, p, "alpha", "Fy", "Y")
    nominal = _nominal_rows(df, p)
    shapes = _shapes(nominal, "alpha", "Fy")
    if not shapes:
        return guess
    K = np.array([s.K for s in shapes])
    Kt = np.array([template_slope(s.Fz) for s in shapes])
    ok = np.abs(Kt) > 0
    if ok.any():
        ratio = float(np.median(K[ok] / Kt[ok]))
        if ratio != 0 and np.isfinite(ratio):
            guess["PKY1"] = p["PKY1"] * ratio
    Fz = np.array([s.Fz for s in shapes])
    _, dfz, _ = increments(p, Fz, p["NOMPRES"])  # eqs 4.E1, 4.E2a
    SHy = (p["PHY1"] + p["PHY2"] * dfz) * p["LHY"]
    sv = (np.array([s.y0 for s in shapes]) - K * SHy) / (Fz * p["LVY"] * p["LMUY"])
    guess["PVY1"] = float(np.median(sv - p["PVY2"] * dfz))
    return guess
