"""Standard characteristic curves of a tyre (the data behind ``mftire plot``).

Pure longitudinal Fx(kappa), pure lateral Fy, Mz and Mx against alpha, at 0.5, 1
and 1.5 × FNOMIN; combined Fx and Fy against kappa at several slip angles at FNOMIN.
All at zero camber, nominal speed LONGVL and inflation pressure INFLPRES.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from mftire.tyre import Tyre, TyreLike, as_tyre

#: Load factors of the standard curves, × FNOMIN.
LOAD_FACTORS: tuple[float, ...] = (0.5, 1.0, 1.5)
#: Slip angles of the combined-slip curves [deg].
COMBINED_ALPHAS_DEG: tuple[float, ...] = (0.0, 2.0, 5.0, 10.0)


def _kappa_grid(tyre: Tyre, n: int) -> np.ndarray:
    lo = max(tyre["KPUMIN"], -1.0)
    hi = min(tyre["KPUMAX"], 1.0)
    return np.linspace(lo, hi, n)


def _alpha_grid(tyre: Tyre, n: int) -> np.ndarray:
    lim = np.deg2rad(15.0)
    return np.linspace(max(tyre["ALPMIN"], -lim), min(tyre["ALPMAX"], lim), n)


def standard_curves(tyre: TyreLike, n: int = 101, mode: int = 111) -> pd.DataFrame:
    """Evaluate the standard curves of ``tyre`` (a Tyre, a .tir path, TirParameters or a mapping).

    Returns a long DataFrame with a ``curve`` column (``pure_long``, ``pure_lat``,
    ``combined``), ``load_factor``, ``alpha_set_deg`` and the 30 output channels.
    """
    tyre = as_tyre(tyre)
    F0 = tyre["FNOMIN"]
    frames = []
    kappa = _kappa_grid(tyre, n)
    alpha = _alpha_grid(tyre, n)
    for lf in LOAD_FACTORS:
        out = tyre.evaluate(lf * F0, kappa, 0.0, mode=mode).to_frame()
        out.insert(0, "curve", "pure_long")
        out.insert(1, "load_factor", lf)
        out.insert(2, "alpha_set_deg", 0.0)
        frames.append(out)
        out = tyre.evaluate(lf * F0, 0.0, alpha, mode=mode).to_frame()
        out.insert(0, "curve", "pure_lat")
        out.insert(1, "load_factor", lf)
        out.insert(2, "alpha_set_deg", np.nan)
        frames.append(out)
    for a_deg in COMBINED_ALPHAS_DEG:
        out = tyre.evaluate(F0, kappa, np.deg2rad(a_deg), mode=mode).to_frame()
        out.insert(0, "curve", "combined")
        out.insert(1, "load_factor", 1.0)
        out.insert(2, "alpha_set_deg", a_deg)
        frames.append(out)
    return pd.concat(frames, ignore_index=True)
