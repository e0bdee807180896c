"""Carcass: vertical deflection, radii, and the in-plane / lateral / yaw compliances.

The carcass is treated as a rigid ring on an elastic foundation (Pacejka 2012,
ch. 9 "SWIFT" rigid-ring idea, reduced to steady state): the tread base in the
contact zone translates by (u_c, v_c) = (Fx/Cx, Fy/Cy) and twists by
psi_c = Mz/Cpsi relative to the wheel plane.  The radii follow the MF 6.2 /
MF-Swift expressions (Pacejka 2012 section 4.3.5 and appendix 3), with an
additional saturating speed growth fitted to the thesis's Table 5.1.
All functions are vectorised over numpy arrays; SI units.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from mftire.fe.config import TyreConfig


def pressure_increment(tyre: TyreConfig, P: ArrayLike) -> np.ndarray:
    """Normalised inflation-pressure increment dpi = (P - P0)/P0 (MF 6.1 dpi, Pacejka 2012 section 4.3)."""
    p0 = tyre.size.nominal_pressure
    return (np.asarray(P, dtype=float) - p0) / p0


def free_radius(tyre: TyreConfig, Vx: ArrayLike) -> np.ndarray:
    """Free radius of the rolling tyre R_Omega [m].

    Centrifugal growth R0 (1 + qv1 (V/v0)^2) (the MF 6.2 free radius R_Omega, Pacejka 2012 section 4.3) plus
    a saturating belt growth dr_v (1 - exp(-V/v_r)), fitted to thesis Table 5.1 (experiment).
    """
    v = tyre.vertical
    Vx = np.abs(np.asarray(Vx, dtype=float))
    return tyre.unloaded_radius * (1.0 + v.qv1 * (Vx / v.v0) ** 2) + v.dr_v * (1.0 - np.exp(-Vx / v.v_r))


def vertical_stiffness(tyre: TyreConfig, Vx: ArrayLike, P: ArrayLike) -> np.ndarray:
    """Vertical stiffness Cz [N/m]: Cz0 (1 + pfz1 dpi)(1 + qv2 |V|/v0).

    MF 6.2 vertical stiffness, Pacejka 2012 section 4.3.
    """
    v = tyre.vertical
    Vx = np.abs(np.asarray(Vx, dtype=float))
    return v.cz0 * (1.0 + v.pfz1 * pressure_increment(tyre, P)) * (1.0 + v.qv2 * Vx / v.v0)


def vertical_deflection(tyre: TyreConfig, Fz: ArrayLike, Vx: ArrayLike, P: ArrayLike) -> np.ndarray:
    """Radial deflection rho = Fz / Cz [m] (linear carcass spring)."""
    return np.asarray(Fz, dtype=float) / vertical_stiffness(tyre, Vx, P)


def loaded_radius(
    tyre: TyreConfig, Fz: ArrayLike, Vx: ArrayLike, P: ArrayLike, Fy: ArrayLike = 0.0
) -> np.ndarray:
    """Loaded radius rl = R_Omega - rho [m]; lateral force softens Cz by (1 - q_fcy (Fy/Fz_LI)^2).

    The Fy term is the MF 6.2 vertical-stiffness reduction by lateral force (q_Fcy, Pacejka 2012 section 4.3),
    which gives the bell-shaped rl(alpha) of thesis Fig. 6.7.
    """
    fy_n = np.asarray(Fy, dtype=float) / tyre.load_index_load
    soft = np.clip(1.0 - tyre.vertical.q_fcy * fy_n**2, 0.3, 1.0)
    return free_radius(tyre, Vx) - vertical_deflection(tyre, Fz, Vx, P) / soft


def belt_rolling_radius(tyre: TyreConfig, Fz: ArrayLike, Vx: ArrayLike, P: ArrayLike) -> np.ndarray:
    """Kinematic rolling radius of the tread base (belt) r_b [m].

    MF-Swift effective rolling radius (Pacejka 2012 section 4.3, the 'Reff' relation with BREFF, DREFF, FREFF):
    r_b = R_Omega - rho_Fz0 (D arctan(B rho_d) + F rho_d), rho_d = rho / rho_Fz0,
    rho_Fz0 = Fz_LI / Cz0.  The belt speed in the contact zone is omega * r_b.
    """
    v = tyre.vertical
    rho = vertical_deflection(tyre, Fz, Vx, P)
    rho_fz0 = tyre.load_index_load / v.cz0
    rho_d = rho / rho_fz0
    return free_radius(tyre, Vx) - rho_fz0 * (v.d_re * np.arctan(v.b_re * rho_d) + v.f_re * rho_d)


def compliances(tyre: TyreConfig, Fz: ArrayLike, P: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Carcass stiffnesses (Cx [N/m], Cy [N/m], Cpsi [N·m/rad]) at load Fz and pressure P.

    Lateral and yaw stiffness grow with inflation pressure; the yaw stiffness also
    grows with load (longer contact base), cf. Pacejka 2012 section 9.2.
    """
    c = tyre.carcass
    Fz = np.asarray(Fz, dtype=float)
    pf = np.clip(1.0 + c.pressure_sensitivity * pressure_increment(tyre, P), 0.2, None)
    fz_n = Fz / tyre.load_index_load
    cx = np.full_like(Fz, c.cx) * np.clip(1.0 + 0.5 * c.pressure_sensitivity * pressure_increment(tyre, P), 0.2, None)
    cy = c.cy * pf
    cpsi = c.cpsi * pf * (1.0 + c.cpsi_load * (fz_n - 1.0)).clip(0.2)
    return cx, cy, cpsi


def rolling_resistance_coefficient(
    tyre: TyreConfig, rho: ArrayLike, a: ArrayLike, Vx: ArrayLike
) -> np.ndarray:
    """Rolling-resistance coefficient f_r = eta_h(V) rho / (4 a) [-].

    The deflection energy Fz rho / 2 is renewed every contact length 2a of travel and
    a fraction eta_h of it is lost in hysteresis; eta_h grows with speed like the
    MF qsy3 / qsy4 rolling-resistance terms (Pacejka 2012 section 4.3).
    """
    rr = tyre.rolling_resistance
    vn = np.abs(np.asarray(Vx, dtype=float)) / tyre.vertical.v0
    eta = rr.hysteresis_loss * (1.0 + rr.speed_linear * vn + rr.speed_quartic * vn**4)
    return eta * np.asarray(rho, dtype=float) / (4.0 * np.asarray(a, dtype=float))
