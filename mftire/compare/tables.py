"""Error tables of a comparison: curve errors, stiffnesses, pneumatic trail, free rolling.

All functions take the grouped data table of :func:`mftire.compare.data.prepare_comparison_data`
and model predictions at its rows (``{model: DataFrame}`` from
:func:`mftire.compare.models.evaluate_models`, same index as the data) and return long
DataFrames (one row per curve / condition / point and model) in SI units.

Definitions
-----------
* **RMS error** of a curve (one sweep of one source, one channel, one model):
  ``sqrt(mean((model - data)^2))`` over the sweep's points [N or N·m]; ``rms_pct`` is it
  in % of the curve's data peak ``max|data|``; ``max_err`` is ``max|model - data|``.
* **Peak error**: ``peak_err = max|model| - max|data|`` over the sweep's points (the
  difference of the curves' extreme magnitudes; positive when the model's peak is
  higher) and ``peak_err_pct`` in % of ``max|data|``.
* **Cornering / aligning stiffness** (thesis eqs 6.2/6.3): slope of the linear
  least-squares fit ``Fy = C_Fa·α + Fy0`` and ``Mz = C_Ma·α + Mz0`` over the points of a
  pure cornering sweep with ``|α| ≤ 2.5°`` (``alpha_window_deg``).  The slope is signed
  as ``dFy/dα`` (negative for this evaluator's sign convention, like the MF output
  ``Kya``).  Models are fitted by the same LSQ at the *same* α points.  ``Kya`` of a
  model (its exact slope at α = 0 at the sweep's set point) is listed beside it: over
  ±2.5° the LSQ slope of a curve that saturates early is lower than ``Kya`` (a few %
  for a passenger-car tyre, up to ~15 % for one with its peak near 5°).
* **Pneumatic trail**: the model's ``t`` output (``t = -(Mz - Mzr)/Fy``, eq 4.E31 ...) and,
  for data, the estimate ``-Mz/Fy`` (the residual torque Mzr cannot be separated from
  measured Mz) where ``|Fy| ≥ min_fy_fraction · max|Fy|`` of the sweep (default 10 %),
  since the ratio is ill-conditioned where Fy crosses zero.  The same estimate
  ``-Mz/Fy`` of the model (``t_est``) is what the error ``t_err`` compares;
  ``t0 = -C_Ma/C_Fa`` is the trail as α → 0 from the stiffnesses.
* **Free-rolling Fx**: the data's Fx at κ = 0 per braking sweep: the intercept of a
  linear LSQ fit over ``|κ| ≤ kappa_window`` (default 0.005: Fx is steep and curved
  near κ = 0, so a wider window biases the intercept by the curvature, ~100 N for a
  passenger-car tyre over ±0.02) when two or more points are in the window, else linear
  interpolation between the points bracketing κ = 0 (the nearest point when the sweep
  is one-sided).  The model is evaluated at κ = 0, α = held α and the mean Fz, γ, Vx, P
  of the points used [N].
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import pandas as pd

from mftire.compare.data import FAMILIES, FAMILY_CHANNELS
from mftire.compare.models import evaluate_at
from mftire.tyre import Tyre

__all__ = [
    "curve_errors",
    "error_summary",
    "linear_stiffness",
    "stiffness_table",
    "trail_points",
    "trail_summary",
    "free_rolling_table",
]

_COND = ["Fz_set", "gamma_set", "P_set", "Vx_set"]
_SWEEP = ["source", "origin", "sweep_id", "curve_id", "family", *_COND, "held"]


def _pct(num, den):
    num = np.asarray(num, dtype=float)
    den = np.asarray(den, dtype=float)
    with np.errstate(all="ignore"):
        return np.where(np.abs(den) > 0, 100.0 * num / np.abs(den), np.nan)


def curve_errors(data: pd.DataFrame, predictions: Mapping[str, pd.DataFrame]) -> pd.DataFrame:
    """RMS and peak errors per curve, channel and model (see module docstring).

    Returns
    -------
    DataFrame
        ``model, source, origin, sweep_id, curve_id, family, Fz_set [N], gamma_set [rad],
        P_set [Pa], Vx_set [m/s], held, channel, n, rms, rms_pct, max_err, peak_data,
        peak_model, peak_err, peak_err_pct`` (errors in the channel's unit, N or N·m).
    """
    cols = ["model", *_SWEEP, "channel", "n", "rms", "rms_pct", "max_err", "peak_data", "peak_model",
            "peak_err", "peak_err_pct"]
    parts = []
    for name, pred in predictions.items():
        for fam in FAMILIES:
            for ch in FAMILY_CHANNELS[fam]:
                if ch not in data.columns:
                    continue
                sub = data[(data["family"] == fam) & data[ch].notna()]
                if sub.empty:
                    continue
                y = sub[ch].to_numpy(float)
                m = pred.loc[sub.index, ch].to_numpy(float)
                tmp = sub[_SWEEP].assign(_e2=(m - y) ** 2, _ae=np.abs(m - y), _ay=np.abs(y), _am=np.abs(m))
                g = tmp.groupby(_SWEEP, sort=True, dropna=False)
                agg = g.agg(n=("_e2", "size"), ms=("_e2", "mean"), max_err=("_ae", "max"),
                            peak_data=("_ay", "max"), peak_model=("_am", "max")).reset_index()
                agg["rms"] = np.sqrt(agg.pop("ms"))
                agg["model"] = name
                agg["channel"] = ch
                parts.append(agg)
    if not parts:
        return pd.DataFrame(columns=cols)
    out = pd.concat(parts, ignore_index=True)
    out["rms_pct"] = _pct(out["rms"], out["peak_data"])
    out["peak_err"] = out["peak_model"] - out["peak_data"]
    out["peak_err_pct"] = _pct(out["peak_err"], out["peak_data"])
    return out[cols]


def error_summary(errors: pd.DataFrame) -> pd.DataFrame:
    """Per model, source, family and channel: curves, median / worst RMS %, worst max error.

    Returns
    -------
    DataFrame
        ``model, source, family, channel, curves, rms_median, rms_pct_median, rms_pct_max,
        max_err, peak_err_pct_median`` (absolute values in N or N·m).
    """
    keys = ["model", "source", "family", "channel"]
    cols = [*keys, "curves", "rms_median", "rms_pct_median", "rms_pct_max", "max_err", "peak_err_pct_median"]
    if errors.empty:
        return pd.DataFrame(columns=cols)
    g = errors.groupby(keys, sort=False)
    out = g.agg(curves=("n", "size"), rms_median=("rms", "median"), rms_pct_median=("rms_pct", "median"),
                rms_pct_max=("rms_pct", "max"), max_err=("max_err", "max"),
                peak_err_pct_median=("peak_err_pct", "median")).reset_index()
    return out[cols]


def linear_stiffness(alpha: np.ndarray, y: np.ndarray, alpha_window_deg: float = 2.5) -> tuple[float, float, int]:
    """Slope [unit of y per rad] and intercept of ``y = C·α + y0`` over ``|α| ≤ window``.

    Linear least squares (thesis eqs 6.2/6.3).  Returns ``(nan, nan, n)`` with fewer
    than three usable points or no spread in α.
    """
    alpha = np.asarray(alpha, dtype=float)
    y = np.asarray(y, dtype=float)
    m = (np.abs(alpha) <= math.radians(alpha_window_deg) + 1e-12) & np.isfinite(y) & np.isfinite(alpha)
    n = int(m.sum())
    if n < 3 or np.ptp(alpha[m]) <= 0:
        return math.nan, math.nan, n
    slope, intercept = np.polyfit(alpha[m], y[m], 1)
    return float(slope), float(intercept), n


def _condition_point(g: pd.DataFrame, kappa: float, alpha: float) -> pd.DataFrame:
    """One operating point at a sweep's mean Fz, γ, Vx, P (and mean extension variables)."""
    row = {c: float(g[c].mean()) for c in ("Fz", "gamma", "Vx", "P")}
    row.update(kappa=kappa, alpha=alpha, phit=0.0)
    for c in g.columns:
        if c not in row and c not in ("Fx", "Fy", "Mz", "Mx", "My") and pd.api.types.is_float_dtype(g[c]):
            row[c] = float(g[c].mean())
    return pd.DataFrame([row])


def stiffness_table(
    data: pd.DataFrame,
    predictions: Mapping[str, pd.DataFrame],
    models: Mapping[str, Tyre] | None = None,
    alpha_window_deg: float = 2.5,
    mode: int = 111,
) -> pd.DataFrame:
    """Cornering and aligning stiffness per cornering sweep, for the data and each model.

    Parameters
    ----------
    data, predictions
        Grouped data and model predictions at its rows.
    models : mapping, optional
        The models, to add ``Kya`` (exact slope at α = 0, κ = 0 and the sweep's mean
        Fz, γ, Vx, P) [N/rad].
    alpha_window_deg : float
        Half-width of the α window [deg] (2.5 as in the thesis).

    Returns
    -------
    DataFrame
        ``source, origin, sweep_id, Fz_set, gamma_set, P_set, Vx_set, who, n, C_Fa [N/rad],
        C_Fa_deg [N/deg], C_Ma [N·m/rad], C_Ma_deg [N·m/deg], t0 [m], Kya [N/rad],
        C_Fa_err_pct, C_Ma_err_pct`` (``who`` is ``"data"`` or a model name; errors are
        the model's difference from the data's value in % of ``|data|``).
    """
    cols = ["source", "origin", "sweep_id", *_COND, "who", "n", "C_Fa", "C_Fa_deg", "C_Ma", "C_Ma_deg", "t0",
            "Kya", "C_Fa_err_pct", "C_Ma_err_pct"]
    sub = data[(data["family"] == "cornering") & data["Fy"].notna()] if "Fy" in data.columns else data.iloc[:0]
    rows = []
    for (src, sid), g in sub.groupby(["source", "sweep_id"], sort=True):
        base = {"source": src, "origin": g["origin"].iloc[0], "sweep_id": int(sid),
                **{c: float(g[c].iloc[0]) for c in _COND}}
        a = g["alpha"].to_numpy(float)
        series = {"data": (g["Fy"].to_numpy(float), g["Mz"].to_numpy(float) if "Mz" in g else np.full(len(g), np.nan))}
        for name, pred in predictions.items():
            series[name] = (pred.loc[g.index, "Fy"].to_numpy(float), pred.loc[g.index, "Mz"].to_numpy(float))
        ref = None
        for who, (fy, mz) in series.items():
            cf, _, n = linear_stiffness(a, fy, alpha_window_deg)
            cm, _, _ = linear_stiffness(a, mz, alpha_window_deg)
            r = {**base, "who": who, "n": n, "C_Fa": cf, "C_Fa_deg": cf * math.pi / 180, "C_Ma": cm,
                 "C_Ma_deg": cm * math.pi / 180, "t0": -cm / cf if cf and np.isfinite(cf) else math.nan,
                 "Kya": math.nan}
            if who == "data":
                ref = r
                r["C_Fa_err_pct"] = r["C_Ma_err_pct"] = math.nan
            else:
                r["C_Fa_err_pct"] = float(_pct(cf - ref["C_Fa"], ref["C_Fa"]))
                r["C_Ma_err_pct"] = float(_pct(cm - ref["C_Ma"], ref["C_Ma"]))
                if models is not None and who in models:
                    pt = _condition_point(g, 0.0, 0.0)
                    r["Kya"] = float(evaluate_at(models[who], pt, mode, ("Kya",))["Kya"].iloc[0])
            rows.append(r)
    return pd.DataFrame(rows, columns=cols)


def trail_points(
    data: pd.DataFrame, predictions: Mapping[str, pd.DataFrame], min_fy_fraction: float = 0.1
) -> pd.DataFrame:
    """Pneumatic trail against α at the points of every cornering sweep.

    Returns
    -------
    DataFrame
        ``model, source, origin, sweep_id, Fz_set, gamma_set, P_set, Vx_set, alpha [rad],
        alpha_deg, t_data, t_model, t_est, t_err`` [m]: ``t_data = -Mz/Fy`` of the data,
        ``t_model`` the model's ``t`` output, ``t_est = -Mz/Fy`` of the model and
        ``t_err = t_est - t_data``; only points with ``|Fy| ≥ min_fy_fraction · max|Fy|``
        of the sweep.  With no model one row per point with ``model = ""``.
    """
    cols = ["model", "source", "origin", "sweep_id", *_COND, "alpha", "alpha_deg", "t_data", "t_model", "t_est",
            "t_err"]
    if not {"Fy", "Mz"} <= set(data.columns):
        return pd.DataFrame(columns=cols)
    sub = data[(data["family"] == "cornering") & data["Fy"].notna() & data["Mz"].notna()]
    if sub.empty:
        return pd.DataFrame(columns=cols)
    peak = sub.groupby(["source", "sweep_id"])["Fy"].transform(lambda v: np.max(np.abs(v)))
    sub = sub[np.abs(sub["Fy"]) >= min_fy_fraction * peak]
    base = sub[["source", "origin", "sweep_id", *_COND, "alpha"]].copy()
    base["alpha_deg"] = np.degrees(base["alpha"])
    with np.errstate(all="ignore"):
        base["t_data"] = -sub["Mz"] / sub["Fy"]
    parts = []
    for name, pred in (predictions or {"": None}).items():
        part = base.copy()
        part.insert(0, "model", name)
        if pred is None:
            part["t_model"] = part["t_est"] = part["t_err"] = math.nan
        else:
            p = pred.loc[sub.index]
            part["t_model"] = p["t"].to_numpy(float)
            with np.errstate(all="ignore"):
                part["t_est"] = (-p["Mz"] / p["Fy"]).to_numpy(float)
            part["t_err"] = part["t_est"] - part["t_data"]
        parts.append(part)
    return pd.concat(parts, ignore_index=True)[cols]


def trail_summary(trail: pd.DataFrame, stiffness: pd.DataFrame | None = None) -> pd.DataFrame:
    """Per model and cornering sweep: points, RMS and max of ``t_err`` [m], and ``t0`` of data and model."""
    cols = ["model", "source", "sweep_id", *_COND, "n", "t_rms_err", "t_max_err", "t0_data", "t0_model"]
    if trail.empty:
        return pd.DataFrame(columns=cols)
    t = trail.assign(_e2=trail["t_err"] ** 2, _ae=trail["t_err"].abs())
    out = t.groupby(["model", "source", "sweep_id", *_COND], sort=True).agg(
        n=("_e2", "size"), ms=("_e2", "mean"), t_max_err=("_ae", "max")).reset_index()
    out["t_rms_err"] = np.sqrt(out.pop("ms"))
    out["t0_data"] = out["t0_model"] = math.nan
    if stiffness is not None and len(stiffness):
        s = stiffness.set_index(["source", "sweep_id", "who"])["t0"]
        for i, r in out.iterrows():
            out.loc[i, "t0_data"] = s.get((r["source"], r["sweep_id"], "data"), math.nan)
            out.loc[i, "t0_model"] = s.get((r["source"], r["sweep_id"], r["model"]), math.nan)
    return out[cols]


def free_rolling_table(
    data: pd.DataFrame, models: Mapping[str, Tyre], kappa_window: float = 0.005, mode: int = 111
) -> pd.DataFrame:
    """Fx at κ = 0 per braking sweep, data against each model (see module docstring).

    Returns
    -------
    DataFrame
        ``source, origin, sweep_id, Fz_set, gamma_set, P_set, Vx_set, n, Fx0_data, model,
        Fx0_model, err`` [N]; with no model one row per sweep with ``model = ""``.
    """
    cols = ["source", "origin", "sweep_id", *_COND, "n", "Fx0_data", "model", "Fx0_model", "err"]
    if "Fx" not in data.columns:
        return pd.DataFrame(columns=cols)
    sub = data[(data["family"] == "braking") & data["Fx"].notna()]
    rows = []
    for (src, sid), g in sub.groupby(["source", "sweep_id"], sort=True):
        k = g["kappa"].to_numpy(float)
        fx_all = g["Fx"].to_numpy(float)
        near = np.abs(k) <= kappa_window
        if near.sum() >= 2 and np.ptp(k[near]) > 0:
            fx0 = float(np.polyval(np.polyfit(k[near], fx_all[near], 1), 0.0))
        else:
            order = np.argsort(k, kind="stable")
            near = np.zeros(k.size, bool)
            near[np.argsort(np.abs(k), kind="stable")[:2]] = True
            fx0 = float(np.interp(0.0, k[order], fx_all[order]))  # nearest value when one-sided
        gk = g[near]
        base = {"source": src, "origin": g["origin"].iloc[0], "sweep_id": int(sid),
                **{c: float(g[c].iloc[0]) for c in _COND}, "n": int(near.sum()), "Fx0_data": fx0}
        pt = _condition_point(gk, 0.0, float(np.nan_to_num(g["alpha_set"].iloc[0])))
        for name, tyre in (models or {"": None}).items():
            fxm = float(evaluate_at(tyre, pt, mode, ("Fx",))["Fx"].iloc[0]) if tyre is not None else math.nan
            rows.append({**base, "model": name, "Fx0_model": fxm, "err": fxm - fx0})
    return pd.DataFrame(rows, columns=cols)
