"""Carcass stiffnesses and relaxation lengths (Besselink et al. 2010 eqs 17–19)."""

from __future__ import annotations

import numpy as np

from mftire.mf.basic import increments
from mftire.mf.family import is_mf52
from mftire.mf.inputs import Conditions


def relaxation(
    p: dict, c: Conditions, Kxk: np.ndarray, Kya: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Longitudinal and lateral carcass stiffness and relaxation lengths.

    Returns ``(Cx [N/m], Cy [N/m], sigmax [m], sigmay [m])``.
    """
    Fz0, R0 = p["FNOMIN"], p["UNLOADED_RADIUS"]
    Fz0p, dfz, dpi = increments(p, c.Fz, c.P)  # eqs 4.E1, 4.E2a, 4.E2b
    Cx = p["LONGITUDINAL_STIFFNESS"] * (1.0 + p["PCFX1"] * dfz + p["PCFX2"] * dfz**2) * (1.0 + p["PCFX3"] * dpi)  # 17
    Cy = p["LATERAL_STIFFNESS"] * (1.0 + p["PCFY1"] * dfz + p["PCFY2"] * dfz**2) * (1.0 + p["PCFY3"] * dpi)  # 18
    if is_mf52(p):
        # MF 5.2 relaxation lengths (TNO equation manual)
        sigmax = (p["PTX1"] + p["PTX2"] * dfz) * np.exp(-p["PTX3"] * dfz) * p["LSGKP"] * R0 * c.Fz / Fz0
        sigmay = (
            p["PTY1"]
            * np.sin(2.0 * np.arctan(c.Fz / (p["PTY2"] * Fz0p)))
            * (1.0 - p["PKY3"] * np.abs(c.gamma))
            * R0
            * p["LFZO"]
            * p["LSGAL"]
        )
    else:
        sigmax = np.abs(Kxk / Cx)  # eq 19
        sigmay = np.abs(Kya / Cy)  # eq 19
    return Cx, Cy, sigmax, sigmay
