"""The held-out check of a thermal fit: fit on the first part of a continuous series, replay the rest, and
compare with two references on the same rows (issue 22's "done when"; ``mftire demo``'s thermal stage and
``validation/make_thermal_runs.py --check``).

The three models, each judged by its RMS error of Fx and Fy [N] over the held-out rows (``ET > split``):

* **thermal**: :func:`mftire.thermal.thermal_fit.fit_thermal` on ``ET <= split``, then
  :func:`mftire.thermal.simulation.replay` along the whole series, given only kinematics and conditions
  (no temperature input); also the surface node against the infrared mean [K] and the gas law's pressure
  against the measured one [Pa];
* **measured temperature** (:func:`measured_temperature_model`): the same temperature laws fed the measured
  surface temperature (mean of ``TSTI/TSTC/TSTO``: the diagnosis's situation) and the measured pressure,
  their coefficients fitted on ``ET <= split``;
* **isothermal** (:func:`isothermal_fit`): ``LMUX, LMUY, LKX, LKY`` of the ``.tir`` refitted on ``ET <= split``
  at the cold pressure, replayed without a thermal section.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from mftire.errors import MftireInputError
from mftire.thermal.simulation import Replay, cold_pressure, replay
from mftire.thermal.thermal_fit import (
    ThermalResult,
    _force_rows,
    fit_laws,
    fit_thermal,
    is_temperature_variable,
    measured_surface,
    temperature_laws,
    with_default_laws,
)

#: The models of the check, in report order.
MODELS = ("thermal", "measured_temperature", "isothermal")
#: The scaling factors an isothermal fit refits.
ISOTHERMAL_KEYS = ("LMUX", "LMUY", "LKX", "LKY")


def rms(x) -> float:
    """Root mean square of the finite values of ``x`` (nan when none is)."""
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    return float(np.sqrt(np.mean(x ** 2))) if x.size else math.nan


def _fit_part(df: pd.DataFrame, split: float, name: str) -> pd.DataFrame:
    fit = df[df["ET"].to_numpy(float) <= split].reset_index(drop=True)
    if len(fit) < 20 or len(fit) == len(df):
        raise MftireInputError(f"{name}: split at ET = {split:g} s leaves {len(fit)} of {len(df)} rows to fit on and "
                               f"{len(df) - len(fit)} held out; both parts need rows")  # fmt: skip
    return fit


def measured_temperature_model(tyre, fit: pd.DataFrame, name: str = "data"):
    """The model fed the measured temperature: the temperature laws of ``tyre`` (none: the default grip and
    stiffness laws of :func:`~mftire.thermal.thermal_fit.with_default_laws`, referred to the median surface
    reading) fitted on the series ``fit`` with every law reading the measured surface temperature and the
    MF the measured pressure.  Returns the :class:`~mftire.tyre.Tyre`; evaluate it with each temperature
    variable the measured surface temperature (:func:`evaluate_measured`)."""
    from mftire.tyre import Tyre, as_tyre

    tyre = as_tyre(tyre)
    ir = measured_surface(fit, name)
    base = tyre if temperature_laws(tyre) else Tyre(with_default_laws(tyre.parameters,
                                                                      float(np.round(np.nanmedian(ir)))))
    laws = temperature_laws(base)
    P = fit["P"].to_numpy(float) if "P" in fit.columns else cold_pressure(fit, None, base.flat)
    coeffs, _, _ = fit_laws(base, fit, np.repeat(ir[:, None], 3, axis=1), P, {n: "surface" for n in laws},
                            _force_rows(fit))  # fmt: skip
    base.flat.update(coeffs)
    return base


def evaluate_measured(model, df: pd.DataFrame, name: str = "data", channels=("Fx", "Fy")):
    """Forces of :func:`measured_temperature_model` along ``df``: each temperature variable is the measured
    surface temperature, the pressure the measured one (else the cold pressure)."""
    ir = measured_surface(df, name)
    var = {v: (ir if is_temperature_variable(v) else df[v].to_numpy(float)) for v in model.required_variables}
    P = df["P"].to_numpy(float) if "P" in df.columns else cold_pressure(df, None, model.flat)
    return model.evaluate(df["Fz"].to_numpy(float), df["kappa"].to_numpy(float), df["alpha"].to_numpy(float),
                          df["gamma"].to_numpy(float), Vx=df["Vx"].to_numpy(float), P=P, channels=channels,
                          **var)  # fmt: skip


def isothermal_fit(tyre, fit: pd.DataFrame):
    """``tyre``'s parameters (TirParameters) with ``LMUX, LMUY, LKX, LKY`` refitted (least squares on Fx and
    Fy of the slip rows of the series ``fit``) at the cold pressure, without a thermal section."""
    from scipy.optimize import least_squares

    from mftire.mf.thermal_section import SECTION
    from mftire.tyre import Tyre, as_tyre

    p = as_tyre(tyre).parameters.copy()
    p.sections.pop(SECTION, None)
    iso = Tyre(p)
    rows = _force_rows(fit)
    p0 = float(cold_pressure(fit, None, iso.flat)[0])
    cols = {c: fit[c].to_numpy(float)[rows] for c in ("Fz", "kappa", "alpha", "gamma", "Vx", "Fx", "Fy")}
    x0 = np.array([iso.flat[k] for k in ISOTHERMAL_KEYS])

    def residuals(x):
        iso.flat.update(dict(zip(ISOTHERMAL_KEYS, x, strict=True)))
        o = iso.evaluate(cols["Fz"], cols["kappa"], cols["alpha"], cols["gamma"], Vx=cols["Vx"], P=p0,
                         channels=("Fx", "Fy"))  # fmt: skip
        return np.concatenate([o["Fx"] - cols["Fx"], o["Fy"] - cols["Fy"]])

    sol = least_squares(residuals, x0, diff_step=1e-4)
    for k, v in zip(ISOTHERMAL_KEYS, sol.x, strict=True):
        p.set(k, float(v))
    return p


@dataclass
class HeldOutCheck:
    """Result of :func:`heldout_check` (errors over the held-out rows)."""

    split: float  #: the fit uses ET <= split [s]
    n_fit: int
    n_heldout: int
    surface_rms: float  #: thermal replay's surface node − infrared mean [K]
    pressure_rms: float  #: thermal replay's pressure − measured [Pa] (nan without P)
    errors: dict[str, dict[str, float]]  #: model (:data:`MODELS`) -> channel -> RMS error [N]
    fit: ThermalResult  #: the thermal fit (``fit.tir`` is the THERMAL.tir)
    replay: Replay  #: thermal replay of the whole series
    isothermal: Replay  #: isothermal replay of the whole series
    measured: dict[str, np.ndarray]  #: forces of the measured-temperature model along the whole series [N]

    def numbers(self) -> dict[str, float]:
        """Flat numbers for reports: split, rows, surface and pressure RMS, ``{model}_{channel}_rms_N``, and per
        channel the thermal replay's error over the measured-temperature model's and its cut against the
        isothermal fit."""
        out = {"split_s": self.split, "fit_rows": self.n_fit, "heldout_rows": self.n_heldout,
               "surface_rms_K": self.surface_rms, "pressure_rms_kPa": self.pressure_rms / 1e3}  # fmt: skip
        for m in MODELS:
            for ch, v in self.errors[m].items():
                out[f"{m}_{ch}_rms_N"] = v
        for ch, v in self.errors["thermal"].items():
            out[f"{ch}_ratio_to_measured_temperature"] = v / self.errors["measured_temperature"][ch]
            out[f"{ch}_cut_vs_isothermal"] = 1.0 - v / self.errors["isothermal"][ch]
        return out

    def table(self) -> pd.DataFrame:
        """One row per model: RMS error of each channel over the held-out rows [N]."""
        return pd.DataFrame([{"model": m, **{f"{ch}_rms_N": v for ch, v in self.errors[m].items()}} for m in MODELS])


def heldout_check(tyre, df: pd.DataFrame, split: float, *, name: str = "data", sealed: bool = True,
                  channels=("Fx", "Fy")) -> HeldOutCheck:
    """Fit the thermal tyre on ``ET <= split`` [s] of the continuous series ``df`` (imported: ISO, SI, °C, the
    columns :func:`~mftire.thermal.thermal_fit.fit_thermal` takes), replay the rest, and compare with the two
    references of the module docstring.  ``tyre`` is the fitted (isothermal) MF model, ``.tir`` path or
    :class:`~mftire.tyre.Tyre`; ``sealed`` as :func:`~mftire.thermal.thermal_fit.fit_thermal`."""
    from mftire.tyre import Tyre, as_tyre

    tyre = as_tyre(tyre)
    df = df.reset_index(drop=True)
    fit = _fit_part(df, split, name)
    held = df["ET"].to_numpy(float) > split
    res = fit_thermal(tyre, df, fit_until=split, name=name, sealed=sealed)
    rep = replay(Tyre(res.tir, name=tyre.name), df, name=name)
    iso = replay(Tyre(isothermal_fit(tyre, fit), name=tyre.name), df, name=name)
    measured = evaluate_measured(measured_temperature_model(tyre, fit, name), df, name, channels)
    ir = measured_surface(df, name)
    t = rep.table
    errors = {"thermal": {}, "measured_temperature": {}, "isothermal": {}}
    for ch in channels:
        y = df[ch].to_numpy(float)[held]
        errors["thermal"][ch] = rms(t[f"{ch}_model"].to_numpy(float)[held] - y)
        errors["measured_temperature"][ch] = rms(np.asarray(measured[ch], float)[held] - y)
        errors["isothermal"][ch] = rms(iso.table[f"{ch}_model"].to_numpy(float)[held] - y)
    p_rms = rms(t["P_model"].to_numpy(float)[held] - t["P"].to_numpy(float)[held]) if "P" in t.columns else math.nan
    return HeldOutCheck(split, len(fit), int(held.sum()), rms(t["T_surface"].to_numpy(float)[held] - ir[held]), p_rms,
                        errors, res, rep, iso, {ch: np.asarray(measured[ch], float) for ch in channels})  # fmt: skip


__all__ = ["ISOTHERMAL_KEYS", "MODELS", "HeldOutCheck", "evaluate_measured", "heldout_check", "isothermal_fit",
           "measured_temperature_model", "rms"]
