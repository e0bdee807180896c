"""The thermal tyre along a time series: node temperatures, hot pressure and forces.

:func:`simulate_nodes` integrates the node equations of :mod:`mftire.thermal.heat` for given heat
inputs (backward Euler per sample: stable for any sample interval).  :func:`replay` runs the whole
model along a measured series given only kinematics and conditions: the Magic Formula gives the
forces at the node temperatures and the hot pressure, the forces give the friction power, the power
the temperatures.  The coupling is resolved over the whole series by fixed-point (waveform)
iteration, so every sample satisfies the implicit step with its own end-of-step forces.

Series columns (SI, ISO W axes, temperatures °C, as ``mftire import`` writes them): ``ET`` [s],
``Fz``, ``kappa``, ``alpha``, ``gamma``, ``Vx``, ``AMBTMP`` (ambient) and the road temperature
``RST`` (TTC name; ``T_road`` also accepted; without it the road is at the ambient temperature, with
a warning).  The cold pressure is ``P_cold`` when the series has it, else ``TH_COLD_PRESSURE``, else
the first sample of the measured ``P`` (the tyre starts cold).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd

from mftire.errors import MftireInputError
from mftire.mf.thermal_section import NODE_VARIABLES, SECTION, ThermalParameters, check_nodes, parse_thermal
from mftire.thermal.heat import (
    air_conductance,
    friction_power,
    hot_pressure,
    hysteresis_loss,
    implicit_step,
    rolling_loss,
)

#: Road temperature column names, best first.
ROAD_COLUMNS = ("RST", "T_road")
#: Kinematic and condition columns a replay needs.
REPLAY_COLUMNS = ("ET", "Fz", "kappa", "alpha", "gamma", "Vx", "AMBTMP")
#: Force channels written next to the measured ones.
FORCE_CHANNELS = ("Fx", "Fy", "Mz", "Mx", "My")


def thermal_of(tyre) -> ThermalParameters | None:
    """The validated ``[MFTIRE_THERMAL]`` of a :class:`~mftire.tyre.Tyre` (None: isothermal)."""
    params = parse_thermal(tyre.parameters.sections.get(SECTION))
    if params is not None:
        check_nodes(params, [t.index for t in tyre.extension_set.terms])
    return params


def node_tyre(tyre, params: ThermalParameters | None):
    """``tyre`` with each temperature law of an ``EXTn_NODE`` reading its node's temperature
    (variable ``T_surface``, ``T_bulk`` or ``T_gas``)."""
    from mftire.tyre import Tyre

    if params is None or not params.nodes:
        return tyre
    p = tyre.parameters.copy()
    ext = dict(p.sections["MFTIRE_EXTENSIONS"])
    for n, node in params.nodes.items():
        ext[f"EXT{n}_VARIABLE"] = NODE_VARIABLES[node]
    p.sections["MFTIRE_EXTENSIONS"] = ext
    return Tyre(p, name=tyre.name)


def check_series(df: pd.DataFrame, name: str, columns=REPLAY_COLUMNS) -> None:
    """Clear errors for a series a replay or fit cannot take (missing column, NaN, time not increasing)."""
    missing = [c for c in columns if c not in df.columns]
    if missing:
        have = ", ".join(map(str, df.columns))
        raise MftireInputError(f"{name}: missing column(s) {', '.join(missing)} (have: {have})")
    for c in columns:
        x = pd.to_numeric(df[c], errors="coerce").to_numpy(float)
        bad = ~np.isfinite(x)
        if bad.any():
            row = int(np.flatnonzero(bad)[0]) + 1
            raise MftireInputError(f"{name}: column {c}, data row {row}: not a finite number")
    t = df["ET"].to_numpy(float)
    if t.size < 2:
        raise MftireInputError(f"{name}: a time series needs at least 2 rows, not {t.size}")
    back = np.flatnonzero(np.diff(t) <= 0.0)
    if back.size:
        raise MftireInputError(f"{name}: ET does not increase at data row {int(back[0]) + 2} ({t[back[0]]:g} -> "
                               f"{t[back[0] + 1]:g} s); a continuous series in time order is needed")  # fmt: skip


def road_temperature(df: pd.DataFrame, name: str = "data") -> np.ndarray:
    for c in ROAD_COLUMNS:
        if c in df.columns:
            return df[c].to_numpy(float)
    warnings.warn(f"{name}: no road temperature column (RST or T_road); the road is taken at the ambient temperature",
                  stacklevel=2)  # fmt: skip
    return df["AMBTMP"].to_numpy(float)


def cold_pressure(df: pd.DataFrame, params: ThermalParameters | None, flat: Mapping[str, float]) -> np.ndarray:
    """The cold (set) gauge pressure per row [Pa] (module docstring)."""
    n = len(df)
    if "P_cold" in df.columns:
        return df["P_cold"].to_numpy(float)
    if params is not None and params.cold_pressure is not None:
        return np.full(n, params.cold_pressure)
    if "P" in df.columns:
        return np.full(n, float(df["P"].iloc[0]))
    return np.full(n, float(flat["INFLPRES"]))


def initial_temperatures(params: ThermalParameters, T_amb0: float) -> tuple[float, float, float]:
    """Initial node temperatures [°C]: the section's, else the ambient temperature at the start."""
    return tuple(T_amb0 if v is None else v for v in (params.t_init_surface, params.t_init_bulk,
                                                     params.t_init_gas))  # type: ignore[return-value]


def bulk_power(params: ThermalParameters, Fz, Vx, Fx, Fy, fnomin: float) -> np.ndarray:
    """Heat into the bulk node [W]: rolling loss plus force hysteresis (:mod:`mftire.thermal.heat`)."""
    return rolling_loss(Fz, Vx, params.roll_loss) + hysteresis_loss(Fx, Fy, Fz, Vx, params.hysteresis, fnomin)


def simulate_nodes(params: ThermalParameters, t, q_s, q_b, Vx, T_amb, T_road,
                   T0: tuple[float, float, float]) -> np.ndarray:
    """Node temperatures [°C] along ``t`` [s] for the heat inputs ``q_s`` (surface, before
    ``TH_SLIP_SHARE``) and ``q_b`` (bulk) [W]; ``T0`` at ``t[0]``.  Returns an (n, 3) array
    (surface, bulk, gas)."""
    t = np.asarray(t, float)
    n = t.size
    qs = np.broadcast_to(params.slip_share * np.asarray(q_s, float), (n,)).tolist()
    qb = np.broadcast_to(np.asarray(q_b, float), (n,)).tolist()
    g_air = air_conductance(Vx, params.h_air0, params.h_air1)
    g_air = np.broadcast_to(g_air, (n,)).tolist()
    ta = np.broadcast_to(np.asarray(T_amb, float), (n,)).tolist()
    tr = np.broadcast_to(np.asarray(T_road, float), (n,)).tolist()
    dts = np.diff(t).tolist()
    caps, gsb, gbg, gba, grd = params.caps, params.g_surface_bulk, params.g_bulk_gas, params.g_bulk_ambient, \
        params.g_road
    out = np.empty((n, 3))
    T = (float(T0[0]), float(T0[1]), float(T0[2]))
    out[0] = T
    for i in range(1, n):
        T = implicit_step(T, dts[i - 1], qs[i], qb[i], g_air[i], ta[i], tr[i], caps, gsb, gbg, gba, grd)
        out[i] = T
    return out


@dataclass
class Replay:
    """The result of :func:`replay`: the output table and how the coupling converged."""

    table: pd.DataFrame
    iterations: int
    change: float  #: last iteration's largest change of a node temperature [°C]
    thermal: bool  #: False: the .tir has no thermal section (isothermal replay)


def _variables(tyre, df: pd.DataFrame, nodes: Mapping[str, np.ndarray] | None, name: str,
               temperature: float | None) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    for v in tyre.required_variables:
        if nodes is not None and v in nodes:
            out[v] = nodes[v]
        elif v in df.columns:
            out[v] = df[v].to_numpy(float)
        elif temperature is not None:
            out[v] = np.full(len(df), float(temperature))
        else:
            raise MftireInputError(f"{name}: the model needs the variable '{v}' (a column of the series, or a "
                                   f"[{SECTION}] TH_TEMPERATURE default)")  # fmt: skip
    return out


def replay(tyre, df: pd.DataFrame, *, name: str = "data", max_iterations: int = 30, tolerance: float = 1e-3,
           mode: int = 111) -> Replay:
    """Run the model along a series given only kinematics and conditions (module docstring).

    Returns a :class:`Replay` whose table holds ``ET``, the node temperatures ``T_surface``,
    ``T_bulk``, ``T_gas`` [°C] (thermal only), the model pressure ``P_model`` [Pa] and
    ``Fx_model``, ``Fy_model``, ``Mz_model``, ``Mx_model``, ``My_model`` [N, N.m], next to the
    measured columns of the series that have a model counterpart (``Fx``, ``Fy``, ``Mz``, ``P``,
    ``TSTI/TSTC/TSTO``).
    """
    from mftire.tyre import as_tyre

    tyre = as_tyre(tyre)
    check_series(df, name)
    params = thermal_of(tyre)
    model = node_tyre(tyre, params)
    n = len(df)
    t = df["ET"].to_numpy(float)
    Fz, kappa, alpha, gamma, Vx = (df[c].to_numpy(float) for c in ("Fz", "kappa", "alpha", "gamma", "Vx"))
    T_amb = df["AMBTMP"].to_numpy(float)
    p_cold = cold_pressure(df, params, tyre.flat)
    default_T = params.temperature if params is not None else None

    def forces(nodes, P):
        out = model.evaluate(Fz, kappa, alpha, gamma, Vx=Vx, P=P, mode=mode,
                             **_variables(model, df, nodes, name, default_T))  # fmt: skip
        return out

    if params is None:
        out = forces(None, p_cold)
        table = _table(df, out, None, p_cold)
        return Replay(table, 0, 0.0, False)
    T_road = road_temperature(df, name)
    T0 = initial_temperatures(params, float(T_amb[0]))
    nodes_T = np.tile(np.asarray(T0, float), (n, 1))
    change, it = math.inf, 0
    for it in range(1, max_iterations + 1):  # noqa: B007
        nodes = {NODE_VARIABLES[k]: nodes_T[:, i] for i, k in enumerate(("surface", "bulk", "gas"))}
        P = hot_pressure(nodes_T[:, 2], p_cold, params.cold_temperature, params.atmosphere) if params.pressure \
            else p_cold
        out = forces(nodes, P)
        q_s = friction_power(out["Fx"], out["Fy"], kappa, alpha, Vx)
        q_b = bulk_power(params, Fz, Vx, out["Fx"], out["Fy"], float(tyre.flat["FNOMIN"]))
        new = simulate_nodes(params, t, q_s, q_b, Vx, T_amb, T_road, T0)
        change = float(np.max(np.abs(new - nodes_T)))
        nodes_T = new
        if change < tolerance:
            break
    else:
        warnings.warn(f"{name}: the thermal coupling did not converge in {max_iterations} iterations (last change "
                      f"{change:.3g} °C)", stacklevel=2)  # fmt: skip
    nodes = {NODE_VARIABLES[k]: nodes_T[:, i] for i, k in enumerate(("surface", "bulk", "gas"))}
    P = hot_pressure(nodes_T[:, 2], p_cold, params.cold_temperature, params.atmosphere) if params.pressure else p_cold
    out = forces(nodes, P)
    return Replay(_table(df, out, nodes, P), it, change, True)


def _table(df: pd.DataFrame, out, nodes, P) -> pd.DataFrame:
    cols: dict[str, np.ndarray] = {"ET": df["ET"].to_numpy(float)}
    if nodes is not None:
        cols.update(nodes)
    for c in ("TSTI", "TSTC", "TSTO"):
        if c in df.columns:
            cols[c] = df[c].to_numpy(float)
    cols["P_model"] = np.broadcast_to(np.asarray(P, float), (len(df),))
    if "P" in df.columns:
        cols["P"] = df["P"].to_numpy(float)
    for ch in FORCE_CHANNELS:
        cols[f"{ch}_model"] = np.broadcast_to(np.asarray(out[ch], float), (len(df),))
        if ch in df.columns:
            cols[ch] = df[ch].to_numpy(float)
    return pd.DataFrame(cols, index=df.index)


__all__ = ["FORCE_CHANNELS", "REPLAY_COLUMNS", "ROAD_COLUMNS", "Replay", "bulk_power", "check_series", "cold_pressure",
           "initial_temperatures", "node_tyre", "replay", "road_temperature", "simulate_nodes", "thermal_of"]
