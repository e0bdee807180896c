"""Figures of the standard curves (matplotlib, no screen needed).

Library code draws with matplotlib's object-oriented API only (:func:`subplots` here):
no pyplot, no ``matplotlib.use``, so importing or running mftire never changes the
caller's backend or figure registry. ``Figure.savefig`` picks the Agg canvas for PNG itself.
"""

from __future__ import annotations

import os

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from mftire.iotools.atomic import atomic_path

_FIGURE_KW = ("figsize", "dpi", "constrained_layout", "layout", "facecolor")


def subplots(nrows: int = 1, ncols: int = 1, **kw) -> tuple[Figure, object]:
    """``(figure, axes)`` like ``pyplot.subplots`` but without pyplot: a bare :class:`Figure`.

    Figure keywords (``figsize``, ``dpi``, ``constrained_layout``, ``layout``, ``facecolor``)
    go to :class:`Figure`, the rest (``squeeze``, ``sharex``, ...) to ``Figure.subplots``.
    Nothing needs closing: the figure is garbage once unreferenced.
    """
    fig = Figure(**{k: kw.pop(k) for k in _FIGURE_KW if k in kw})
    return fig, fig.subplots(nrows, ncols, **kw)


def plot_standard_curves(curves: pd.DataFrame, path: str | os.PathLike, title: str = "") -> None:
    """Draw the six standard panels from :func:`mftire.curves.standard_curves` to a figure file
    whose format follows the suffix (PNG, PDF, SVG, ...)."""
    fig, axes = subplots(2, 3, figsize=(15, 8.5), constrained_layout=True)
    pl = curves[curves.curve == "pure_long"]
    lat = curves[curves.curve == "pure_lat"]
    comb = curves[curves.curve == "combined"]
    panels = [
        (axes[0, 0], pl, "kappa", "Fx", "load_factor", "pure longitudinal", "κ [-]", "Fx [N]", 1.0),
        (axes[0, 1], lat, "alpha", "Fy", "load_factor", "pure lateral", "α [deg]", "Fy [N]", np.degrees(1)),
        (axes[0, 2], lat, "alpha", "Mz", "load_factor", "aligning moment", "α [deg]", "Mz [N·m]", np.degrees(1)),
        (axes[1, 0], lat, "alpha", "Mx", "load_factor", "overturning moment", "α [deg]", "Mx [N·m]", np.degrees(1)),
        (axes[1, 1], comb, "kappa", "Fx", "alpha_set_deg", "combined slip", "κ [-]", "Fx [N]", 1.0),
        (axes[1, 2], comb, "kappa", "Fy", "alpha_set_deg", "combined slip", "κ [-]", "Fy [N]", 1.0),
    ]
    for ax, df, x, y, group, name, xl, yl, xs in panels:
        for key, g in df.groupby(group, sort=True):
            label = f"{key:g}×FNOMIN" if group == "load_factor" else f"α = {key:g}°"
            ax.plot(g[x] * xs, g[y], label=label)
        ax.set_title(name)
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    if title:
        fig.suptitle(title)
    from mftire.iotools.output import figure_format

    fmt = figure_format(path)  # the format follows the suffix (.png, .pdf, .svg, ...)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format=fmt)
