"""Heat sources, heat paths and the gas law of the three-node thermal tyre: small pure functions.

Temperatures are in °C throughout the thermal package (the rig's unit; a difference of 1 °C is
1 K, and the gas law converts to kelvin itself).  Everything else is SI: W, W/K, J/K, Pa, m/s.

The nodes (Harsh & Shyrokau, *Appl. Sci.* 9(24) 5328, 2019, §2: a tread surface, a tread
bulk/carcass and an inflation-gas node feeding MF scaling factors) exchange heat by lumped
conduction ``Q = G·ΔT`` (Fourier's law over a thermal resistance ``1/G = L/(k·A)``:
Incropera & DeWitt, *Fundamentals of Heat and Mass Transfer*, 6th ed., eqs 3.6 and 3.19),
and each node stores heat ``C·dT/dt`` (lumped capacitance, Incropera & DeWitt §5.1):

    C_s dT_s/dt = q_s − G_sb (T_s − T_b) − G_air(V) (T_s − T_amb) − G_road (T_s − T_road)
    C_b dT_b/dt = q_b + G_sb (T_s − T_b) − G_bg (T_b − T_g) − G_ba (T_b − T_amb)
    C_g dT_g/dt =       G_bg (T_b − T_g)

with ``q_s`` the sliding friction power (:func:`friction_power`) and ``q_b`` the rolling loss
(:func:`rolling_loss` and :func:`hysteresis_loss`).  :func:`implicit_step` advances it by one
backward-Euler step (L-stable: any step size is safe, and the steady state is exact); :func:`steady_state` solves it for
constant inputs.
"""

from __future__ import annotations

import math

import numpy as np

#: 0 °C in kelvin.
KELVIN = 273.15
#: Standard atmosphere [Pa]; rig pressures are gauge pressures, the gas law needs absolute ones.
ATMOSPHERE = 101325.0


def slip_velocities(kappa, alpha, Vx) -> tuple[np.ndarray, np.ndarray]:
    """Longitudinal and lateral slip velocities of the contact point [m/s].

    ``Vsx = −κ·Vx`` and ``Vsy = Vx·tan α`` (Pacejka 2012, eqs 2.10–2.12 and 4.E5, with
    ``κ = −Vsx/Vx``, ``tan α = Vsy/Vx`` in the ISO/TYDEX W-axis system).  ``kappa`` [-],
    ``alpha`` [rad], ``Vx`` [m/s].
    """
    Vx = np.asarray(Vx, dtype=float)
    return -np.asarray(kappa, dtype=float) * Vx, Vx * np.tan(np.asarray(alpha, dtype=float))


def friction_power(Fx, Fy, kappa, alpha, Vx) -> np.ndarray:
    """Sliding friction power dissipated in the contact patch [W].

    ``P = |Fx·Vsx| + |Fy·Vsy|`` (Harsh & Shyrokau 2019, eq 3: friction power from the forces and
    slip velocities; each product's magnitude, so that a sign convention of the data cannot turn
    dissipation into a heat sink).  Forces [N], ``kappa`` [-], ``alpha`` [rad], ``Vx`` [m/s].
    """
    vsx, vsy = slip_velocities(kappa, alpha, Vx)
    return np.abs(np.asarray(Fx, dtype=float) * vsx) + np.abs(np.asarray(Fy, dtype=float) * vsy)


def rolling_loss(Fz, Vx, coefficient: float) -> np.ndarray:
    """Rolling (hysteresis) loss heating the bulk [W].

    ``P = c·Fz·|Vx|``: the power of a rolling resistance moment ``My = c·Fz·R0`` at wheel speed
    ``Vx/R0`` (Pacejka 2012, eq 4.E70, its load term ``QSY1``), ``c`` [-] the rolling-loss
    coefficient, ``Fz`` [N] (negative loads give 0), ``Vx`` [m/s].
    """
    return coefficient * np.maximum(np.asarray(Fz, dtype=float), 0.0) * np.abs(np.asarray(Vx, dtype=float))


def hysteresis_loss(Fx, Fy, Fz, Vx, coefficient: float, load: float) -> np.ndarray:
    """Force-dependent hysteresis loss heating the bulk [W].

    ``P = c·|Vx|·(Fx² + Fy²)/max(Fz, 0.1·Fz0)``: the deformation energy of the carcass grows with the
    square of the transmitted force over its stiffness (a spring's ``F²/(2k)``), the stiffness grows
    about in proportion to the load (Pacejka 2012 §4.3.2: cornering stiffness ∝ Fz at moderate loads),
    and a fixed share of it is lost per revolution by hysteresis (Harsh & Shyrokau 2019, §2.2, the
    deformation loss of the bulk node).  ``c`` [-], forces [N], ``Vx`` [m/s], ``Fz`` [N], ``load``
    the nominal load ``Fz0`` [N] (the floor keeps a light load finite).
    """
    F2 = np.asarray(Fx, dtype=float) ** 2 + np.asarray(Fy, dtype=float) ** 2
    return coefficient * np.abs(np.asarray(Vx, dtype=float)) * F2 / np.maximum(np.asarray(Fz, dtype=float),
                                                                              0.1 * load)


def air_conductance(Vx, h0: float, h1: float) -> np.ndarray:
    """Convective conductance of the tread surface to the ambient air [W/K].

    ``G = h0 + h1·|Vx|^0.8``: natural convection plus forced convection of a turbulent boundary
    layer, whose Nusselt number grows as ``Re^0.8`` (Incropera & DeWitt, eq 7.38,
    ``Nu = 0.037·Re^(4/5)·Pr^(1/3)``), times the surface area.  ``h0`` [W/K], ``h1``
    [W/K/(m/s)^0.8], ``Vx`` [m/s].
    """
    return h0 + h1 * np.abs(np.asarray(Vx, dtype=float)) ** 0.8


def hot_pressure(T_gas, cold_pressure: float, cold_temperature: float, atmosphere: float = ATMOSPHERE):
    """Gauge inflation pressure of the hot gas [Pa].

    A fixed mass of ideal gas in a fixed volume (Gay-Lussac, ``p/T`` constant; Harsh & Shyrokau 2019,
    eq 9) on absolute pressures: ``p = (p_cold + p_atm)·(T_g + 273.15)/(T_cold + 273.15) − p_atm``.
    ``T_gas``, ``cold_temperature`` [°C]; ``cold_pressure`` the gauge pressure set at
    ``cold_temperature`` [Pa]; ``atmosphere`` [Pa].
    """
    return (cold_pressure + atmosphere) * (np.asarray(T_gas, dtype=float) + KELVIN) / (cold_temperature + KELVIN) \
        - atmosphere


def gas_temperature(pressure, cold_pressure: float, cold_temperature: float, atmosphere: float = ATMOSPHERE):
    """The inverse of :func:`hot_pressure`: gas temperature [°C] from a gauge pressure [Pa]."""
    return (np.asarray(pressure, dtype=float) + atmosphere) / (cold_pressure + atmosphere) \
        * (cold_temperature + KELVIN) - KELVIN


def gas_heat_capacity(unloaded_radius: float, rim_radius: float, width: float, pressure: float,
                      temperature: float = 20.0, atmosphere: float = ATMOSPHERE) -> float:
    """Heat capacity of the inflation gas at constant volume [J/K].

    ``C = m·c_v`` with the mass of air ``m = p_abs·V/(R·T)`` (ideal gas, R = 287.05 J/(kg·K),
    c_v = 718 J/(kg·K): Incropera & DeWitt Table A.4) in the torus volume
    ``V ≈ π·(R0² − R_rim²)·w`` (radii and width [m]).  ``pressure`` gauge [Pa], ``temperature`` [°C].
    """
    volume = math.pi * max(unloaded_radius ** 2 - rim_radius ** 2, 0.0) * width
    mass = (pressure + atmosphere) * volume / (287.05 * (temperature + KELVIN))
    return mass * 718.0


def implicit_step(T: tuple[float, float, float], dt: float, q_s: float, q_b: float, g_air: float, T_amb: float,
                  T_road: float, caps: tuple[float, float, float], g_sb: float, g_bg: float, g_ba: float,
                  g_road: float) -> tuple[float, float, float]:
    """One backward-Euler step of the node equations (module docstring) [°C].

    ``(C/dt + K)·T⁺ = C/dt·T + q + sinks``, inputs held at their end-of-step values; the matrix is
    tridiagonal and diagonally dominant, so the step is stable and positive for any ``dt`` [s] and
    reaches :func:`steady_state` exactly for constant inputs.  ``caps`` = (C_s, C_b, C_g) [J/K],
    powers [W], conductances [W/K], temperatures [°C].

    The elimination (Thomas algorithm) carries each row's excess of the diagonal over its off-diagonal
    conductances, a sum of positive terms, instead of forming the pivot as a difference (the GTH variant of
    Grassmann, Taksar & Heyman 1985): with a capacity tiny against a conductance (a long step) the pivot
    would otherwise cancel, and a node could leave the range of its neighbours by round-off.
    """
    cs, cb, cg = caps[0] / dt, caps[1] / dt, caps[2] / dt
    s1 = cs + g_air + g_road  # row excess of the surface node
    d1 = s1 + g_sb
    r1 = cs * T[0] + q_s + g_air * T_amb + g_road * T_road
    s2 = cb + g_ba + g_sb * s1 / d1  # bulk node, the surface eliminated
    d2 = s2 + g_bg
    r2 = cb * T[1] + q_b + g_ba * T_amb + g_sb / d1 * r1
    s3 = cg + g_bg * s2 / d2  # gas node, the bulk eliminated: its whole pivot
    r3 = cg * T[2] + g_bg / d2 * r2
    x3 = r3 / s3
    x2 = (r2 + g_bg * x3) / d2
    x1 = (r1 + g_sb * x2) / d1
    return x1, x2, x3


def node_rates(T: tuple[float, float, float], q_s, q_b, g_air, T_amb, T_road, caps: tuple[float, float, float],
               g_sb: float, g_bg: float, g_ba: float, g_road: float) -> tuple:
    """Time derivatives of the node temperatures [K/s]: the node equations of the module docstring.

    ``C_s dT_s/dt = q_s − G_sb (T_s − T_b) − G_air (T_s − T_amb) − G_road (T_s − T_road)``,
    ``C_b dT_b/dt = q_b + G_sb (T_s − T_b) − G_bg (T_b − T_g) − G_ba (T_b − T_amb)``,
    ``C_g dT_g/dt = G_bg (T_b − T_g)`` (lumped capacitance, Incropera & DeWitt §5.1; conduction
    ``Q = G·ΔT``, eqs 3.6 and 3.19).  The rates of the transient block's Model Exchange states
    (:mod:`mftire.transient`); :func:`implicit_step` is their backward-Euler step.  ``T`` (T_s, T_b, T_g)
    [°C], powers [W], conductances [W/K], ``caps`` [J/K].
    """
    Ts, Tb, Tg = T
    q_sb, q_bg = g_sb * (Ts - Tb), g_bg * (Tb - Tg)
    dTs = (q_s - q_sb - g_air * (Ts - T_amb) - g_road * (Ts - T_road)) / caps[0]
    dTb = (q_b + q_sb - q_bg - g_ba * (Tb - T_amb)) / caps[1]
    return dTs, dTb, q_bg / caps[2]


def steady_state(q_s: float, q_b: float, g_air: float, T_amb: float, T_road: float, g_sb: float, g_bg: float,
                 g_ba: float, g_road: float) -> tuple[float, float, float]:
    """Node temperatures [°C] for constant inputs (the node equations with ``dT/dt = 0``).

    The gas carries no heat out in steady state, so ``T_g = T_b``; the surface and bulk solve the
    two-node balance (Incropera & DeWitt §3.1, thermal circuit).  Powers [W], conductances [W/K].
    """
    # surface: q_s = (g_sb + g_air + g_road) Ts - g_sb Tb - g_air Tamb - g_road Troad
    # bulk:    q_b = -g_sb Ts + (g_sb + g_ba) Tb - g_ba Tamb
    a11, a12, a21, a22 = g_sb + g_air + g_road, -g_sb, -g_sb, g_sb + g_ba
    r1 = q_s + g_air * T_amb + g_road * T_road
    r2 = q_b + g_ba * T_amb
    det = a11 * a22 - a12 * a21
    Ts = (r1 * a22 - a12 * r2) / det
    Tb = (a11 * r2 - a21 * r1) / det
    return Ts, Tb, Tb


__all__ = ["ATMOSPHERE", "KELVIN", "air_conductance", "friction_power", "gas_heat_capacity", "gas_temperature",
           "hot_pressure", "hysteresis_loss", "implicit_step", "node_rates", "rolling_loss", "slip_velocities",
           "steady_state"]
