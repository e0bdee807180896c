"""Comparison figures (matplotlib, object-oriented API, no pyplot), one per curve family plus summaries.

Encoding, the same in every figure: **colour** = the curve within a panel (load, or
held slip for combined sweeps), **line style** = MF model, **marker** = data source,
**shaded band** = bootstrap band of a fitted model (light: prediction band, dark:
confidence band of the mean curve; see :mod:`mftire.fitting.bands`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
from matplotlib import colormaps

from mftire.compare.data import CURVE_KEYS, FAMILY_CHANNELS
from mftire.iotools.units import PLOT_UNITS
from mftire.plotting import subplots

__all__ = ["plot_family", "plot_stiffness", "plot_trail", "plot_free_rolling", "match_band"]

_UNITS = PLOT_UNITS
_LINESTYLES = ("-", "--", ":", "-.", (0, (5, 1, 1, 1)), (0, (1, 3)))
_MARKERS = ("o", "s", "^", "v", "D", "P", "X", "<", ">")
_TITLES = {
    "braking": "Pure braking: Fx against κ (per speed, colour = load)",
    "cornering": "Pure cornering: Fy, Mz, Mx against α (colour = load)",
    "combined": "Combined slip: Fx, Fy, Mz against κ at several α (one load per column)",
    "combined_alpha": "Combined slip: Fx, Fy, Mz against α at several κ (one load per column)",
}


def _style_maps(sources: Sequence[str], models: Sequence[str]) -> tuple[dict, dict]:
    return ({s: _MARKERS[i % len(_MARKERS)] for i, s in enumerate(sources)},
            {m: _LINESTYLES[i % len(_LINESTYLES)] for i, m in enumerate(models)})


def _panel_keys(family: str) -> tuple[list[str], str]:
    """(columns that define a panel, column that defines a series within it)."""
    if family in ("braking", "cornering"):
        return ["gamma_set", "P_set", "Vx_set"], "Fz_set"
    return ["Fz_set", "gamma_set", "P_set", "Vx_set"], "held"


def _cond_title(key: Mapping) -> str:
    parts = []
    if "Fz_set" in key:
        parts.append(f"Fz {key['Fz_set']:.0f} N")
    parts.append(f"γ {math.degrees(key['gamma_set']):.1f}°")
    parts.append(f"{key['P_set'] / 1e5:.3g} bar")
    parts.append(f"{key['Vx_set'] * 3.6:.0f} km/h")
    return ", ".join(parts)


def _series_label(family: str, value: float) -> str:
    if family in ("braking", "cornering"):
        return f"Fz {value:.0f} N"
    if family == "combined":
        return f"α {math.degrees(value):.1f}°"
    return f"κ {value:.3g}"


def match_band(bands: pd.DataFrame | None, curve: Mapping) -> pd.DataFrame | None:
    """Rows of a band table (grid format, see :func:`mftire.compare.data.curve_grid`) for one curve.

    Curves match when the family is equal and the set points agree within 3 % (Fz, P),
    5 % or 0.5 m/s (Vx), 0.2° (γ) and 0.2° / 0.002 (held α / κ).
    """
    if bands is None or len(bands) == 0:
        return None
    b = bands[bands["family"] == curve["family"]]
    if b.empty:
        return None
    m = (np.isclose(b["Fz_set"], curve["Fz_set"], rtol=0.03)
         & np.isclose(b["P_set"], curve["P_set"], rtol=0.03)
         & np.isclose(b["Vx_set"], curve["Vx_set"], rtol=0.05, atol=0.5)
         & np.isclose(b["gamma_set"], curve["gamma_set"], atol=math.radians(0.2))
         & np.isclose(b["held"], curve["held"], atol=math.radians(0.2) if curve["family"] == "combined" else 0.002))
    b = b[m]
    if b.empty:
        return None
    first = b["curve_id"].iloc[0] if "curve_id" in b.columns else None
    return (b[b["curve_id"] == first] if first is not None else b).sort_values("x")


def plot_family(
    family: str,
    data: pd.DataFrame,
    grid: pd.DataFrame,
    grid_predictions: Mapping[str, pd.DataFrame],
    path: str,
    bands: pd.DataFrame | None = None,
    max_panels: int = 8,
    dpi: int = 90,
) -> str | None:
    """One figure for a family: rows = channels, columns = conditions (at most ``max_panels``).

    Parameters
    ----------
    family : str
        ``braking``, ``cornering``, ``combined`` or ``combined_alpha``.
    data : DataFrame
        Grouped comparison data (points drawn as markers, one per source).
    grid, grid_predictions
        Plotting grid (:func:`~mftire.compare.data.curve_grid`) and each model's
        channels on it (lines, one style per model).
    bands : DataFrame, optional
        Band table in grid format with ``{ch}_lo, {ch}_hi, {ch}_pred_lo, {ch}_pred_hi``.
    path : str
        PNG to write.

    Returns
    -------
    str or None
        ``path``, or None when the data hold no curve of the family.
    """
    channels = [c for c in FAMILY_CHANNELS[family] if c in data.columns and data[c].notna().any()]
    d = data[data["family"] == family]
    gr = grid[grid["family"] == family]
    if (d.empty and gr.empty) or not channels:
        return None
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    pkeys, skey = _panel_keys(family)
    src_all = list(dict.fromkeys(data["source"]))
    models = list(grid_predictions)
    markers, styles = _style_maps(src_all, models)
    curves = gr.drop_duplicates("curve_id") if len(gr) else d.drop_duplicates("curve_id")
    panels = list(curves.groupby(pkeys, sort=True))[:max_panels]
    series_vals = sorted(curves[skey].unique())
    cmap = colormaps["viridis"] if family in ("braking", "cornering") else colormaps["coolwarm"]
    colors = {v: cmap(x) for v, x in zip(series_vals, np.linspace(0.05, 0.9, max(len(series_vals), 1)),
                                          strict=False)}
    ncol, nrow = len(panels), len(channels)
    wrap = nrow == 1 and ncol > 3  # one channel: panels in rows of three
    fig_cols, fig_rows = (3, math.ceil(ncol / 3)) if wrap else (ncol, nrow)
    fig, grid_axes = subplots(fig_rows, fig_cols, figsize=(3.6 * fig_cols + 1.8, 2.8 * fig_rows + 0.6),
                                  squeeze=False)
    axes = grid_axes.reshape(1, -1) if wrap else grid_axes
    for ax in list(axes.flat)[ncol * nrow:]:
        ax.set_visible(False)
    var = "alpha" if family in ("cornering", "combined_alpha") else "kappa"
    xs = 180 / math.pi if var == "alpha" else 1.0
    has_band = False
    for j, (pkey, pcurves) in enumerate(panels):
        pk = dict(zip(pkeys, pkey if isinstance(pkey, tuple) else (pkey,), strict=True))
        for i, ch in enumerate(channels):
            ax = axes[i, j]
            for _, cur in pcurves.iterrows():
                color = colors[cur[skey]]
                cid = cur["curve_id"]
                band = match_band(bands, cur) if bands is not None else None
                if band is not None and f"{ch}_lo" in band.columns:
                    bx = band["x"].to_numpy(float) * xs
                    ax.fill_between(bx, band[f"{ch}_pred_lo"], band[f"{ch}_pred_hi"], color=color, alpha=0.13, lw=0)
                    ax.fill_between(bx, band[f"{ch}_lo"], band[f"{ch}_hi"], color=color, alpha=0.35, lw=0)
                    has_band = True
                g = gr[gr["curve_id"] == cid]
                for m in models:
                    pred = grid_predictions[m].loc[g.index, ch]
                    ax.plot(g["x"] * xs, pred, linestyle=styles[m], color=color, lw=1.3)
                pts = d[(d["curve_id"] == cid) & d[ch].notna()]
                for src, s in pts.groupby("source", sort=False):
                    ax.plot(s[var] * xs, s[ch], linestyle="none", marker=markers[src], ms=3.2, color=color,
                            alpha=0.75, mfc="none" if str(s["origin"].iloc[0]) == "fe" else color)
            if i == 0:
                ax.set_title(_cond_title(pk), fontsize=8)
            if i == nrow - 1:
                ax.set_xlabel("α [deg]" if var == "alpha" else "κ [-]", fontsize=8)
            if j == 0 or (wrap and j % 3 == 0):
                ax.set_ylabel(f"{ch} [{_UNITS[ch]}]", fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(True, lw=0.3)
    handles = [Line2D([], [], color=colors[v], lw=3, label=_series_label(family, v)) for v in series_vals]
    handles += [Line2D([], [], color="k", linestyle=styles[m], lw=1.3, label=f"MF: {m}") for m in models]
    used = list(dict.fromkeys(d["source"]))
    for s in used:
        fe = str(d.loc[d["source"] == s, "origin"].iloc[0]) == "fe"
        handles.append(Line2D([], [], color="0.3", marker=markers[s], linestyle="none", mfc="none" if fe else "0.3",
                              label=f"{'FE' if fe else 'data'}: {s}"))
    if has_band:
        handles += [Patch(color="0.5", alpha=0.35, label="confidence band (mean curve)"),
                    Patch(color="0.5", alpha=0.13, label="prediction band (+ scatter)")]
    fig.legend(handles=handles, loc="center right", fontsize=7, frameon=False)
    fig.suptitle(_TITLES[family] + ("" if len(curves.groupby(pkeys)) <= max_panels
                                    else f" (first {max_panels} conditions)"), fontsize=10)
    fig.tight_layout(rect=(0, 0, 1 - 1.7 / (3.6 * fig_cols + 1.8), 0.96))
    _save(fig, path, dpi)
    return path


def _save(fig, path: str, dpi: int) -> None:
    from mftire.iotools.atomic import atomic_path

    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png")


def _cond_groups(df: pd.DataFrame) -> tuple[list, dict]:
    keys = sorted({tuple(r) for r in df[["gamma_set", "P_set", "Vx_set"]].to_numpy(float)})
    cols = colormaps["tab10"](np.arange(len(keys)) % 10)
    return keys, {k: cols[i] for i, k in enumerate(keys)}


def _cond_label(k) -> str:
    return f"γ {math.degrees(k[0]):.1f}°, {k[1] / 1e5:.3g} bar, {k[2] * 3.6:.0f} km/h"


def plot_stiffness(stiffness: pd.DataFrame, path: str, dpi: int = 90) -> str | None:
    """Cornering and aligning stiffness [per deg] against load: data markers, model lines."""
    if stiffness.empty or stiffness["C_Fa"].notna().sum() == 0:
        return None
    from matplotlib.lines import Line2D

    sources = list(dict.fromkeys(stiffness["source"]))
    models = [w for w in dict.fromkeys(stiffness["who"]) if w != "data"]
    markers, styles = _style_maps(sources, models)
    keys, colors = _cond_groups(stiffness)
    fig, axes = subplots(1, 2, figsize=(11, 3.8))
    what = ((axes[0], "C_Fa_deg", "C_Fα = dFy/dα [N/deg]"), (axes[1], "C_Ma_deg", "C_Mα = dMz/dα [N·m/deg]"))
    for ax, col, lab in what:
        for (who, src, g0, p0, v0), g in stiffness.groupby(["who", "source", "gamma_set", "P_set", "Vx_set"]):
            g = g.sort_values("Fz_set")
            c = colors[(g0, p0, v0)]
            if who == "data":
                fe = str(g["origin"].iloc[0]) == "fe"
                ax.plot(g["Fz_set"], g[col], linestyle="none", marker=markers[src], color=c, mfc="none" if fe else c)
            else:
                ax.plot(g["Fz_set"], g[col], linestyle=styles[who], color=c, lw=1.2)
        ax.set_xlabel("Fz [N]")
        ax.set_ylabel(lab)
        ax.grid(True, lw=0.3)
    handles = [Line2D([], [], color=colors[k], lw=3, label=_cond_label(k)) for k in keys]
    handles += [Line2D([], [], color="k", linestyle=styles[m], label=f"MF: {m}") for m in models]
    handles += [Line2D([], [], color="0.3", marker=markers[s], linestyle="none", label=f"data: {s}") for s in sources]
    fig.legend(handles=handles, loc="center right", fontsize=7, frameon=False)
    fig.suptitle("Cornering and aligning stiffness against load (linear LSQ over |α| ≤ 2.5°)", fontsize=10)
    fig.tight_layout(rect=(0, 0, 0.8, 0.95))
    _save(fig, path, dpi)
    return path


def plot_trail(
    trail: pd.DataFrame, grid: pd.DataFrame, grid_predictions: Mapping[str, pd.DataFrame], path: str,
    max_panels: int = 6, dpi: int = 90,
) -> str | None:
    """Pneumatic trail against α per condition: data estimate −Mz/Fy (markers), model ``t`` (lines)."""
    gr = grid[grid["family"] == "cornering"]
    if trail.empty and gr.empty:
        return None
    from matplotlib.lines import Line2D

    pts = trail.drop_duplicates(["source", "sweep_id", "alpha"])
    sources = list(dict.fromkeys(pts["source"])) if len(pts) else []
    models = list(grid_predictions)
    markers, styles = _style_maps(sources, models)
    base = gr if len(gr) else pts
    panels = list(base.groupby(["gamma_set", "P_set", "Vx_set"], sort=True))[:max_panels]
    loads = sorted(set(base["Fz_set"]))
    colors = {v: colormaps["viridis"](x)
              for v, x in zip(loads, np.linspace(0.05, 0.9, max(len(loads), 1)), strict=False)}
    fig, axes = subplots(1, len(panels), figsize=(4.2 * len(panels) + 1.8, 3.6), squeeze=False)
    for ax, (key, _) in zip(axes[0], panels, strict=True):

        def sel(df, key=key):
            return df[np.isclose(df["gamma_set"], key[0]) & np.isclose(df["P_set"], key[1])
                      & np.isclose(df["Vx_set"], key[2])]

        yv = []
        for m in models:
            g = sel(gr)
            for fz, gg in g.groupby("Fz_set"):
                t = grid_predictions[m].loc[gg.index, "t"]
                ax.plot(np.degrees(gg["x"]), t, linestyle=styles[m], color=colors[fz], lw=1.2)
                yv.append(t.to_numpy(float))
        p = sel(pts)
        for (src, fz), s in p.groupby(["source", "Fz_set"]):
            fe = str(s["origin"].iloc[0]) == "fe"
            ax.plot(s["alpha_deg"], s["t_data"], linestyle="none", marker=markers[src], ms=3.2, color=colors[fz],
                    mfc="none" if fe else colors[fz], alpha=0.8)
            yv.append(s["t_data"].to_numpy(float))
        if yv:
            y = np.concatenate(yv)
            y = y[np.isfinite(y)]
            if y.size:
                lo, hi = np.quantile(y, [0.02, 0.98])
                pad = 0.1 * (hi - lo) + 1e-4
                ax.set_ylim(lo - pad, hi + pad)
        ax.set_title(_cond_label(key), fontsize=8)
        ax.set_xlabel("α [deg]")
        ax.set_ylabel("pneumatic trail t [m]")
        ax.grid(True, lw=0.3)
    handles = [Line2D([], [], color=colors[v], lw=3, label=f"Fz {v:.0f} N") for v in loads]
    handles += [Line2D([], [], color="k", linestyle=styles[m], label=f"MF t: {m}") for m in models]
    handles += [Line2D([], [], color="0.3", marker=markers[s], linestyle="none", label=f"−Mz/Fy: {s}")
                for s in sources]
    fig.legend(handles=handles, loc="center right", fontsize=7, frameon=False)
    fig.suptitle("Pneumatic trail against α (data: −Mz/Fy where |Fy| ≥ 10 % of the sweep's peak)", fontsize=10)
    fig.tight_layout(rect=(0, 0, 1 - 1.7 / (4.2 * len(panels) + 1.8), 0.93))
    _save(fig, path, dpi)
    return path


def plot_free_rolling(free: pd.DataFrame, path: str, dpi: int = 90) -> str | None:
    """Free-rolling Fx (κ = 0) against load: data markers, model lines, colour per condition."""
    if free.empty:
        return None
    from matplotlib.lines import Line2D

    sources = list(dict.fromkeys(free["source"]))
    models = [m for m in dict.fromkeys(free["model"]) if m]
    markers, styles = _style_maps(sources, models)
    keys, colors = _cond_groups(free)
    fig, ax = subplots(figsize=(8, 3.8))
    for (src, g0, p0, v0), g in free.groupby(["source", "gamma_set", "P_set", "Vx_set"]):
        c = colors[(g0, p0, v0)]
        d = g.drop_duplicates("sweep_id").sort_values("Fz_set")
        fe = str(d["origin"].iloc[0]) == "fe"
        ax.plot(d["Fz_set"], d["Fx0_data"], linestyle="none", marker=markers[src], color=c, mfc="none" if fe else c)
        for m in models:
            gm = g[g["model"] == m].sort_values("Fz_set")
            ax.plot(gm["Fz_set"], gm["Fx0_model"], linestyle=styles[m], color=c, lw=1.2)
    ax.set_xlabel("Fz [N]")
    ax.set_ylabel("Fx at κ = 0 [N]")
    ax.grid(True, lw=0.3)
    handles = [Line2D([], [], color=colors[k], lw=3, label=_cond_label(k)) for k in keys]
    handles += [Line2D([], [], color="k", linestyle=styles[m], label=f"MF: {m}") for m in models]
    handles += [Line2D([], [], color="0.3", marker=markers[s], linestyle="none", label=f"data: {s}") for s in sources]
    fig.legend(handles=handles, loc="center right", fontsize=7, frameon=False)
    fig.suptitle("Free-rolling Fx (κ = 0) per condition", fontsize=10)
    fig.tight_layout(rect=(0, 0, 0.68, 0.93))
    _save(fig, path, dpi)
    return path


#: Curve key columns (re-exported for band tables).
BAND_KEYS = CURVE_KEYS
