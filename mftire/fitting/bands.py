"""Uncertainty bands of fitted curves: bootstrap over sweeps, prediction bands, coverage.

:func:`bootstrap_bands` answers "how well do the data pin the fitted curves down, and
where should a new measurement fall?":

1. **Full fit** (:func:`~mftire.fitting.fitter.fit_tir`) gives the curve f̂(x).
2. **Bootstrap over sweeps.** Whole sweeps (the unit of a measurement, whose points
   share drift, temperature and wear) are resampled with replacement, *stratified by
   source and sweep kind*, so every replicate keeps each source's pure longitudinal,
   pure lateral and combined sweeps and the staged fit sees the same kinds of data.
   Each replicate is refitted and evaluated; the pointwise ``(1 ± level)/2`` quantiles
   of the replicate curves form the **confidence band** of the mean curve.
3. **Replicate fits are warm-started** from the full fit (the fitted ``.tir`` is the
   replicate's template) and run only the stages the full fit ran (or ``stages``).
   This makes a replicate about 2–4 times faster than a cold fit and keeps every
   replicate in the same basin as the full fit (no spurious multi-modal bands from a
   replicate stuck in a far local minimum).  Effect on coverage: the optimizer stops
   when the cost stops improving (a relative change of 1e-6 and an evaluation budget), so a
   replicate may stay slightly closer to the full fit than a fully converged refit —
   the confidence band is, if anything, a little narrow.  Restricting ``stages`` (e.g.
   ``"1,2,3"``) leaves the other stages' coefficients at the full fit in every replicate:
   those channels then get a zero-width confidence band and only the scatter term below.
4. **Prediction band, calibrated** (:class:`Calibration`, default).  What it means: a band that
   a *new measured point* falls in with probability ``level`` — a point of a new sweep at a
   condition the fit did not see (a new load, speed or camber between the measured ones), noise,
   sweep offset and the model's lack of fit included; not a band of the mean curve.  Held-out
   measured points carry all three, none of which the confidence band holds.  The data's sweeps
   are split into folds (``calibrate``, default 5; whole sweeps, because the noise is correlated
   within a sweep, or the levels of a condition, ``calibrate_by``); each fold is refitted out and
   predicted.  A fold refit that can no longer identify a coefficient the full fit identified (it left
   out the only sweeps of a load, say) sets that coefficient back to the template before refitting:
   left at the full fit's value, which has seen the left-out sweeps, its residuals there would be
   in-sample and the band too narrow for such sweeps.  Per channel, source and slip class (pure
   longitudinal, pure lateral, combined points; a class with fewer than 5 sweeps uses the source's
   pooled cell) the out-of-fold residuals give
   (:func:`fit_cell_scale`):

   * a heteroscedastic scale ``s(f̂) = sqrt(a² + (b·f̂)²)`` (noise floor plus a part proportional
     to the value),
   * a local factor ``v(x)`` of the operating conditions (load, speed, pressure, camber): the
     kernel-weighted geometric mean of the calibration sweeps' scatter near ``x``, bandwidth chosen
     by leave-one-sweep-out likelihood (``∞``, one factor, when the data show no trend): the
     scatter that grows with the load where the channel's value does not (Fy, My of a braking
     sweep) is followed,
   * the conformal quantile ``q`` of the normalised scores ``|r|/(s·sqrt(v))`` over the
     *effective* number of independent points (Kish: the points of a sweep share its offset, so
     12 sweeps of an offset-dominated channel are about 12 draws, not 480), with Student's
     prediction quantile when fewer than ``level/(1 − level)`` draws make every order statistic
     too low (:func:`grouped_conformal_quantile`).

   The band is ``f̂ ± q·s(f̂)·sqrt(v(x))`` (never narrower than the confidence band).
5. **Condition folds: a new level of a condition** (``calibrate_conditions=True``; off by default).  Where a
   condition has at least 4 set-point levels in a (source, sweep kind) stratum (the speeds of a braking
   programme, say), each level's sweeps are also left out in turn and refitted (leave one level out; a
   refit that loses a coefficient of the full fit is dropped).  A left-out level strictly between the
   others is an *interior* fold (the refit interpolates to it), the lowest and highest are *exterior*
   folds (it extrapolates).  A point whose condition is a level the calibration data do not have (farther
   than 0.4 × the smallest gap between levels from each of them; :func:`new_level`) is an interpolation
   when it lies inside the levels' range and an extrapolation otherwise, and its band uses the condition
   folds of the same kind: their own cell (scale, local factor and the largest score as the quantile: the
   independent units of these folds are the 2–3 levels left out, far fewer than ``level/(1 − level)``).
   This is done only where the sweep folds' band misses the level on the condition folds' points by more
   than twice its standard error over their sweeps (or 1 point); otherwise the sweep folds' band stands.
   Why: where the model's error depends on the condition (MF 6.1 has no speed effect on Fx; its error is
   largest at the ends of the speed range), the sweep folds pool every level, and an interior speed held
   out is given the end speeds' error (it covered every point at 80 km/h).  Why off by default: with 4
   levels the cell rests on 2 interior levels (6 sweeps).  Averaged over 60 campaigns the held-out 80 km/h
   speed is then covered at 96.1 % for Fx (100 % without), but from one campaign to the next the band
   there held 78–100 % of the Fx points (31.7 % in the reduced demo), and Mz and Mx fell (on 40 of those
   campaigns 95.9 → 91.9 % and 92.4 → 87.7 %: a quantile of 6 sweep offsets; validation/README.md).
   **What it claims:** a point of a new sweep *of the same campaign* (the same rig set-up, its zero offsets
   and drift) at conditions like the calibration sweeps' falls inside with probability ``level``,
   on average over such sweeps.  Measured by ``validation/band_coverage.py`` (sweeps drawn at random
   and held out, ``--design slip_speed_sweeps``; campaigns re-measured with new noise) and by the
   nested cross-validated coverage ``Calibration.cv_coverage`` of every run.  It does not claim a new
   campaign: a new campaign brings its own offsets and drift, a campaign-level draw that one
   campaign does not show (an offset-dominated channel such as Mx is then under-covered).  Nor is it
   a guarantee at one particular condition: where the model's error differs from condition to
   condition (a missing speed effect) a held-out condition with a smaller error than the
   campaign's average is over-covered (item 5 is the option for it); re-measuring a
   condition the fit *has* seen gives a little more than the level (the fold refits lack that
   sweep); and a count on a few held-out sweeps scatters widely (:func:`coverage_table` gives its
   standard error over the sweeps).
   Before the calibration, a Gaussian ``z·σ`` band held 62 % of the demo's held-out Fx points.
   With ``calibrate=0`` the band is the uncalibrated one: replicate quantiles and the full fit's
   robust residual scatter σ (1.4826 × median |residual| per channel and source) in quadrature,
   ``f̂ ± sqrt((f̂ − q)² + (z·σ)²)``.

The bands evaluate replicate models with the full evaluator (:meth:`Tyre.evaluate`) in
the fitting mode (no input limits, combined slip: ``211``, or ``221`` with α*).
"""

from __future__ import annotations

import json
import math
import os
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats

from mftire.errors import MftireInputError
from mftire.fitting.fitter import FitResult, fit_tir
from mftire.iotools.columns import SET_POINT_COLUMNS
from mftire.iotools.jsonutil import jsonable
from mftire.iotools.tir import TirParameters
from mftire.parallel import Executor, Pending
from mftire.progress import reporter
from mftire.tyre import Tyre

__all__ = ["Bands", "bootstrap_bands", "start_bootstrap_bands", "PendingBands", "band_coverage", "coverage_table",
           "resample_sweeps", "write_bands", "BAND_CHANNELS", "Calibration", "CellScale", "fit_cell_scale",
           "effective_sample_size", "grouped_conformal_quantile", "SCALE_CONDITIONS",
           "ConditionFold", "condition_folds", "new_level"]

#: Channels given bands.
BAND_CHANNELS: tuple[str, ...] = ("Fx", "Fy", "Mz", "Mx", "My")
_DERIVED = ("Fz_set", "gamma_set", "P_set", "Vx_set", "sweep_id", "kind", "sweep_var", "kappa_set", "alpha_set",
            "sweep_dir", "direction", "weight", "family", "var", "held", "curve_id")


@dataclass
class Bands:
    """Bootstrap replicates of a fit and the band they give at any operating point.

    Attributes
    ----------
    base : TirParameters
        The full fit.
    replicates : list of TirParameters
        The refitted replicates (failed replicates are left out).
    level : float
        Nominal coverage of the bands, e.g. 0.95 (quantiles 2.5 % and 97.5 %).
    sigma : dict
        ``{channel: {source: σ}}`` residual scatter of the full fit [N or N·m].
    mode : int
        Evaluation mode of the bands (``211`` or ``221``).
    keys : list of str
        Coefficients fitted (those that vary between replicates).
    n_requested, n_failed : int
        Replicates asked for and replicates whose fit failed.
    stages : str
        Stages run per replicate.
    time : float
        Wall time of the bootstrap [s].
    grid : DataFrame or None
        Grid points with their bands (see :meth:`at`), filled by :func:`bootstrap_bands`.
    notes : list of str
        How the bands were made (for reports).
    calibration : Calibration or None
        Conformal calibration of the prediction band (see :class:`Calibration`); None: the
        uncalibrated band (replicate spread and z·σ in quadrature).
    """

    base: TirParameters
    replicates: list[TirParameters]
    level: float
    sigma: dict[str, dict[str, float]]
    mode: int
    keys: list[str]
    n_requested: int
    n_failed: int = 0
    stages: str = "all"
    time: float = 0.0
    grid: pd.DataFrame | None = None
    notes: list[str] = field(default_factory=list)
    calibration: Calibration | None = None

    def sigma_for(self, channel: str, sources: np.ndarray | None) -> np.ndarray | float:
        """σ [channel unit] per row for the given source labels (largest σ for unknown sources)."""
        per = self.sigma.get(channel, {})
        fallback = max(per.values()) if per else 0.0
        if sources is None:
            return fallback
        return np.array([per.get(str(s), fallback) for s in sources], dtype=float)

    def curves(self, points: pd.DataFrame, channels: Sequence[str] = BAND_CHANNELS) -> tuple[dict, dict]:
        """(full fit, replicate matrix) per channel at ``points``: ``{ch: (P,)}``, ``{ch: (B, P)}``."""
        base = _evaluate(Tyre(self.base), points, self.mode, channels)
        reps = [_evaluate(Tyre(r), points, self.mode, channels) for r in self.replicates]
        mat = {ch: np.vstack([r[ch] for r in reps]) if reps else np.empty((0, len(points))) for ch in channels}
        return base, mat

    def at(self, points: pd.DataFrame, source: str | Sequence[str] | None = None,
           channels: Sequence[str] = BAND_CHANNELS) -> pd.DataFrame:
        """Bands at arbitrary operating points.

        Parameters
        ----------
        points : DataFrame
            ``Fz`` [N], ``kappa`` [-], ``alpha`` [rad], ``gamma`` [rad], ``Vx`` [m/s],
            ``P`` [Pa] (``phit`` ignored: the fit is at φt = 0).
        source : str or sequence, optional
            Source label(s) whose σ widens the prediction band; default the ``source``
            column of ``points`` when present, else the largest σ.

        Returns
        -------
        DataFrame
            Same index as ``points``; per channel ``{ch}`` (full fit), ``{ch}_lo``,
            ``{ch}_hi`` (confidence band), ``{ch}_pred_lo``, ``{ch}_pred_hi``
            (prediction band).
        """
        if source is None and "source" in points.columns:
            src = points["source"].astype(str).to_numpy()
        elif source is None:
            src = None
        else:
            src = np.broadcast_to(np.asarray(source, dtype=object), (len(points),))
        base, mat = self.curves(points, channels)
        z = float(stats.norm.ppf(0.5 + self.level / 2))
        q = (0.5 - self.level / 2, 0.5 + self.level / 2)
        out = {}
        for ch in channels:
            f = base[ch]
            if mat[ch].shape[0]:
                lo, hi = _column_quantiles(mat[ch], q)
            else:
                lo = hi = f
            dlo, dhi = np.maximum(f - lo, 0.0), np.maximum(hi - f, 0.0)
            out[ch] = f
            out[f"{ch}_lo"] = f - dlo
            out[f"{ch}_hi"] = f + dhi
            if self.calibration is not None and ch in self.calibration.q:
                # calibrated: q·s(f̂), never narrower than the confidence band
                w = self.calibration.half_width(ch, f, src, slip_class(points), points)
                out[f"{ch}_pred_lo"] = f - np.maximum(w, dlo)
                out[f"{ch}_pred_hi"] = f + np.maximum(w, dhi)
            else:
                s = z * self.sigma_for(ch, src)
                out[f"{ch}_pred_lo"] = f - np.sqrt(dlo**2 + s**2)
                out[f"{ch}_pred_hi"] = f + np.sqrt(dhi**2 + s**2)
        return pd.DataFrame(out, index=points.index)

    def coefficient_table(self) -> pd.DataFrame:
        """Per fitted coefficient: full-fit value, replicate mean, std and the level quantiles."""
        q = (0.5 - self.level / 2, 0.5 + self.level / 2)
        rows = []
        for k in self.keys:
            v = np.array([r.get(k) for r in self.replicates], dtype=float)
            rows.append({"coefficient": k, "fit": float(self.base.get(k)),
                         "mean": float(np.mean(v)) if v.size else math.nan,
                         "std": float(np.std(v, ddof=1)) if v.size > 1 else math.nan,
                         "lo": float(np.quantile(v, q[0])) if v.size else math.nan,
                         "hi": float(np.quantile(v, q[1])) if v.size else math.nan})
        return pd.DataFrame(rows, columns=["coefficient", "fit", "mean", "std", "lo", "hi"])

    def to_dict(self) -> dict[str, Any]:
        """Summary for ``bands.json``: settings, σ, coefficient quantiles and replicate values."""
        return {
            "level": self.level, "mode": self.mode, "n_requested": self.n_requested,
            "n_replicates": len(self.replicates), "n_failed": self.n_failed, "stages": self.stages,
            "time_s": self.time, "sigma": self.sigma, "notes": self.notes,
            "calibration": self.calibration.to_dict() if self.calibration is not None else None,
            "coefficients": self.coefficient_table().to_dict(orient="records"),
            "replicates": [{k: float(r.get(k)) for k in self.keys} for r in self.replicates],
        }  # fmt: skip


@dataclass
class Calibration:
    """Conformal calibration of the prediction band on out-of-fold residuals.

    The data's groups (whole sweeps by default, or the levels of a condition column such as
    ``Vx_set``) are split into ``folds`` folds, stratified by source and sweep kind; each fold
    is left out in turn, the model refitted (warm-started, like the replicates) without it and
    evaluated on it.  Those out-of-fold residuals ``r`` measure what a *new* measurement
    misses: noise, sweep-to-sweep scatter and the model's lack of fit, with the fit's own
    absorption of the noise removed.  Per channel and source:

    * per cell (source and slip class: pure longitudinal, pure lateral or combined points, whose
      errors differ in kind; :func:`slip_class`) a heteroscedastic scale
      ``s(f̂) = sqrt(a² + (b·f̂)²)`` (a noise floor plus a part
      proportional to the force, e.g. grip scatter, fitted by non-negative least squares of
      ``r²`` on ``[1, f̂²]``; ``a`` is kept ≥ 10 % of the RMS residual), and
    * a local factor ``v(x)`` of the operating conditions ``x`` (load, speed, pressure, camber:
      :data:`SCALE_CONDITIONS`): the kernel-weighted mean of the normalised squared residuals
      ``u² = r²/s(f̂)²`` of the calibration sweeps near ``x`` (Gaussian kernel, each condition in
      units of its spread over the cell's sweeps; Fan & Yao 1998, variance by local smoothing).  Its
      bandwidth is chosen per cell from :data:`_BANDWIDTHS` by the Gaussian likelihood of each
      sweep's residuals under the factor made of the *other* sweeps (leave one sweep out), and
      ``∞`` (one factor for the cell, the plain scale) wins whenever the data show no predictable
      trend over the conditions.  A held-out condition (a new speed, a new load) thus gets the
      scatter of the sweeps nearest to it, where the model's error differs from condition to
      condition (a missing speed effect: large at the ends of the speed range), and noise that
      grows with the load is followed even where the channel's own value does not grow
      (Fy and My in a braking sweep);
    * the split-conformal quantile ``q`` of the scores ``|r| / (s(f̂)·sqrt(v₋(x)))`` (``v₋``: the
      factor without the point's own sweep, as for a new measurement): the
      ``ceil((n + 1)·level)``-th smallest (Vovk et al. 2005; Lei et al. 2018, normalised
      scores; Barber et al. 2021 for cross-fitting).

    The prediction band is ``f̂ ± q·s(f̂)·sqrt(v(x))`` (never narrower than the confidence band).
    It is a band for a new *measured point* (noise, sweep offsets and the model's lack of fit
    included), not for the mean curve.  Its level holds on average over new sweeps exchangeable
    with the calibration sweeps; at one particular condition it holds only as well as the local
    factor follows the error there, and on a few sweeps the counted coverage scatters widely
    (points of one sweep share its offset: three sweeps give three draws, not 120).

    Attributes
    ----------
    level : float
    by : list of str
        Columns whose distinct values are the groups left out together.
    folds : int
        Folds used (at most the number of groups).
    scale : dict
        ``{channel: {cell: (a, b)}}`` with ``a`` [channel unit], ``b`` [-]; a cell is
        ``"source|slip class"`` (:func:`slip_class`: longitudinal, lateral, combined) or
        ``"source|*"`` (all the source's points).
    q : dict
        ``{channel: {cell: q}}`` conformal quantiles of the normalised scores.
    n : dict
        ``{channel: {cell: points}}`` calibration points.
    cells : dict
        ``{channel: {cell: CellScale}}`` the fitted scale of each cell (the numbers above and the
        local factor).
    failed : int
        Fold fits that failed (their points are left out).
    cv_coverage : dict
        ``{channel: {source: fraction}}`` cross-validated coverage: each fold's points against
        the band calibrated on the other folds only (scale and quantile), by a model that did
        not see them — an honest held-out coverage of the procedure.
    conditions : dict
        ``{channel: {cell: {"condition|kind": CellScale}}}`` the cells of the condition folds
        (:func:`condition_folds`; kind ``interior`` or ``exterior``) that replace the sweep folds' band at a
        new level of that condition (:meth:`half_width`); a cell whose sweep band held the level on the
        condition folds' points has none.
    levels : dict
        ``{cell: {condition: [set-point levels]}}`` of the calibration data (what :func:`new_level` compares).
    condition_folds : list of dict
        Per condition fold its condition, level, kind, stratum, sweeps and status (used, dropped because the
        refit lost a coefficient, failed), then per channel, cell and condition kind the sweep folds' band's
        coverage of the condition folds' points, its standard error and the band chosen.
    """

    level: float
    by: list[str]
    folds: int
    scale: dict[str, dict[str, tuple[float, float]]]
    q: dict[str, dict[str, float]]
    n: dict[str, dict[str, int]]
    cells: dict[str, dict[str, CellScale]] = field(default_factory=dict)
    failed: int = 0
    cv_coverage: dict[str, dict[str, float]] = field(default_factory=dict)
    conditions: dict[str, dict[str, dict[str, CellScale]]] = field(default_factory=dict)
    levels: dict[str, dict[str, list[float]]] = field(default_factory=dict)
    condition_folds: list[dict[str, Any]] = field(default_factory=list)

    def half_width(self, channel: str, f: np.ndarray, sources: np.ndarray | None,
                   slip: np.ndarray | None = None, conditions: pd.DataFrame | None = None) -> np.ndarray:
        """Half-width ``q·s(f̂, x)`` [channel unit] of the prediction band at model values ``f``, per row
        for the given source labels, slip classes (:func:`slip_class`) and operating conditions
        (``conditions``: columns of :data:`SCALE_CONDITIONS`; None: the cell's mean local factor; a row at a
        new level of a condition with condition folds takes their cell, :attr:`conditions`).  A
        (source, slip class) cell without calibration points takes the source's pooled cell; an unknown
        source, or None, the widest source."""
        f = np.asarray(f, dtype=float)
        n = f.shape[0]
        slip = np.full(n, "*", dtype=object) if slip is None else np.asarray(slip, dtype=object)
        per_q = self.q[channel]
        srcs = sorted({c.split("|")[0] for c in per_q})
        X = _condition_matrix(conditions, n)

        def width(src: str) -> np.ndarray:
            out = np.full(n, np.nan)
            for cls in set(slip.tolist()):
                m = slip == cls
                cell = f"{src}|{cls}" if f"{src}|{cls}" in per_q else f"{src}|*"
                out[m] = self.cells[channel][cell].half_width(f[m], None if X is None else X[m])
                if X is not None:
                    out[m] = self._condition_width(channel, cell, f[m], X[m], out[m])
            return out

        w = {src: width(src) for src in srcs}
        widest = np.vstack(list(w.values())).max(axis=0)
        if sources is None:
            return widest
        sources = np.asarray(sources).astype(str)
        out = widest.copy()
        for src in srcs:
            m = sources == src
            out[m] = w[src][m]
        return out

    def _condition_width(self, channel: str, cell: str, f: np.ndarray, X: np.ndarray, w: np.ndarray) -> np.ndarray:
        """Half-widths ``w`` of the sweep folds' cell, replaced at rows whose conditions are a new level of a
        condition with condition folds (:func:`new_level`): the width of that condition's interior or exterior
        cell (the largest over the conditions a row is new in; the sweep folds' width where that kind has no
        cell)."""
        per = self.conditions.get(channel, {}).get(cell)
        lev = self.levels.get(cell, {})
        if not per:
            return w
        out = np.full(w.shape, -np.inf)
        new_any = np.zeros(w.shape, bool)
        for j, cond in enumerate(SCALE_CONDITIONS):
            if not any(k.split("|")[0] == cond for k in per):
                continue
            new, interior = new_level(X[:, j], lev.get(cond, []))
            for kind, mk in (("interior", new & interior), ("exterior", new & ~interior)):
                if mk.any():
                    cs = per.get(f"{cond}|{kind}")
                    out[mk] = np.maximum(out[mk], cs.half_width(f[mk], X[mk]) if cs is not None else w[mk])
                    new_any |= mk
        return np.where(new_any, out, w)

    def to_dict(self) -> dict[str, Any]:
        return {"level": self.level, "by": self.by, "folds": self.folds, "failed": self.failed,
                "condition_folds": self.condition_folds, "levels": self.levels,
                "condition_cells": {c: {k: {ck: cs.summary() | {"q": cs.q, "factor": float(cs.factor(None)[0])}
                                            for ck, cs in per.items()} for k, per in cells.items()}
                                    for c, cells in self.conditions.items()},
                "scale": {c: {s: {"a": v[0], "b": v[1]} for s, v in per.items()} for c, per in self.scale.items()},
                "q": self.q, "n": self.n, "cv_coverage": self.cv_coverage,
                "local": {c: {k: cs.summary() for k, cs in per.items()} for c, per in self.cells.items()}}


#: Tolerances of :func:`slip_class`: |α| below 0.5° is "no side slip", |κ| below 0.01 "no longitudinal slip".
_ALPHA_TOL = math.radians(0.5)
_KAPPA_TOL = 0.01


def new_level(x: np.ndarray, levels: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """``(new, interior)`` per value of a condition ``x`` against the calibration data's set-point ``levels``:
    new when farther than :data:`_LEVEL_TOL` × the smallest gap between levels from every level (a load
    wandering about its set point is that level), interior when strictly inside the levels' range.  NaN and
    fewer than two levels: never new."""
    x = np.asarray(x, dtype=float)
    L = np.sort(np.asarray(levels, dtype=float))
    if L.size < 2:
        return np.zeros(x.shape, bool), np.zeros(x.shape, bool)
    tol = _LEVEL_TOL * float(np.min(np.diff(L)))
    with np.errstate(invalid="ignore"):
        d = np.min(np.abs(x[:, None] - L[None, :]), axis=1)
        new = np.isfinite(x) & (d > tol)
        interior = (x > L[0]) & (x < L[-1])
    return new, interior


def slip_class(points: pd.DataFrame) -> np.ndarray:
    """Per point ``"longitudinal"`` (|α| < 0.5°), ``"lateral"`` (|κ| < 0.01, α ≠ 0) or ``"combined"``,
    from the inputs alone (grid points and raw held-out rows alike)."""
    a = np.abs(points["alpha"].to_numpy(float)) if "alpha" in points else np.zeros(len(points))
    k = np.abs(points["kappa"].to_numpy(float)) if "kappa" in points else np.zeros(len(points))
    return np.where(a < _ALPHA_TOL, "longitudinal", np.where(k < _KAPPA_TOL, "lateral", "combined"))


def conformal_quantile(scores: np.ndarray, level: float) -> float:
    """The ``ceil((n + 1)·level)``-th smallest score (the largest when that exceeds ``n``)."""
    s = np.sort(np.asarray(scores, dtype=float)[np.isfinite(scores)])
    if s.size == 0:
        return math.nan
    k = min(math.ceil((s.size + 1) * level), s.size)
    return float(s[k - 1])


def heteroscedastic_scale(residual: np.ndarray, f: np.ndarray) -> tuple[float, float]:
    """``(a, b)`` of ``s(f) = sqrt(a² + (b·f)²)``: NNLS of ``r²`` on ``[1, f²]``, ``a ≥ 0.1·RMS(r)``."""
    from scipy.optimize import nnls

    r2 = np.asarray(residual, dtype=float) ** 2
    f2 = np.asarray(f, dtype=float) ** 2
    ok = np.isfinite(r2) & np.isfinite(f2)
    r2, f2 = r2[ok], f2[ok]
    rms = math.sqrt(float(np.mean(r2))) if r2.size else 0.0
    if r2.size < 3 or rms == 0.0:
        return max(rms, 1e-12), 0.0
    cs = max(float(np.mean(f2)), 1e-300)  # column scaling for a well-conditioned NNLS
    coef, _ = nnls(np.column_stack([np.ones_like(f2), f2 / cs]), r2)
    a = max(math.sqrt(coef[0]), 0.1 * rms)
    b = math.sqrt(coef[1] / cs)
    return a, b


#: Operating conditions of the local factor of the prediction band's scale (:class:`CellScale`).
SCALE_CONDITIONS: tuple[str, ...] = ("Fz", "Vx", "P", "gamma")
#: Kernel bandwidths tried for the local factor [spread of each condition over the cell's sweeps]; ``inf``: one
#: factor for the whole cell.
_BANDWIDTHS = (0.35, 0.5, 0.7, 1.0, 1.4, 2.0, math.inf)


def _condition_matrix(points: pd.DataFrame | None, n: int) -> np.ndarray | None:
    """``(n, len(SCALE_CONDITIONS))`` operating conditions of ``points`` (NaN for a missing column)."""
    if points is None:
        return None
    return np.column_stack([points[c].to_numpy(float) if c in points.columns else np.full(n, np.nan)
                            for c in SCALE_CONDITIONS])


@dataclass
class CellScale:
    """Scale of the prediction band in one calibration cell: ``q·sqrt(a² + (b·f̂)²)·sqrt(v(x))``.

    ``v(x)`` is the local factor of the operating conditions ``x`` (:data:`SCALE_CONDITIONS`): the
    kernel-weighted mean, over the calibration sweeps, of each sweep's mean normalised squared residual
    ``u²`` (kernel ``exp(-d²/2h²)`` times the sweep's points; ``d`` the distance in units of each
    condition's spread ``sd`` over the sweeps; conditions that do not vary are left out); ``h = inf``
    gives one factor for the cell.
    """

    a: float  #: noise floor [channel unit]
    b: float  #: part proportional to the model value [-]
    q: float  #: conformal quantile of the normalised scores [-]
    h: float  #: kernel bandwidth [spread units]; inf: no local factor
    mu: np.ndarray  #: centre of each condition (NaN: not used)
    sd: np.ndarray  #: spread of each condition over the sweeps (NaN: not used)
    xs: np.ndarray  #: (S, d) conditions of the calibration sweeps, normalised
    us: np.ndarray  #: (S,) mean u² per sweep
    ns: np.ndarray  #: (S,) points per sweep
    n_eff: float = math.nan  #: effective number of independent calibration points (:func:`effective_sample_size`)

    def factor(self, X: np.ndarray | None, exclude_own: bool = False) -> np.ndarray:
        """Local factor ``v`` at raw conditions ``X`` (rows; None: the cell's mean); ``exclude_own``:
        ``X`` are the calibration sweeps themselves and each leaves itself out."""
        return _local_factor(self.xs, self.us, self.ns, None if X is None else self._norm(X), self.h, exclude_own)

    def _norm(self, X: np.ndarray) -> np.ndarray:
        use = np.isfinite(self.sd)
        Z = (X[:, use] - self.mu[use]) / self.sd[use]
        return np.where(np.isfinite(Z), Z, 0.0)  # a missing condition counts as the centre

    def half_width(self, f: np.ndarray, X: np.ndarray | None = None) -> np.ndarray:
        """Half-width [channel unit] at model values ``f`` and raw conditions ``X``."""
        f = np.asarray(f, dtype=float)
        v = self.factor(X) if X is not None else np.full(f.shape, self.factor(None)[0])
        return self.q * np.hypot(self.a, self.b * f) * np.sqrt(v)

    def summary(self) -> dict[str, Any]:
        used = [c for c, s in zip(SCALE_CONDITIONS, self.sd, strict=True) if np.isfinite(s)]
        return {"bandwidth": self.h if math.isfinite(self.h) else None, "conditions": used,
                "sweeps": int(self.us.size), "effective_points": self.n_eff}


def _local_factor(xs: np.ndarray, us: np.ndarray, ns: np.ndarray, Z: np.ndarray | None, h: float,
                  exclude_own: bool = False) -> np.ndarray:
    """Kernel-weighted geometric mean of ``us`` (weights ``ns·exp(-d²/2h²)``) at normalised conditions ``Z``.

    Geometric: the logarithm of the scatter is smoothed (a multiplicative model of the variance, Harvey
    1976; Yu & Jones 2004), which interpolates a scatter that grows fast over a condition (the error of a
    missing speed effect towards the ends of the speed range) without the upward bias of an arithmetic mean
    between a small and a large neighbour."""
    lu = np.log(np.maximum(us, 1e-12 * max(float(us.max()), 1e-300)))
    glob = float(np.exp(ns @ lu / ns.sum()))
    if Z is None:
        return np.array([glob])
    if exclude_own:
        w = np.broadcast_to(ns, (len(Z), ns.size)).copy()
        np.fill_diagonal(w, 0.0)
    else:
        w = np.broadcast_to(ns, (len(Z), ns.size)).astype(float)
    if math.isfinite(h) and xs.shape[1]:
        d2 = ((Z[:, None, :] - xs[None, :, :]) ** 2).sum(axis=2)
        w = w * np.exp(-d2 / (2.0 * h * h))
    tot = w.sum(axis=1)
    # a point far from every sweep (all weights underflow) gets the cell's mean factor
    return np.where(tot > 1e-300, np.exp((w @ lu) / np.where(tot > 1e-300, tot, 1.0)), glob)


def fit_cell_scale(residual: np.ndarray, f: np.ndarray, X: np.ndarray, sweep: np.ndarray,
                   level: float, few: str = "student") -> CellScale:
    """:class:`CellScale` of out-of-fold residuals ``r`` at model values ``f``, raw conditions ``X``
    (rows of :data:`SCALE_CONDITIONS`) and sweep labels ``sweep``; ``few``: the quantile's rule below
    ``level/(1 − level)`` effective draws (:func:`grouped_conformal_quantile`)."""
    r = np.asarray(residual, dtype=float)
    f = np.asarray(f, dtype=float)
    a, b = heteroscedastic_scale(r, f)
    u2 = (r / np.hypot(a, b * f)) ** 2
    ids, inv = np.unique(np.asarray(sweep), return_inverse=True)
    inv = inv.ravel()
    ns = np.bincount(inv).astype(float)
    us = np.bincount(inv, weights=u2) / ns
    # each sweep's conditions: the median of its points (loads wander about their set point)
    xs_raw = np.vstack([np.nanmedian(X[inv == i], axis=0) for i in range(ids.size)])
    mu = np.nanmean(xs_raw, axis=0)
    sd = np.nanstd(xs_raw, axis=0)
    vary = np.isfinite(sd) & (sd > 1e-6 * np.maximum(np.abs(mu), 1.0))
    mu, sd = np.where(vary, mu, np.nan), np.where(vary, sd, np.nan)
    xs = (xs_raw[:, vary] - mu[vary]) / sd[vary]
    best_h, best_v = math.inf, None
    if ids.size >= 3:
        best = math.inf
        for h in _BANDWIDTHS:
            if math.isfinite(h) and not vary.any():
                continue
            v = np.maximum(_local_factor(xs, us, ns, xs, h, exclude_own=True), 1e-12)
            nll = float(ns @ (np.log(v) + us / v))  # Gaussian likelihood of each sweep's points, leave-one-sweep-out
            if not math.isfinite(best) or nll < best - 1e-9 * abs(best):  # ties: the wider kernel (listed later) loses
                best, best_h, best_v = nll, h, v
    if best_v is None:  # fewer than three sweeps: no local factor
        best_v = np.ones(ids.size)
        us = np.ones(ids.size)
    score = np.sqrt(u2 / best_v[inv])
    n_eff = effective_sample_size(r / np.hypot(a, b * f) / np.sqrt(best_v[inv]), inv)
    return CellScale(a, b, grouped_conformal_quantile(score, level, n_eff, few), best_h, mu, sd, xs, us, ns, n_eff)


def effective_sample_size(u: np.ndarray, group: np.ndarray) -> float:
    """Kish's effective number of independent points ``N / (1 + (m − 1)·ρ)`` of values ``u`` in groups (sweeps),
    ``ρ`` the intra-class correlation of one-way ANOVA (clipped to 0..1), ``m`` the mean group size
    (ANOVA's ``m₀``); between the number of groups and of points."""
    u = np.asarray(u, dtype=float)
    ids, inv = np.unique(np.asarray(group), return_inverse=True)
    inv = inv.ravel()
    N, S = u.size, ids.size
    if S < 2 or N <= S:
        return float(max(S, 1))
    n = np.bincount(inv).astype(float)
    mean_g = np.bincount(inv, weights=u) / n
    msb = float(n @ (mean_g - u.mean()) ** 2) / (S - 1)
    msw = float(np.sum((u - mean_g[inv]) ** 2)) / (N - S)
    m0 = (N - float(n @ n) / N) / (S - 1)
    den = msb + (m0 - 1.0) * msw
    rho = min(max((msb - msw) / den, 0.0), 1.0) if den > 0 else 0.0
    return float(min(max(N / (1.0 + (m0 - 1.0) * rho), S), N))


def grouped_conformal_quantile(scores: np.ndarray, level: float, n_eff: float, few: str = "student") -> float:
    """Conformal quantile of scores that are ``n_eff`` independent draws (the points of a sweep share its
    offset): the empirical quantile at ``level·(1 + 1/n_eff)`` (the split-conformal rank ``(n + 1)·level``
    with ``n = n_eff``).  When that exceeds 1 (fewer than ``level/(1 − level)`` effective draws, e.g. 19 for
    95 %), no order statistic holds the level and the Gaussian prediction quantile
    ``t_{n_eff−1}((1 + level)/2)·sqrt(1 + 1/n_eff)·RMS(scores)`` is used (Student's prediction interval of a
    new draw), never below the plain split-conformal quantile of the points.  ``few="max"``: the largest score
    instead (the conformal rank clipped to the largest: for scores that are the shape of a systematic model
    error along a sweep, not Gaussian draws, such as the condition folds' of :class:`Calibration`)."""
    if few not in ("student", "max"):
        raise ValueError(f"few must be 'student' or 'max', got {few!r}")
    s = np.asarray(scores, dtype=float)
    s = s[np.isfinite(s)]
    if s.size == 0:
        return math.nan
    lev = level * (1.0 + 1.0 / n_eff)
    if lev < 1.0:
        return max(float(np.quantile(s, lev, method="higher")), conformal_quantile(s, level))
    if few == "max":
        return float(s.max())
    dof = max(n_eff - 1.0, 1.0)
    t = float(stats.t.ppf(0.5 + level / 2, dof)) * math.sqrt(1.0 + 1.0 / n_eff)
    return max(t * math.sqrt(float(np.mean(s**2))), conformal_quantile(s, level))


#: Fewest calibration points and sweeps of a (source, slip class) cell; smaller cells use the source's pooled cell
#: (the points of a sweep share its offset and drift: the sweeps, not the points, are the independent draws).
_MIN_CELL = 40
_MIN_CELL_SWEEPS = 5


def _fold_ids(table: pd.DataFrame, by: Sequence[str], folds: int, rng: np.random.Generator) -> np.ndarray:
    """Fold number per row: the groups (distinct ``by`` values) shuffled within each source/kind
    stratum and dealt round-robin, so every fold holds a share of every stratum."""
    key = table[list(by)].astype(str).agg("|".join, axis=1) if len(by) > 1 else table[by[0]].astype(str)
    info = pd.DataFrame({"g": key, "s": table["source"].astype(str) + "|" + table["kind"].astype(str)})
    first = info.drop_duplicates("g")
    fold_of: dict[str, int] = {}
    i = 0
    for _, grp in first.groupby("s", sort=True):
        for g in rng.permutation(grp["g"].to_numpy()):
            if g not in fold_of:
                fold_of[g] = i % folds
                i += 1
    return key.map(fold_of).to_numpy(int)


#: Fewest levels of a condition in a (source, sweep kind) stratum for its condition folds: a fold leaving one
#: level out keeps 3, which still identify a quadratic in the condition (fewer: the fold's refit loses the
#: full fit's coefficients of that condition and measures another model's error).
_MIN_LEVELS = 4
#: A condition value within this share of the gap to the nearest other level counts as that level.
_LEVEL_TOL = 0.4


def _levels(values: np.ndarray) -> np.ndarray:
    """Distinct set-point levels (to 6 decimals of the SI value; NaN left out)."""
    v = np.asarray(values, dtype=float)
    return np.unique(np.round(v[np.isfinite(v)], 6))


@dataclass(frozen=True)
class ConditionFold:
    """One condition fold: the sweeps of a (source, sweep kind) stratum at one level of a condition.

    ``kind`` is ``"interior"`` when the level lies strictly between the stratum's other levels of that
    condition (the refit interpolates to it) and ``"exterior"`` otherwise (the refit extrapolates)."""

    condition: str  #: a name of :data:`SCALE_CONDITIONS`
    level: float  #: the set point left out [SI]
    kind: str  #: "interior" or "exterior"
    stratum: str  #: "source|sweep kind"
    rows: np.ndarray  #: boolean mask of the table's rows left out


def condition_folds(table: pd.DataFrame, conditions: Sequence[str] = SCALE_CONDITIONS,
                    min_levels: int = _MIN_LEVELS) -> list[ConditionFold]:
    """The leave-one-level-out folds of a grouped table: per (source, sweep kind) stratum and condition with at
    least ``min_levels`` set-point levels (``Fz_set``, ``Vx_set``, ``P_set``, ``gamma_set``), one fold per level."""
    if "source" not in table.columns or "kind" not in table.columns:
        return []
    stratum = (table["source"].astype(str) + "|" + table["kind"].astype(str)).to_numpy()
    out = []
    for st in sorted(set(stratum)):
        m = stratum == st
        for cond in conditions:
            col = SET_POINT_COLUMNS[cond]
            if col not in table.columns:
                continue
            x = np.round(table[col].to_numpy(float), 6)
            lev = _levels(x[m])
            if lev.size < min_levels:
                continue
            for i, L in enumerate(lev):
                kind = "interior" if 0 < i < lev.size - 1 else "exterior"
                out.append(ConditionFold(cond, float(L), kind, st, m & (x == L)))
    return out


def _strip(table: pd.DataFrame) -> pd.DataFrame:
    return table.drop(columns=[c for c in table.columns if c in _DERIVED or str(c).startswith("fit_")])


def _calibrate(table: pd.DataFrame, fold: np.ndarray, results: list, mode: int, level: float, by: list[str],
               channels: Sequence[str], cond: Sequence[ConditionFold] = (), cond_results: Sequence = (),
               ) -> Calibration:
    """:class:`Calibration` from the fold fits (``results[k]``: parameters or an error text) and the condition
    folds' fits (``cond_results[k]`` of ``cond[k]``)."""
    chans = [c for c in channels if c in table.columns and table[c].notna().any()]
    fhat = {c: np.full(len(table), np.nan) for c in chans}
    failed = 0
    for k, r in enumerate(results):
        if isinstance(r, str):
            failed += 1
            continue
        rows = np.nonzero(fold == k)[0]
        ev = _evaluate(Tyre(r), table.iloc[rows], mode, chans)
        for c in chans:
            fhat[c][rows] = ev[c]
    src = table["source"].astype(str).to_numpy()
    cls = slip_class(table)
    X = _condition_matrix(table, len(table))
    sweep = table["sweep_id"].to_numpy()
    scale: dict = {}
    qs: dict = {}
    ns: dict = {}
    cells: dict = {}
    for c in chans:
        y = table[c].to_numpy(float)
        ok = np.isfinite(y) & np.isfinite(fhat[c])
        for s in sorted(set(src)):
            for k in ("*", "longitudinal", "lateral", "combined"):
                m = ok & (src == s) & ((cls == k) if k != "*" else True)
                if k != "*" and (m.sum() < _MIN_CELL or np.unique(sweep[m]).size < _MIN_CELL_SWEEPS):
                    continue
                if m.sum() < 5:
                    continue
                cs = fit_cell_scale(y[m] - fhat[c][m], fhat[c][m], X[m], sweep[m], level)
                cell = f"{s}|{k}"
                cells.setdefault(c, {})[cell] = cs
                scale.setdefault(c, {})[cell] = (cs.a, cs.b)
                qs.setdefault(c, {})[cell] = cs.q
                ns.setdefault(c, {})[cell] = int(m.sum())
    cv: dict = {}
    for c in qs:  # nested: each fold against the cell's scale, local factor and quantile from the other folds
        y = table[c].to_numpy(float)
        ok = np.isfinite(y) & np.isfinite(fhat[c])
        for s in sorted(set(src)):
            inside = np.zeros(len(table), bool)
            used = np.zeros(len(table), bool)
            for k in ("longitudinal", "lateral", "combined"):
                cell = f"{s}|{k}" if f"{s}|{k}" in qs[c] else f"{s}|*"
                if cell not in qs[c]:
                    continue
                m = ok & (src == s) & (cls == k)
                mc = ok & (src == s) & ((cls == k) if cell.endswith(k) else True)  # the cell's calibration points
                for i in range(len(results)):
                    test, train = m & (fold == i), mc & (fold != i)
                    if not test.any() or train.sum() < 5:
                        continue
                    cs = fit_cell_scale(y[train] - fhat[c][train], fhat[c][train], X[train], sweep[train], level)
                    inside[test] = np.abs(y[test] - fhat[c][test]) <= cs.half_width(fhat[c][test], X[test])
                    used[test] = True
            if used.any():
                cv.setdefault(c, {})[s] = float(inside[used].mean())
    levels, conds, info = _condition_cells(table, cond, cond_results, mode, level, chans, cells, src, cls, X, sweep)
    return Calibration(level, by, len(results), scale, qs, ns, cells, failed, cv, conds, levels, info)


#: The sweep folds' band is kept at a new level when it covers the condition folds' points within this many
#: standard errors (over their sweeps) of the level, or within ``_CHECK_TOL``.
_CHECK_Z = 2.0
_CHECK_TOL = 0.01


def _condition_cells(table: pd.DataFrame, cond: Sequence[ConditionFold], results: Sequence, mode: int,
                     level: float, chans: Sequence[str], cells: dict, src: np.ndarray, cls: np.ndarray,
                     X: np.ndarray, sweep: np.ndarray) -> tuple[dict, dict, list]:
    """The condition cells of :class:`Calibration` (``{channel: {cell: {"condition|kind": CellScale}}}``), each
    cell's set-point levels, and a summary of the condition folds."""
    info: list[dict] = []
    fhat: dict[tuple[str, str], dict[str, np.ndarray]] = {}
    for cf, r in zip(cond, results, strict=True):
        if isinstance(r, str):
            status = ("dropped: not identified " + r[len(_UNIDENTIFIED):]) if r.startswith(_UNIDENTIFIED) \
                else "failed: " + r
        else:
            status = "used"
            rows = np.nonzero(cf.rows)[0]
            ev = _evaluate(Tyre(r), table.iloc[rows], mode, chans)
            per = fhat.setdefault((cf.condition, cf.kind), {c: np.full(len(table), np.nan) for c in chans})
            for c in chans:
                per[c][rows] = ev[c]
        info.append({"condition": cf.condition, "level": cf.level, "kind": cf.kind, "stratum": cf.stratum,
                     "sweeps": int(np.unique(sweep[cf.rows]).size), "status": status})
    levels: dict[str, dict[str, list[float]]] = {}
    for per_cell in cells.values():
        for cell in per_cell:
            if cell not in levels:
                s, k = cell.split("|")
                m = (src == s) & ((cls == k) if k != "*" else True)
                levels[cell] = {c: _levels(table[col].to_numpy(float)[m]).tolist()
                                for c, col in SET_POINT_COLUMNS.items() if col in table.columns}
    out: dict = {}
    checks: list[dict] = []
    for (cname, kind), per in fhat.items():
        for c in chans:
            y = table[c].to_numpy(float)
            for cell, base in cells.get(c, {}).items():
                s, k = cell.split("|")
                m = np.isfinite(y) & np.isfinite(per[c]) & (src == s) & ((cls == k) if k != "*" else True)
                if m.sum() < 5 or np.unique(sweep[m]).size < 2:
                    continue
                r, f = y[m] - per[c][m], per[c][m]
                # the sweep folds' band checked on the condition folds' points: kept where it holds the level
                # there within twice its standard error over the sweeps (the data show no difference of kind)
                inside = np.abs(r) <= base.half_width(f, X[m])
                cov, se = float(inside.mean()), _cluster_se(inside, sweep[m])
                keep = math.isfinite(se) and abs(cov - level) <= max(_CHECK_Z * se, _CHECK_TOL)
                checks.append({"channel": c, "cell": cell, "condition": cname, "kind": kind,
                               "sweeps": int(np.unique(sweep[m]).size), "sweep_band_coverage": cov,
                               "se": se, "band": "sweep folds" if keep else "condition folds"})
                if keep:
                    continue
                # the cell of the condition folds, the largest score as its quantile: its independent units are
                # the 2-3 levels left out (Student's quantile covered 99.9 % of the Fx points at 80 km/h over 20
                # campaigns: validation/README.md)
                cs = fit_cell_scale(r, f, X[m], sweep[m], level, few="max")
                out.setdefault(c, {}).setdefault(cell, {})[f"{cname}|{kind}"] = cs
    return levels, out, info + checks


def _column_quantiles(mat: np.ndarray, q: tuple[float, float]) -> np.ndarray:
    """``np.nanquantile(mat, q, axis=0)``, the same numbers: columns without NaN in one vectorised
    call (numpy's nanquantile goes column by column in Python)."""
    nan = np.isnan(mat).any(axis=0)
    out = np.empty((len(q), mat.shape[1]))
    out[:, ~nan] = np.quantile(mat[:, ~nan], q, axis=0)
    if nan.any():
        out[:, nan] = np.nanquantile(mat[:, nan], q, axis=0)
    return out


def _evaluate(tyre: Tyre, points: pd.DataFrame, mode: int, channels: Sequence[str]) -> dict[str, np.ndarray]:
    out = tyre.evaluate_frame(points.drop(columns=["phit", "omega"], errors="ignore"), mode=mode)
    return {ch: out[ch].to_numpy(dtype=float, copy=True) for ch in channels}


def resample_sweeps(table: pd.DataFrame, rng: np.random.Generator, strata: Sequence[str] = ("source", "kind"),
                    ) -> pd.DataFrame:
    """One bootstrap replicate: whole sweeps drawn with replacement within each stratum.

    ``table`` is a grouped table (``sweep_id``, ``kind``, ``source``).  Each drawn copy
    gets its own ``file`` label (``b<draw>/<file>``: the base name, and hence per-file
    weights, are unchanged) so that two copies of one sweep stay two sweeps.  The
    derived grouping columns are dropped: the fit groups the replicate afresh.
    """
    sweeps = table.groupby("sweep_id", sort=True)
    info = sweeps[list(strata)].first()
    parts = []
    draw = 0
    for _, ids in info.groupby(list(strata), sort=True).groups.items():
        ids = np.asarray(ids)
        for sid in rng.choice(ids, size=ids.size, replace=True):
            part = table.iloc[sweeps.indices[sid]]
            part = part.assign(file=[f"b{draw}/{f}" for f in part["file"].astype(str)])
            parts.append(part)
            draw += 1
    out = pd.concat(parts, ignore_index=True)
    drop = [c for c in out.columns if c in _DERIVED or str(c).startswith("fit_")]
    return out.drop(columns=drop)


#: Start of the result text of a condition fold dropped because its refit lost coefficients of the full fit.
_UNIDENTIFIED = "not identified without the fold: "


@dataclass
class _ReplicateFit:
    """Warm-started refit of one replicate (a picklable callable for process pools).

    With ``prior`` (a calibration fold's refit): a coefficient the full fit identified that the fold's data
    cannot identify (the fold left out the only sweeps of a load, say) would stay at the full fit's value,
    which has seen the left-out sweeps, and the fold's residuals there would not be out-of-sample.  Such
    coefficients are set back to ``prior`` (the full fit's template) and the fold refitted from there.
    """

    start: TirParameters
    stages: Any
    weights: Any
    alpha_star: bool
    identified: tuple[str, ...] = ()
    prior: Mapping[str, float] | None = None
    strict: bool = False  #: a condition fold: losing a coefficient drops the fold (its refit is another model)

    def __call__(self, sample: pd.DataFrame) -> TirParameters | str:
        weights = self.weights
        if isinstance(weights, Mapping):  # a source or file the sample lacks (a fold left it out) weighs nothing
            names = set(sample["source"].astype(str)) if "source" in sample.columns else set()
            if "file" in sample.columns:
                files = sample["file"].astype(str).unique()
                names |= set(files) | {os.path.basename(f) for f in files}
                names |= {os.path.splitext(os.path.basename(f))[0] for f in files}
            weights = {k: v for k, v in weights.items() if k in names}
        try:
            with warnings.catch_warnings():  # degenerate resamples make scipy/numpy warn inside the fit
                warnings.simplefilter("ignore", RuntimeWarning)
                res = fit_tir(sample, self.start, stages=self.stages, weights=weights, alpha_star=self.alpha_star,
                              progress=False)
                lost = sorted(set(self.identified) - set(res.identified))
                if lost and self.strict:
                    return _UNIDENTIFIED + ", ".join(lost)
                if lost and self.prior is not None:
                    start = self.start.copy()
                    for k in lost:
                        if k in self.prior:
                            start.set(k, self.prior[k])
                    res = fit_tir(sample, start, stages=self.stages, weights=weights, alpha_star=self.alpha_star,
                                  progress=False)
                return res.parameters
        except (MftireInputError, ValueError, np.linalg.LinAlgError) as exc:
            return str(exc)


def _fit_weights(fit: FitResult) -> dict[str, float] | None:
    """The per-source weights a given fit ran with (its rows' ``weight``), so that the replicate and fold refits
    weigh the sources as the fit did; None when every row weighs the same or a source's rows differ."""
    df = fit.data
    if "weight" not in df.columns or "source" not in df.columns:
        return None
    w = df.groupby(df["source"].astype(str))["weight"].agg(["min", "max"])
    if not np.allclose(w["min"], w["max"]) or np.allclose(w["min"], w["min"].iloc[0]):
        return None
    return {str(k): float(v) for k, v in w["min"].items()}


def _run_job(task: tuple) -> TirParameters | str:
    fn, sample = task
    return fn(sample)


def _collect(r, reps: list, b: int, n: int, say, t0: float) -> int:
    if isinstance(r, str):
        say(f"replicate {b + 1}/{n} failed: {r}")
        return 1
    reps.append(r)
    say(f"replicate {b + 1}/{n} done ({time.perf_counter() - t0:.1f} s)")
    return 0


def _residual_sigma(result: FitResult, channels: Sequence[str]) -> dict[str, dict[str, float]]:
    df = result.data
    out: dict[str, dict[str, float]] = {}
    for ch in channels:
        if ch not in df.columns or f"fit_{ch}" not in df.columns:
            continue
        r = (df[f"fit_{ch}"] - df[ch]).to_numpy(float)
        ok = np.isfinite(r)
        per = {}
        for src in sorted(df["source"].astype(str).unique()):
            m = ok & (df["source"].astype(str) == src).to_numpy()
            if m.sum() >= 3:
                per[src] = float(1.4826 * np.median(np.abs(r[m])))
        if per:
            out[ch] = per
    return out


def bootstrap_bands(data, template: TirParameters | str | os.PathLike | Tyre, n: int = 50, **options: Any) -> Bands:
    """Bootstrap-over-sweeps bands of the fitted curves (see the module docstring); the keyword ``options`` are
    those of :func:`start_bootstrap_bands` (listed here), which this runs and waits for.

    Parameters
    ----------
    data : DataFrame, path or sequence
        Sweep data as for :func:`~mftire.fitting.fitter.fit_tir` (ignored when ``fit`` is given,
        whose ``data`` is resampled).
    template : TirParameters or path
        Template of the full fit (used only when ``fit`` is None).
    n : int
        Number of bootstrap replicates (each one refit; ≥ 20 for 95 % bands, 50–200 for
        stable tails).
    level : float
        Nominal coverage of the bands (0 < level < 1).
    grid : DataFrame, optional
        Points at which :attr:`Bands.grid` is evaluated; default
        :func:`mftire.compare.data.curve_grid` of the data's sweeps.
    fit : FitResult, optional
        An existing full fit (saves one fit).
    stages : str or sequence, optional
        Stages per replicate; default the stages the full fit ran.
    weights, alpha_star
        As for :func:`fit_tir` (the same in the full fit and every replicate; with ``fit`` given and no
        ``weights``, the per-source weights that fit ran with).
    seed : int, optional
        Random seed of the resampling.
    strata : sequence of str
        Columns of the grouped data within which sweeps are resampled (default source
        and sweep kind; add ``"Fz_set"`` to keep every load in every replicate when each
        load has several sweeps of a kind).
    calibrate : int
        Folds of the conformal calibration of the prediction band (:class:`Calibration`;
        default 5, 0: the uncalibrated band of replicate spread and z·σ).
    calibrate_by : str or sequence of str
        Column(s) whose distinct values are left out together: ``"sweep_id"`` (default:
        calibrated for a new measurement of conditions like the data's) or a condition such
        as ``"Vx_set"`` (calibrated for a speed not measured).
    calibrate_conditions : bool
        Also run the condition folds (module docstring, item 5; :func:`condition_folds`): one more refit
        per level of a condition with 4 or more levels.  Off by default: with 4 speed levels the band at a
        held-out interior speed holds the level on average over campaigns, but one campaign's band there
        rests on 2 levels and can miss two thirds of the points (validation/README.md).
    executor : Executor, optional
        Where the replicate fits run (default: in this process; see :mod:`mftire.parallel`).
        The replicates are drawn beforehand from ``seed`` and collected in order, so the
        bands are bit for bit the same whatever the executor.
    progress : bool or callable, optional
        Progress lines per replicate on stderr (default: only when stderr is a terminal;
        see :mod:`mftire.progress`), or a callable that takes each message.

    Returns
    -------
    Bands
    """
    return start_bootstrap_bands(data, template, n, **options).result()


def start_bootstrap_bands(
    data,
    template: TirParameters | str | os.PathLike | Tyre,
    n: int = 50,
    *,
    level: float = 0.95,
    grid: pd.DataFrame | None = None,
    fit: FitResult | None = None,
    stages: str | Sequence | None = None,
    weights: str | Mapping[str, float] | None = None,
    alpha_star: bool = False,
    seed: int | None = 0,
    strata: Sequence[str] = ("source", "kind"),
    calibrate: int = 5,
    calibrate_by: str | Sequence[str] = "sweep_id",
    calibrate_conditions: bool = False,
    executor: Executor | None = None,
    progress: bool | Callable[[str], None] | None = None,
) -> PendingBands:
    """:func:`bootstrap_bands` started: the replicates are drawn and handed to ``executor`` at once
    (in an :meth:`~mftire.parallel.Executor.session` they run while the caller goes on), and
    :meth:`PendingBands.result` collects them into the :class:`Bands` (the same bit for bit)."""
    if not 0 < level < 1:
        raise MftireInputError(f"band level must be between 0 and 1, got {level}")
    if n < 2:
        raise MftireInputError(f"--bands needs at least 2 replicates, got {n}")
    say = reporter(progress, "mftire bands")
    t0 = time.perf_counter()
    if fit is None:
        fit = fit_tir(data, template, stages=stages, weights=weights, alpha_star=alpha_star, progress=False)
    elif weights is None:
        weights = _fit_weights(fit)
    ran = sorted({s.number for s in fit.stages if s.status == "fitted"})
    rep_stages = stages if stages is not None else (",".join(str(s) for s in ran) or "all")
    table = fit.data
    rng = np.random.default_rng(seed)
    samples = [resample_sweeps(table, rng, strata) for _ in range(n)]  # drawn up front: results do not
    job = _ReplicateFit(fit.parameters, rep_stages, weights, alpha_star)  # depend on the executor
    by = [calibrate_by] if isinstance(calibrate_by, str) else list(calibrate_by)
    missing = [c for c in by if c not in table.columns]
    if missing:
        raise MftireInputError(f"calibrate_by: no column {missing} in the grouped data "
                               f"(e.g. sweep_id, Fz_set, Vx_set, P_set, gamma_set)")
    fold = None
    cond: list[ConditionFold] = []
    if calibrate:
        if calibrate < 2:
            raise MftireInputError(f"calibration needs at least 2 folds, got {calibrate}")
        n_groups = int(table[by].drop_duplicates().shape[0])
        k = min(int(calibrate), n_groups)
        if k < 2:
            raise MftireInputError(f"calibration needs at least 2 distinct {'/'.join(by)} values, got {n_groups}")
        fold = _fold_ids(table, by, k, np.random.default_rng(None if seed is None else seed + 1))
        # the fold fits run every stage the full fit ran (a channel the replicates leave at the full fit still
        # gets out-of-fold residuals)
        fold_job = _ReplicateFit(fit.parameters, ",".join(str(s) for s in ran) or "all", weights, alpha_star,
                                 tuple(dict.fromkeys(fit.identified)), dict(fit.template))
        samples = [*((job, x) for x in samples), *((fold_job, _strip(table[fold != i])) for i in range(k))]
        if calibrate_conditions:
            cond = condition_folds(table)
            cond_job = _ReplicateFit(fold_job.start, fold_job.stages, weights, alpha_star, fold_job.identified,
                                     fold_job.prior, strict=True)
            samples += [(cond_job, _strip(table[~cf.rows])) for cf in cond]
    else:
        samples = [(job, x) for x in samples]
    pending = (executor or Executor()).start_map(_run_job, samples)
    return PendingBands(pending, fit, rep_stages, n, level, grid, say, t0, fold, by, cond)


@dataclass
class PendingBands:
    """Bootstrap replicates under way (:func:`start_bootstrap_bands`)."""

    pending: Pending
    fit: FitResult
    rep_stages: str | Sequence
    n: int
    level: float
    grid: pd.DataFrame | None
    say: Callable[[str], None]
    t0: float
    fold: np.ndarray | None = None
    by: list[str] = field(default_factory=list)
    cond: list[ConditionFold] = field(default_factory=list)

    def result(self) -> Bands:
        """Wait for the replicates and build the bands."""
        fit, n, level, say, t0 = self.fit, self.n, self.level, self.say, self.t0
        rep_stages, grid = self.rep_stages, self.grid
        stages_txt = rep_stages if isinstance(rep_stages, str) else ",".join(str(s) for s in rep_stages)
        reps: list[TirParameters] = []
        failed = 0
        fold_fits: list = []
        n_fold = 0 if self.fold is None else int(self.fold.max()) + 1
        for b, r in enumerate(self.pending):
            if b < n:
                failed += _collect(r, reps, b, n, say, t0)
            else:
                fold_fits.append(r)
                what = "calibration fold" if len(fold_fits) <= n_fold else "condition fold"
                say(f"{what} {len(fold_fits)} {'failed' if isinstance(r, str) else 'done'} "
                    f"({time.perf_counter() - t0:.1f} s)")
        table = fit.data
        keys = list(dict.fromkeys(fit.identified))
        bands = Bands(base=fit.parameters, replicates=reps, level=level, sigma=_residual_sigma(fit, BAND_CHANNELS),
                      mode=fit.mode + 100, keys=keys, n_requested=n, n_failed=failed, stages=stages_txt)
        bands.notes = [
            f"bootstrap over whole sweeps, stratified by source and sweep kind: {len(reps)} replicates "
            f"({failed} failed), level {level:g}",
            f"replicate fits warm-started from the full fit, stages {stages_txt}",
            "confidence band: pointwise replicate quantiles; prediction band: adds the full fit's robust "
            "residual scatter per channel and source in quadrature (use for held-out measured points)",
        ]
        if self.fold is not None:
            bands.calibration = _calibrate(table, self.fold, fold_fits[:n_fold], bands.mode, level, self.by,
                                           BAND_CHANNELS, self.cond, fold_fits[n_fold:])
            bands.notes[-1] = (
                f"prediction band: conformal calibration on out-of-fold residuals ({len(fold_fits)} folds of "
                f"{'/'.join(self.by)} groups, refitted without each fold), heteroscedastic scale "
                "sqrt(a² + (b·f̂)²)·sqrt(v(x)) per channel, source and slip class (v: local factor of load, speed, "
                "pressure and camber), quantile over the effective number of sweeps; band f̂ ± q·s (use for a new "
                "measured point at a condition the fit did not see)")
            cal = bands.calibration
            used = [f for f in cal.condition_folds if f.get("status") == "used"]
            if used:
                switched = sorted({f"{d['channel']} {d['condition']} {d['kind']}" for d in cal.condition_folds
                                   if d.get("band") == "condition folds"})
                bands.notes.append(
                    f"condition folds: {len(used)} of {len(self.cond)} set-point levels left out and refitted "
                    f"(interior: interpolated, exterior: extrapolated); at a new level of a condition the band of "
                    f"the same kind's folds where the sweep folds' band misses the level on their points: "
                    + (", ".join(switched) if switched else "none"))
        if grid is None:
            from mftire.compare.data import assign_families, curve_grid

            grid = curve_grid(assign_families(table.assign(origin="")))
        bands.grid = pd.concat([grid, bands.at(grid, source=None)], axis=1) if len(grid) else grid
        bands.time = time.perf_counter() - t0
        return bands


def _heldout_table(heldout) -> pd.DataFrame:
    """The held-out sweep rows (rows an importer kept outside the sweeps, ``fit_row`` False, are left out)."""
    from mftire.iotools.sweeps import fit_rows

    if isinstance(heldout, pd.DataFrame):
        return fit_rows(heldout)
    from mftire.fitting.weights import load_sweep_files

    paths = [heldout] if isinstance(heldout, (str, os.PathLike)) else list(heldout)
    return fit_rows(load_sweep_files(paths)[0])


def coverage_table(bands: Bands, heldout, channels: Sequence[str] = BAND_CHANNELS,
                   source: str | None = None) -> pd.DataFrame:
    """Per channel: held-out points and sweeps, fraction inside the prediction and the confidence band.

    Parameters
    ----------
    bands : Bands
    heldout : DataFrame, path or sequence of paths
        Held-out measured sweeps (sweep schema, SI), not used in the fit.
    source : str, optional
        Source whose calibration applies (default: each row's ``source``; the widest band when unknown).

    Returns
    -------
    DataFrame
        ``channel, n, sweeps, inside_prediction, se_prediction, inside_confidence, nominal`` (fractions
        0..1); a last row ``channel = "all"`` pools every channel's points.  ``se_prediction`` is the
        standard error of ``inside_prediction`` with the sweeps as the independent units (the points of
        a sweep share its offset and drift: a count over few sweeps scatters far more than a binomial
        count of its points; NaN for fewer than two sweeps).
    """
    from mftire.segmentation.grouping import group_sweeps

    df = _heldout_table(heldout)
    chans = [c for c in channels if c in df.columns and df[c].notna().any() and c in bands.sigma]
    at = bands.at(df, source=source, channels=chans)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the grouping's range warnings concern the fit, not this count
        sweep = group_sweeps(df.reset_index(drop=True))["sweep_id"].to_numpy() if len(df) else np.zeros(0, int)
    rows = []
    ins_all, ok_all, sw_all = [], [], []
    for ch in chans:
        y = df[ch].to_numpy(float)
        ok = np.isfinite(y)
        ip = (y >= at[f"{ch}_pred_lo"].to_numpy()) & (y <= at[f"{ch}_pred_hi"].to_numpy())
        ic = (y >= at[f"{ch}_lo"].to_numpy()) & (y <= at[f"{ch}_hi"].to_numpy())
        n = int(ok.sum())
        rows.append({"channel": ch, "n": n, "sweeps": int(np.unique(sweep[ok]).size),
                     "inside_prediction": float(ip[ok].mean()) if n else math.nan,
                     "se_prediction": _cluster_se(ip[ok], sweep[ok]),
                     "inside_confidence": float(ic[ok].mean()) if n else math.nan, "nominal": bands.level})
        ins_all.append(np.column_stack([ip[ok], ic[ok]]))
        sw_all.append(sweep[ok])
        ok_all.append(n)
    both = np.vstack(ins_all) if ins_all else np.zeros((0, 2), bool)
    sw = np.concatenate(sw_all) if sw_all else np.zeros(0, int)
    tot = int(sum(ok_all))
    rows.append({"channel": "all", "n": tot, "sweeps": int(np.unique(sw).size),
                 "inside_prediction": float(both[:, 0].mean()) if tot else math.nan,
                 "se_prediction": _cluster_se(both[:, 0], sw),
                 "inside_confidence": float(both[:, 1].mean()) if tot else math.nan, "nominal": bands.level})
    return pd.DataFrame(rows, columns=["channel", "n", "sweeps", "inside_prediction", "se_prediction",
                                       "inside_confidence", "nominal"])


def _cluster_se(inside: np.ndarray, cluster: np.ndarray) -> float:
    """Standard error of the mean of ``inside`` with clusters as the units (ratio estimator over clusters)."""
    ids, inv = np.unique(cluster, return_inverse=True)
    k = ids.size
    if k < 2:
        return math.nan
    n = np.bincount(inv.ravel()).astype(float)
    c = np.bincount(inv.ravel(), weights=inside.astype(float))
    p = c.sum() / n.sum()
    return float(math.sqrt(k / (k - 1) * np.sum((c - p * n) ** 2)) / n.sum())


def band_coverage(bands: Bands, heldout_data, channels: Sequence[str] = BAND_CHANNELS,
                  kind: str = "prediction") -> float:
    """Fraction of held-out measured points inside the bands (all channels pooled).

    ``kind="prediction"`` (default) uses the prediction band, the honest one for noisy
    measured points; ``"confidence"`` the band of the mean curve.
    """
    if kind not in ("prediction", "confidence"):
        raise ValueError("kind must be 'prediction' or 'confidence'")
    t = coverage_table(bands, heldout_data, channels)
    return float(t.iloc[-1][f"inside_{kind}"])


def write_bands(bands: Bands, directory: str | os.PathLike, coverage: pd.DataFrame | None = None) -> dict[str, str]:
    """Write ``bands.csv`` (grid points and bands) and ``bands.json`` (settings, σ, coefficients, coverage)."""
    from mftire.iotools.atomic import atomic_path, write_text_atomic

    directory = os.fspath(directory)
    os.makedirs(directory, exist_ok=True)
    csv = os.path.join(directory, "bands.csv")
    with atomic_path(csv) as tmp:
        (bands.grid if bands.grid is not None else pd.DataFrame()).to_csv(tmp, index=False, float_format="%.10g")
    payload = bands.to_dict()
    if coverage is not None:
        payload["coverage"] = coverage.to_dict(orient="records")
    js = os.path.join(directory, "bands.json")
    write_text_atomic(js, json.dumps(jsonable(payload), indent=1, allow_nan=False) + "\n")
    return {"csv": csv, "json": js}
