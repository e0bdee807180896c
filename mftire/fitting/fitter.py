"""Staged Magic Formula fit: :func:`fit_tir` and its result objects.

Each stage (see :mod:`mftire.fitting.stages`) is a bounded nonlinear least-squares
problem solved with :func:`scipy.optimize.least_squares` (trust-region reflective):

* residual of row i: ``sqrt(w_i) * (model_i - measured_i) / sigma`` where ``w_i`` is the
  row's source weight and ``sigma`` [channel unit] the channel's noise standard
  deviation estimated from the data (:func:`mftire.fitting.weights.noise_std`, floored
  at 0.1 % of the channel's peak for noise-free simulation data);
* robust ``soft_l1`` loss with ``f_scale = 3`` (three noise standard deviations):
  residuals beyond 3σ (gross outliers) count linearly, not quadratically;
* bounds from :mod:`mftire.fitting.stages` (widened to hold the template value) and
  parameter scales ``x_scale = max(|start|, typical magnitude)``;
* exact Jacobians: algorithmic (reverse-mode) derivatives through the model pipeline
  (:mod:`mftire.mf.derivatives`), the extension terms' coefficients included; BLAS held to
  one thread inside the solver (threadpoolctl);
* two passes: first the nominal and load coefficients, then every identified
  coefficient;
* the start values are the template's, replaced by data estimates
  (:mod:`mftire.fitting.initial`) when those give a lower cost.

Stage 1 respects free rolling: when the measured Fx at κ = 0 of a condition is
negative (rolling resistance), a one-sided penalty keeps the model's Fx(κ = 0) at or
below zero there; :attr:`FitResult.free_rolling` lists the measured and fitted
free-rolling force per condition.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from scipy.optimize import least_squares
from threadpoolctl import threadpool_limits

from mftire.errors import MftireInputError
from mftire.fitting import initial
from mftire.fitting.identify import DataLevels, data_levels, split_identified
from mftire.fitting.model import Inputs, Model, fitting_mode, predict
from mftire.fitting.stages import FITTED_KEYS, STAGES, Coefficient, Stage, resolve_stages
from mftire.fitting.weights import load_sweep_files, noise_std, parse_weights, prepare_table, row_weights
from mftire.iotools.sweeps import fit_rows
from mftire.iotools.tir import TirParameters, read_tir
from mftire.mf import derivatives
from mftire.mf.extensions import SECTION, ExtensionSet, parse_section
from mftire.mf.modes import Mode
from mftire.parameters import with_defaults
from mftire.progress import Progress, reporter
from mftire.segmentation.grouping import group_sweeps
from mftire.tyre import Tyre

__all__ = ["StageResult", "FitResult", "fit_tir", "LOSS", "F_SCALE", "CONDITION_KEYS"]

#: Robust loss of every stage (scipy.optimize.least_squares ``loss``).
LOSS = "soft_l1"
#: Soft threshold of the loss, in units of the channel's noise standard deviation.
F_SCALE = 3.0
#: Columns that identify an operating condition (set points from group_sweeps).
CONDITION_KEYS = ("Fz_set", "gamma_set", "P_set", "Vx_set")
_NOISE_FLOOR = 1e-3  # sigma >= this fraction of the channel peak
#: Relative change of the robust cost at which a stage pass stops (least_squares ``ftol``). At 1e-9 the
#: passes crawled to their evaluation cap with the cost already within 1e-4 of its end value.
_FTOL = 1e-6
_NO_EXTENSIONS = ExtensionSet(())


@dataclass
class StageResult:
    """Outcome of one stage (one entry per channel group for stage 4).

    Attributes
    ----------
    number, name, title : int, str, str
        Stage identity (see :data:`mftire.fitting.stages.STAGES`).
    channel : str
        Fitted channel.
    status : str
        ``"fitted"``, ``"skipped"`` or ``"failed"``.
    message : str
        Why a stage was skipped, or scipy's termination message.
    n_points : int
        Rows used.
    n_nan : int
        Rows of the stage's sweep kinds skipped because the channel is NaN there.
    noise : float
        Estimated noise standard deviation of the channel [N or N·m].
    levels : dict
        Distinct operating conditions (:class:`~mftire.fitting.identify.DataLevels`).
    identified : list of str
        Coefficients fitted.
    not_identified : dict
        ``{key: reason}`` of coefficients left at the template value.
    start, values : dict
        Start and fitted values of the identified coefficients.
    rms_start, rms : float
        RMS error of the channel before and after the stage [channel unit].
    nfev, time : int, float
        Function evaluations and wall time [s].
    success : bool
        scipy's success flag.
    """

    number: int
    name: str
    title: str
    channel: str
    status: str = "skipped"
    message: str = ""
    n_points: int = 0
    n_nan: int = 0
    noise: float = math.nan
    levels: dict = field(default_factory=dict)
    identified: list[str] = field(default_factory=list)
    not_identified: dict[str, str] = field(default_factory=dict)
    start: dict[str, float] = field(default_factory=dict)
    values: dict[str, float] = field(default_factory=dict)
    rms_start: float = math.nan
    rms: float = math.nan
    nfev: int = 0
    time: float = 0.0
    success: bool = False

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


@dataclass
class FitResult:
    """Result of :func:`fit_tir`, in the spirit of :class:`scipy.optimize.OptimizeResult`.

    Attributes
    ----------
    parameters : TirParameters
        The fitted ``.tir`` (template with the identified coefficients replaced).
    flat : dict
        Flat parameter dictionary of the fitted tyre (:func:`with_defaults`).
    template : dict
        Flat parameter dictionary of the template.
    stages : list of StageResult
    identified : list of str
        Every fitted coefficient.
    not_identified : dict
        ``{key: reason}`` for coefficients of the run stages left at the template value.
    free_rolling : DataFrame
        Per condition: measured and fitted Fx at κ = 0 [N], their difference, and
        ``sign_ok`` (False when the data show Fx < 0 but the model gives Fx > 0).
    data : DataFrame
        The fitted table (grouped, with ``weight`` and per-channel ``fit_*`` columns).
    messages : list of str
        Notes: rows dropped, stages skipped, free-rolling violations ...
    n_dropped_nan : int
        Rows dropped because an input was NaN or every channel was NaN.
    mode : int
        Evaluation mode the coefficients were fitted for (``111`` or ``121``).
    success : bool
        True when every stage that ran converged.
    time : float
        Total wall time [s].
    """

    parameters: TirParameters
    flat: dict[str, float]
    template: dict[str, float]
    stages: list[StageResult]
    identified: list[str]
    not_identified: dict[str, str]
    free_rolling: pd.DataFrame
    data: pd.DataFrame
    messages: list[str]
    n_dropped_nan: int
    mode: int
    success: bool
    time: float

    def __repr__(self) -> str:
        lines = [f"FitResult(success={self.success}, time={self.time:.1f} s, "
                 f"{len(self.identified)} coefficients fitted, {len(self.not_identified)} not identified)"]
        for s in self.stages:
            lines.append(f"  stage {s.number} {s.name} [{s.channel}]: {s.status}"
                         + (f", {s.n_points} points, rms {s.rms_start:.4g} -> {s.rms:.4g}" if s.status == "fitted"
                            else f" ({s.message})"))
        lines.extend(f"  note: {m}" for m in self.messages)
        return "\n".join(lines)


# ------------------------------------------------------------------------------------
# progress
# ------------------------------------------------------------------------------------


def _progress_printer(progress: bool | Callable[[str], None] | Progress | None) -> Progress:
    return reporter(progress, "mftire fit")


# ------------------------------------------------------------------------------------
# channel evaluators with cached inputs
# ------------------------------------------------------------------------------------


class _Evaluator:
    """``q -> channel`` at ``x`` through the model pipeline (:class:`Model`), with its Jacobian.

    Piece 1 (conditioning, eqs 4.E1–4.E8 inputs) runs once.  For the moments, the forces
    and the zero-camber lateral force of eq 4.E74 are computed once when no coefficient
    of ``fitted`` changes them (aligning, overturning and rolling coefficients only).
    :meth:`jacobian` differentiates algorithmically (:mod:`mftire.mf.derivatives`), through the
    extension terms' forms too.
    """

    def __init__(self, channel: str, p: dict, x: Inputs, mode: Mode, ext: ExtensionSet, fitted: Sequence[str] = ()):
        self.model = Model(p, x, mode, ext)
        self.channel = channel
        self.n = len(x)
        force_free = channel not in ("Fx", "Fy") and all(k.startswith(("Q", "SSZ", "PPZ", "PPMX")) for k in fitted)
        self.given = self.model.channels(p, (channel,)) if force_free else None

    def value(self, q: Mapping) -> np.ndarray:
        """The channel (a :class:`~mftire.mf.derivatives.Var` when ``q`` holds some)."""
        return getattr(self.model.channels(q, (self.channel,), self.given), self.channel)  # eqs 4.E9 ... A48

    def __call__(self, q: Mapping) -> np.ndarray:
        return np.real(self.value(q))

    def jacobian(self, q: Mapping, keys: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
        """The channel (n,) and its derivatives by ``q[keys]`` (n, k)."""
        qv, leaves = derivatives.seed(q, keys)  # seed, evaluate here, sweep: mftire.mf calls nothing up here
        with np.errstate(all="ignore"):
            out = self.value(qv)
        return derivatives.sweep(out, leaves, self.n)


# ------------------------------------------------------------------------------------
# one least-squares problem
# ------------------------------------------------------------------------------------


def _bounds(coeffs: Sequence[Coefficient], x0: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    lb = np.array([c.lower for c in coeffs], dtype=float)
    ub = np.array([c.upper for c in coeffs], dtype=float)
    scale = np.array([c.scale for c in coeffs], dtype=float)
    for i, c in enumerate(coeffs):
        if c.keep_sign and x0[i] != 0:
            tiny = 1e-3 * scale[i]
            if x0[i] > 0:
                lb[i] = max(lb[i], tiny)
            else:
                ub[i] = min(ub[i], -tiny)
        # widen to hold the start value with room on both sides
        if not lb[i] < x0[i]:
            lb[i] = x0[i] - max(abs(x0[i]), scale[i])
        if not x0[i] < ub[i]:
            ub[i] = x0[i] + max(abs(x0[i]), scale[i])
    return lb, ub, np.maximum(np.abs(x0), scale)


def _robust_cost(r: np.ndarray) -> float:
    z = (r / F_SCALE) ** 2
    return float(np.sum(2.0 * (np.sqrt(1.0 + z) - 1.0)) * F_SCALE**2 / 2.0)  # soft_l1


@dataclass
class _Penalty:
    """One-sided penalty ``w · max(model + margin, 0)`` on a channel (stage 1: free rolling)."""

    evaluate: _Evaluator
    w: np.ndarray
    margin: np.ndarray

    def __call__(self, q: dict) -> np.ndarray:
        return self.w * np.maximum(self.evaluate(q) + self.margin, 0.0)

    def jacobian(self, q: dict, keys: Sequence[str]) -> np.ndarray:
        value, d = self.evaluate.jacobian(q, keys)
        return (self.w * (value + self.margin > 0.0))[:, None] * d


@dataclass
class _Problem:
    evaluate: _Evaluator
    y: np.ndarray
    sw: np.ndarray  # sqrt(weight) / sigma
    penalty: _Penalty | None = None

    def residuals(self, q: dict) -> np.ndarray:
        r = (self.evaluate(q) - self.y) * self.sw
        r = np.where(np.isfinite(r), r, 1e4)
        if self.penalty is not None:
            r = np.concatenate([r, self.penalty(q)])
        return r

    def jacobian(self, q: dict, keys: Sequence[str]) -> np.ndarray:
        """d residuals / d q[keys] (rows of non-finite residuals: 0)."""
        value, d = self.evaluate.jacobian(q, keys)
        finite = np.isfinite((value - self.y) * self.sw)
        jac = np.where(finite, self.sw, 0.0)[:, None] * d
        if self.penalty is not None:
            jac = np.concatenate([jac, self.penalty.jacobian(q, keys)])
        return jac


def _solve(prob: _Problem, p: dict, coeffs: Sequence[Coefficient], max_nfev: int, jacobian: str = "exact"):
    keys = [c.key for c in coeffs]
    x0 = np.array([p[k] for k in keys], dtype=float)
    lb, ub, xs = _bounds(coeffs, x0)
    x0 = np.clip(x0, lb + 1e-12 * (ub - lb), ub - 1e-12 * (ub - lb))
    q = dict(p)

    def fun(x):
        q.update(zip(keys, x, strict=True))
        return prob.residuals(q)

    def jac(x):
        q.update(zip(keys, x, strict=True))
        return prob.jacobian(q, keys)

    # one BLAS thread: least_squares' SVDs are small, and threads fight over the cores
    with np.errstate(all="ignore"), threadpool_limits(limits=1, user_api="blas"):
        res = least_squares(fun, x0, jac=jac if jacobian == "exact" else "2-point", bounds=(lb, ub), x_scale=xs,
                            loss=LOSS, f_scale=F_SCALE, method="trf", max_nfev=max_nfev, ftol=_FTOL, xtol=1e-9,
                            gtol=1e-9)
    out = dict(p)
    out.update(zip(keys, (float(v) for v in res.x), strict=True))
    return out, res


# ------------------------------------------------------------------------------------
# stage driver
# ------------------------------------------------------------------------------------


def _channel_sigma(y: np.ndarray, table: pd.DataFrame, xcol: str | None) -> float:
    peak = float(np.quantile(np.abs(y), 0.99)) if y.size else 0.0
    if xcol is None:
        xcol = "alpha" if np.ptp(table["alpha"].to_numpy(float)) > np.ptp(table["kappa"].to_numpy(float)) else "kappa"
    sigma = noise_std(y, table[xcol].to_numpy(float), table["sweep_id"].to_numpy())
    floor = max(_NOISE_FLOOR * peak, 1e-9)
    return max(sigma, floor) if np.isfinite(sigma) else floor


def _free_rolling_targets(table: pd.DataFrame, variables: Sequence[str] = ()) -> pd.DataFrame:
    """Measured Fx at κ = 0 per condition of pure longitudinal sweeps (Theil–Sen intercept)."""
    rows = []
    for key, g in table.groupby(list(CONDITION_KEYS), sort=True):
        s = initial.sweep_shape(g["kappa"].to_numpy(float), g["Fx"].to_numpy(float), float(g["Fz"].mean()))
        near = g[np.abs(g["kappa"]) <= 0.002]
        if s is None and len(near) == 0:
            continue
        measured = s.y0 if s is not None else float(near["Fx"].median())
        extra = {v: float(g[v].mean()) for v in variables}
        rows.append(dict(zip(CONDITION_KEYS, key, strict=True), measured=measured, n=len(g), **extra))
    return pd.DataFrame(rows, columns=[*CONDITION_KEYS, "measured", "n", *variables])


def _condition_inputs(df: pd.DataFrame, ext: ExtensionSet) -> Inputs:
    """Free rolling (kappa = alpha = 0) at each condition's set points (and mean external variables)."""
    n = len(df)
    return Inputs(df["Fz_set"].to_numpy(float), np.zeros(n), np.zeros(n), df["gamma_set"].to_numpy(float),
                  df["Vx_set"].to_numpy(float), df["P_set"].to_numpy(float),
                  {v: df[v].to_numpy(float) for v in ext.external_variables})  # fmt: skip


def _template_slope_fn(p: dict, rows: pd.DataFrame, mode: Mode) -> Callable[[float], float]:
    g = float(rows["gamma_set"].abs().min()) if len(rows) else 0.0
    Pn = float(p["NOMPRES"])
    vx = float(rows["Vx"].median()) if len(rows) else float(p["LONGVL"])
    h = math.radians(0.25)

    def slope(Fz: float) -> float:
        x = Inputs(np.full(2, Fz), np.zeros(2), np.array([-h, h]), np.full(2, g), np.full(2, vx), np.full(2, Pn))
        fy = predict(p, x, "Fy", mode)
        return float((fy[1] - fy[0]) / (2 * h))

    return slope


def _aligning_guess(p: dict, rows: pd.DataFrame, evaluate: Callable[[dict], np.ndarray]) -> dict[str, float]:
    """QBZ1 from the slip angle of the Mz peak, QDZ1 from the slope at zero (model/data ratios)."""
    model = evaluate(p)
    mask = (rows["gamma_set"].abs() == rows["gamma_set"].abs().min()).to_numpy()
    ratios_x, ratios_k = [], []
    sub = rows[mask]
    msub = model[mask]
    for _, idx in sub.groupby(list(CONDITION_KEYS)).indices.items():
        g = sub.iloc[idx]
        a = g["alpha"].to_numpy(float)
        sd = initial.sweep_shape(a, g["Mz"].to_numpy(float), float(g["Fz"].mean()))
        sm = initial.sweep_shape(a, msub[idx], float(g["Fz"].mean()))
        if sd is None or sm is None or sm.x_peak == 0 or sm.K == 0:
            continue
        ratios_x.append(abs(sd.x_peak / sm.x_peak))
        ratios_k.append(sd.K / sm.K)
    guess = {}
    if ratios_x:
        rx = float(np.median(ratios_x))
        if 0.2 < rx < 5:
            guess["QBZ1"] = p["QBZ1"] / rx
        rk = float(np.median(ratios_k))
        if 0.2 < rk < 5:
            guess["QDZ1"] = p["QDZ1"] * rk
    return guess


def _run_group(
    stage: Stage,
    channel: str,
    coeffs: Sequence[Coefficient],
    p: dict,
    table: pd.DataFrame,
    sqrt_w: np.ndarray,
    mode: Mode,
    free_rolling: list,
    say: Callable[[str], None],
    refine: bool = False,
    ext: ExtensionSet | None = None,
    jacobian: str = "exact",
) -> tuple[dict, StageResult]:
    ext = ext or _NO_EXTENSIONS
    res = StageResult(stage.number, stage.name, stage.title, channel)
    t0 = time.perf_counter()
    if channel not in table.columns or table[channel].isna().all():
        res.message = f"no {channel} channel in the data"
        res.not_identified = {c.key: f"no {channel} data" for c in coeffs}
        return p, res
    kind_ok = table["kind"].isin(stage.kinds).to_numpy() if stage.kinds else np.ones(len(table), bool)
    has = table[channel].notna().to_numpy()
    res.n_nan = int(np.sum(kind_ok & ~has))
    sel = kind_ok & has
    rows = table[sel]
    res.n_points = len(rows)
    kinds_txt = "/".join(k.replace("_", " ") for k in stage.kinds if k != "free_rolling") or "any"
    if stage.kinds and not (rows["kind"] == stage.kinds[0]).any():
        # the first kind is the one the stage needs; the others only add rows
        kinds_txt = stage.kinds[0].replace("_", " ")
        rows = rows.iloc[:0]
    if len(rows) == 0:
        res.message = f"no {kinds_txt} sweeps with {channel} data"
        res.not_identified = {c.key: res.message for c in coeffs}
        return p, res
    levels: DataLevels = data_levels(rows)
    res.levels = levels.to_dict()
    ident, not_ident = split_identified(coeffs, levels, p)
    ident, not_ext = _extension_identified(ext, ident, rows)
    not_ident.update(not_ext)
    res.not_identified = not_ident
    need = max(stage.min_points, 2 * len(ident) + 1)
    if len(rows) < need:
        res.message = (f"too few points: {len(rows)} {kinds_txt} rows with {channel}, "
                       f"at least {need} needed for {len(ident)} coefficients")
        res.not_identified = {c.key: "too few points" for c in coeffs}
        return p, res
    if not ident:
        res.message = "no identifiable coefficient"
        return p, res

    x = Inputs.from_frame(rows, ext.external_variables)
    y = rows[channel].to_numpy(float)
    xcol = {"Fx": "kappa", "Fy": "alpha", "Mz": "alpha"}.get(channel) if stage.number <= 3 else None
    sigma = _channel_sigma(y, rows, xcol)
    res.noise = sigma
    evaluate = _Evaluator(channel, p, x, mode, ext, [c.key for c in ident])
    prob = _Problem(evaluate, y, sqrt_w[sel] / sigma)

    if stage.number == 1:
        targets = _free_rolling_targets(rows, ext.external_variables)
        neg = targets[targets["measured"] < 0]
        if len(neg):
            free_model = _Evaluator("Fx", p, _condition_inputs(neg, ext), mode, ext, [c.key for c in ident])
            wfr = 10.0 * np.sqrt(neg["n"].to_numpy(float)) / sigma
            # keep a small margin below zero so that the constraint holds strictly
            margin = np.minimum(0.05 * sigma, 0.5 * np.abs(neg["measured"].to_numpy(float)))

            # one-sided: model Fx(kappa=0) must not be > 0
            prob.penalty = _Penalty(free_model, wfr, margin)
        free_rolling.append(targets)

    def rms(q):
        with np.errstate(all="ignore"):
            return float(np.sqrt(np.nanmean((evaluate(q) - y) ** 2)))

    # initial values from the data, kept when they lower the robust cost
    ident_keys = {c.key for c in ident}
    guess: dict[str, float] = {}
    if stage.number == 1:
        guess = initial.longitudinal_guess(rows, p)
    elif stage.number == 2:
        guess = initial.lateral_guess(rows, p, _template_slope_fn(p, rows, mode))
    elif stage.number == 3:
        guess = _aligning_guess(p, rows, evaluate)
    guess = {k: v for k, v in guess.items() if k in ident_keys and np.isfinite(v)}
    q = dict(p)
    if guess:
        trial = dict(p)
        trial.update(guess)
        with np.errstate(all="ignore"):
            if _robust_cost(prob.residuals(trial)) < _robust_cost(prob.residuals(p)):
                q = trial
    res.start = {c.key: float(q[c.key]) for c in ident}
    res.rms_start = rms(p)

    first = [c for c in ident if set(c.needs) <= {"loads2", "loads3", "combined"}]
    passes = [first, list(ident)] if 0 < len(first) < len(ident) and not refine else [list(ident)]
    nfev = 0
    ok = True
    msg = ""
    for i, group in enumerate(passes):
        say(f"stage {stage.number} {stage.name} [{channel}]: pass {i + 1}/{len(passes)}, "
            f"{len(group)} coefficients, {len(rows)} points")
        budget = 30 * len(group) if i < len(passes) - 1 else min(60 * len(group), 600)
        q, sol = _solve(prob, q, group, max_nfev=budget, jacobian=jacobian)
        nfev += int(sol.nfev)
        ok = bool(sol.success)
        msg = str(sol.message)
    res.values = {c.key: float(q[c.key]) for c in ident}
    res.identified = [c.key for c in ident]
    res.rms = rms(q)
    res.nfev = nfev
    res.success = ok
    res.status = "fitted"
    res.message = msg
    res.time = time.perf_counter() - t0
    say(f"stage {stage.number} {stage.name} [{channel}]: rms {res.rms_start:.4g} -> {res.rms:.4g} "
        f"({res.time:.1f} s)")
    return q, res


# ------------------------------------------------------------------------------------
# public entry point
# ------------------------------------------------------------------------------------


def _as_template(template) -> TirParameters:
    if isinstance(template, Tyre):
        return template.parameters.copy()
    if isinstance(template, TirParameters):
        return template.copy()
    if isinstance(template, (str, os.PathLike)):
        return read_tir(template)
    if isinstance(template, Mapping):
        return _from_flat(template)
    raise TypeError(f"template must be a TirParameters, a path or a mapping, not {type(template).__name__}")


def _from_flat(flat: Mapping) -> TirParameters:
    t = TirParameters()
    for k, v in flat.items():
        t.set(str(k), v)
    return t


def _as_table(data) -> tuple[pd.DataFrame, int, list[str]]:
    """Validated table, rows dropped for NaN, messages."""
    messages: list[str] = []
    if isinstance(data, pd.DataFrame):
        if "report" in data.attrs:
            table = data.copy()
            rep = [data.attrs["report"]]
        else:
            table, r = prepare_table(data, "data")
            rep = [r]
    elif isinstance(data, (str, os.PathLike)):
        table, rep = load_sweep_files([data])
    else:
        items = list(data)
        if items and all(isinstance(d, pd.DataFrame) for d in items):
            frames, rep = [], []
            for i, d in enumerate(items):
                t, r = prepare_table(d, f"data[{i}]")
                frames.append(t)
                rep.append(r)
            table = pd.concat(frames, ignore_index=True, sort=False)
        else:
            table, rep = load_sweep_files(items)
    n_nan = 0
    for r in rep:
        n_nan += int(r.get("n_dropped_nan", 0))
        if r.get("n_dropped_nan"):
            detail = ", ".join(f"{k}: {v}" for k, v in r.get("nan_by_column", {}).items() if v)
            extra = r.get("n_dropped_all_measured_nan", 0)
            messages.append(f"{r['name']}: {r['n_dropped_nan']} rows with NaN dropped"
                            + (f" (inputs {detail})" if detail else "")
                            + (f" ({extra} with every channel NaN)" if extra else ""))
        if r.get("n_dropped_nonpositive_fz"):
            messages.append(f"{r['name']}: {r['n_dropped_nonpositive_fz']} rows with Fz <= 0 dropped")
    if "source" not in table.columns:
        table["source"] = "data"
    table = fit_rows(table)  # rows an importer kept for the diagnosis only (fit_row False) are not fitted
    return table.reset_index(drop=True), n_nan, messages


def fit_tir(
    data: pd.DataFrame | str | os.PathLike | Sequence,
    template: TirParameters | str | os.PathLike | Mapping | Tyre,
    *,
    stages: str | Sequence | None = None,
    weights: str | Mapping[str, float] | None = None,
    alpha_star: bool = False,
    progress: bool | Callable[[str], None] | None = None,
    fixed: Sequence[str] = (),
    jacobian: str = "exact",
) -> FitResult:
    """Fit Magic Formula 6.1/6.2 coefficients to slip sweeps, stage by stage.

    Parameters
    ----------
    data : DataFrame, path, or sequence of DataFrames / paths
        Sweep tables in the schema of :mod:`mftire.iotools.sweeps` (SI: Fz [N], kappa
        [-], alpha [rad], gamma [rad], Vx [m/s], P [Pa]; channels Fx, Fy [N], Mz, Mx,
        My [N·m]) or CSV / TYDEX files.  Rows with NaN inputs are dropped and counted.
    template : TirParameters or path
        Start values and every never-fitted constant (FNOMIN, NOMPRES,
        UNLOADED_RADIUS, LONGVL, ranges, scaling factors).  FITTYP 61 or 62.
    stages : str or sequence, optional
        Stages to run, e.g. ``"1,2,3"`` or ``["longitudinal", "lateral"]`` (default all).
    weights : str or mapping, optional
        Per-source weights, ``"fe=1,measured=5"``, keyed on the ``source`` column or
        the file name (default 1).
    alpha_star : bool
        Fit for evaluation with alpha* = tan(α) (mode x2x, eq 4.E3); default α.
    progress : bool or callable, optional
        Print per-stage progress to stderr (default: only when stderr is a terminal),
        or call this function with each message.
    fixed : sequence of str, optional
        Coefficients held at their template values (e.g. the pressure terms, to fit a
        model without them); reported as not identified, "fixed by the user".
    jacobian : {"exact", "2-point"}
        ``"exact"`` (default): algorithmic (reverse-mode) derivatives through the model
        (:mod:`mftire.mf.derivatives`, the extension terms' coefficients included); ``"2-point"``: forward
        finite differences (slower; the reference the exact derivatives are tested against).

    Returns
    -------
    FitResult
    """
    t_start = time.perf_counter()
    if jacobian not in ("exact", "2-point"):
        raise ValueError(f"jacobian must be 'exact' or '2-point', not {jacobian!r}")
    say = _progress_printer(progress)
    tmpl = _as_template(template)
    from mftire.input_checks import check_constants  # the one parameter check (mftire.iotools.tir_checks)

    check_constants(with_defaults(tmpl.flat()), getattr(tmpl, "path", None) or "template", tmpl.sections.get(SECTION))
    if tmpl.fittyp not in (61, 62):
        raise MftireInputError(
            f"template FITTYP {tmpl.get('FITTYP')!r}: fitting needs an MF 6.1 or 6.2 template (FITTYP 61 or 62)"
        )
    try:
        chosen = resolve_stages(stages)
    except ValueError as exc:
        raise MftireInputError(str(exc)) from None
    table, n_nan, messages = _as_table(data)
    w = row_weights(table, parse_weights(weights))
    table = _classify_rows(group_sweeps(table))
    table["weight"] = w
    sqrt_w = np.sqrt(w)
    ext = parse_section(tmpl.sections.get(SECTION))
    missing = [v for v in ext.external_variables if v not in table.columns]
    if missing:
        raise MftireInputError(
            f"the template's [{SECTION}] reads {', '.join(missing)}: no such column in the data"
        )
    p0 = with_defaults(tmpl.flat())  # the layer below takes a plain mapping
    for t in ext.terms:  # coefficients absent from the section start at the form's start values
        for k in t.coefficient_keys:
            p0.setdefault(k, t.start(k))
    p = dict(p0)
    mode = fitting_mode(alpha_star)
    say(f"{len(table)} points, {table['sweep_id'].nunique()} sweeps, stages "
        f"{', '.join(str(s.number) for s in chosen)}")

    phit = table["phit"].to_numpy(float) if "phit" in table.columns else np.zeros(len(table))
    if np.any(phit != 0):
        messages.append("turn slip (phit) is not fitted: rows are evaluated at phit = 0")

    results: list[StageResult] = []
    free_rolling: list[pd.DataFrame] = []
    fixed_keys = {str(k).upper() for k in fixed}
    unknown = sorted(fixed_keys - FITTED_KEYS - set(ext.coefficient_keys))
    if unknown:
        raise MftireInputError(f"cannot fix {', '.join(unknown)}: not a fitted coefficient")
    for stage in chosen:
        for channel, coeffs in zip(_stage_channels(stage), stage.groups, strict=True):
            coeffs = tuple(coeffs) + _extension_coefficients(ext, stage.number, channel)
            held = [c.key for c in coeffs if c.key in fixed_keys]
            coeffs = tuple(c for c in coeffs if c.key not in fixed_keys)
            p, r = _run_group(stage, channel, coeffs, p, table, sqrt_w, mode, free_rolling, say, ext=ext,
                              jacobian=jacobian)
            r.not_identified.update({k: "fixed by the user" for k in held})
            results.append(r)
            if stage.number == 5 and r.status == "fitted":
                # Mz at kappa = 0 holds s·Fx (eq 4.E71) with the SSZ and combined Fx just fitted:
                # polish the aligning coefficients together with SSZ on all Mz rows.
                p, r2 = _refine_mz(p, results, table, sqrt_w, mode, say, ext, jacobian)
                if r2 is not None:
                    results.append(r2)
            if r.status != "fitted":
                messages.append(f"stage {stage.number} {stage.name} [{channel}] skipped: {r.message}")
                say(f"stage {stage.number} {stage.name} [{channel}] skipped: {r.message}")
            elif r.n_nan:
                messages.append(f"stage {stage.number} {stage.name}: {r.n_nan} rows without {channel} skipped")

    if not any(r.status == "fitted" for r in results):
        few = [r for r in results if r.message.startswith("too few points")]
        if few:
            r = few[0]
            raise MftireInputError(f"{len(table)} data point(s) are too few for the stages asked for: stage {r.number} "
                                   f"{r.name} [{r.channel}]: {r.message}; nothing fitted")
    fitted = tmpl.copy()
    identified: list[str] = []
    not_identified: dict[str, str] = {}
    for r in results:
        identified.extend(r.identified)
        not_identified.update(r.not_identified)
        for k in r.identified:
            fitted.set(k, float(p[k]), section=SECTION if k in ext.coefficient_keys else None)

    fr = _free_rolling_report(p, free_rolling, mode, ext)
    if len(fr) and not fr["sign_ok"].all():
        bad = fr[~fr["sign_ok"]]
        messages.append(f"free rolling: the model gives Fx > 0 at kappa = 0 in {len(bad)} condition(s) "
                        "where the data show Fx < 0")
    table = _add_fit_columns(table, p, mode, ext)
    ran = [r for r in results if r.status == "fitted"]
    return FitResult(
        parameters=fitted,
        flat=with_defaults(fitted.flat()),
        template=p0,
        stages=results,
        identified=identified,
        not_identified=not_identified,
        free_rolling=fr,
        data=table,
        messages=messages,
        n_dropped_nan=n_nan,
        mode=int(mode.code) - 100,
        success=bool(ran) and all(r.success for r in ran),
        time=time.perf_counter() - t_start,
    )


def _refine_mz(p, results, table, sqrt_w, mode, say, ext, jacobian="exact"):
    keys = [k for r in results if r.number in (3, 5) and r.status == "fitted" for k in r.identified]
    if not any(r.number == 3 and r.status == "fitted" for r in results):
        return p, None
    by_key = {c.key: c for s in STAGES for c in s.coefficients}
    by_key.update({c.key: c for n in (3, 5) for c in _extension_coefficients(ext, n, "Mz")})
    coeffs = tuple(by_key[k] for k in dict.fromkeys(keys))
    stage = Stage(5, "combined_mz", ("Mz",), ("pure_lateral", "free_rolling", "combined"), (coeffs,),
                  "aligning moment refinement on pure and combined sweeps")
    p, r = _run_group(stage, "Mz", coeffs, p, table, sqrt_w, mode, [], say, refine=True, ext=ext, jacobian=jacobian)
    r.name = "combined_mz_refine"
    r.not_identified = {}
    return p, (r if r.status == "fitted" else None)


def _classify_rows(table: pd.DataFrame) -> pd.DataFrame:
    """Keep group_sweeps' sweep kinds for ordered data; classify row by row otherwise.

    Sweeps are found in row order; data that are not stored sweep by sweep (shuffled
    simulation output) give tiny "sweeps", and each row is then classified on its own
    slips: pure longitudinal when |alpha| <= 0.5 deg, pure lateral when |kappa| <= 0.005.
    """
    sizes = table.groupby("sweep_id").size()
    if len(sizes) == 0 or float(sizes.median()) >= 5:
        return table
    a = np.abs(table["alpha"].to_numpy(float)) <= math.radians(0.5)
    k = np.abs(table["kappa"].to_numpy(float)) <= 0.005
    kind = np.where(a & k, "free_rolling", np.where(a, "pure_longitudinal",
                                                     np.where(k, "pure_lateral", "combined")))
    out = table.copy()
    out["kind"] = kind
    out["sweep_var"] = np.where(a & ~k, "kappa", np.where(k & ~a, "alpha", "none"))
    return out


def _stage_channels(stage: Stage) -> tuple[str, ...]:
    return stage.channels if len(stage.channels) == len(stage.groups) else stage.channels * len(stage.groups)


def _free_rolling_report(p: dict, targets: list[pd.DataFrame], mode: Mode, ext: ExtensionSet) -> pd.DataFrame:
    cols = [*CONDITION_KEYS, "measured", "fitted", "error", "sign_ok"]
    if not targets or all(len(t) == 0 for t in targets):
        return pd.DataFrame(columns=cols)
    t = pd.concat(targets, ignore_index=True)
    fitted = predict(p, _condition_inputs(t, ext), "Fx", mode, ext)
    t["fitted"] = fitted
    t["error"] = fitted - t["measured"]
    t["sign_ok"] = ~((t["measured"] < 0) & (fitted > 0))
    return t[cols]


def _add_fit_columns(table: pd.DataFrame, p: dict, mode: Mode, ext: ExtensionSet) -> pd.DataFrame:
    """Add ``fit_<channel>`` model columns for every measured channel present."""
    model = Model(p, Inputs.from_frame(table, ext.external_variables), mode, ext)
    out = table.copy()
    present = tuple(ch for ch in ("Fx", "Fy", "Mz", "Mx", "My") if ch in out.columns)
    if present:
        ch = model.channels(p, present)
        for name in present:
            out[f"fit_{name}"] = np.real(getattr(ch, name))
    return out


#: The stage that fits an extension term, by the first channel it acts on.
_EXTENSION_STAGE = {"Fx": 1, "Fy": 2, "Mz": 3, "Mx": 6, "My": 7}


def _extension_coefficients(ext: ExtensionSet, stage: int, channel: str) -> tuple[Coefficient, ...]:
    """The coefficients of the extension terms fitted in ``stage`` (bounds from their form)."""
    out = []
    for t in ext.terms:
        if _EXTENSION_STAGE.get(t.channels[0]) == stage and t.channels[0] == channel:
            for k in t.coefficient_keys:
                lo, hi = t.bounds(k)
                out.append(Coefficient(k, lo, hi, scale=0.1))
    return tuple(out)


def _extension_identified(
    ext: ExtensionSet, coeffs: Sequence[Coefficient], rows: pd.DataFrame
) -> tuple[list[Coefficient], dict[str, str]]:
    """Drop extension coefficients whose variable does not vary over ``rows``."""
    if not ext:
        return list(coeffs), {}
    owner = {k: t for t in ext.terms for k in t.coefficient_keys}
    ok, not_ok = [], {}
    for c in coeffs:
        t = owner.get(c.key)
        if t is None:
            ok.append(c)
            continue
        cols = [v for v in t.variables() if v in rows.columns]  # builtin variables vary with the slips
        if all(np.unique(np.round(rows[v].to_numpy(float), 9)).size >= 2 for v in cols):
            ok.append(c)
        else:
            not_ok[c.key] = f"{', '.join(cols)} does not vary in the stage's data"
    return ok, not_ok


#: Re-exported for convenience.
ALL_STAGES = STAGES
