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
   when the cost stops improving (tolerances 1e-9 and an evaluation budget), so a
   replicate may stay slightly closer to the full fit than a fully converged refit —
   the confidence band is, if anything, a little narrow.  Restricting ``stages`` (e.g.
   ``"1,2,3"``) leaves the other stages' coefficients at the full fit in every replicate:
   those channels then get a zero-width confidence band and only the scatter term below.
4. **Prediction band.** Held-out *measured* points carry measurement noise, repeat-to-repeat
   scatter and model error, none of which a confidence band for the mean curve holds;
   with noisy data it contains a small fraction of new points (see
   ``coverage["confidence"]``).  The honest band for "where will a new measured point
   fall" adds the residual scatter σ of the full fit in quadrature::

       lo = f̂ − sqrt((f̂ − q_lo)² + (z·σ)²),   hi = f̂ + sqrt((q_hi − f̂)² + (z·σ)²)

   with ``q_lo, q_hi`` the replicate quantiles and ``z`` the normal quantile of the
   level.  σ is per channel and per source: 1.4826 × the median |residual| of the full
   fit (robust to gross outliers, and measured about zero so a systematic lack of fit
   counts as scatter).  A point of an unknown source uses the largest σ among the
   sources (measured data are the noisiest).  Held-out measurements are judged against
   this prediction band by :func:`band_coverage`.

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
from mftire.iotools.jsonutil import jsonable
from mftire.iotools.tir import TirParameters
from mftire.parallel import Executor, Pending
from mftire.progress import reporter
from mftire.tyre import Tyre

__all__ = ["Bands", "bootstrap_bands", "start_bootstrap_bands", "PendingBands", "band_coverage", "coverage_table",
           "resample_sweeps", "write_bands", "BAND_CHANNELS"]

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
            s = z * self.sigma_for(ch, src)
            out[ch] = f
            out[f"{ch}_lo"] = f - dlo
            out[f"{ch}_hi"] = f + dhi
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
            "coefficients": self.coefficient_table().to_dict(orient="records"),
            "replicates": [{k: float(r.get(k)) for k in self.keys} for r in self.replicates],
        }  # fmt: skip


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


@dataclass
class _ReplicateFit:
    """Warm-started refit of one replicate (a picklable callable for process pools)."""

    start: TirParameters
    stages: Any
    weights: Any
    alpha_star: bool

    def __call__(self, sample: pd.DataFrame) -> TirParameters | str:
        try:
            with warnings.catch_warnings():  # degenerate resamples make scipy/numpy warn inside the fit
                warnings.simplefilter("ignore", RuntimeWarning)
                return fit_tir(sample, self.start, stages=self.stages, weights=self.weights, alpha_star=self.alpha_star,
                               progress=False).parameters
        except (MftireInputError, ValueError, np.linalg.LinAlgError) as exc:
            return str(exc)


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


def bootstrap_bands(
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
    executor: Executor | None = None,
    progress: bool | Callable[[str], None] | None = None,
) -> Bands:
    """Bootstrap-over-sweeps bands of the fitted curves (see the module docstring).

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
        As for :func:`fit_tir` (the same in the full fit and every replicate).
    seed : int, optional
        Random seed of the resampling.
    strata : sequence of str
        Columns of the grouped data within which sweeps are resampled (default source
        and sweep kind; add ``"Fz_set"`` to keep every load in every replicate when each
        load has several sweeps of a kind).
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
    return start_bootstrap_bands(
        data, template, n, level=level, grid=grid, fit=fit, stages=stages, weights=weights, alpha_star=alpha_star,
        seed=seed, strata=strata, executor=executor, progress=progress).result()


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
    ran = sorted({s.number for s in fit.stages if s.status == "fitted"})
    rep_stages = stages if stages is not None else (",".join(str(s) for s in ran) or "all")
    table = fit.data
    rng = np.random.default_rng(seed)
    samples = [resample_sweeps(table, rng, strata) for _ in range(n)]  # drawn up front: results do not
    job = _ReplicateFit(fit.parameters, rep_stages, weights, alpha_star)  # depend on the executor
    pending = (executor or Executor()).start_map(job, samples)
    return PendingBands(pending, fit, rep_stages, n, level, grid, say, t0)


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

    def result(self) -> Bands:
        """Wait for the replicates and build the bands."""
        fit, n, level, say, t0 = self.fit, self.n, self.level, self.say, self.t0
        rep_stages, grid = self.rep_stages, self.grid
        stages_txt = rep_stages if isinstance(rep_stages, str) else ",".join(str(s) for s in rep_stages)
        reps: list[TirParameters] = []
        failed = 0
        for b, r in enumerate(self.pending):
            failed += _collect(r, reps, b, n, say, t0)
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
    """Per channel: held-out points, fraction inside the prediction and the confidence band.

    Parameters
    ----------
    bands : Bands
    heldout : DataFrame, path or sequence of paths
        Held-out measured sweeps (sweep schema, SI), not used in the fit.
    source : str, optional
        Source whose σ applies (default: each row's ``source``; largest σ when unknown).

    Returns
    -------
    DataFrame
        ``channel, n, inside_prediction, inside_confidence, nominal`` (fractions 0..1);
        a last row ``channel = "all"`` pools every channel's points.
    """
    df = _heldout_table(heldout)
    chans = [c for c in channels if c in df.columns and df[c].notna().any() and c in bands.sigma]
    at = bands.at(df, source=source, channels=chans)
    rows = []
    tot = np.zeros(3)
    for ch in chans:
        y = df[ch].to_numpy(float)
        ok = np.isfinite(y)
        ip = (y >= at[f"{ch}_pred_lo"].to_numpy()) & (y <= at[f"{ch}_pred_hi"].to_numpy())
        ic = (y >= at[f"{ch}_lo"].to_numpy()) & (y <= at[f"{ch}_hi"].to_numpy())
        n = int(ok.sum())
        rows.append({"channel": ch, "n": n, "inside_prediction": float(ip[ok].mean()) if n else math.nan,
                     "inside_confidence": float(ic[ok].mean()) if n else math.nan, "nominal": bands.level})
        tot += (n, ip[ok].sum(), ic[ok].sum())
    rows.append({"channel": "all", "n": int(tot[0]), "inside_prediction": tot[1] / tot[0] if tot[0] else math.nan,
                 "inside_confidence": tot[2] / tot[0] if tot[0] else math.nan, "nominal": bands.level})
    return pd.DataFrame(rows, columns=["channel", "n", "inside_prediction", "inside_confidence", "nominal"])


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
