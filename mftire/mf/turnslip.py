"""Turn-slip reduction factors zeta_0..zeta_8 (Pacejka 2012 §4.3.3, eqs 4.77–4.106).

Every function returns factors equal to one when turn slip is off, so the force
equations can multiply by them unconditionally.
"""

from __future__ import annotations

import numpy as np

from mftire.mf.basic import increments


def zeta1(p: dict, dfz: np.ndarray, kappa: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Fx peak reduction zeta1 [-] (eqs 4.105, 4.106)."""
    Bxp = p["PDXP1"] * (1.0 + p["PDXP2"] * dfz) * np.cos(np.arctan(p["PDXP3"] * kappa))  # eq 4.106
    return np.cos(np.arctan(Bxp * p["UNLOADED_RADIUS"] * phi))  # eq 4.105


def zeta2_zeta3(p: dict, dfz: np.ndarray, alpha: np.ndarray, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fy peak reduction zeta2 and cornering-stiffness reduction zeta3 [-] (eqs 4.77–4.79)."""
    R0 = p["UNLOADED_RADIUS"]
    zeta3 = np.cos(np.arctan(p["PKYP1"] * R0**2 * phi**2))  # eq 4.79
    Byp = p["PDYP1"] * (1.0 + p["PDYP2"] * dfz) * np.cos(np.arctan(p["PDYP3"] * np.tan(alpha)))  # eq 4.78
    aphi = np.abs(phi)
    zeta2 = np.cos(np.arctan(Byp * (R0 * aphi + p["PDYP4"] * np.sqrt(R0 * aphi))))  # eq 4.77
    return zeta2, zeta3


def zeta5(p: dict, phi: np.ndarray) -> np.ndarray:
    """Pneumatic-trail reduction zeta5 [-] (eq 4.91)."""
    return np.cos(np.arctan(p["QDTP1"] * p["UNLOADED_RADIUS"] * phi))


def zeta6(p: dict, phi: np.ndarray) -> np.ndarray:
    """Residual-torque slope reduction zeta6 [-] (eq 4.102)."""
    return np.cos(np.arctan(p["QBRP1"] * p["UNLOADED_RADIUS"] * phi))


def turn_slip_spin(p: dict, c) -> tuple[np.ndarray, np.ndarray]:
    """Spin slip phi and camber reduction factor epsilon_gamma.

    phi = (psi_dot - (1 - eps_gamma)·omega·sin(gamma)) / Vc'  (Pacejka 2012 eq 4.76,
    with psi_dot = -phit·Vc' from eq 4.75); eps_gamma = PECP1·(1 + PECP2·dfz) (eq 4.90).

    MFeval departure: Vc' is the contact-centre speed sqrt(Vx² + Vsy²) (TNO equation
    manual) protected to ±VXLOW below VXLOW, and eq 4.76 is used without the
    book's sign change because the road z axis points up.
    """
    _, dfz, _ = increments(p, c.Fz, c.P)  # eqs 4.E1, 4.E2a
    Vsy = -np.tan(c.alpha) * np.abs(c.Vx)
    V = np.sqrt(c.Vx**2 + Vsy**2)
    eps_gamma = p["PECP1"] * (1.0 + p["PECP2"] * dfz)  # eq 4.90
    low = np.abs(c.Vx) < p["VXLOW"]
    sgn = np.sign(c.Vx)
    sgn = np.where(sgn == 0.0, 1.0, sgn)
    Vc_prime = np.where(low, p["VXLOW"] * sgn, V)
    psi_dot = -c.phit * Vc_prime  # eq 4.75
    phi = (1.0 / Vc_prime) * (psi_dot - (1.0 - eps_gamma) * c.omega * np.sin(c.gamma))  # eq 4.76
    return phi, eps_gamma
