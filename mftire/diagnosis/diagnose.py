"""The closed loop: residuals → ranked causes → model extension → refit → held-out check.

Procedure (:func:`diagnose`)
----------------------------
1. Residuals of every measured channel, data minus the fitted model.
2. Candidates (:mod:`mftire.diagnosis.candidates`) ranked by the residual variance
   they explain beyond the MF inputs, cross-validated by sweep, with a permutation
   test (:mod:`mftire.diagnosis.ranking`).
3. No significant candidate: "no significant effect", nothing changes.
4. Otherwise a condition is held out (``holdout`` or an interior level of the top
   candidate, else of load, speed or pressure).  For the significant candidates
   close to the top (score >= 60 % of the best, at most three), the mapped model
   extensions are fitted on the remaining data (:mod:`mftire.diagnosis.effects`);
   the candidate whose effect fits best (lowest BIC, physical before generic) is
   the cause, and is listed first.
5. Before/after errors on the held-out condition per channel: RMS, RMS in % of the
   channel's peak, and the share of residual variance removed.
"""

from __future__ import annotations

import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from mftire.diagnosis.candidates import Candidate, candidates, with_sweeps
from mftire.diagnosis.effects import EffectFit, choose_effect, drop_outliers, make_problem, primary_rows
from mftire.diagnosis.holdout import default_holdout, holdout_mask, levels
from mftire.diagnosis.ranking import (
    CandidateScore,
    baseline_features,
    normalised_residual,
    rank_candidates,
)
from mftire.errors import MftireInputError
from mftire.extensions import LIBRARY
from mftire.iotools.sweeps import MEASURED_COLUMNS
from mftire.tyre import Tyre


@dataclass
class ChannelError:
    """Held-out error of one channel before and after the extension."""

    channel: str
    n: int
    rms_before: float
    rms_after: float
    rms_pct_before: float  #: RMS / peak |y| of the held-out data [%]
    rms_pct_after: float
    variance_removed: float  #: 1 − SS_after/SS_before [-]


@dataclass
class DiagnosisResult:
    """Everything :func:`diagnose` found."""

    significant: bool
    ranking: list[CandidateScore]
    effect: EffectFit | None
    holdout: dict | None  #: {"column", "values", "n_rows"}
    errors: list[ChannelError] = field(default_factory=list)
    extended: Tyre | None = None
    tried: list[EffectFit] = field(default_factory=list)
    messages: list[str] = field(default_factory=list)
    data: pd.DataFrame | None = None  #: the grouped data with derived candidates and residuals
    train: np.ndarray | None = None  #: boolean mask of the rows used to fit the effect

    def summary(self) -> str:
        if not self.significant:
            return "no significant effect: the residual is not explained by any candidate beyond the MF inputs"
        e = self.effect
        head = f"cause: {self.ranking[0].variable} ({self.ranking[0].channel}, score {self.ranking[0].score:.2f})"
        if e is None:
            return head + "; no extension reduced the residual"
        kind = "physical extension" if e.physical else "GENERIC correction (not physics)"
        return head + f"; {kind} '{e.name}' removes {100 * e.removed:.0f} % of the training residual"


def _progress(msg: str, enabled: bool) -> None:
    if enabled:
        print(f"[diagnose] {msg}", file=sys.stderr, flush=True)


def _model(tyre: Tyre, df: pd.DataFrame, variables: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    return tyre.evaluate(
        df["Fz"].to_numpy(float), df["kappa"].to_numpy(float), df["alpha"].to_numpy(float),
        df["gamma"].to_numpy(float), Vx=df["Vx"].to_numpy(float), P=df["P"].to_numpy(float),
        **{k: np.asarray(v)[: len(df)] for k, v in variables.items()},
    )  # fmt: skip


def _variables_for(tyre: Tyre, df: pd.DataFrame, cand: Mapping[str, Candidate]) -> dict[str, np.ndarray]:
    out = {}
    for name in tyre.required_variables:
        if name in df.columns:
            out[name] = df[name].to_numpy(float)
        elif name in cand:
            out[name] = cand[name].values
        else:
            raise MftireInputError(f"the model's extensions need the input column '{name}', which the data lack")
    return out


def channel_errors(
    df: pd.DataFrame, before: Mapping[str, np.ndarray], after: Mapping[str, np.ndarray], channels: Sequence[str]
) -> list[ChannelError]:
    """Per-channel RMS, RMS % of peak and share of residual variance removed, on the
    rows where the channel is a primary response (:func:`~mftire.diagnosis.effects.primary_rows`)."""
    out = []
    for ch in channels:
        y = df[ch].to_numpy(float)
        ok = np.isfinite(y) & primary_rows(df, ch)
        if ok.sum() < 5:
            continue
        rb = (y - before[ch])[ok]
        ra = (y - after[ch])[ok]
        peak = float(np.max(np.abs(y[ok]))) or 1.0
        ssb, ssa = float(rb @ rb), float(ra @ ra)
        out.append(
            ChannelError(
                ch, int(ok.sum()), float(np.sqrt(ssb / ok.sum())), float(np.sqrt(ssa / ok.sum())),
                100 * float(np.sqrt(ssb / ok.sum())) / peak, 100 * float(np.sqrt(ssa / ok.sum())) / peak,
                1.0 - ssa / ssb if ssb > 0 else 0.0,
            )  # fmt: skip
        )
    return out


def diagnose(
    data: pd.DataFrame,
    tyre: Tyre,
    holdout: tuple[str, Sequence[float]] | None = None,
    *,
    channels: Sequence[str] | None = None,
    n_perm: int = 99,
    seed: int = 0,
    progress: bool | None = None,
    ranking_kwargs: Mapping | None = None,
) -> DiagnosisResult:
    """Diagnose the residual of ``tyre`` on sweep ``data`` (see the module docstring).

    Parameters
    ----------
    data : DataFrame
        Validated sweep table (SI), any extra columns kept.
    tyre : Tyre
        The fitted model.
    holdout : (column, values), optional
        The held-out condition; default chosen automatically.
    channels : sequence of str, optional
        Channels to analyse (default: every measured channel present).
    """
    if progress is None:
        progress = sys.stderr.isatty()
    df = with_sweeps(data.reset_index(drop=True))
    chans = [c for c in (channels or MEASURED_COLUMNS) if c in df.columns and df[c].notna().sum() > 10]
    if not chans:
        raise MftireInputError("no measured channel (Fx, Fy, Mz, Mx, My) with data to diagnose")
    if holdout is not None:  # a held-out level given by the user must exist, whatever the ranking finds
        holdout_mask(df, holdout[0], list(holdout[1]))
    cands = candidates(df)
    by_name = {c.name: c for c in cands}
    variables = _variables_for(tyre, df, by_name)
    _progress(f"{len(df)} rows, {df['sweep_id'].nunique()} sweeps, channels {', '.join(chans)}", progress)

    model = _model(tyre, df, variables)
    R0 = tyre["UNLOADED_RADIUS"]
    Fz = df["Fz"].to_numpy(float)
    residuals, peaks = {}, {}
    for ch in chans:
        y = df[ch].to_numpy(float)
        residuals[ch] = normalised_residual(ch, y, model[ch], Fz, R0)
        scale = Fz * R0 if ch in ("Mz", "Mx", "My") else Fz
        peaks[ch] = float(np.nanmax(np.abs(y / scale)))
        df[f"residual_{ch}"] = y - model[ch]
    X0 = baseline_features(df["kappa"].to_numpy(float), df["alpha"].to_numpy(float), df["gamma"].to_numpy(float),
                           Fz, tyre["FNOMIN"])  # fmt: skip
    _progress(f"ranking {len(cands)} candidates", progress)
    ranking = rank_candidates(residuals, peaks, X0, cands, df["sweep_id"].to_numpy(), n_perm=n_perm, seed=seed,
                              **(ranking_kwargs or {}))  # fmt: skip
    for name, c in by_name.items():
        if name not in df.columns:
            df[name] = c.values
    significant = [e for e in ranking if e.significant]
    if not significant:
        return DiagnosisResult(False, ranking, None, None, messages=["no significant effect"], data=df)

    # hold out an operating condition
    top = significant[0]
    if holdout is None:
        pref = [top.variable] if by_name[top.variable].sweep_level and top.variable in df.columns else []
        misfit = np.where(primary_rows(df, top.channel), residuals[top.channel] ** 2, np.nan)
        holdout = default_holdout(df, pref, misfit)
    column, values = holdout[0], list(holdout[1])
    test = holdout_mask(df, column, values)
    train = ~test
    _progress(f"holding out {column} = {values} ({int(test.sum())} rows)", progress)

    group = [e for e in significant if e.score >= 0.6 * top.score][:3]
    n_pressures = len(levels(df[train], "P"))
    best: tuple[EffectFit, CandidateScore] | None = None
    tried: list[EffectFit] = []
    control: EffectFit | None = None  # the refit without any effect, shared by the candidates
    dtrain = df[train].reset_index(drop=True)
    for e in group:
        c = by_name[e.variable]
        v = c.values[train]
        monotone = bool(np.all(np.diff(v) >= 0))
        dtr = dtrain.assign(_cand=v)
        prob = make_problem(tyre, dtr, chans)
        prob.variables = {k: np.asarray(val)[train] for k, val in variables.items()}
        prob = drop_outliers(prob)
        v = prob.df["_cand"].to_numpy(float)
        _progress(f"fitting effects for {e.variable}", progress)
        eff_ch = [ch for ch, sc in e.channel_scores.items() if sc >= max(0.05, 0.25 * e.score)] or [e.channel]
        chosen, fits = choose_effect(prob, e.variable, v, c.derived, monotone, n_pressures, e.channel, control,
                                     eff_ch)  # fmt: skip
        control = fits[0]
        tried += fits[1:] if len(tried) else fits
        if chosen is None or chosen.removed <= 0:
            continue
        key = (not chosen.physical, chosen.bic)
        if best is None or key < (not best[0].physical, best[0].bic):
            best = (chosen, e)
    if best is None:
        msg = ("no significant effect: candidates were flagged, but no model term explains the residual better "
               "than refitting the model without it")
        return DiagnosisResult(False, ranking, None, {"column": column, "values": values, "n_rows": int(test.sum())},
                               tried=tried, messages=[msg], data=df, train=train)
    effect, cause = best
    fixed_var = LIBRARY[effect.name].fixed_variable if effect.name in LIBRARY else None
    named = [e for e in ranking if e.variable == fixed_var and e.significant]
    if named:  # e.g. a slip-speed extension chosen for the Vx candidate: the cause is Vs
        cause = named[0]
    if fixed_var is not None:
        effect.variable = fixed_var
    ranking.remove(cause)
    ranking.insert(0, cause)

    extended = effect.apply(tyre)
    ext_vars = dict(variables)
    for name in extended.required_variables:
        if name not in ext_vars:
            ext_vars[name] = df[name].to_numpy(float) if name in df.columns else by_name[name].values
    dtest = df[test].reset_index(drop=True)
    before = _model(tyre, dtest, {k: np.asarray(v)[test] for k, v in variables.items()})
    after = _model(extended, dtest, {k: np.asarray(v)[test] for k, v in ext_vars.items()})
    errors = channel_errors(dtest, before, after, chans)
    full_after = _model(extended, df, ext_vars)
    for ch in chans:
        df[f"residual_after_{ch}"] = df[ch].to_numpy(float) - full_after[ch]
    return DiagnosisResult(True, ranking, effect, {"column": column, "values": values, "n_rows": int(test.sum())},
                           errors, extended, tried, data=df, train=train)  # fmt: skip

