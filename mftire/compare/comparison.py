"""One comparison: models x data, its tables, figures, ``compare.md`` and ``compare.json``."""

from __future__ import annotations

import json
import os
import warnings
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from mftire.compare.data import FAMILIES, curve_grid, prepare_comparison_data
from mftire.compare.models import evaluate_models, load_models
from mftire.compare.plots import plot_family, plot_free_rolling, plot_stiffness, plot_trail
from mftire.compare.tables import (
    curve_errors,
    error_summary,
    free_rolling_table,
    stiffness_table,
    trail_points,
    trail_summary,
)
from mftire.iotools.atomic import atomic_path, write_text_atomic
from mftire.iotools.jsonutil import jsonable
from mftire.parallel import Executor
from mftire.tyre import Tyre

__all__ = ["Comparison", "compare", "write_comparison", "bands_frame"]


@dataclass
class Comparison:
    """Everything a comparison computed (tables in SI units; see :mod:`mftire.compare.tables`).

    Attributes
    ----------
    data : DataFrame
        Grouped data of all sources (:func:`~mftire.compare.data.prepare_comparison_data`).
    models : dict
        ``{name: Tyre}``.
    predictions : dict
        ``{name: DataFrame}`` model channels at the data rows (same index).
    grid, grid_predictions
        Plotting grid and the models on it.
    bands : DataFrame or None
        Band table in grid format (drawn in the family figures).
    errors, summary, stiffness, trail, trail_summary, free_rolling : DataFrame
        The tables.
    mode : int
        Evaluation mode of the models.
    """

    data: pd.DataFrame
    models: dict[str, Tyre]
    predictions: dict[str, pd.DataFrame]
    grid: pd.DataFrame
    grid_predictions: dict[str, pd.DataFrame]
    errors: pd.DataFrame
    summary: pd.DataFrame
    stiffness: pd.DataFrame
    trail: pd.DataFrame
    trail_summary: pd.DataFrame
    free_rolling: pd.DataFrame
    bands: pd.DataFrame | None = None
    mode: int = 111
    notes: list[str] = field(default_factory=list)

    def tables(self) -> dict[str, pd.DataFrame]:
        """Every table by name (what ``compare.json`` holds)."""
        return {"summary": self.summary, "curve_errors": self.errors, "stiffness": self.stiffness,
                "trail_summary": self.trail_summary, "trail_points": self.trail,
                "free_rolling": self.free_rolling}

    def sources(self) -> pd.DataFrame:
        """Per source: origin, rows, sweeps per family."""
        d = self.data
        t = d.groupby(["source", "origin", "family"])["sweep_id"].nunique().unstack(fill_value=0)
        t.insert(0, "rows", d.groupby(["source", "origin"]).size())
        return t.reset_index()

    def plots(self, directory: str | os.PathLike, dpi: int = 90, executor: Executor | None = None) -> list[str]:
        """Write the PNGs: one per family, stiffness, trail, free rolling. Returns their paths.

        ``executor`` draws the figures (each one a task; default: in this process, one after the
        other); the files do not depend on it."""
        directory = os.fspath(directory)
        os.makedirs(directory, exist_ok=True)
        jobs = [_Plot(plot_family, (fam, self.data, self.grid, self.grid_predictions,
                                    os.path.join(directory, f"{fam}.png")), {"bands": self.bands, "dpi": dpi})
                for fam in FAMILIES]  # fmt: skip
        jobs.append(_Plot(plot_stiffness, (self.stiffness, os.path.join(directory, "stiffness.png")), {"dpi": dpi}))
        jobs.append(_Plot(plot_trail, (self.trail, self.grid, self.grid_predictions,
                                       os.path.join(directory, "trail.png")), {"dpi": dpi}))  # fmt: skip
        jobs.append(_Plot(plot_free_rolling, (self.free_rolling, os.path.join(directory, "free_rolling.png")),
                          {"dpi": dpi}))  # fmt: skip
        out = (executor or Executor()).map(_run_plot, jobs)
        return [p for p in out if p]


@dataclass(frozen=True)
class _Plot:
    """One figure of :meth:`Comparison.plots`: ``fn(*args, **kwargs)`` (a picklable task)."""

    fn: Any
    args: tuple
    kwargs: dict


def _run_plot(job: _Plot) -> str | None:
    return job.fn(*job.args, **job.kwargs)


def bands_frame(bands, grid: pd.DataFrame) -> pd.DataFrame | None:
    """A band table in grid format from a :class:`~mftire.fitting.bands.Bands` (evaluated on ``grid``),
    a DataFrame (``bands.csv``, returned as is) or a path to ``bands.csv``."""
    if bands is None:
        return None
    if isinstance(bands, (str, os.PathLike)):
        from mftire.iotools.loaders import read_numeric_csv

        return read_numeric_csv(os.fspath(bands), ())
    if isinstance(bands, pd.DataFrame):
        return bands
    if len(grid) == 0:
        return None
    return pd.concat([grid, bands.at(grid, source=None)], axis=1)


def compare(
    models: Iterable | Mapping,
    data: pd.DataFrame,
    *,
    mode: int = 111,
    bands=None,
    alpha_window_deg: float = 2.5,
    n_grid: int = 81,
) -> Comparison:
    """Compare MF models with sweep data of any sources.

    Parameters
    ----------
    models : iterable or mapping
        ``.tir`` paths or :class:`Tyre` objects (``{name: ...}`` to name them).
    data : DataFrame
        Sweep table (SI schema) with a ``source`` column, e.g. from
        :func:`~mftire.compare.data.load_comparison_data`; grouped here when needed.
    mode : int
        Evaluation mode of the models (default 111).
    bands : Bands, DataFrame or path, optional
        Bootstrap bands (:func:`mftire.fitting.bands.bootstrap_bands`) to draw.
    alpha_window_deg : float
        α window of the stiffness fits [deg].
    n_grid : int
        Points per plotted model curve.
    """
    tyres = load_models(models)
    if "curve_id" not in data.columns:
        data = prepare_comparison_data(data)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        preds = evaluate_models(tyres, data, mode)
        grid = curve_grid(data, n=n_grid)
        gpreds = evaluate_models(tyres, grid, mode)
        errors = curve_errors(data, preds)
        stiff = stiffness_table(data, preds, tyres, alpha_window_deg, mode)
        free = free_rolling_table(data, tyres, mode=mode)
    trail = trail_points(data, preds)
    comp = Comparison(
        data=data, models=tyres, predictions=preds, grid=grid, grid_predictions=gpreds, errors=errors,
        summary=error_summary(errors), stiffness=stiff, trail=trail, trail_summary=trail_summary(trail, stiff),
        free_rolling=free, bands=bands_frame(bands, grid), mode=mode,
    )  # fmt: skip
    comp.notes = [
        f"models evaluated with mode {mode} at the exact operating points of every data row",
        f"stiffness: linear LSQ over |α| ≤ {alpha_window_deg:g}° at the data's α points (data and models alike)",
        "pneumatic trail of data: −Mz/Fy where |Fy| ≥ 10 % of the sweep's peak; models: t output and −Mz/Fy",
        "free-rolling Fx: intercept of a linear LSQ of Fx(κ) over |κ| ≤ 0.005, else interpolation at κ = 0",
    ]
    comp.notes += [f"evaluator: {m}" for m in dict.fromkeys(str(w.message) for w in caught)]
    return comp


# ------------------------------------------------------------------------------------
# writing
# ------------------------------------------------------------------------------------


def _md_table(df: pd.DataFrame, floatfmt: str = "{:.4g}", max_rows: int = 60) -> str:
    if df is None or df.empty:
        return "_(none)_\n"
    d = df.head(max_rows)

    def cell(v):
        if isinstance(v, (float, np.floating)):
            return "–" if not np.isfinite(v) else floatfmt.format(v)
        return str(v)

    lines = ["| " + " | ".join(str(c) for c in d.columns) + " |", "|" + "---|" * len(d.columns)]
    lines += ["| " + " | ".join(cell(v) for v in row) + " |" for row in d.itertuples(index=False)]
    more = f"\n_({len(df) - max_rows} more rows in compare.json)_" if len(df) > max_rows else ""
    return "\n".join(lines) + more + "\n"


def _conditions_readable(df: pd.DataFrame) -> pd.DataFrame:
    """Set points in readable units for markdown (γ deg, P bar, Vx km/h, held α deg)."""
    d = df.copy()
    if "gamma_set" in d:
        d["gamma_set"] = np.degrees(d["gamma_set"].astype(float))
        d = d.rename(columns={"gamma_set": "γ [deg]"})
    if "P_set" in d:
        d["P_set"] = d["P_set"].astype(float) / 1e5
        d = d.rename(columns={"P_set": "P [bar]"})
    if "Vx_set" in d:
        d["Vx_set"] = d["Vx_set"].astype(float) * 3.6
        d = d.rename(columns={"Vx_set": "V [km/h]"})
    if "Fz_set" in d:
        d = d.rename(columns={"Fz_set": "Fz [N]"})
    return d


def _markdown(comp: Comparison, pngs: list[str]) -> str:
    L = ["# MF / FE / measurement comparison", ""]
    L += [f"Models: {', '.join(f'`{m}` ({t.format})' for m, t in comp.models.items())}.", ""]
    L += ["## Data sources", "", _md_table(comp.sources())]
    L += ["## Notes", ""] + [f"- {n}" for n in comp.notes] + [""]
    L += ["## Error summary (per model, source, family, channel)", "",
          "RMS error in % of the curve's peak |data|; `max_err` is the largest point error [N or N·m]; "
          "`peak_err_pct` is (max|model| − max|data|) in % of max|data|.", "",
          _md_table(comp.summary[["model", "source", "family", "channel", "curves", "rms_pct_median", "rms_pct_max",
                                  "max_err", "peak_err_pct_median"]])]
    cols = ["model", "source", "family", "channel", "Fz_set", "gamma_set", "P_set", "Vx_set", "held", "n", "rms",
            "rms_pct", "max_err", "peak_err_pct"]
    L += ["## RMS and peak error per curve", "", _md_table(_conditions_readable(comp.errors[cols]), max_rows=80)]
    st = comp.stiffness[["source", "who", "Fz_set", "gamma_set", "P_set", "Vx_set", "n", "C_Fa_deg", "C_Ma_deg",
                         "t0", "Kya", "C_Fa_err_pct", "C_Ma_err_pct"]]
    L += ["## Cornering and aligning stiffness against load", "",
          "Linear LSQ slope over |α| ≤ 2.5° (thesis eqs 6.2/6.3), per deg; `Kya` [N/rad] is the model's exact "
          "slope at α = 0; `t0 = −C_Mα/C_Fα` [m]; errors in % of the data's value.", "",
          _md_table(_conditions_readable(st))]
    L += ["## Pneumatic trail against α", "",
          "Per cornering sweep: RMS / max error of the model's −Mz/Fy against the data's [m] (points with "
          "|Fy| ≥ 10 % of peak), trail at α → 0 from the stiffnesses. Every point is in compare.json "
          "(`trail_points`: α, t_data, t_model, t_est).", "",
          _md_table(_conditions_readable(comp.trail_summary))]
    L += ["## Free-rolling Fx (κ = 0)", "", _md_table(_conditions_readable(comp.free_rolling))]
    if pngs:
        L += ["## Figures", ""] + [f"![{os.path.basename(p)}]({os.path.basename(p)})" for p in pngs] + [""]
    return "\n".join(L)


def write_comparison(comp: Comparison, directory: str | os.PathLike, plots: bool = True) -> dict[str, Any]:
    """Write ``compare.md``, ``compare.json`` (every number of every table) and the PNGs.

    Returns ``{"markdown": path, "json": path, "plots": [paths]}``.
    """
    directory = os.fspath(directory)
    os.makedirs(directory, exist_ok=True)
    pngs = comp.plots(directory) if plots else []
    md = os.path.join(directory, "compare.md")
    write_text_atomic(md, _markdown(comp, pngs))
    payload = {
        "models": {m: {"file": getattr(t.parameters, "path", None) and str(t.parameters.path), "fittyp": t.fittyp,
                       "format": t.format} for m, t in comp.models.items()},
        "mode": comp.mode,
        "notes": comp.notes,
        "sources": comp.sources().to_dict(orient="records"),
        **{k: v.to_dict(orient="records") for k, v in comp.tables().items()},
        "units": {"forces": "N", "moments": "N·m", "angles": "rad (alpha_deg, C_*_deg: deg)", "P_set": "Pa",
                  "Vx_set": "m/s", "t": "m", "C_Fa": "N/rad", "C_Ma": "N·m/rad", "Kya": "N/rad"},
    }
    js = os.path.join(directory, "compare.json")
    write_text_atomic(js, json.dumps(jsonable(payload), indent=1, allow_nan=False) + "\n")
    if comp.bands is not None:
        with atomic_path(os.path.join(directory, "bands_drawn.csv")) as tmp:
            comp.bands.to_csv(tmp, index=False, float_format="%.10g")
    return {"markdown": md, "json": js, "plots": pngs}


