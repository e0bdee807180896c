"""Comparison figures (matplotlib, object-oriented API, no pyplot): every condition of the data, no truncation.

Each family (braking, cornering, combined, combined_alpha) gets one figure per channel,
``<family>.png`` for its first channel and ``<family>_<channel>.png`` for the others, made of
small multiples: one panel per operating condition, **columns = speed**, **rows = the
other set points** (pressure and camber; load too for combined sweeps).  The stiffness,
trail and free-rolling figures are small multiples by pressure and camber with one colour
per speed.

Encoding, the same in every figure: **colour** = the curve within a panel (load, or held
slip for combined sweeps; speed in the stiffness / free-rolling figures), **line style** =
MF model, **marker** = data source (open: FE surrogate), **shaded band** = bootstrap band
of a fitted model (light: prediction band, dark: confidence band of the mean curve; see
:mod:`mftire.fitting.bands`).  A **held-out** condition (not used in any fit) has a red
frame and "held out" in its panel title, or in its legend entry.

The ``*_figures`` functions return matplotlib :class:`~matplotlib.figure.Figure` objects
(tests inspect them); the ``plot_*`` functions write them as PNG.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
from matplotlib import colormaps

from mftire.compare.data import CURVE_KEYS, FAMILY_CHANNELS
from mftire.iotools.columns import SET_POINT_COLUMNS
from mftire.iotools.units import PLOT_UNITS
from mftire.plotting import subplots

__all__ = ["plot_family", "plot_stiffness", "plot_trail", "plot_free_rolling", "match_band", "family_figures",
           "stiffness_figure", "trail_figure", "free_rolling_figure", "Heldout", "MAX_COLUMNS"]

_UNITS = PLOT_UNITS
_LINESTYLES = ("-", "--", ":", "-.", (0, (5, 1, 1, 1)), (0, (1, 3)))
_MARKERS = ("o", "s", "^", "v", "D", "P", "X", "<", ">")
_TITLES = {
    "braking": "Pure braking: {ch} against κ (colour = load)",
    "cornering": "Pure cornering: {ch} against α (colour = load)",
    "combined": "Combined slip: {ch} against κ at held α (colour = α)",
    "combined_alpha": "Combined slip: {ch} against α at held κ (colour = κ)",
}
#: Most panel columns in one row of a figure (more wrap to further rows): keeps every panel readable
#: at the report's width (1200 px).
MAX_COLUMNS = 5
_PANEL_W, _PANEL_H, _LEGEND_W = 2.9, 2.5, 2.4  # inches
_FONT = 10.0


#: A held-out condition: ``(column, values)`` or ``(column, values, source)``, e.g. ``("Vx", [22.22],
#: "measured")`` (column of the sweep schema or its ``*_set`` name, values in SI; with a source, only the
#: panels holding that source's data at the condition are marked).
Heldout = tuple


def _panel_held(key: Mapping, sources, heldout: Heldout | None) -> bool:
    """Whether a panel (set points ``key``, data ``sources`` in it) shows the held-out condition."""
    if heldout is None or not _held_mask(pd.DataFrame([dict(key)]), heldout).any():
        return False
    return len(heldout) < 3 or heldout[2] in set(sources)


def _held_mask(df: pd.DataFrame, heldout: Heldout | None) -> np.ndarray:
    """Rows of ``df`` (with set-point columns) at a held-out condition (set points within 3 %)."""
    if heldout is None or len(df) == 0:
        return np.zeros(len(df), bool)
    col, values = heldout[0], heldout[1]
    col = SET_POINT_COLUMNS.get(col, col)
    if col not in df.columns:
        return np.zeros(len(df), bool)
    x = df[col].to_numpy(float)
    return np.any([np.isclose(x, v, rtol=0.03, atol=1e-6) for v in np.atleast_1d(values)], axis=0)


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


def _distinct_colors(n: int, cmap: str = "viridis") -> list:
    """``n`` colours far enough apart to tell apart (qualitative up to 10, else a sampled map)."""
    if n <= 10 and cmap == "tab10":
        return [colormaps["tab10"](i) for i in range(n)]
    return [colormaps[cmap](x) for x in np.linspace(0.05, 0.92, max(n, 1))][:n]


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


def _layout(keys: list[tuple], pkeys: list[str]) -> tuple[dict, int, int]:
    """Panel position per condition: columns = speed levels, rows = the other set points; rows wrap at
    :data:`MAX_COLUMNS` columns.  Returns ``({key: (row, col)}, n_rows, n_cols)``."""
    iv = pkeys.index("Vx_set")
    speeds = sorted({k[iv] for k in keys})
    rest = sorted({k[:iv] + k[iv + 1:] for k in keys})
    if 1 < len(speeds) <= MAX_COLUMNS:
        pos = {k: (rest.index(k[:iv] + k[iv + 1:]), speeds.index(k[iv])) for k in keys}
        return pos, len(rest), len(speeds)
    # one speed (a column of panels would be tall and narrow) or more speeds than columns: rows of panels
    ncol = MAX_COLUMNS if len(speeds) > 1 else min(len(keys), 3)
    ordered = sorted(keys, key=lambda k: (k[:iv] + k[iv + 1:], k[iv]))
    pos = {k: divmod(i, ncol) for i, k in enumerate(ordered)}
    return pos, math.ceil(len(ordered) / ncol), ncol


def _legend_width(handles) -> float:
    """Width [in] the figure legend needs (its longest label at the legend font)."""
    return max(_LEGEND_W, 0.8 + 0.078 * max((len(h.get_label()) for h in handles), default=0))


def _finish(fig, handles, panels_width: float, top: float) -> None:
    """Legend on the right (the figure widened to hold it), tight layout of the panels beside it."""
    lw = _legend_width(handles)
    w = panels_width + lw
    fig.set_size_inches(w, fig.get_size_inches()[1])
    fig.legend(handles=handles, loc="center right", fontsize=_FONT, frameon=False)
    fig.tight_layout(rect=(0, 0, 1 - lw / w, top))


def _label_panel(ax, title: str, held: bool, xlabel: str, ylabel: str) -> None:
    """A panel's title (marked when it holds the held-out condition), axis labels with units, ticks and grid."""
    if held:
        _mark_heldout(ax, title)
    else:
        ax.set_title(title, fontsize=_FONT)
    ax.set_xlabel(xlabel, fontsize=_FONT)
    ax.set_ylabel(ylabel, fontsize=_FONT)
    ax.tick_params(labelsize=_FONT - 1)
    ax.grid(True, lw=0.3)


def _hide_unused(axes, used) -> None:
    """Hide the panels of the grid ``axes`` whose (row, column) is not in ``used``."""
    nrow, ncol = axes.shape
    for r in range(nrow):
        for c in range(ncol):
            if (r, c) not in used:
                axes[r, c].set_visible(False)


def _mark_heldout(ax, title: str) -> None:
    ax.set_title(title + "\nHELD OUT", fontsize=_FONT, color="tab:red")
    for sp in ax.spines.values():
        sp.set_edgecolor("tab:red")
        sp.set_linewidth(2.0)


def family_figures(
    family: str,
    data: pd.DataFrame,
    grid: pd.DataFrame,
    grid_predictions: Mapping[str, pd.DataFrame],
    bands: pd.DataFrame | None = None,
    heldout: Heldout | None = None,
) -> list[tuple[str, object]]:
    """The figures of one family, one per channel: ``[(channel, Figure), ...]`` (empty without curves).

    Every condition of the data (all speeds, pressures, cambers; loads too for combined
    sweeps) gets its own panel; see the module docstring for the layout and encoding.
    """
    d = data[data["family"] == family]
    gr = grid[grid["family"] == family]

    no_data = not any(c in data.columns and data[c].notna().any() for c in FAMILY_CHANNELS[family])

    def drawn(c: str) -> bool:  # a channel of the data, or (a comparison without data) of the models
        if c in data.columns and data[c].notna().any():
            return True
        return no_data and any(c in p.columns for p in grid_predictions.values())

    channels = [c for c in FAMILY_CHANNELS[family] if drawn(c)]
    if (d.empty and gr.empty) or not channels:
        return []
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    pkeys, skey = _panel_keys(family)
    src_all = list(dict.fromkeys(data["source"]))
    models = list(grid_predictions)
    markers, styles = _style_maps(src_all, models)
    curves = pd.concat([gr.drop_duplicates("curve_id"), d.drop_duplicates("curve_id")]).drop_duplicates("curve_id")
    panels = list(curves.groupby(pkeys, sort=True))
    keys = [k if isinstance(k, tuple) else (k,) for k, _ in panels]
    pos, nrow, ncol = _layout(keys, pkeys)
    series_vals = sorted(curves[skey].unique())
    cols = _distinct_colors(len(series_vals), "viridis" if family in ("braking", "cornering") else "coolwarm")
    colors = dict(zip(series_vals, cols, strict=True))
    var = "alpha" if family in ("cornering", "combined_alpha") else "kappa"
    xs = 180 / math.pi if var == "alpha" else 1.0
    xlabel = "α [deg]" if var == "alpha" else "κ [-]"
    out = []
    for ch in channels:
        width = _PANEL_W * ncol + _LEGEND_W
        fig, axes = subplots(nrow, ncol, figsize=(width, _PANEL_H * nrow + 0.7), squeeze=False)
        used_axes = set()
        has_band = False
        for key, (_, pcurves) in zip(keys, panels, strict=True):
            pk = dict(zip(pkeys, key, strict=True))
            r, c = pos[key]
            ax = axes[r, c]
            used_axes.add((r, c))
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
                    ax.plot(g["x"] * xs, grid_predictions[m].loc[g.index, ch], linestyle=styles[m], color=color,
                            lw=1.3)
                pts = d[(d["curve_id"] == cid) & d[ch].notna()] if ch in d.columns else d.iloc[:0]
                for src, sp in pts.groupby("source", sort=False):
                    ax.plot(sp[var] * xs, sp[ch], linestyle="none", marker=markers[src], ms=3.2, color=color,
                            alpha=0.75, mfc="none" if str(sp["origin"].iloc[0]) == "fe" else color)
            _label_panel(ax, _cond_title(pk),
                         _panel_held(pk, d.loc[d["curve_id"].isin(pcurves["curve_id"]), "source"], heldout),
                         xlabel, f"{ch} [{_UNITS[ch]}]")  # fmt: skip
        _hide_unused(axes, used_axes)
        held_series = _held_mask(pd.DataFrame({skey: series_vals}), heldout) if skey == "Fz_set" else []
        handles = [Line2D([], [], color=colors[v], lw=3,
                          label=_series_label(family, v) + (" (held out)" if len(held_series) and held_series[i]
                                                            else ""))
                   for i, v in enumerate(series_vals)]  # fmt: skip
        handles += [Line2D([], [], color="k", linestyle=styles[m], lw=1.3, label=f"MF: {m}") for m in models]
        for sname in dict.fromkeys(d.loc[d[ch].notna(), "source"] if ch in d.columns else []):
            fe = str(d.loc[d["source"] == sname, "origin"].iloc[0]) == "fe"
            handles.append(Line2D([], [], color="0.3", marker=markers[sname], linestyle="none",
                                  mfc="none" if fe else "0.3", label=f"{'FE' if fe else 'data'}: {sname}"))
        if has_band:
            handles += [Patch(color="0.5", alpha=0.35, label="confidence band (mean curve)"),
                        Patch(color="0.5", alpha=0.13, label="prediction band (new point)")]
        if any("HELD OUT" in ax.get_title() for ax in fig.axes):
            handles.append(Patch(facecolor="none", edgecolor="tab:red", lw=2, label="held-out condition"))
        fig.suptitle(_TITLES[family].format(ch=ch) + f": {len(panels)} conditions", fontsize=_FONT + 2)
        _finish(fig, handles, _PANEL_W * ncol, 0.97)
        out.append((ch, fig))
    return out


def family_file(family: str, channel: str, first: bool) -> str:
    """File name of a family figure: ``<family>.png`` for the first channel, else ``<family>_<channel>.png``."""
    return f"{family}.png" if first else f"{family}_{channel}.png"


def plot_family(
    family: str,
    data: pd.DataFrame,
    grid: pd.DataFrame,
    grid_predictions: Mapping[str, pd.DataFrame],
    path: str,
    bands: pd.DataFrame | None = None,
    dpi: int = 90,
    heldout: Heldout | None = None,
) -> list[str]:
    """Write the family's figures (:func:`family_figures`): ``path`` for its first channel and
    ``<stem>_<channel>.png`` beside it for the others.  Returns the paths written (empty
    when the data hold no curve of the family)."""
    import os

    stem, ext = os.path.splitext(path)
    written = []
    for i, (ch, fig) in enumerate(family_figures(family, data, grid, grid_predictions, bands, heldout)):
        p = path if i == 0 else f"{stem}_{ch}{ext}"
        _save(fig, p, dpi)
        written.append(p)
    return written


def _save(fig, path: str, dpi: int) -> None:
    from mftire.iotools.atomic import atomic_path

    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png")


def _write(fig, path: str, dpi: int) -> str | None:
    """Write ``fig`` to ``path`` (None: no figure, nothing written); the path written or None."""
    if fig is None:
        return None
    _save(fig, path, dpi)
    return path


def _style_legend(labels: Mapping[float, str], colors: Mapping, models: Sequence[str], styles: Mapping,
                  model_prefix: str, sources: Sequence[str], markers: Mapping, data_prefix: str) -> list:
    """Legend handles of the summary figures: a colour per condition value (``labels``), a line style per model,
    a marker per data source."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=colors[v], lw=3, label=lab) for v, lab in labels.items()]
    handles += [Line2D([], [], color="k", linestyle=styles[m], label=f"{model_prefix}: {m}") for m in models]
    handles += [Line2D([], [], color="0.3", marker=markers[s], linestyle="none", label=f"{data_prefix}: {s}")
                for s in sources]
    return handles


def _pg_panels(df: pd.DataFrame) -> list[tuple[float, float]]:
    """(γ, P) panels of the summary figures."""
    return sorted({(float(a), float(b)) for a, b in df[["gamma_set", "P_set"]].to_numpy(float)})


def _pg_title(k) -> str:
    return f"γ {math.degrees(k[0]):.1f}°, {k[1] / 1e5:.3g} bar"


def _speed_colors(df: pd.DataFrame) -> dict:
    speeds = sorted(set(df["Vx_set"].astype(float)))
    return dict(zip(speeds, _distinct_colors(len(speeds), "plasma"), strict=True))


def _speed_label(v: float, heldout: Heldout | None) -> str:
    held = _held_mask(pd.DataFrame({"Vx_set": [v]}), heldout).any()
    who = f": {heldout[2]}" if heldout is not None and len(heldout) > 2 else ""
    return f"{v * 3.6:.0f} km/h" + (f" (held out{who})" if held else "")


def _panel_axes(n: int, extra_rows: int = 1) -> tuple:
    ncol = min(n, 3)
    nrow = math.ceil(n / ncol)
    width = 4.0 * ncol + _LEGEND_W
    fig, axes = subplots(nrow * extra_rows, ncol, figsize=(width, 3.1 * nrow * extra_rows + 0.7), squeeze=False)
    return fig, axes, nrow, ncol, width


def stiffness_figure(stiffness: pd.DataFrame, heldout: Heldout | None = None):
    """Cornering and aligning stiffness [per deg] against load: one pair of panels per pressure and camber,
    one colour per speed; data markers, model lines.  None without stiffness values."""
    if stiffness.empty or stiffness["C_Fa"].notna().sum() == 0:
        return None

    sources = list(dict.fromkeys(stiffness["source"]))
    models = [w for w in dict.fromkeys(stiffness["who"]) if w != "data"]
    markers, styles = _style_maps(sources, models)
    colors = _speed_colors(stiffness)
    pgs = _pg_panels(stiffness)
    fig, axes, nrow, ncol, width = _panel_axes(len(pgs), extra_rows=2)
    what = (("C_Fa_deg", "C_Fα = dFy/dα [N/deg]"), ("C_Ma_deg", "C_Mα = dMz/dα [N·m/deg]"))
    for i, pg in enumerate(pgs):
        r, c = divmod(i, ncol)
        sub = stiffness[np.isclose(stiffness["gamma_set"], pg[0]) & np.isclose(stiffness["P_set"], pg[1])]
        for j, (col, lab) in enumerate(what):
            ax = axes[2 * r + j, c]
            for (who, src, v0), g in sub.groupby(["who", "source", "Vx_set"]):
                g = g.sort_values("Fz_set")
                cc = colors[v0]
                if who == "data":
                    fe = str(g["origin"].iloc[0]) == "fe"
                    ax.plot(g["Fz_set"], g[col], linestyle="none", marker=markers[src], color=cc,
                            mfc="none" if fe else cc)
                else:
                    ax.plot(g["Fz_set"], g[col], linestyle=styles[who], color=cc, lw=1.2)
            ax.set_title(_pg_title(pg), fontsize=_FONT)
            ax.set_xlabel("Fz [N]", fontsize=_FONT)
            ax.set_ylabel(lab, fontsize=_FONT)
            ax.tick_params(labelsize=_FONT - 1)
            ax.grid(True, lw=0.3)
    for k in range(len(pgs), nrow * ncol):
        r, c = divmod(k, ncol)
        axes[2 * r, c].set_visible(False)
        axes[2 * r + 1, c].set_visible(False)
    handles = _style_legend({v: _speed_label(v, heldout) for v in colors}, colors, models, styles, "MF",
                            sources, markers, "data")
    fig.suptitle("Cornering and aligning stiffness against load (linear LSQ over |α| ≤ 2.5°), colour = speed",
                 fontsize=_FONT + 2)
    _finish(fig, handles, width - _LEGEND_W, 0.96)
    return fig


def plot_stiffness(stiffness: pd.DataFrame, path: str, dpi: int = 90, heldout: Heldout | None = None) -> str | None:
    """Write :func:`stiffness_figure` to ``path``."""
    return _write(stiffness_figure(stiffness, heldout), path, dpi)


def trail_figure(trail: pd.DataFrame, grid: pd.DataFrame, grid_predictions: Mapping[str, pd.DataFrame],
                 heldout: Heldout | None = None):
    """Pneumatic trail against α, one panel per condition (all of them): data estimate −Mz/Fy
    (markers), model ``t`` (lines), colour = load.  None without cornering curves."""
    gr = grid[grid["family"] == "cornering"]
    if trail.empty and gr.empty:
        return None
    from matplotlib.patches import Patch

    if trail.empty:
        trail = pd.DataFrame(columns=["source", "origin", "sweep_id", "alpha", "alpha_deg", "t_data", "gamma_set",
                                      "P_set", "Vx_set", "Fz_set"])
    pts = trail.drop_duplicates(["source", "sweep_id", "alpha"])
    sources = list(dict.fromkeys(pts["source"])) if len(pts) else []
    models = list(grid_predictions)
    markers, styles = _style_maps(sources, models)
    pkeys = ["gamma_set", "P_set", "Vx_set"]
    base = pd.concat([gr[pkeys + ["Fz_set"]], pts[pkeys + ["Fz_set"]]]) if len(pts) else gr
    keys = sorted({tuple(k) for k in base[pkeys].to_numpy(float)})
    pos, nrow, ncol = _layout(keys, pkeys)
    loads = sorted(set(base["Fz_set"]))
    colors = dict(zip(loads, _distinct_colors(len(loads)), strict=True))
    width = _PANEL_W * ncol + _LEGEND_W
    fig, axes = subplots(nrow, ncol, figsize=(width, _PANEL_H * nrow + 0.7), squeeze=False)
    used = set()
    for key in keys:
        r, c = pos[key]
        ax = axes[r, c]
        used.add((r, c))

        def sel(df, key=key):
            return df[np.isclose(df["gamma_set"], key[0]) & np.isclose(df["P_set"], key[1])
                      & np.isclose(df["Vx_set"], key[2])]

        yv = []
        g = sel(gr)
        for m in models:
            for fz, gg in g.groupby("Fz_set"):
                t = grid_predictions[m].loc[gg.index, "t"]
                ax.plot(np.degrees(gg["x"]), t, linestyle=styles[m], color=colors[fz], lw=1.2)
                yv.append(t.to_numpy(float))
        for (src, fz), sp in sel(pts).groupby(["source", "Fz_set"]):
            fe = str(sp["origin"].iloc[0]) == "fe"
            ax.plot(sp["alpha_deg"], sp["t_data"], linestyle="none", marker=markers[src], ms=3.2, color=colors[fz],
                    mfc="none" if fe else colors[fz], alpha=0.8)
            yv.append(sp["t_data"].to_numpy(float))
        if yv:
            y = np.concatenate(yv)
            y = y[np.isfinite(y)]
            if y.size:
                lo, hi = np.quantile(y, [0.02, 0.98])
                pad = 0.1 * (hi - lo) + 1e-4
                ax.set_ylim(lo - pad, hi + pad)
        cond = dict(zip(pkeys, key, strict=True))
        _label_panel(ax, _cond_title(cond), _panel_held(cond, sel(pts)["source"], heldout), "α [deg]", "trail t [m]")
    _hide_unused(axes, used)
    handles = _style_legend({v: f"Fz {v:.0f} N" for v in loads}, colors, models, styles, "MF t", sources, markers,
                            "−Mz/Fy")
    if heldout is not None:
        handles.append(Patch(facecolor="none", edgecolor="tab:red", lw=2, label="held-out condition"))
    fig.suptitle(f"Pneumatic trail against α, {len(keys)} conditions (data: −Mz/Fy where |Fy| ≥ 10 % of the "
                 "sweep's peak)", fontsize=_FONT + 2)
    _finish(fig, handles, width - _LEGEND_W, 0.96)
    return fig


def plot_trail(trail: pd.DataFrame, grid: pd.DataFrame, grid_predictions: Mapping[str, pd.DataFrame], path: str,
               dpi: int = 90, heldout: Heldout | None = None) -> str | None:
    """Write :func:`trail_figure` to ``path``."""
    return _write(trail_figure(trail, grid, grid_predictions, heldout), path, dpi)


def free_rolling_figure(free: pd.DataFrame, heldout: Heldout | None = None):
    """Free-rolling Fx (κ = 0) against load: one panel per pressure and camber, one colour per speed;
    data markers, model lines.  None without free-rolling values."""
    if free.empty:
        return None

    sources = list(dict.fromkeys(free["source"]))
    models = [m for m in dict.fromkeys(free["model"]) if m]
    markers, styles = _style_maps(sources, models)
    colors = _speed_colors(free)
    pgs = _pg_panels(free)
    fig, axes, nrow, ncol, width = _panel_axes(len(pgs))
    for i, pg in enumerate(pgs):
        ax = axes[divmod(i, ncol)]
        sub = free[np.isclose(free["gamma_set"], pg[0]) & np.isclose(free["P_set"], pg[1])]
        for (src, v0), g in sub.groupby(["source", "Vx_set"]):
            cc = colors[v0]
            dd = g.drop_duplicates("sweep_id").sort_values("Fz_set")
            fe = str(dd["origin"].iloc[0]) == "fe"
            ax.plot(dd["Fz_set"], dd["Fx0_data"], linestyle="none", marker=markers[src], color=cc,
                    mfc="none" if fe else cc)
            for m in models:
                gm = g[g["model"] == m].sort_values("Fz_set")
                ax.plot(gm["Fz_set"], gm["Fx0_model"], linestyle=styles[m], color=cc, lw=1.2)
        ax.set_title(_pg_title(pg), fontsize=_FONT)
        ax.set_xlabel("Fz [N]", fontsize=_FONT)
        ax.set_ylabel("Fx at κ = 0 [N]", fontsize=_FONT)
        ax.tick_params(labelsize=_FONT - 1)
        ax.grid(True, lw=0.3)
    for k in range(len(pgs), nrow * ncol):
        axes[divmod(k, ncol)].set_visible(False)
    handles = _style_legend({v: _speed_label(v, heldout) for v in colors}, colors, models, styles, "MF",
                            sources, markers, "data")
    fig.suptitle("Free-rolling Fx (κ = 0) against load, colour = speed", fontsize=_FONT + 2)
    _finish(fig, handles, width - _LEGEND_W, 0.93)
    return fig


def plot_free_rolling(free: pd.DataFrame, path: str, dpi: int = 90, heldout: Heldout | None = None) -> str | None:
    """Write :func:`free_rolling_figure` to ``path``."""
    return _write(free_rolling_figure(free, heldout), path, dpi)


#: Curve key columns (re-exported for band tables).
BAND_KEYS = CURVE_KEYS
