"""Identification of the thermal tyre from a continuous rig series (``mftire fit-thermal``).

Two steps, each a least-squares fit with a clear result:

1. **Thermal parameters** (:func:`fit_thermal_parameters`).  The measured forces give the heat
   input (friction power from the measured Fx, Fy and slips, :func:`mftire.thermal.heat.friction_power`),
   so the node equations are fitted without the tyre's force model.  Residuals: the surface node
   against the measured surface temperature, and the gas law's pressure against the measured
   pressure (which identifies the gas node).  The infrared sensors (``TSTI``, ``TSTC``, ``TSTO``)
   read the emission of the tread surface across its width, at a point of the circumference away
   from the contact patch (no flash temperature); the surface node is the width- and circumference-
   mean of the thin surface layer, so it is compared with the mean of the available readings (the
   sensors' emissivity correction is the rig's).  The series is averaged over ``bin_s`` bins (the
   heat input as a mean power, so energy is kept) before the fit.  Each parameter is fitted as its
   logarithm (positive); its standard error comes from the Jacobian at the solution,
   ``cov = s²·(JᵀJ)⁻¹`` (residuals are correlated in time, so these are lower bounds).
2. **Temperature laws** (:func:`fit_laws`).  The laws of ``[MFTIRE_EXTENSIONS]`` that read a
   temperature (grip, stiffness; when the file has none, a quadratic grip law on LMUX, LMUY and a
   linear stiffness law on LKX, LKY are added) read a node of the fitted thermal model.  The node of
   each law is chosen by held-out error: every assignment (surface or bulk per law) is scored by
   blocked cross-validation (the fit rows cut into ``folds`` contiguous blocks in time, each block
   predicted by the laws fitted on the others; RMS of Fx and Fy over FNOMIN); the best is refitted on
   all of them.
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.optimize import least_squares

from mftire.errors import MftireInputError
from mftire.mf.thermal_section import SECTION, ThermalParameters
from mftire.thermal.heat import friction_power, gas_heat_capacity, gas_temperature, hot_pressure, hysteresis_loss
from mftire.thermal.simulation import (
    NODE_VARIABLES,
    bulk_power,
    check_series,
    initial_temperatures,
    road_temperature,
    simulate_nodes,
    thermal_of,
)

#: Surface temperature columns of the rig (infrared, inner / centre / outer).
SURFACE_COLUMNS = ("TSTI", "TSTC", "TSTO")
#: The parameters fitted in step 1 (the others keep their start or default value).
#: Not fitted: TH_CAP_GAS (from the tyre's size, :func:`mftire.thermal.heat.gas_heat_capacity`),
#: TH_G_BULK_AMBIENT, TH_H_AIR0 and TH_SLIP_SHARE (their start values): the bulk is seen only through the
#: gas, and its loss to the air trades against its capacity and heat input along a direction the data do
#: not resolve (with it free the bulk drifts to a large capacity clamped to ambient; tried on the shipped run).
FITTED: tuple[str, ...] = ("cap_surface", "cap_bulk", "g_surface_bulk", "g_bulk_gas", "h_air1", "g_road",
                           "roll_loss", "hysteresis")  # fmt: skip
#: Units of the parameters (reports).
UNITS = {"cap_surface": "J/K", "cap_bulk": "J/K", "cap_gas": "J/K", "g_surface_bulk": "W/K", "g_bulk_gas": "W/K",
         "g_bulk_ambient": "W/K", "h_air0": "W/K", "h_air1": "W/K/(m/s)^0.8", "g_road": "W/K", "roll_loss": "-",
         "hysteresis": "-", "slip_share": "-"}  # fmt: skip
#: Nodes a law may read in the held-out choice.
LAW_NODES = ("surface", "bulk", "gas")
#: A variable read as a temperature (a law on it becomes a law of a node).
_TEMPERATURE_NAME = re.compile(r"^(temperature|T|T_.*|TST[ICO]|.*TEMP.*)$", re.IGNORECASE)
#: The weak prior on the logarithm of each fitted parameter around its start (the typical passenger-car
#: values of :class:`ThermalParameters`): width (a factor e^PRIOR_WIDTH), weight relative to the data, and
#: the bounds (a factor e^BOUND either way).  The bulk is seen only through the gas, so without it the
#: fit trades capacity against heat loss along unobserved directions.
PRIOR_WIDTH, PRIOR_WEIGHT, BOUND = math.log(10.0), 0.05, math.log(30.0)
#: Pressure residual scale [Pa per K of surface residual].
PRESSURE_SCALE = 1000.0


def measured_surface(df: pd.DataFrame, name: str = "data") -> np.ndarray:
    """The surface temperature the IR sensors read [°C]: the row mean of the available ``TSTI/TSTC/TSTO``."""
    cols = [c for c in SURFACE_COLUMNS if c in df.columns]
    if not cols:
        raise MftireInputError(f"{name}: no surface temperature column ({', '.join(SURFACE_COLUMNS)}); "
                               "the thermal fit compares the surface node with them")  # fmt: skip
    x = df[cols].to_numpy(float)
    with np.errstate(all="ignore"):
        m = np.nanmean(np.where(np.isfinite(x), x, np.nan), axis=1)
    return m


def is_temperature_variable(name: str) -> bool:
    return bool(_TEMPERATURE_NAME.match(name))


@dataclass
class ThermalFit:
    """Result of :func:`fit_thermal_parameters`."""

    params: ThermalParameters
    sigma: dict[str, float]  #: standard error of each fitted parameter (its unit)
    rms_surface: float  #: RMS of surface node − measured surface [K]
    rms_pressure: float  #: RMS of model − measured pressure [Pa] (nan without a P column)
    prediction: pd.DataFrame  #: binned ET, measured and predicted surface temperature, node temperatures
    success: bool
    message: str


@dataclass
class LawChoice:
    """The node a law reads, with the held-out errors of the assignments tried."""

    index: int  #: its EXTn
    description: str
    node: str
    heldout: dict[str, float] = field(default_factory=dict)  #: node -> held-out RMS (best over the others)


@dataclass
class ThermalResult:
    """Result of :func:`fit_thermal`: the ``.tir`` to write and what the fit found."""

    tir: object  #: TirParameters with [MFTIRE_EXTENSIONS] and [MFTIRE_THERMAL]
    thermal: ThermalFit
    laws: list[LawChoice]
    law_sigma: dict[str, float]
    rms_forces: dict[str, float]  #: fit-part RMS of Fx, Fy with the chosen laws [N]
    fit_until: float

    def summary(self) -> str:
        p = self.thermal.params
        lines = [f"thermal parameters (fit until ET = {self.fit_until:g} s; ± one standard error):"]
        for k in FITTED:
            lines.append(f"  TH_{k.upper():<18s} {getattr(p, k):12.5g} ± {self.thermal.sigma.get(k, math.nan):.3g} "
                         f"{UNITS[k]}")  # fmt: skip
        lines.append(f"surface node vs IR mean: RMS {self.thermal.rms_surface:.2f} K; pressure RMS "
                     f"{self.thermal.rms_pressure / 1e3:.2f} kPa")  # fmt: skip
        lines.append("temperature laws (node by held-out RMS of Fx, Fy / FNOMIN):")
        for law in self.laws:
            tried = ", ".join(f"{k} {v:.4f}" for k, v in law.heldout.items())
            lines.append(f"  EXT{law.index} {law.description}: node {law.node} ({tried})")
        for k, v in self.law_sigma.items():
            lines.append(f"  {k} ± {v:.3g}")
        lines.append("fit-part force RMS: " + ", ".join(f"{k} {v:.1f} N" for k, v in self.rms_forces.items()))
        return "\n".join(lines)


def _bin(df: pd.DataFrame, width: float) -> pd.DataFrame:
    t = df["ET"].to_numpy(float)
    b = np.floor((t - t[0]) / width).astype(int)
    g = df.groupby(b, sort=True).mean(numeric_only=True)
    return g.reset_index(drop=True)


def _sigma(res, names) -> dict[str, float]:
    J = res.jac
    m, k = J.shape
    s2 = float(np.sum(res.fun ** 2)) / max(m - k, 1)
    try:
        cov = np.linalg.pinv(J.T @ J) * s2
    except np.linalg.LinAlgError:
        return {n: math.nan for n in names}
    d = np.sqrt(np.maximum(np.diag(cov), 0.0))
    return {n: float(math.exp(x) * s) for n, x, s in zip(names, res.x, d, strict=True)}


def fit_thermal_parameters(df: pd.DataFrame, start: ThermalParameters | None = None, *, name: str = "data",
                           bin_s: float = 0.5, fitted: Sequence[str] = FITTED, fnomin: float = 1.0,
                           sealed: bool = True) -> ThermalFit:
    """Step 1 of the module docstring on a series (ET, Fz, kappa, alpha, gamma, Vx, Fx, Fy, AMBTMP,
    road temperature, surface temperatures, P); ``fnomin`` [N] normalises the hysteresis loss.

    ``sealed`` False: the rig regulates the pressure, so the measured ``P`` says nothing of the gas
    temperature; the pressure is left out of the residuals, ``TH_PRESSURE`` is 0 (the replay takes the
    cold pressure as the MF's ``P``) and the gas-node conductance is not fitted."""
    check_series(df, name, ("ET", "Fz", "kappa", "alpha", "Vx", "Fx", "Fy", "AMBTMP"))
    work = pd.DataFrame({
        "ET": df["ET"].to_numpy(float),
        "q_s": friction_power(df["Fx"], df["Fy"], df["kappa"], df["alpha"], df["Vx"]),
        "fzv": np.maximum(df["Fz"].to_numpy(float), 0.0) * np.abs(df["Vx"].to_numpy(float)),
        "vf2": hysteresis_loss(df["Fx"], df["Fy"], df["Fz"], df["Vx"], 1.0, fnomin),
        "Vx": df["Vx"].to_numpy(float), "T_amb": df["AMBTMP"].to_numpy(float),
        "T_road": road_temperature(df, name), "T_ir": measured_surface(df, name),
    })  # fmt: skip
    has_p = sealed and "P" in df.columns and np.isfinite(df["P"].to_numpy(float)).all()
    if not sealed:
        fitted = [n for n in fitted if n != "g_bulk_gas"]
    if has_p:
        work["P"] = df["P"].to_numpy(float)
    b = _bin(work, bin_s)
    ok = np.isfinite(b["T_ir"].to_numpy())
    if ok.sum() < 10:
        raise MftireInputError(f"{name}: fewer than 10 finite surface temperature readings")
    start = start or ThermalParameters()
    T0 = float(b["T_amb"].iloc[0])
    ir0 = float(b["T_ir"].iloc[0]) if ok[0] else T0
    init = {}
    if abs(ir0 - T0) > 3.0:  # the run starts with a warm tyre: start every node at the first reading
        init = {"t_init_surface": ir0, "t_init_bulk": ir0, "t_init_gas": ir0}
        T0 = ir0
    p_first = float(df["P"].iloc[0]) if "P" in df.columns and math.isfinite(float(df["P"].iloc[0])) else None
    p_cold = p_first if p_first is not None else start.cold_pressure
    start = start.replace(cold_pressure=p_cold, cold_temperature=T0, pressure=int(bool(sealed)), **init)
    t, qs, fzv, vf2, V, Ta, Tr = (b[c].to_numpy(float) for c in ("ET", "q_s", "fzv", "vf2", "Vx", "T_amb",
                                                                   "T_road"))
    Tir = b["T_ir"].to_numpy(float)
    P = b["P"].to_numpy(float) if has_p else None
    names = list(fitted)

    def params_of(x):
        return start.replace(**{n: float(math.exp(v)) for n, v in zip(names, x, strict=True)})

    def run(x):
        p = params_of(x)
        return p, simulate_nodes(p, t, qs, p.roll_loss * fzv + p.hysteresis * vf2, V, Ta, Tr, (T0, T0, T0))

    def residuals(x):
        p, nodes = run(x)
        r = [nodes[ok, 0] - Tir[ok]]
        if P is not None:
            r.append((hot_pressure(nodes[:, 2], p.cold_pressure, p.cold_temperature, p.atmosphere) - P)
                     / PRESSURE_SCALE)  # fmt: skip
        r.append((x - x0) / PRIOR_WIDTH * math.sqrt(ok.sum() / len(names)) * PRIOR_WEIGHT)
        return np.concatenate(r)

    x0 = np.log([max(getattr(start, n), 1e-6) for n in names])
    res = least_squares(residuals, x0, bounds=(x0 - BOUND, x0 + BOUND), x_scale=1.0, diff_step=1e-4, max_nfev=400)
    p, nodes = run(res.x)
    pred = pd.DataFrame({"ET": t, "T_measured": Tir, "T_surface": nodes[:, 0], "T_bulk": nodes[:, 1],
                         "T_gas": nodes[:, 2]})  # fmt: skip
    rms_p = math.nan
    if P is not None:
        Pm = hot_pressure(nodes[:, 2], p.cold_pressure, p.cold_temperature, p.atmosphere)
        pred["P_measured"], pred["P_model"] = P, Pm
        pred["T_gas_measured"] = gas_temperature(P, p.cold_pressure, p.cold_temperature, p.atmosphere)
        rms_p = float(np.sqrt(np.mean((Pm - P) ** 2)))
    rms_t = float(np.sqrt(np.mean((nodes[ok, 0] - Tir[ok]) ** 2)))
    return ThermalFit(p, _sigma(res, names), rms_t, rms_p, pred, bool(res.success), str(res.message))


def temperature_laws(tyre) -> list[int]:
    """Indices of the extension terms that read a temperature variable."""
    return [t.index for t in tyre.extension_set.terms if is_temperature_variable(t.variable)]


def with_default_laws(params, reference: float, scale: float = 50.0):
    """``params`` (TirParameters) with a quadratic grip law (LMUX LMUY) and a linear stiffness law
    (LKX LKY) in ``temperature`` appended to ``[MFTIRE_EXTENSIONS]`` (coefficients 0: neutral)."""
    p = params.copy()
    ext = dict(p.sections.get("MFTIRE_EXTENSIONS") or {})
    used = [int(m.group(1)) for k in ext if (m := re.match(r"^EXT(\d+)_", str(k)))]
    n = max(used, default=0) + 1
    ext.update({f"EXT{n}_TARGET": "LMUX LMUY", f"EXT{n}_FORM": "quadratic", f"EXT{n}_VARIABLE": "temperature",
                f"EXT{n}_REF": float(reference), f"EXT{n}_SCALE": scale, f"EXT{n}_C1": 0.0, f"EXT{n}_C2": 0.0,
                f"EXT{n + 1}_TARGET": "LKX LKY", f"EXT{n + 1}_FORM": "linear", f"EXT{n + 1}_VARIABLE": "temperature",
                f"EXT{n + 1}_REF": float(reference), f"EXT{n + 1}_SCALE": scale, f"EXT{n + 1}_C1": 0.0})  # fmt: skip
    p.sections["MFTIRE_EXTENSIONS"] = ext
    return p


def _force_rows(df: pd.DataFrame, most: int = 4000) -> np.ndarray:
    slip = (np.abs(df["alpha"].to_numpy(float)) > np.radians(0.5)) | (np.abs(df["kappa"].to_numpy(float)) > 0.01)
    rows = np.flatnonzero(slip & (df["Fz"].to_numpy(float) > 0))
    if rows.size > most:
        rows = rows[np.linspace(0, rows.size - 1, most).astype(int)]
    return rows


def fit_laws(tyre, df: pd.DataFrame, nodes_T: np.ndarray, P: np.ndarray, assignment: dict[int, str],
             rows: np.ndarray, score_rows: np.ndarray | None = None
             ) -> tuple[dict[str, float], dict[str, float], float]:
    """Fit the coefficients of the laws ``assignment`` (EXTn -> node) on ``rows``.

    Returns ``(coefficients, standard errors, RMS)``; the RMS is of Fx and Fy over FNOMIN on
    ``score_rows`` (default ``rows``).
    """
    from mftire.tyre import Tyre

    p = tyre.parameters.copy()
    ext = dict(p.sections["MFTIRE_EXTENSIONS"])
    for n, node in assignment.items():
        ext[f"EXT{n}_VARIABLE"] = NODE_VARIABLES[node]
    p.sections["MFTIRE_EXTENSIONS"] = ext
    model = Tyre(p, name=tyre.name)
    terms = {t.index: t for t in model.extension_set.terms}
    keys = [k for n in assignment for k in terms[n].coefficient_keys]
    fn = float(model.flat["FNOMIN"])
    cols = {c: df[c].to_numpy(float) for c in ("Fz", "kappa", "alpha", "gamma", "Vx", "Fx", "Fy")}
    nodes = {NODE_VARIABLES[k]: nodes_T[:, i] for i, k in enumerate(("surface", "bulk", "gas"))}
    others = {v: df[v].to_numpy(float) for v in model.required_variables if v not in nodes and v in df.columns}

    def evaluate(x, r):
        model.flat.update(dict(zip(keys, map(float, x), strict=True)))
        var = {v: a[r] for v, a in {**nodes, **others}.items() if v in model.required_variables}
        out = model.evaluate(cols["Fz"][r], cols["kappa"][r], cols["alpha"][r], cols["gamma"][r], Vx=cols["Vx"][r],
                             P=P[r], channels=("Fx", "Fy"), **var)  # fmt: skip
        return np.concatenate([(out["Fx"] - cols["Fx"][r]) / fn, (out["Fy"] - cols["Fy"][r]) / fn])

    x0 = np.array([model.flat.get(k, 0.0) for k in keys], float)
    res = least_squares(lambda x: evaluate(x, rows), x0, diff_step=1e-3, max_nfev=200)
    sr = rows if score_rows is None else score_rows
    rms = float(np.sqrt(np.mean(evaluate(res.x, sr) ** 2)))
    J = res.jac
    s2 = float(np.sum(res.fun ** 2)) / max(J.shape[0] - J.shape[1], 1)
    sd = np.sqrt(np.maximum(np.diag(np.linalg.pinv(J.T @ J) * s2), 0.0))
    return dict(zip(keys, map(float, res.x), strict=True)), dict(zip(keys, map(float, sd), strict=True)), rms


def fit_thermal(tyre, df: pd.DataFrame, *, fit_until: float | None = None, name: str = "data",
                nodes: Sequence[str] = LAW_NODES, folds: int = 3, sealed: bool = True) -> ThermalResult:
    """Fit the thermal model and its temperature laws on the rows with ``ET <= fit_until`` (all rows
    by default) of a continuous series; returns the ``.tir`` to write (module docstring).  ``sealed``
    False: a rig that regulates the pressure (:func:`fit_thermal_parameters`)."""
    from mftire.tyre import Tyre, as_tyre

    tyre = as_tyre(tyre)
    check_series(df, name, ("ET", "Fz", "kappa", "alpha", "gamma", "Vx", "Fx", "Fy", "AMBTMP"))
    df = df.reset_index(drop=True)
    if fit_until is not None:
        df = df[df["ET"].to_numpy(float) <= fit_until].reset_index(drop=True)
        if len(df) < 20:
            raise MftireInputError(f"{name}: only {len(df)} rows with ET <= {fit_until:g} s to fit on")
    t_end = float(df["ET"].iloc[-1])
    start = thermal_of(tyre)
    if start is None:  # the gas node's capacity from the tyre's size (not fitted: the pressure pins the gas node)
        f = tyre.flat
        start = ThermalParameters(cap_gas=gas_heat_capacity(f["UNLOADED_RADIUS"], f["RIM_RADIUS"], f["WIDTH"],
                                                            float(f["INFLPRES"])))
    fnomin = float(tyre.flat["FNOMIN"])
    th = fit_thermal_parameters(df, start, name=name, fnomin=fnomin, sealed=sealed)
    # node temperatures along every row (fit-part simulation driven by the measured forces)
    p = th.params
    qs = friction_power(df["Fx"], df["Fy"], df["kappa"], df["alpha"], df["Vx"])
    T0 = initial_temperatures(p, float(df["AMBTMP"].iloc[0]))
    nodes_T = simulate_nodes(p, df["ET"].to_numpy(float), qs,
                             bulk_power(p, df["Fz"], df["Vx"], df["Fx"], df["Fy"], fnomin),
                             df["Vx"].to_numpy(float), df["AMBTMP"].to_numpy(float), road_temperature(df, name), T0)
    P = hot_pressure(nodes_T[:, 2], p.cold_pressure, p.cold_temperature, p.atmosphere) if p.pressure \
        else np.full(len(df), p.cold_pressure)
    # the laws: the file's temperature laws, or the default grip and stiffness laws
    base = tyre
    if not temperature_laws(tyre):
        ref = float(np.round(np.nanmedian(measured_surface(df, name)), 0))
        base = Tyre(with_default_laws(tyre.parameters, ref), name=tyre.name)
    laws = temperature_laws(base)
    rows = _force_rows(df)
    if rows.size < 20:
        raise MftireInputError(f"{name}: fewer than 20 rows with slip to fit the temperature laws on")
    blocks = np.array_split(rows, folds)
    scores: dict[tuple[str, ...], float] = {}
    for combo in itertools.product(nodes, repeat=len(laws)):
        errs = []
        for k in range(folds):  # contiguous blocks in time: fit on the others, score on block k
            train = np.concatenate([b for j, b in enumerate(blocks) if j != k])
            _, _, e = fit_laws(base, df, nodes_T, P, dict(zip(laws, combo, strict=True)), train, blocks[k])
            errs.append(e * e * blocks[k].size)
        scores[combo] = float(np.sqrt(sum(errs) / rows.size))
    best = min(scores, key=scores.get)
    assignment = dict(zip(laws, best, strict=True))
    coeffs, sd, _ = fit_laws(base, df, nodes_T, P, assignment, rows)
    choices = []
    terms = {t.index: t for t in base.extension_set.terms}
    for i, n in enumerate(laws):
        tried = {node: min(v for c, v in scores.items() if c[i] == node) for node in nodes}
        choices.append(LawChoice(n, terms[n].describe(), assignment[n], tried))
    out = base.parameters.copy()
    ext = dict(out.sections["MFTIRE_EXTENSIONS"])
    ext.update(coeffs)
    out.sections["MFTIRE_EXTENSIONS"] = ext
    ref = terms[laws[0]].value("REF")
    final = p.replace(nodes=assignment, temperature=p.temperature if p.temperature is not None else ref)
    out.sections[SECTION] = final.section()
    # the fit-part force RMS of the chosen model
    model = Tyre(out, name=tyre.name)
    from mftire.thermal.simulation import node_tyre

    nt = node_tyre(model, final)
    var = {NODE_VARIABLES[k]: nodes_T[:, i] for i, k in enumerate(("surface", "bulk", "gas"))}
    var = {k: v for k, v in var.items() if k in nt.required_variables}
    f = nt.evaluate(df["Fz"].to_numpy(float), df["kappa"].to_numpy(float), df["alpha"].to_numpy(float),
                    df["gamma"].to_numpy(float), Vx=df["Vx"].to_numpy(float), P=P, channels=("Fx", "Fy"), **var)
    rms = {ch: float(np.sqrt(np.mean((f[ch][rows] - df[ch].to_numpy(float)[rows]) ** 2))) for ch in ("Fx", "Fy")}
    th.params = final
    return ThermalResult(out, th, choices, sd, rms, t_end)


__all__ = ["FITTED", "LAW_NODES", "LawChoice", "SURFACE_COLUMNS", "ThermalFit", "ThermalResult", "fit_laws",
           "fit_thermal", "fit_thermal_parameters", "is_temperature_variable", "measured_surface",
           "temperature_laws", "with_default_laws"]
