"""Overturning couple Mx (Besselink et al. 2010 draft eq 49, as the reference uses)."""

from __future__ import annotations

import numpy as np

from mftire.mf.inputs import Conditions


def mx(p: dict, c: Conditions, dpi: np.ndarray, Fy: np.ndarray) -> np.ndarray:
    """Overturning moment Mx [N·m].

    MFeval departure: book eq 4.E69 and paper eq A47 do not match TNO's solver; the
    draft of Besselink et al. (2010), eq 49, with QSX12–QSX14 does.  Below FZMIN the
    load is reduced as Fz·(Fz/FZMIN)² (found empirically by the reference's author).
    """
    Fz = c.Fz
    FZMIN = p["FZMIN"]
    with np.errstate(divide="ignore", invalid="ignore"):
        Fz = np.where(Fz < FZMIN, Fz * (Fz / FZMIN) ** 2, Fz)
    R0, Fz0, g = p["UNLOADED_RADIUS"], p["FNOMIN"], c.gamma
    return R0 * Fz * p["LMX"] * (
        p["QSX1"] * p["LVMX"]
        - p["QSX2"] * g * (1.0 + p["PPMX1"] * dpi)
        - p["QSX12"] * g * np.abs(g)
        + p["QSX3"] * Fy / Fz0
        + p["QSX4"] * np.cos(p["QSX5"] * np.arctan((p["QSX6"] * Fz / Fz0) ** 2))
        * np.sin(p["QSX7"] * g + p["QSX8"] * np.arctan(p["QSX9"] * Fy / Fz0))
        + p["QSX10"] * np.arctan(p["QSX11"] * Fz / Fz0) * g
    ) + R0 * Fy * p["LMX"] * (p["QSX13"] + p["QSX14"] * np.abs(g))  # draft eq 49
