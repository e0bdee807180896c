"""Fit report: ``report.md``, ``metrics.json`` and one PNG per sweep family.

For every measured channel and every operating condition (load, camber, pressure,
speed set points; pure and combined sweeps apart) :func:`compute_metrics` gives the
RMS error [N or N·m], the RMS error as a percentage of the channel's peak in that
condition (99th percentile of |measured| over all sweeps of the condition, robust to
gross outliers) and the maximum
absolute error.  The free-rolling Fx error is reported separately.
"""

from __future__ import annotations

import json
import math
import os
from typing import Any

import numpy as np
import pandas as pd

from mftire.fitting.fitter import CONDITION_KEYS, FitResult
from mftire.fitting.model import CHANNELS, Inputs, predict
from mftire.iotools.atomic import atomic_path, write_text_atomic
from mftire.iotools.jsonutil import jsonable
from mftire.iotools.units import PLOT_UNITS
from mftire.mf.modes import Mode

__all__ = ["compute_metrics", "channel_summary", "write_report", "plot_families"]

_UNITS = PLOT_UNITS


def compute_metrics(result: FitResult) -> pd.DataFrame:
    """Error metrics per channel, sweep family and condition.

    Returns
    -------
    DataFrame
        Columns ``channel, family, Fz_set [N], gamma_set [rad], P_set [Pa], Vx_set [m/s],
        n, rms, peak, rms_pct, rms_inliers_pct, n_outliers, max_err`` (errors in the channel's
        unit; ``family`` is the sweep kind; ``rms_inliers_pct`` leaves out gross outliers,
        residuals more than 5 normalised MADs from the median).
    """
    df = result.data
    rows: list[dict[str, Any]] = []
    family = df["kind"].astype(str).to_numpy()
    for ch in CHANNELS:
        if ch not in df.columns or f"fit_{ch}" not in df.columns:
            continue
        ok = df[ch].notna().to_numpy()
        sub = df[ok].assign(_family=family[ok])
        err_all = (sub[f"fit_{ch}"] - sub[ch]).to_numpy(float)
        sub = sub.assign(_err=err_all)
        # the channel's peak in a condition is taken over all its sweeps (pure and combined)
        peaks = sub.groupby(list(CONDITION_KEYS))[ch].apply(lambda v: float(np.quantile(np.abs(v), 0.99)))
        for key, g in sub.groupby(["_family", *CONDITION_KEYS], sort=True):
            e = g["_err"].to_numpy(float)
            peak = float(peaks.loc[tuple(key[1:])])
            rms = float(np.sqrt(np.mean(e**2)))
            # robust RMS: without gross outliers (|e - median| > 5 normalised MAD)
            mad = 1.4826 * float(np.median(np.abs(e - np.median(e))))
            inl = np.abs(e - np.median(e)) <= 5.0 * mad if mad > 0 else np.ones(e.size, bool)
            rms_in = float(np.sqrt(np.mean(e[inl] ** 2)))
            rows.append({
                "channel": ch, "family": key[0], **dict(zip(CONDITION_KEYS, key[1:], strict=True)),
                "n": int(len(g)), "rms": rms, "peak": peak,
                "rms_pct": 100.0 * rms / peak if peak > 0 else math.nan,
                "rms_inliers_pct": 100.0 * rms_in / peak if peak > 0 else math.nan, "n_outliers": int((~inl).sum()),
                "max_err": float(np.max(np.abs(e))),
            })  # fmt: skip
    return pd.DataFrame(rows, columns=["channel", "family", *CONDITION_KEYS, "n", "rms", "peak", "rms_pct",
                                       "rms_inliers_pct", "n_outliers", "max_err"])


def channel_summary(metrics: pd.DataFrame) -> pd.DataFrame:
    """Worst and median RMS % of peak per channel and family."""
    if metrics.empty:
        return pd.DataFrame(columns=["channel", "family", "conditions", "rms_pct_median", "rms_pct_max",
                                     "rms_inliers_pct_max", "max_err"])
    g = metrics.groupby(["channel", "family"], sort=False)
    return pd.DataFrame({
        "conditions": g.size(), "rms_pct_median": g["rms_pct"].median(), "rms_pct_max": g["rms_pct"].max(),
        "rms_inliers_pct_max": g["rms_inliers_pct"].max(), "max_err": g["max_err"].max(),
    }).reset_index()  # fmt: skip


def _fmt_condition(r) -> str:
    return (f"{r['Fz_set']:.0f} N, {math.degrees(r['gamma_set']):.2f} deg, {r['P_set'] / 1e5:.3g} bar, "
            f"{r['Vx_set']:.3g} m/s")


def _markdown(result: FitResult, metrics: pd.DataFrame, pngs: list[str]) -> str:
    L = ["# mftire fit report", ""]
    L.append(f"- points fitted: {len(result.data)}; rows dropped for NaN: {result.n_dropped_nan}")
    L.append(f"- fitted for evaluation mode {result.mode}; total time {result.time:.1f} s; "
             f"success: {result.success}")
    L.append(f"- coefficients fitted: {len(result.identified)}; not identified: {len(result.not_identified)}")
    L += ["", "## Stages", "",
          "| stage | channel | status | points | RMS before | RMS after | noise σ | time [s] | note |",
          "|---|---|---|---|---|---|---|---|---|"]
    for s in result.stages:
        L.append(f"| {s.number} {s.name} | {s.channel} | {s.status} | {s.n_points} | {s.rms_start:.4g} | "
                 f"{s.rms:.4g} | {s.noise:.3g} | {s.time:.2f} | {s.message if s.status != 'fitted' else ''} |")
    L += ["", "## Summary per channel", "", "| channel | family | conditions | median RMS % of peak | "
          "worst RMS % of peak | worst RMS % without outliers | max error |", "|---|---|---|---|---|---|---|"]
    for _, r in channel_summary(metrics).iterrows():
        L.append(f"| {r['channel']} | {r['family']} | {r['conditions']} | {r['rms_pct_median']:.3f} | "
                 f"{r['rms_pct_max']:.3f} | {r['rms_inliers_pct_max']:.3f} | {r['max_err']:.4g} "
                 f"{_UNITS[r['channel']]} |")
    L += ["", "## Free rolling (Fx at kappa = 0)", ""]
    fr = result.free_rolling
    if len(fr):
        L += ["| condition | measured [N] | fitted [N] | error [N] | sign ok |", "|---|---|---|---|---|"]
        for _, r in fr.iterrows():
            L.append(f"| {_fmt_condition(r)} | {r['measured']:.4g} | {r['fitted']:.4g} | {r['error']:.4g} | "
                     f"{'yes' if r['sign_ok'] else 'NO'} |")
        L.append("")
        L.append(f"RMS free-rolling Fx error: {float(np.sqrt(np.mean(fr['error'] ** 2))):.4g} N")
    else:
        L.append("No pure longitudinal sweeps.")
    L += ["", "## Errors per channel and condition", "",
          "| channel | family | condition (Fz, gamma, P, Vx) | n | RMS | RMS % of peak | "
          "RMS % without outliers (n) | max error |",
          "|---|---|---|---|---|---|---|---|"]
    for _, r in metrics.iterrows():
        u = _UNITS[r["channel"]]
        L.append(f"| {r['channel']} | {r['family']} | {_fmt_condition(r)} | {r['n']} | {r['rms']:.4g} {u} | "
                 f"{r['rms_pct']:.3f} | {r['rms_inliers_pct']:.3f} ({r['n_outliers']}) | {r['max_err']:.4g} {u} |")
    L += ["", "## Not identified (kept at template values)", ""]
    if result.not_identified:
        L += ["| coefficient | reason |", "|---|---|"]
        L += [f"| {k} | {v} |" for k, v in sorted(result.not_identified.items())]
    else:
        L.append("None.")
    L += ["", "## Fitted coefficients", "", "| coefficient | template | fitted |", "|---|---|---|"]
    for k in dict.fromkeys(result.identified):
        L.append(f"| {k} | {result.template.get(k, math.nan):.6g} | {result.flat[k]:.6g} |")
    if result.messages:
        L += ["", "## Messages", ""] + [f"- {m}" for m in result.messages]
    if pngs:
        L += ["", "## Plots", ""] + [f"![{os.path.basename(p)}]({os.path.basename(p)})" for p in pngs]
    return "\n".join(L) + "\n"


def plot_families(result: FitResult, directory: str, max_panels: int = 12) -> list[str]:
    """One PNG per sweep family (kind x channel): measured points and fitted curves.

    Panels are the camber / pressure / speed (and held-slip) conditions, one colour per
    load; the fitted curve is the model at the set points on a fine slip grid.
    """
    from matplotlib import colormaps

    from mftire.plotting import subplots

    df = result.data
    mode = Mode.from_code(result.mode + 100)
    out: list[str] = []
    held = np.where(df["sweep_var"] == "kappa", df["alpha_set"], df["kappa_set"])
    df = df.assign(_held=np.round(np.nan_to_num(held.astype(float)), 4))
    for kind in ("pure_longitudinal", "pure_lateral", "combined"):
        dk = df[(df["kind"] == kind) & (df["sweep_var"] != "none")]
        if dk.empty:
            continue
        for ch in CHANNELS:
            if ch not in dk.columns or dk[ch].notna().sum() == 0:
                continue
            d = dk[dk[ch].notna()]
            panel_keys = ["sweep_var", "gamma_set", "P_set", "Vx_set", "_held"]
            panels = list(d.groupby(panel_keys, sort=True))[:max_panels]
            ncol = min(3, len(panels))
            nrow = math.ceil(len(panels) / ncol)
            fig, axes = subplots(nrow, ncol, figsize=(4.6 * ncol, 3.4 * nrow), squeeze=False)
            for ax, (key, g) in zip(axes.flat, panels, strict=False):
                var = key[0]
                loads = sorted(g["Fz_set"].unique())
                colors = colormaps["viridis"](np.linspace(0, 0.9, max(len(loads), 1)))
                for color, fz in zip(colors, loads, strict=False):
                    s = g[g["Fz_set"] == fz]
                    xv = s[var].to_numpy(float)
                    scale = 180 / math.pi if var == "alpha" else 1.0
                    ax.plot(xv * scale, s[ch], ".", ms=3, color=color, alpha=0.6)
                    grid = np.linspace(xv.min(), xv.max(), 120)
                    n = grid.size
                    other = float(s["alpha_set" if var == "kappa" else "kappa_set"].median())
                    other = 0.0 if not np.isfinite(other) else other
                    x = Inputs(np.full(n, fz), grid if var == "kappa" else np.full(n, other),
                               grid if var == "alpha" else np.full(n, other), np.full(n, key[1]),
                               np.full(n, key[3]), np.full(n, key[2]))
                    ax.plot(grid * scale, predict(result.flat, x, ch, mode), "-", color=color, lw=1.2,
                            label=f"{fz:.0f} N")
                title = f"γ {math.degrees(key[1]):.1f}°, {key[2] / 1e5:.3g} bar, {key[3]:.3g} m/s"
                if kind == "combined":
                    title += f", {'α' if var == 'kappa' else 'κ'} = " + (
                        f"{math.degrees(key[4]):.1f}°" if var == "kappa" else f"{key[4]:.3g}")
                ax.set_title(title, fontsize=8)
                ax.set_xlabel("α [deg]" if var == "alpha" else "κ [-]", fontsize=8)
                ax.set_ylabel(f"{ch} [{_UNITS[ch]}]", fontsize=8)
                ax.tick_params(labelsize=7)
                ax.grid(True, lw=0.3)
                ax.legend(fontsize=6)
            for ax in list(axes.flat)[len(panels):]:
                ax.set_visible(False)
            fig.suptitle(f"{kind.replace('_', ' ')} sweeps: {ch} measured (dots) and fitted (lines)", fontsize=10)
            fig.tight_layout()
            path = os.path.join(directory, f"{kind}_{ch}.png")
            with atomic_path(path) as tmp:
                fig.savefig(tmp, dpi=90, format="png")
            out.append(path)
    return out


def write_report(result: FitResult, directory: str | os.PathLike, plots: bool = True) -> dict[str, str]:
    """Write ``report.md``, ``metrics.json`` and the PNGs into ``directory``.

    Returns ``{"report": path, "metrics": path, "plots": [paths]}``.
    """
    directory = os.fspath(directory)
    os.makedirs(directory, exist_ok=True)
    metrics = compute_metrics(result)
    pngs = plot_families(result, directory) if plots else []
    md = os.path.join(directory, "report.md")
    write_text_atomic(md, _markdown(result, metrics, pngs))
    fr = result.free_rolling
    payload = {
        "n_points": len(result.data),
        "n_dropped_nan": result.n_dropped_nan,
        "mode": result.mode,
        "success": result.success,
        "time_s": result.time,
        "summary": channel_summary(metrics).to_dict(orient="records"),
        "conditions": metrics.to_dict(orient="records"),
        "free_rolling": {
            "conditions": fr.to_dict(orient="records"),
            "rms_error_N": float(np.sqrt(np.mean(fr["error"].to_numpy(float) ** 2))) if len(fr) else None,
            "sign_violations": int((~fr["sign_ok"].astype(bool)).sum()) if len(fr) else 0,
        },
        "stages": [s.to_dict() for s in result.stages],
        "identified": list(dict.fromkeys(result.identified)),
        "not_identified": result.not_identified,
        "messages": result.messages,
    }
    js = os.path.join(directory, "metrics.json")
    write_text_atomic(js, json.dumps(jsonable(payload), indent=1, allow_nan=False) + "\n")
    return {"report": md, "metrics": js, "plots": pngs}
