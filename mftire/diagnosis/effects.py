"""Map a candidate variable to model extensions, fit them, and choose one.

Each extension of :mod:`mftire.extensions` is fitted by bounded robust least
squares on the training data, together with the main pure-slip coefficients of the
measured channels (:data:`REFIT_KEYS`: shape, peak, curvature and stiffness of Fx
and Fy, trail and residual torque of Mz), because a base fit made on data
containing the effect has absorbed part of it into them.  The other Magic Formula
coefficients stay as fitted.  The inflation-pressure effect refits the
standard MF 6.1 pressure coefficients instead of an extension section.

Extensions are compared by the Bayesian information criterion of the weighted
residual, n·ln(SS/n) + k·ln(n), so a term with more parameters must earn them.  If
no physical extension removes at least half of what a generic smooth correction in
the same variable removes, the generic correction is offered, labelled as such.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.optimize import least_squares

from mftire.extensions import BUILTIN_VARIABLES, LIBRARY, SECTION
from mftire.tyre import Tyre

#: Extensions tried for each derived candidate (data columns: see :func:`effects_for`).
EFFECTS_FOR: dict[str, tuple[str, ...]] = {
    "Vs": ("slip_speed_friction", "slip_speed_peak", "speed_friction"),
    "Vx": ("speed_friction", "slip_speed_friction", "slip_speed_peak"),
    "P": ("pressure",),
    "Fz_dev": ("load_friction",),
    "sign_alpha": ("asymmetry",),
    "sign_kappa": ("rolling_resistance",),
    "sweep_dir": (),
    "sequence": ("fade", "friction_variable"),
    "energy": ("fade", "friction_variable"),
}

#: Standard pressure coefficients refitted by the ``pressure`` effect, by channel,
#: split into terms linear and quadratic in dpi (Pacejka 2012 eqs 4.E13, 4.E15,
#: 4.E23, 4.E25, 4.E30, A60, 4.E47).
PRESSURE_KEYS = {
    "Fx": (("PPX1", "PPX3"), ("PPX2", "PPX4")),
    "Fy": (("PPY1", "PPY2", "PPY3"), ("PPY4",)),
    "Mz": (("PPZ1", "PPZ2"), ()),
}

#: Main pure-slip coefficients refitted with an effect, by channel (Pacejka 2012
#: eqs 4.E11–4.E15, 4.E21–4.E25, 4.E40–4.E47): a base fit made on data containing
#: the effect has absorbed part of it into these.
REFIT_KEYS = {
    "Fx": ("PCX1", "PDX1", "PDX2", "PEX1", "PEX2", "PKX1", "PKX2"),
    "Fy": ("PCY1", "PDY1", "PDY2", "PEY1", "PEY2", "PKY1", "PKY2"),
    "Mz": ("QBZ1", "QBZ2", "QCZ1", "QDZ1", "QDZ2", "QEZ1", "QDZ6"),
}


@dataclass
class EffectFit:
    """A fitted effect."""

    name: str  #: extension name, ``pressure`` or ``generic``
    variable: str
    physical: bool
    parameters: dict[str, float]  #: fitted extension (or pressure) parameters
    section: dict[str, object]  #: the ``[MFTIRE_EXTENSIONS]`` entries (empty for pressure)
    standard: dict[str, float]  #: standard .tir keys changed (friction level, pressure terms)
    ss_before: float
    ss_after: float
    bic: float
    n_params: int
    messages: list[str] = field(default_factory=list)

    @property
    def removed(self) -> float:
        """Share of the weighted training residual removed [-]."""
        return 1.0 - self.ss_after / self.ss_before if self.ss_before > 0 else 0.0

    def apply(self, tyre: Tyre) -> Tyre:
        """The tyre with this effect added (a new :class:`Tyre`; ``tyre`` is unchanged)."""
        return _tyre_with(tyre, self.standard, self.section)


def _tyre_with(tyre: Tyre, standard: Mapping[str, float], section: Mapping[str, object]) -> Tyre:
    params = tyre.parameters.copy()
    for k, v in standard.items():
        params.set(k, float(v))
    for k, v in section.items():
        params.set(k, v, section=SECTION)
    return Tyre(params, name=tyre.name)


def effects_for(variable: str, derived: bool, monotone: bool) -> tuple[str, ...]:
    """Extensions to try for a candidate.

    Data columns: ``fade`` when the variable never decreases along the sequence
    (time, energy, distance ...), and ``friction_variable`` (e.g. temperature, road).
    """
    if derived:
        return EFFECTS_FOR.get(variable, ())
    return ("fade", "friction_variable") if monotone else ("friction_variable",)


@dataclass
class _Problem:
    """The training data of an effect fit."""

    tyre: Tyre
    df: pd.DataFrame
    channels: tuple[str, ...]
    scale: dict[str, float]
    variables: dict[str, np.ndarray]
    weights: np.ndarray


def make_problem(tyre: Tyre, df: pd.DataFrame, channels: Sequence[str], weights: np.ndarray | None = None) -> _Problem:
    """Prepare the training data: channels present, residual scales (peak |y|)."""
    chans = tuple(c for c in channels if c in df.columns and df[c].notna().any())
    scale = {c: float(np.nanmax(np.abs(df[c].to_numpy(float)))) or 1.0 for c in chans}
    w = np.ones(len(df)) if weights is None else np.asarray(weights, float)
    return _Problem(tyre, df, chans, scale, {}, w)


def covered_channels(prob: _Problem) -> list[str]:
    """Channels whose main coefficients the training data can refit: Fx needs slip
    beyond |kappa| 0.05, Fy and Mz slip angles beyond 2 deg."""
    d = prob.df
    out = []
    for ch in prob.channels:
        if ch == "Fx":
            ok = (np.abs(d["kappa"].to_numpy(float)) > 0.05) & np.isfinite(d["Fx"].to_numpy(float))
        elif ch in ("Fy", "Mz"):
            ok = (np.abs(d["alpha"].to_numpy(float)) > np.radians(2.0)) & np.isfinite(d[ch].to_numpy(float))
        else:
            continue
        if ok.sum() >= 20:
            out.append(ch)
    return out


def _residuals(prob: _Problem, tyre: Tyre, variables: Mapping[str, np.ndarray]) -> np.ndarray:
    d = prob.df
    out = tyre.evaluate(
        d["Fz"].to_numpy(float), d["kappa"].to_numpy(float), d["alpha"].to_numpy(float),
        d["gamma"].to_numpy(float), Vx=d["Vx"].to_numpy(float), P=d["P"].to_numpy(float), **variables,
    )  # fmt: skip
    parts = []
    sw = np.sqrt(prob.weights)
    for c in prob.channels:
        r = (d[c].to_numpy(float) - out[c]) / prob.scale[c]
        parts.append(np.where(np.isfinite(r), r, 0.0) * sw)
    return np.concatenate(parts)


def _spec(name: str, variable: str, v: np.ndarray | None, tyre: Tyre, n_pressures: int, channels):
    """Keys, initial values, bounds and fixed entries of an effect's fit."""
    fixed: dict[str, object] = {}
    V0 = tyre["LONGVL"]
    if name == "slip_speed_friction":
        return ["VS_DECAY"], [0.05], [(-0.5, 5.0)], fixed
    if name == "slip_speed_peak":
        return (["VS_PEAK_GAIN", "VS_PEAK_SPEED", "VS_PEAK_WIDTH"], [0.2, 0.1 * V0, 0.5],
                [(-0.9, 5.0), (1e-3, 5.0 * V0), (0.05, 3.0)], fixed)  # fmt: skip
    if name == "speed_friction":
        return ["VX_FRIC1", "VX_FRIC2"], [0.0, 0.0], [(-1.0, 1.0), (-1.0, 1.0)], fixed
    if name == "load_friction":
        return ["LOAD_MU2"], [0.0], [(-1.0, 1.0)], fixed
    if name == "rolling_resistance":
        return ["RR_FX"], [0.01], [(-0.1, 0.1)], fixed
    if name == "asymmetry":
        return ["ASYM_MUY", "ASYM_FY"], [0.0, 0.0], [(-0.5, 0.5), (-0.2, 0.2)], fixed
    if name == "fade":
        span = float(np.nanmax(v)) if v is not None and np.nanmax(v) > 0 else 1.0
        fixed["FADE_VARIABLE"] = variable
        return ["FADE_DEPTH", "FADE_SCALE"], [0.05, 0.5 * span], [(-0.5, 0.9), (1e-3 * span, 100.0 * span)], fixed
    if name == "friction_variable":
        ref = float(np.nanmedian(v))
        sc = float(np.nanstd(v)) or 1.0
        fixed.update({"FVAR_VARIABLE": variable, "FVAR_REF": ref, "FVAR_SCALE": sc})
        return ["FVAR_C1", "FVAR_C2"], [0.0, 0.0], [(-1.0, 1.0), (-1.0, 1.0)], fixed
    if name == "generic":
        ref = float(np.nanmedian(v))
        sc = float(np.nanstd(v)) or 1.0
        fixed.update({"GEN_VARIABLE": variable, "GEN_REF": ref, "GEN_SCALE": sc, "GEN_CHANNEL": channels[0]})
        return ["GEN_C1", "GEN_C2", "GEN_C3"], [0.0, 0.0, 0.0], [(-2.0, 2.0)] * 3, fixed
    if name == "none":
        return [], [], [], fixed
    if name == "pressure":
        keys: list[str] = []
        for ch in channels:
            lin, quad = PRESSURE_KEYS.get(ch, ((), ()))
            keys += list(lin) if n_pressures >= 2 else []
            keys += list(quad) if n_pressures >= 3 else []
        return keys, [float(tyre[k]) for k in keys], [(-3.0, 3.0)] * len(keys), fixed
    raise ValueError(f"unknown effect {name!r}")


def fit_effect(
    prob: _Problem,
    name: str,
    variable: str,
    values: np.ndarray | None,
    n_pressures: int = 1,
    generic_channel: str | None = None,
    refit_base: bool = True,
) -> EffectFit:
    """Fit one effect on the training problem, with the main pure-slip coefficients
    of the measured channels (:data:`REFIT_KEYS`) refitted alongside when
    ``refit_base``; ``refit_base=False`` with ``name="none"`` is the control refit."""
    tyre = prob.tyre
    channels = (generic_channel,) if name == "generic" and generic_channel else prob.channels
    keys, x0, bounds, fixed = _spec(name, variable, values, tyre, n_pressures, channels)
    uses_data = name in ("fade", "friction_variable", "generic") and values is not None
    variables = {variable: values} if uses_data and variable not in BUILTIN_VARIABLES else {}
    variables.update(prob.variables)
    needed = set(tyre.required_variables)
    base_r = _residuals(prob, tyre, {k: v for k, v in variables.items() if k in needed})
    ss0 = float(base_r @ base_r)
    refit = [k for ch in covered_channels(prob) for k in REFIT_KEYS.get(ch, ()) if k not in keys]
    refit = list(dict.fromkeys(refit)) if refit_base else []
    lo = [b[0] for b in bounds] + [tyre[k] - 0.5 * abs(tyre[k]) - 1e-3 for k in refit]
    hi = [b[1] for b in bounds] + [tyre[k] + 0.5 * abs(tyre[k]) + 1e-3 for k in refit]
    start = np.clip(np.array(list(x0) + [tyre[k] for k in refit], float), lo, hi)

    def build(x):
        standard: dict[str, float] = {k: float(v) for k, v in zip(refit, x[len(keys):], strict=True)}
        section: dict[str, object] = dict(fixed)
        for k, val in zip(keys, x[: len(keys)], strict=True):
            if name == "pressure":
                standard[k] = float(val)
            else:
                section[k] = float(val)
        return standard, section

    def fun(x):
        standard, section = build(x)
        return _residuals(prob, _tyre_with(tyre, standard, section), variables)

    messages = []
    if not len(start):
        return EffectFit(name, variable, True, {}, {}, {}, ss0, ss0, np.inf, 0, messages)
    if name == "pressure" and not keys:
        messages.append("one inflation pressure in the training data: pressure terms not identifiable")
        return EffectFit(name, variable, True, {}, {}, {}, ss0, ss0, np.inf, 0, messages)
    f_scale = max(float(np.sqrt(np.median(base_r**2))), 1e-6)
    res = least_squares(fun, start, bounds=(lo, hi), loss="soft_l1", f_scale=2.0 * f_scale, x_scale="jac",
                        max_nfev=60 * (len(start) + 1))  # fmt: skip
    r = fun(res.x)
    ss1 = float(r @ r)
    n = max(len(r), 1)
    k = len(start)
    bic = n * np.log(max(ss1, 1e-300) / n) + k * np.log(n)
    standard, section = build(res.x)
    params = {kk: float(vv) for kk, vv in zip(keys, res.x[: len(keys)], strict=True)}
    physical = name in ("pressure", "none") or LIBRARY[name].physical
    return EffectFit(name, variable, physical, params, section, standard, ss0, ss1, float(bic), k, messages)


#: An effect must leave at most this share of the control refit's residual ...
MAX_RESIDUAL_VS_CONTROL = 0.9


def _beats(fit: EffectFit, control: EffectFit) -> bool:
    """The effect explains clearly more than refitting the same coefficients without it:
    10 % less weighted residual than the control refit, and a lower BIC."""
    ref_ss = control.ss_after if np.isfinite(control.bic) else control.ss_before
    ref_bic = control.bic if np.isfinite(control.bic) else np.inf
    return fit.ss_after <= MAX_RESIDUAL_VS_CONTROL * ref_ss and fit.bic < ref_bic


def choose_effect(
    prob: _Problem,
    variable: str,
    values: np.ndarray | None,
    derived: bool,
    monotone: bool,
    n_pressures: int,
    top_channel: str,
) -> tuple[EffectFit | None, list[EffectFit]]:
    """Fit the extensions mapped to ``variable`` and a generic correction; choose one.

    Every fit is compared with a *control*: the same coefficients refitted without
    any extension.  An effect is only chosen if it beats the control (see
    :func:`_beats`), so refitting alone cannot pass for a missing effect.

    Returns ``(chosen, all_fits)``; chosen is None when no effect beats the control.
    """
    control = fit_effect(prob, "none", variable, values, n_pressures)
    fits: list[EffectFit] = []
    for name in effects_for(variable, derived, monotone):
        fits.append(fit_effect(prob, name, variable, values, n_pressures))
    physical = [f for f in fits if f.n_params > 0 and _beats(f, control)]
    generic = None
    if values is not None and variable not in ("P",):
        generic = fit_effect(prob, "generic", variable, values, n_pressures, generic_channel=top_channel)
        fits.append(generic)
    best_phys = min(physical, key=lambda f: f.bic) if physical else None
    if best_phys is not None and (generic is None or best_phys.removed >= 0.5 * generic.removed):
        return best_phys, fits
    if generic is not None and _beats(generic, control):
        generic.messages.append(
            "no physical extension explains this residual; this is a generic smooth correction, not a physical model"
        )
        return generic, fits
    return best_phys, fits
