"""Aligning moment: pneumatic trail, residual torque, Mz0 and Mz (Pacejka 2012 §4.3.2).

Where the reference evaluator uses Besselink et al. (2010) Appendix equations (A54–A60)
instead of the book, so do we; each such place is marked.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from mftire.mf import turnslip
from mftire.mf.basic import Basic
from mftire.mf.family import is_mf52, is_pac2002
from mftire.mf.inputs import EPSILON, Conditions
from mftire.mf.lateral import PureLateral, fy0
from mftire.mf.longitudinal import _clip_curvature, _sign_nonzero
from mftire.mf.modes import Mode


@dataclass
class AligningTerms:
    """Magic Formula factors of the trail (t) and residual torque (r)."""

    alphar: np.ndarray  #: eq 4.E37 [rad]
    alphat: np.ndarray  #: eq 4.E34 [rad]
    Dr: np.ndarray  #: eq 4.E47 [N·m]
    Cr: np.ndarray | float  #: eq 4.E46 [-] (complex in rare turn-slip cases, as in the reference)
    Br: np.ndarray  #: eq 4.E45 [-]
    Dt: np.ndarray  #: A60 [m]
    Ct: float  #: eq 4.E41 [-]
    Bt: np.ndarray  #: A58 [-]
    Et: np.ndarray  #: eq 4.E44 [-]
    Kya_prime: np.ndarray  #: eq 4.E39 [N/rad]


def _trail_mf(Dt, Ct, Bt, Et, alpha, alpha_prime) -> np.ndarray:
    """Pneumatic trail t(alpha) = Dt·cos(Ct·atan(Bt·a − Et·(Bt·a − atan(Bt·a))))·cos(alpha') [m]."""
    Ba = Bt * alpha
    return Dt * np.cos(Ct * np.arctan(Ba - Et * (Ba - np.arctan(Ba)))) * np.cos(alpha_prime)  # eq 4.E33/4.E73


def aligning_terms(
    p: dict,
    mode: Mode,
    c: Conditions,
    b: Basic,
    lat: PureLateral,
    Gyk: np.ndarray | None = None,
) -> AligningTerms:
    """Trail and residual-torque factors (eqs 4.E33–4.E47; Besselink 2010 A58, A60).

    ``lat`` is the pure lateral force at the actual inclination.  ``Gyk`` (combined
    lateral weighting) is needed only with turn slip.
    """
    R0 = p["UNLOADED_RADIUS"]
    dfz, dpi, gamma, gamma_star, alpha_star = b.dfz, b.dpi, c.gamma, b.gamma_star, b.alpha_star
    if mode.limits:
        Fz = np.where(c.Fz <= 0.0, 0.0, c.Fz_low)
    else:
        Fz = c.Fz

    SHt = p["QHZ1"] + p["QHZ2"] * dfz + (p["QHZ3"] + p["QHZ4"] * dfz) * gamma_star  # eq 4.E35
    Kya_prime = lat.Kya + EPSILON * _sign_nonzero(lat.Kya)  # eq 4.E39
    SHf = lat.SHy + lat.SVy / Kya_prime  # eq 4.E38
    alphar = alpha_star + SHf  # eq 4.E37
    alphat = alpha_star + SHt  # eq 4.E34

    if mode.turn_slip:
        z5 = turnslip.zeta5(p, c.phi)
        z6 = turnslip.zeta6(p, c.phi)
    else:
        z5 = z6 = 1.0

    # MFeval departure: Besselink 2010 eq A60 instead of book eqs 4.E42/4.E43 (QDZ3
    # multiplies gamma, not |gamma*|), which matches TNO for negative camber.
    Dt = (
        (p["QDZ1"] + p["QDZ2"] * dfz)
        * (1.0 - p["PPZ1"] * dpi)
        * (1.0 + p["QDZ3"] * gamma + p["QDZ4"] * gamma**2)
        * Fz
        * (R0 / b.Fz0p)
        * p["LTR"]
        * z5
    )  # A60
    # MFeval departure: Besselink 2010 eq A58 instead of book eq 4.E40 (no QBZ6).
    Bt = (
        (p["QBZ1"] + p["QBZ2"] * dfz + p["QBZ3"] * dfz**2)
        * (1.0 + p["QBZ4"] * gamma + p["QBZ5"] * np.abs(gamma))
        * p["LKY"]
        / b.LMUY_star
    )  # A58
    Ct = p["QCZ1"]  # eq 4.E41
    Et = (p["QEZ1"] + p["QEZ2"] * dfz + p["QEZ3"] * dfz**2) * (
        1.0 + (p["QEZ4"] + p["QEZ5"] * gamma_star) * (2.0 / np.pi) * np.arctan(Bt * Ct * alphat)
    )
    Et = _clip_curvature(Et, "ET", mode)  # eq 4.E44

    if mode.turn_slip:
        zeta0 = 0.0
        zeta2 = lat.zeta2
        Fz0p = b.Fz0p
        # Spin moment at 90° slip and its peak (eqs 4.94–4.103, TNO manual).
        Mzp_inf = p["QCRP1"] * np.abs(lat.muy) * R0 * Fz * np.sqrt(Fz / Fz0p) * p["LMP"]  # eq 4.95
        Mzp_inf = np.where(Mzp_inf < 0.0, 1e-6, Mzp_inf)
        CDrp = p["QDRP1"]  # eq 4.96
        DDrp = Mzp_inf / np.sin(0.5 * np.pi * CDrp)  # eq 4.94
        # MFeval departure: QDZ8·QDZ9·dfz (product) as written in the reference evaluator.
        Kzgr0 = Fz * R0 * (p["QDZ8"] * p["QDZ9"] * dfz + (p["QDZ10"] + p["QDZ11"] * dfz * np.abs(gamma))) * p["LKZC"]
        BDrp = Kzgr0 / (CDrp * DDrp * (1.0 - c.eps_gamma))  # TNO manual
        Drp = DDrp * np.sin(CDrp * np.arctan(BDrp * R0 * c.phit))  # TNO manual (uses phit)
        Mzp90 = Mzp_inf * (2.0 / np.pi) * np.arctan(p["QCRP2"] * R0 * np.abs(c.phit)) * Gyk  # eq 4.103
        # acos of a ratio above one is complex in the reference; keep its real outcome.
        # MFeval departure: with Drp = 0 (no camber torque stiffness, e.g. QDZ8..QDZ11 = 0 at
        # zero camber) the ratio is infinite and the reference returns Inf or NaN; we take
        # the limit of the real part of the acos, 0, so that Mzr = Dr.
        ratio = np.where(Drp == 0.0, 1.0, Mzp90 / np.where(Drp == 0.0, 1.0, np.abs(Drp)))
        zeta7 = (2.0 / np.pi) * np.arccos(np.asarray(ratio).astype(complex))  # TNO manual
        zeta8 = 1.0 + Drp
    else:
        zeta0, zeta2, zeta7, zeta8 = 1.0, 1.0, 1.0, 1.0

    Dr = (
        Fz
        * R0
        * (
            (p["QDZ6"] + p["QDZ7"] * dfz) * p["LRES"] * zeta2
            + (
                (p["QDZ8"] + p["QDZ9"] * dfz) * (1.0 + p["PPZ2"] * dpi)
                + (p["QDZ10"] + p["QDZ11"] * dfz) * np.abs(gamma_star)
            )
            * gamma_star
            * p["LKZC"]
            * zeta0
        )
        * b.LMUY_star
        * np.sign(c.Vx)
        * np.cos(alpha_star)
        + zeta8
        - 1.0
    )  # eq 4.E47
    Br = (p["QBZ9"] * p["LKY"] / b.LMUY_star + p["QBZ10"] * lat.By * lat.Cy) * z6  # eq 4.E45
    Cr = zeta7  # eq 4.E46
    return AligningTerms(alphar, alphat, Dr, Cr, Br, Dt, Ct, Bt, Et, Kya_prime)


def mz0(p: dict, mode: Mode, c: Conditions, b: Basic, a: AligningTerms) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pure-slip aligning moment (eqs 4.E31–4.E36).

    Returns ``(Mz0 [N·m], t0 [m], Mzr0 [N·m])``; the trail and residual torque carry
    the low-speed reduction like the combined-slip ones.
    """
    no_ts = dataclasses.replace(mode, turn_slip=False)
    lat0 = fy0(p, no_ts, c, b, np.zeros_like(c.Fz), turn_slip=False)  # Fy0 at gamma = phi = 0
    t0 = _trail_mf(a.Dt, a.Ct, a.Bt, a.Et, a.alphat, b.alpha_prime) * c.smooth  # eq 4.E33
    Mzr0 = np.real(a.Dr * np.cos(a.Cr * np.arctan(a.Br * a.alphar)) * np.cos(b.alpha_prime)) * c.smooth  # 4.E36
    return -t0 * lat0.Fy0 + Mzr0, t0, Mzr0  # eqs 4.E32, 4.E31


def zero_camber_lateral(p: dict, mode: Mode, c: Conditions, b: Basic, lat: PureLateral | None) -> PureLateral:
    """Pure lateral force at zero camber (and zero spin weighting) for the trail term of
    eq 4.E74; ``lat`` (at the actual inclination) itself when every inclination is zero.

    It depends on the lateral-force coefficients only: a fitter of aligning coefficients
    computes it once (:attr:`mftire.mf.solver.Channels.lat0`).
    """
    if lat is not None and not np.any(b.gamma_star):
        return lat
    return fy0(p, mode, c, b, np.zeros_like(c.Fz), turn_slip=mode.turn_slip)


def mz_combined(
    p: dict,
    mode: Mode,
    c: Conditions,
    b: Basic,
    a: AligningTerms,
    Kxk: np.ndarray,
    Fx: np.ndarray,
    Fy: np.ndarray,
    Gyk: np.ndarray,
    lat: PureLateral | None = None,
    lat0: PureLateral | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Combined-slip aligning moment (eqs 4.E71–4.E78; Besselink 2010 A54–A56).

    ``lat``, the pure lateral force at the actual inclination, is reused for the
    zero-camber force when every inclination is zero.  ``lat0``, the zero-camber force
    (:func:`zero_camber_lateral`), is computed when not given.

    Returns ``(Mz [N·m], t [m], Mzr [N·m])``.
    """
    R0 = p["UNLOADED_RADIUS"]
    ratio2 = (Kxk / a.Kya_prime) ** 2 * c.kappa**2
    # MFeval departure: Besselink 2010 A54/A55 (tan inside) instead of book 4.E77/4.E78.
    alphar_eq = np.arctan(np.sqrt(np.tan(a.alphar) ** 2 + ratio2)) * np.sign(a.alphar)  # A54
    alphat_eq = np.arctan(np.sqrt(np.tan(a.alphat) ** 2 + ratio2)) * np.sign(a.alphat)  # A55
    # MFeval departure: A56 uses FNOMIN where book eq 4.E76 has Fz0'; PAC2002 follows the book (eq 4.E76, as
    # Chrono's ChPac02Tire: they differ when LFZO != 1, docs/pac2002.md).
    Fz0s = b.Fz0p if is_pac2002(p) else p["FNOMIN"]
    s = R0 * (p["SSZ1"] + p["SSZ2"] * (Fy / Fz0s) + (p["SSZ3"] + p["SSZ4"] * b.dfz) * c.gamma) * p["LS"]  # A56, 4.E76
    Mzr = a.Dr * np.cos(a.Cr * np.arctan(a.Br * alphar_eq))  # eq 4.E75

    if lat0 is None:
        lat0 = zero_camber_lateral(p, mode, c, b, lat)
    Fy_prime = Gyk * lat0.Fy0  # eq 4.E74; Gyk does not depend on muy or zeta2
    # MFeval departure: t is multiplied by LFZO, as TNO's solver does (not in PAC2002).
    lfzo = 1.0 if is_pac2002(p) else p["LFZO"]
    t = _trail_mf(a.Dt, a.Ct, a.Bt, a.Et, alphat_eq, b.alpha_prime) * lfzo  # eq 4.E73
    t = t * c.smooth
    Mzr = np.real(Mzr) * c.smooth
    if is_pac2002(p) and lat is not None:
        # PAC2002 (Pacejka 2006 eqs 4.E71, 4.E74): F'y = Fy - SVyk = Gyk*Fy0, Fy0 with camber.
        Mz = -t * (Gyk * lat.Fy0) + Mzr + s * Fx
    elif is_mf52(p):
        # MF 5.2 (TNO equation manual): kappa-induced side force excluded from the trail term.
        dfz, gamma_star = b.dfz, b.gamma_star
        DVyk = (
            lat0.muy
            * c.Fz
            * (p["RVY1"] + p["RVY2"] * dfz + p["RVY3"] * gamma_star)
            * np.cos(np.arctan(p["RVY4"] * b.alpha_star))
        )  # eq 4.E67 at zeta2 = 1
        SVyk = DVyk * np.sin(p["RVY5"] * np.arctan(p["RVY6"] * c.kappa)) * p["LVYKA"] * c.smooth  # eq 4.E66
        Mz = -t * (Fy - SVyk) + Mzr + s * Fx
    else:
        Mz = -t * Fy_prime + Mzr + s * Fx  # eqs 4.E72, 4.E71
    return Mz, t, Mzr
