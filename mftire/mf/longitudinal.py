"""Longitudinal force: pure slip Fx0 and combined slip Fx (Pacejka 2012 §4.3.2)."""

from __future__ import annotations

import warnings

import numpy as np

from mftire.mf.basic import Basic
from mftire.mf.inputs import EPSILON, Conditions, MFLimitWarning
from mftire.mf.modes import Mode
from mftire.mf.spec import WARNINGS


def _sign_nonzero(x: np.ndarray) -> np.ndarray:
    """sign(x) with sign(0) = +1, used against 0/0 (Pacejka 2012, p. 177)."""
    return np.sign(x) + (x == 0.0)


_CURVATURE_TEXT = {w.name: w.text for w in WARNINGS}


def _clip_curvature(E: np.ndarray, kind: str, mode: Mode) -> np.ndarray:
    """Curvature factors must not exceed 1; clipped (with the warning ``kind`` of
    :data:`mftire.mf.spec.WARNINGS` in limit mode)."""
    if mode.clips_curvature and np.any(E > 1.0):
        if mode.limits:
            warnings.warn(_CURVATURE_TEXT[kind], MFLimitWarning, stacklevel=3)
        return np.where(E > 1.0, 1.0, E)
    return E


def fx0(
    p: dict, mode: Mode, c: Conditions, b: Basic, zeta1: np.ndarray | float = 1.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pure longitudinal force.

    Returns ``(Fx0 [N], mux [-], Kxk [N])`` where Kxk = dFx0/dkappa at kappa = 0.
    """
    Fz, dfz, dpi = c.Fz, b.dfz, b.dpi
    Cx = p["PCX1"] * p["LCX"]  # eq 4.E11
    mux = (
        (p["PDX1"] + p["PDX2"] * dfz)
        * (1.0 + p["PPX3"] * dpi + p["PPX4"] * dpi**2)
        * (1.0 - p["PDX3"] * c.gamma**2)
        * b.LMUX_star
    )  # eq 4.E13
    no_load = Fz == 0.0
    if no_load.any():
        mux = np.where(no_load, 0.0, mux)
    Dx = mux * Fz * zeta1  # eq 4.E12
    Kxk = (
        Fz
        * (p["PKX1"] + p["PKX2"] * dfz)
        * np.exp(p["PKX3"] * dfz)
        * (1.0 + p["PPX1"] * dpi + p["PPX2"] * dpi**2)
        * p["LKX"]
    )  # eq 4.E15
    Bx = Kxk / (Cx * Dx + EPSILON * _sign_nonzero(Dx))  # eq 4.E16
    SHx = (p["PHX1"] + p["PHX2"] * dfz) * p["LHX"] * c.smooth  # eq 4.E17 (low-speed reduced)
    SVx = Fz * (p["PVX1"] + p["PVX2"] * dfz) * p["LVX"] * b.LMUX_prime * zeta1 * c.smooth  # eq 4.E18
    kappax = c.kappa + SHx  # eq 4.E10
    Ex = (p["PEX1"] + p["PEX2"] * dfz + p["PEX3"] * dfz**2) * (1.0 - p["PEX4"] * np.sign(kappax)) * p["LEX"]
    Ex = _clip_curvature(Ex, "EX", mode)  # eq 4.E14
    Bk = Bx * kappax
    Fx0 = Dx * np.sin(Cx * np.arctan(Bk - Ex * (Bk - np.arctan(Bk)))) + SVx  # eq 4.E9
    backwards = c.Vx < 0.0
    if backwards.any():
        Fx0 = np.where(backwards, -Fx0, Fx0)  # driving backwards
    return Fx0, mux, Kxk


def fx_combined(p: dict, mode: Mode, c: Conditions, b: Basic, Fx0: np.ndarray) -> np.ndarray:
    """Combined-slip longitudinal force Fx = Gxa·Fx0 [N] (eqs 4.E50–4.E57)."""
    Cxa = p["RCX1"]  # eq 4.E55
    Exa = _clip_curvature(p["REX1"] + p["REX2"] * b.dfz, "EXA", mode)  # eq 4.E56
    SHxa = p["RHX1"]  # eq 4.E57
    Bxa = (p["RBX1"] + p["RBX3"] * b.gamma_star**2) * np.cos(np.arctan(p["RBX2"] * c.kappa)) * p["LXAL"]  # 4.E54
    alphas = b.alpha_star + SHxa  # eq 4.E53
    Bs = Bxa * SHxa
    Gxa0 = np.cos(Cxa * np.arctan(Bs - Exa * (Bs - np.arctan(Bs))))  # eq 4.E52
    Ba = Bxa * alphas
    Gxa = np.cos(Cxa * np.arctan(Ba - Exa * (Ba - np.arctan(Ba)))) / Gxa0  # eq 4.E51
    return Gxa * Fx0  # eq 4.E50
