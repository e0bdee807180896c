"""Lateral force: pure slip Fy0 and combined slip Fy (Pacejka 2012 §4.3.2)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mftire.mf import turnslip
from mftire.mf.basic import Basic
from mftire.mf.family import is_mf52
from mftire.mf.inputs import EPSILON, Conditions
from mftire.mf.longitudinal import _clip_curvature, _sign_nonzero
from mftire.mf.modes import Mode


@dataclass
class PureLateral:
    """Pure-slip lateral force and the intermediate terms the aligning moment needs."""

    Fy0: np.ndarray  #: pure lateral force [N]
    muy: np.ndarray  #: lateral friction coefficient [-]
    Kya: np.ndarray  #: cornering stiffness dFy0/dalpha [N/rad] (eq 4.E25)
    Kyg0: np.ndarray  #: camber stiffness [N/rad] (eq 4.E30)
    SHy: np.ndarray  #: horizontal shift [rad] (eq 4.E27)
    SVy: np.ndarray  #: vertical shift [N] (eq 4.E29)
    By: np.ndarray  #: stiffness factor [-] (eq 4.E26)
    Cy: float  #: shape factor [-] (eq 4.E21)
    zeta2: np.ndarray | float  #: turn-slip peak reduction [-]


def _kya(p: dict, Fz, Fz0p, dpi, gamma_star, zeta3) -> np.ndarray:
    """Cornering stiffness Kya [N/rad] (eq 4.E25)."""
    return (
        p["PKY1"]
        * Fz0p
        * (1.0 + p["PPY1"] * dpi)
        * (1.0 - p["PKY3"] * np.abs(gamma_star))
        * np.sin(
            p["PKY4"] * np.arctan((Fz / Fz0p) / ((p["PKY2"] + p["PKY5"] * gamma_star**2) * (1.0 + p["PPY2"] * dpi)))
        )
        * zeta3
        * p["LKY"]
    )


def fy0(
    p: dict,
    mode: Mode,
    c: Conditions,
    b: Basic,
    gamma_star: np.ndarray,
    turn_slip: bool,
) -> PureLateral:
    """Pure lateral force at inclination ``gamma_star`` (eqs 4.E19–4.E30).

    ``turn_slip`` selects the turn-slip zeta factors (they need ``c.phi``).
    """
    Fz, dfz, dpi, Fz0p = c.Fz, b.dfz, b.dpi, b.Fz0p
    if turn_slip:
        zeta2, zeta3 = turnslip.zeta2_zeta3(p, dfz, c.alpha, c.phi)
    else:
        zeta2, zeta3 = 1.0, 1.0

    Kya = _kya(p, Fz, Fz0p, dpi, gamma_star, zeta3)  # eq 4.E25
    SVyg = Fz * (p["PVY3"] + p["PVY4"] * dfz) * gamma_star * p["LKYC"] * b.LMUY_prime * zeta2  # eq 4.E28
    mf52 = is_mf52(p)
    if mf52:
        # MF 5.2 (TNO MF-Tyre equation manual), as the reference evaluator does.
        Kya0_52 = p["PKY1"] * Fz0p * np.sin(p["PKY4"] * np.arctan(Fz / (p["PKY2"] * Fz0p))) * p["LKYC"]
        Kyg0 = (p["PHY3"] * Kya0_52 + Fz * (p["PVY3"] + p["PVY4"] * dfz)) * p["LKYC"]
    else:
        Kyg0 = Fz * (p["PKY6"] + p["PKY7"] * dfz) * (1.0 + p["PPY5"] * dpi) * p["LKYC"]  # eq 4.E30

    sKya = _sign_nonzero(Kya)
    if turn_slip:
        # Lateral shift due to spin (eqs 4.80–4.89).
        R0 = p["UNLOADED_RADIUS"]
        # MFeval departure (after IPG CarMaker): Kya0 is Kya at zero camber.
        Kya0 = _kya(p, Fz, Fz0p, dpi, 0.0, zeta3)
        Kya_prime = Kya + EPSILON * sKya  # eq 4.E39
        Kya0_prime = Kya0 + EPSILON * _sign_nonzero(Kya0)
        CHyp = p["PHYP1"]  # eq 4.85
        DHyp = (p["PHYP2"] + p["PHYP3"] * dfz) * np.sign(c.Vx)  # eq 4.86
        EHyp = p["PHYP4"]  # eq 4.87
        if mode.clips_curvature and EHyp > 1.0:
            EHyp = 1.0
        KyRp0 = Kyg0 / (1.0 - c.eps_gamma)  # eq 4.89
        BHyp = KyRp0 / (CHyp * DHyp * Kya0_prime)  # eq 4.88
        x = BHyp * R0 * c.phi
        SHyp = DHyp * np.sin(CHyp * np.arctan(x - EHyp * (x - np.arctan(x)))) * np.sign(c.Vx)  # eq 4.80
        SHyp = np.where(DHyp == 0.0, 0.0, SHyp)  # standstill: DHyp = 0, BHyp infinite; the limit is 0
        zeta0 = 0.0  # eq 4.83
        zeta4 = 1.0 + SHyp - SVyg / Kya_prime  # eq 4.84
    else:
        zeta0, zeta4 = 1.0, 1.0

    if mf52:
        SHy = (p["PHY1"] + p["PHY2"] * dfz) * p["LHY"] + p["PHY3"] * gamma_star * p["LKYC"]  # MF 5.2 manual
    else:
        SHy = (
            (p["PHY1"] + p["PHY2"] * dfz) * p["LHY"]
            + ((Kyg0 * gamma_star - SVyg) / (Kya + EPSILON * sKya)) * zeta0
            + zeta4
            - 1.0
        )  # eq 4.E27
    SVy = Fz * (p["PVY1"] + p["PVY2"] * dfz) * p["LVY"] * b.LMUY_prime * zeta2 + SVyg  # eq 4.E29
    SVy = SVy * c.smooth
    SHy = SHy * c.smooth

    alphay = b.alpha_star + SHy  # eq 4.E20
    Cy = p["PCY1"] * p["LCY"]  # eq 4.E21
    muy = (
        (p["PDY1"] + p["PDY2"] * dfz)
        * (1.0 + p["PPY3"] * dpi + p["PPY4"] * dpi**2)
        * (1.0 - p["PDY3"] * gamma_star**2)
        * b.LMUY_star
    )  # eq 4.E23
    Dy = muy * Fz * zeta2  # eq 4.E22
    Ey = (
        (p["PEY1"] + p["PEY2"] * dfz)
        * (1.0 + p["PEY5"] * gamma_star**2 - (p["PEY3"] + p["PEY4"] * gamma_star) * _sign_nonzero(alphay))
        * p["LEY"]
    )
    Ey = _clip_curvature(Ey, "EY", mode)  # eq 4.E24
    By = Kya / (Cy * Dy + EPSILON * _sign_nonzero(Dy))  # eq 4.E26
    Ba = By * alphay
    Fy0 = Dy * np.sin(Cy * np.arctan(Ba - Ey * (Ba - np.arctan(Ba)))) + SVy  # eq 4.E19
    if mode.alpha_star:
        backwards = c.Vx < 0.0
        if backwards.any():
            Fy0 = np.where(backwards, -Fy0, Fy0)  # driving backwards
    no_load = Fz == 0.0
    if no_load.any():
        muy = np.where(no_load, 0.0, muy)
    return PureLateral(Fy0=Fy0, muy=muy, Kya=Kya, Kyg0=Kyg0, SHy=SHy, SVy=SVy, By=By, Cy=Cy, zeta2=zeta2)


def fy_combined(
    p: dict,
    mode: Mode,
    c: Conditions,
    b: Basic,
    Fy0: np.ndarray,
    muy: np.ndarray,
    zeta2: np.ndarray | float = 1.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Combined-slip lateral force (eqs 4.E58–4.E67).

    Returns ``(Fy [N], Gyk [-], SVyk [N])``.
    """
    dfz, alpha_star, gamma_star = b.dfz, b.alpha_star, b.gamma_star
    DVyk = (
        muy
        * c.Fz
        * (p["RVY1"] + p["RVY2"] * dfz + p["RVY3"] * gamma_star)
        * np.cos(np.arctan(p["RVY4"] * alpha_star))
        * zeta2
    )  # eq 4.E67
    SVyk = DVyk * np.sin(p["RVY5"] * np.arctan(p["RVY6"] * c.kappa)) * p["LVYKA"]  # eq 4.E66
    SHyk = p["RHY1"] + p["RHY2"] * dfz  # eq 4.E65
    Eyk = _clip_curvature(p["REY1"] + p["REY2"] * dfz, "EYK", mode)  # eq 4.E64
    Cyk = p["RCY1"]  # eq 4.E63
    Byk = (
        (p["RBY1"] + p["RBY4"] * gamma_star**2) * np.cos(np.arctan(p["RBY2"] * (alpha_star - p["RBY3"]))) * p["LYKA"]
    )  # eq 4.E62
    kappas = c.kappa + SHyk  # eq 4.E61
    Bs = Byk * SHyk
    Gyk0 = np.cos(Cyk * np.arctan(Bs - Eyk * (Bs - np.arctan(Bs))))  # eq 4.E60
    Bk = Byk * kappas
    Gyk = np.cos(Cyk * np.arctan(Bk - Eyk * (Bk - np.arctan(Bk)))) / Gyk0  # eq 4.E59
    SVyk = SVyk * c.smooth
    return Gyk * Fy0 + SVyk, Gyk, SVyk  # eq 4.E58
