"""Rolling-resistance moment My (Besselink et al. 2010 eq A48)."""

from __future__ import annotations

import numpy as np

from mftire.mf.family import is_mf52
from mftire.mf.inputs import Conditions


def my(p: dict, c: Conditions, Fx: np.ndarray) -> np.ndarray:
    """Rolling-resistance moment My [N·m], negative when rolling forward (ISO).

    MFeval departure: book eq 4.E70 gives the wrong sign and scales by Fz; paper eq
    A48 (scaled by FNOMIN) is used.  The reference's empirical low-load reduction
    Fz·(Fz/FZMIN) and its low-speed treatment (a sine ramp over slips near lock,
    sign change beyond) are reproduced.  Uses the load and slip as given (unlimited).
    """
    Fz = c.uFz
    FZMIN = p["FZMIN"]
    with np.errstate(divide="ignore", invalid="ignore"):
        Fz = np.where(Fz < FZMIN, Fz * (Fz / FZMIN), Fz)
    Vx, kappa = c.Vx, c.ukappa
    R0, Fz0, V0 = p["UNLOADED_RADIUS"], p["FNOMIN"], p["LONGVL"]
    vr = Vx / V0
    if is_mf52(p):
        # MF 5.2 (TNO equation manual)
        My = -R0 * Fz * p["LMY"] * (p["QSY1"] + p["QSY2"] * (Fx / Fz0) + p["QSY3"] * np.abs(vr) + p["QSY4"] * vr**4)
    else:
        My = (
            -R0
            * Fz0
            * p["LMY"]
            * (
                p["QSY1"]
                + p["QSY2"] * (Fx / Fz0)
                + p["QSY3"] * np.abs(vr)
                + p["QSY4"] * vr**4
                + (p["QSY5"] + p["QSY6"] * (Fz / Fz0)) * c.gamma**2
            )
            * ((Fz / Fz0) ** p["QSY7"] * (c.P / p["NOMPRES"]) ** p["QSY8"])
        )  # A48
    My = np.where(Vx < 0.0, -My, My)  # driving backwards
    with np.errstate(divide="ignore", invalid="ignore"):
        high = p["VXLOW"] / np.abs(Vx) - 1.0
        low = -1.0 - p["VXLOW"] - high
        ramp = kappa >= low
        ramp &= kappa <= high
        # Linear interpolation from (kappa=-1, 0) to (kappa=high, pi/2), then sine.
        red = (0.0 * (high - kappa) + (np.pi / 2) * (kappa + 1.0)) / (high + 1.0)
        My = np.where(ramp, My * np.sin(red), My)
    My = np.where(kappa < low, -My, My)
    return np.where(Vx == 0.0, 0.0, My)
