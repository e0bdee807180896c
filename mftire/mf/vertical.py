"""Vertical model: effective rolling radius, loaded radius, deflection, contact patch.

Besselink et al. (2010) eqs 1, 4, 5, 7, 9, 10 and the MF-Tyre/MF-Swift 6.2 equation
manual (loaded radius with camber and lateral-force terms); Pacejka 2012 eq A3.3.
"""

from __future__ import annotations

import numpy as np

from mftire.mf.family import is_mf52, is_pac2002
from mftire.mf.inputs import Conditions

_EPS = np.finfo(float).eps


def free_radius(p: dict, omega: np.ndarray) -> np.ndarray:
    """Free-spinning radius R_omega with centrifugal growth [m] (Besselink 2010 eq 1)."""
    R0 = p["UNLOADED_RADIUS"]
    return R0 * (p["Q_RE0"] + p["Q_V1"] * ((omega * R0) / p["LONGVL"]) ** 2)


def _re_from_omega(p: dict, Romega: np.ndarray, Fz: np.ndarray, Cz: np.ndarray) -> np.ndarray:
    """Effective rolling radius Re [m] (Besselink 2010 eq 7)."""
    Fz0 = p["FNOMIN"]
    return Romega - (Fz0 / Cz) * (p["DREFF"] * np.arctan(p["BREFF"] * (Fz / Fz0)) + p["FREFF"] * (Fz / Fz0))


def effective_rolling_radius(
    p: dict, c: Conditions, dpi: np.ndarray, omega: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Effective rolling radius, free radius and wheel spin.

    When ``omega`` [rad/s] is not given it is estimated from omega = (1 + kappa)·Vx/Re
    (Pacejka 2012 eq 2.5) by fixed-point iteration on Re, started at 0.965·R0 as the
    reference evaluator does (see the departure note in the code).  Uses the load,
    slip and speed as given.

    Returns ``(Re [m], Romega [m], omega [rad/s])``.
    """
    Cz = p["VERTICAL_STIFFNESS"] * (1.0 + p["PFZ1"] * dpi)  # Besselink 2010 eq 5
    Fz, Vx, kappa = c.uFz, c.Vx, c.ukappa
    if omega is not None:
        omega = omega + _EPS  # as the reference: avoids Romega = 0 exactly
        Romega = free_radius(p, omega)
        return _re_from_omega(p, Romega, Fz, Cz), Romega, omega
    R0 = p["UNLOADED_RADIUS"]
    Re = np.full(np.shape(Vx), R0 * 0.965)
    Re_old = np.full(np.shape(Vx), R0)
    omega = np.zeros(np.shape(Vx))
    Romega = np.full(np.shape(Vx), R0)
    # MFeval departure: the reference iterates while *every* point still changes by
    # more than 1e-9 m (a MATLAB ``while`` over a vector), so the iteration of a batch
    # stops as soon as one of its points has converged.  Reproduced for agreement;
    # the remaining error is below 2e-5 m for speeds up to 40 m/s.
    for _ in range(100):
        if Re.size == 0 or not np.all(np.abs(Re_old - Re) > 1e-9):
            break
        Re_old = Re
        omega = (kappa * Vx + Vx) / Re  # eq 2.5
        Romega = free_radius(p, omega)
        Re = _re_from_omega(p, Romega, Fz, Cz)
    return Re, Romega, omega


def _q_fz1(p: dict) -> float:
    """Linear load-deflection coefficient Q_FZ1 from VERTICAL_STIFFNESS (Besselink 2010 eq 4)."""
    return float(np.sqrt((p["VERTICAL_STIFFNESS"] * p["UNLOADED_RADIUS"] / p["FNOMIN"]) ** 2 - 4.0 * p["Q_FZ2"]))


def loaded_radius_61(
    p: dict, c: Conditions, dpi: np.ndarray, omega: np.ndarray, Romega: np.ndarray, Fx: np.ndarray, Fy: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """MF 6.1 deflection, loaded radius and vertical stiffness (Pacejka 2012 eq A3.3).

    Fz = (Q_FZ2·(rho/R0)² + Q_FZ1·(rho/R0))·(1 + Q_V2·R0/V0·|omega| − (Q_FCX·Fx/Fz0)²
    − (Q_FCY·Fy/Fz0)²)·(1 + PFZ1·dpi)·Fz0 solved for rho in closed form.

    Returns ``(rho [m], Rl [m], Cz [N/m])``.
    """
    Fz = c.Fz_low
    R0, Fz0, V0 = p["UNLOADED_RADIUS"], p["FNOMIN"], p["LONGVL"]
    speed = p["Q_V2"] * (R0 / V0) * np.abs(omega)
    ext = (1.0 + speed - (p["Q_FCX"] * Fx / Fz0) ** 2 - (p["Q_FCY"] * Fy / Fz0) ** 2) * (1.0 + p["PFZ1"] * dpi) * Fz0
    A, B, C = p["Q_FZ2"], _q_fz1(p), -(Fz / ext)
    x = (-B + np.sqrt(B**2 - 4.0 * A * C)) / (2.0 * A)
    rho = np.fmax(x * R0, 0.0)  # NaN (Q_FZ2 = 0) gives 0, as max() in the reference
    Rl = np.fmax(Romega - rho, 0.0)  # Pacejka 2012 eq A3.2
    rho = np.where(Fz == 0.0, 1e-6, rho)
    return rho, Rl, Fz / rho


def vertical_force_62(
    p: dict,
    gamma: np.ndarray,
    omega: np.ndarray,
    Romega: np.ndarray,
    dpi: np.ndarray,
    Rl: np.ndarray,
    Fx: np.ndarray,
    Fy: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """MF 6.2 vertical force for a given loaded radius (MF-Tyre/MF-Swift 6.2 manual).

    Returns ``(Fz [N], rho [m])``.
    """
    R0, Fz0, V0 = p["UNLOADED_RADIUS"], p["FNOMIN"], p["LONGVL"]
    ratio = Rl / Romega
    Sfyg = (p["Q_FYS1"] + p["Q_FYS2"] * ratio + p["Q_FYS3"] * ratio**2) * gamma
    rho_fr = np.fmax(Romega - Rl, 0.0)
    rtw = (1.075 - 0.5 * p["ASPECT_RATIO"]) * p["WIDTH"]  # reference tread width
    q1, q2 = p["Q_CAM1"], p["Q_CAM2"]
    with np.errstate(divide="ignore", invalid="ignore"):
        rho_g = ((q1 * Rl + q2 * Rl**2) * gamma) ** 2 * (rtw / 8.0) * np.abs(np.tan(gamma)) / (
            (q1 * Romega + q2 * Romega**2) * gamma
        ) ** 2 - p["Q_CAM3"] * rho_fr * np.abs(gamma)
    rho_g = np.where(np.isnan(rho_g), 0.0, rho_g)
    rho = np.fmax(rho_fr + rho_g, 0.0)
    fcorr = (
        1.0
        + p["Q_V2"] * (R0 / V0) * np.abs(omega)
        - (p["Q_FCX"] * Fx / Fz0) ** 2
        - ((rho / R0) ** p["Q_FCY2"] * (p["Q_FCY"] * (Fy - Sfyg) / Fz0)) ** 2
    ) * (1.0 + p["PFZ1"] * dpi)
    Fz = fcorr * (_q_fz1(p) * (rho / R0) + p["Q_FZ2"] * (rho / R0) ** 2) * Fz0
    return Fz, rho


def loaded_radius_62(
    p: dict,
    c: Conditions,
    dpi: np.ndarray,
    omega: np.ndarray,
    Romega: np.ndarray,
    Fx: np.ndarray,
    Fy: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """MF 6.2 loaded radius: the root of ``vertical_force_62(Rl) = Fz`` in [0, Romega].

    Solved by a bracketed Newton iteration (bisection whenever a Newton step leaves
    the bracket) to a force residual of 1e-9·Fz.  The reference evaluator minimises the squared error with
    Nelder–Mead from Rl = 0.3 m and sometimes stops on a wrong point; this root is the
    physical one.  Where no root lies in [0, Romega] (e.g. zero load with camber
    deflection), Rl = Romega.

    Returns ``(rho [m], Rl [m], Cz [N/m])``.
    """
    if is_pac2002(p):  # no MF 6.2 vertical terms in PAC2002 (pac2002._ABSENT): the 6.1 closed form
        return loaded_radius_61(p, c, dpi, omega, Romega, Fx, Fy)
    target = c.Fz
    g = c.gamma

    def f(Rl: np.ndarray) -> np.ndarray:
        return vertical_force_62(p, g, omega, Romega, dpi, Rl, Fx, Fy)[0] - target

    lo = np.zeros_like(Romega)
    hi = np.array(Romega, dtype=float)
    f_hi = f(hi)
    # Force at zero free deflection already >= target (camber deflection only).  NaN
    # (0·inf when Q_FCY2 < 0 and rho = 0) counts as below target.
    no_root = f_hi >= 0.0
    # start from the MF 6.1 closed form without camber and force terms
    rho0, _, _ = loaded_radius_61(p, c, dpi, omega, Romega, np.zeros_like(Fx), np.zeros_like(Fy))
    x = np.clip(Romega - rho0, 0.0, Romega)
    h = 1e-7
    tol_f = 1e-9 * np.maximum(target, 1.0)  # [N]
    for _ in range(60):
        fx = f(x)
        lo = np.where(fx > 0.0, x, lo)
        hi = np.where(fx > 0.0, hi, x)
        converged = np.abs(fx) <= tol_f
        if np.all(converged | no_root):
            break
        dfx = (f(x + h) - fx) / h
        with np.errstate(divide="ignore", invalid="ignore"):
            x_new = x - fx / dfx
        bad = (x_new < lo) | (x_new > hi) | ~np.isfinite(x_new)
        x_new = np.where(bad, 0.5 * (lo + hi), x_new)
        x = np.where(converged, x, x_new)
    Rl = np.where(no_root, Romega, x)
    _, rho = vertical_force_62(p, g, omega, Romega, dpi, Rl, Fx, Fy)
    rho = np.where(target == 0.0, 1e-6, rho)
    return rho, Rl, target / rho


def contact_patch(p: dict, c: Conditions, dpi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Contact-patch half length a and half width b [m] (Besselink 2010 eqs 9, 10).

    Uses the load as given; beyond rim bottoming the load is held at the bottoming
    load (empirical rule of the reference evaluator).
    """
    R0, w, Fz0 = p["UNLOADED_RADIUS"], p["WIDTH"], p["FNOMIN"]
    NCz = p["VERTICAL_STIFFNESS"] * (1.0 + p["PFZ1"] * dpi)  # Besselink 2010 eq 5
    Fz = c.uFz
    Rl_approx = R0 - Fz / NCz
    bottom = Rl_approx - (p["RIM_RADIUS"] + p["BOTTOM_OFFST"]) < 0.0
    Fz = np.where(bottom, (R0 - p["RIM_RADIUS"] - p["BOTTOM_OFFST"]) * NCz, Fz)
    if is_mf52(p):
        QA1, QA2 = p["Q_A1"], p["Q_A2"]
        if QA1 == 0 and QA2 == 0:
            # Defaults of the reference evaluator when the MF 5.2 file has none.
            y = np.log10(R0 * (p["VERTICAL_STIFFNESS"] / Fz0))
            QA1 = -0.0388 * y**3 + 0.2509 * y**2 + -0.6283 * y + 0.6279
            QA2 = 1.693 * QA1**2
        a = R0 * (QA2 * (Fz / Fz0) + QA1 * np.sqrt(Fz / Fz0))  # MF 5.2 manual
        b = np.full(np.shape(Fz), w / 2.0)
    else:
        f = Fz / (NCz * R0)
        a = R0 * (p["Q_RA2"] * f + p["Q_RA1"] * np.sqrt(f))  # Besselink 2010 eq 9
        b = w * (p["Q_RB2"] * f + p["Q_RB1"] * f ** (1.0 / 3.0))  # Besselink 2010 eq 10
    return a, b
