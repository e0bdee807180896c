"""Basic quantities shared by all channels (Pacejka 2012 §4.3.2, eqs 4.E1–4.E8)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mftire.mf.family import is_pac2002
from mftire.mf.inputs import EPSILON, Conditions
from mftire.mf.modes import Mode


@dataclass
class Basic:
    """Normalised increments, star and prime quantities."""

    Fz0p: float  #: adapted nominal load Fz0' = LFZO·FNOMIN [N] (eq 4.E1)
    dfz: np.ndarray  #: normalised load increment [-] (eq 4.E2a)
    dpi: np.ndarray  #: normalised pressure increment [-] (eq 4.E2b)
    alpha_star: np.ndarray  #: alpha* [rad or -] (eq 4.E3)
    gamma_star: np.ndarray  #: gamma* [rad or -] (eq 4.E4)
    alpha_prime: np.ndarray  #: alpha' = acos(Vx/Vc') [rad] (eq 4.E6)
    LMUX_star: float | np.ndarray  #: (eq 4.E7)
    LMUY_star: float | np.ndarray
    LMUX_prime: float | np.ndarray  #: (eq 4.E8)
    LMUY_prime: float | np.ndarray


def increments(p: dict, Fz: np.ndarray, P: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """Fz0' [N], dfz [-] and dpi [-] (Pacejka 2012 eqs 4.E1, 4.E2a, 4.E2b)."""
    Fz0p = p["LFZO"] * p["FNOMIN"]  # eq 4.E1
    dfz = (Fz - Fz0p) / Fz0p  # eq 4.E2a
    dpi = (P - p["NOMPRES"]) / p["NOMPRES"]  # eq 4.E2b
    return Fz0p, dfz, dpi


def slip_speed(Vx, kappa, alpha):
    """Slip speed Vs = |Vx|·sqrt(kappa² + tan²alpha) [m/s] of the contact point
    (Pacejka 2012 eqs 4.E5, 2.12, 3.39: Vsx = −kappa·|Vx|, Vsy = tan(alpha)·|Vx|)."""
    return np.abs(Vx) * np.sqrt(kappa**2 + np.tan(alpha) ** 2)


def basic(p: dict, mode: Mode, c: Conditions) -> Basic:
    """Compute :class:`Basic` for the conditioned operating point ``c``.

    The scaling factors of ``p`` may be arrays: the model extensions of
    :mod:`mftire.mf.extensions` act through them (e.g. LMUX, LMUY in eq 4.E7).
    """
    Fz0p, dfz, dpi = increments(p, c.Fz, c.P)
    absVx = np.abs(c.Vx)
    # ISO sign convention: no minus sign in eq 2.12 (the book is in adapted SAE).
    Vsy = np.tan(c.alpha) * absVx  # eq 2.12 / 4.E3
    Vs = slip_speed(c.Vx, c.kappa, c.alpha)  # eqs 4.E5, 3.39
    Vc = np.sqrt(c.Vx**2 + Vsy**2)  # contact-centre speed, Vcy = Vsy
    if mode.alpha_star:
        alpha_star = np.tan(c.alpha) * np.sign(c.Vx)  # eq 4.E3
        gamma_star = np.sin(c.gamma)  # eq 4.E4
    else:
        alpha_star, gamma_star = c.alpha, c.gamma
    sgn = np.where(Vc == 0.0, 1.0, np.sign(Vc))
    Vc_prime = Vc + EPSILON * sgn  # eq 4.E6a
    alpha_prime = np.arccos(c.Vx / Vc_prime)  # eq 4.E6
    # Friction decaying with slip speed: LMUV is not part of MF 6.1/6.2 .tir files,
    # so it is 0 as in the reference evaluator; Amu = 1 (MFeval departure: the book
    # suggests Amu = 10, Amu = 1 matches TNO).  PAC2002 uses the file's LMUV
    # (Pacejka 2006 eq 4.E7, see mftire.mf.pac2002).
    LMUV = p["LMUV"] if is_pac2002(p) else 0.0
    LMUX_star = p["LMUX"] / (1.0 + LMUV * Vs / p["LONGVL"]) if LMUV else p["LMUX"]  # eq 4.E7
    LMUY_star = p["LMUY"] / (1.0 + LMUV * Vs / p["LONGVL"]) if LMUV else p["LMUY"]  # eq 4.E7
    Amu = 1.0
    LMUX_prime = Amu * LMUX_star / (1.0 + (Amu - 1.0) * LMUX_star)  # eq 4.E8
    LMUY_prime = Amu * LMUY_star / (1.0 + (Amu - 1.0) * LMUY_star)  # eq 4.E8
    return Basic(
        Fz0p=Fz0p,
        dfz=dfz,
        dpi=dpi,
        alpha_star=alpha_star,
        gamma_star=gamma_star,
        alpha_prime=alpha_prime,
        LMUX_star=LMUX_star,
        LMUY_star=LMUY_star,
        LMUX_prime=LMUX_prime,
        LMUY_prime=LMUY_prime,
    )
