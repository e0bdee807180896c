"""Synthetic sweep data from a ``.tir``: for tests, benchmarks and demonstrations.

:func:`synthetic_sweeps` evaluates a tyre (mode 111, the standard evaluation) on a
factorial design of loads, cambers, pressures and speeds, with pure longitudinal,
pure lateral and combined sweeps, then adds Gaussian noise (a fraction of each
channel's peak) and gross outliers.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from mftire.mf.solver import evaluate_arrays
from mftire.parameters import with_defaults

__all__ = ["synthetic_sweeps"]

_CHANNELS = ("Fx", "Fy", "Mz", "Mx", "My")


def synthetic_sweeps(
    tir,
    loads: Sequence[float],
    cambers: Sequence[float] = (0.0,),
    pressures: Sequence[float] | None = None,
    speeds: Sequence[float] | None = None,
    *,
    n_kappa: int = 41,
    n_alpha: int = 41,
    kappa_max: float = 0.3,
    alpha_max: float = np.radians(12.0),
    combined_alphas: Sequence[float] = (np.radians(3.0), np.radians(-6.0)),
    combined_kappas: Sequence[float] = (0.04, -0.08),
    n_combined: int = 21,
    noise: float = 0.0,
    outliers: float = 0.0,
    outlier_size: float = 0.3,
    channels: Sequence[str] = _CHANNELS,
    mode: int = 111,
    seed: int | None = 0,
) -> pd.DataFrame:
    """Sweep table (SI) of a tyre over a factorial design.

    Parameters
    ----------
    tir : TirParameters or mapping
        The tyre.
    loads : sequence of float
        Loads [N].
    cambers : sequence of float
        Inclinations [rad].
    pressures, speeds : sequence of float, optional
        Pressures [Pa] (default INFLPRES) and speeds [m/s] (default LONGVL).
    n_kappa, n_alpha : int
        Points of the pure slip-ratio sweep (−kappa_max..kappa_max) and slip-angle
        sweep (−alpha_max..alpha_max [rad]).
    combined_alphas, combined_kappas : sequence of float
        Slip angles [rad] of combined κ sweeps and slip ratios [-] of combined α sweeps
        (``n_combined`` points each).
    noise : float
        Standard deviation of the Gaussian noise as a fraction of each channel's peak
        in the table [-].
    outliers : float
        Fraction of rows [-] whose channels get a gross error of ``outlier_size`` x peak
        (random sign).
    channels : sequence of str
        Channels to keep.
    mode : int
        Evaluation mode.
    seed : int, optional
        Random seed.
    """
    p = with_defaults(tir)
    pressures = [p["INFLPRES"]] if pressures is None else list(pressures)
    speeds = [p["LONGVL"]] if speeds is None else list(speeds)
    kap = np.linspace(-kappa_max, kappa_max, n_kappa)
    alp = np.linspace(-alpha_max, alpha_max, n_alpha)
    kc = np.linspace(-kappa_max, kappa_max, n_combined)
    ac = np.linspace(-alpha_max, alpha_max, n_combined)
    parts = []
    run = 0
    for P in pressures:
        for V in speeds:
            for g in cambers:
                for Fz in loads:
                    sweeps = [(kap, np.zeros_like(kap)), (np.zeros_like(alp), alp)]
                    sweeps += [(kc, np.full_like(kc, a)) for a in combined_alphas]
                    sweeps += [(np.full_like(ac, k), ac) for k in combined_kappas]
                    for k, a in sweeps:
                        parts.append(pd.DataFrame({"Fz": Fz, "kappa": k, "alpha": a, "gamma": g, "Vx": V,
                                                   "P": P, "run": run}))
                        run += 1
    df = pd.concat(parts, ignore_index=True)
    out = evaluate_arrays(p, df["Fz"].to_numpy(), df["kappa"].to_numpy(), df["alpha"].to_numpy(),
                          df["gamma"].to_numpy(), 0.0, df["Vx"].to_numpy(), df["P"].to_numpy(), mode=mode)
    rng = np.random.default_rng(seed)
    n = len(df)
    bad = rng.random(n) < outliers
    for ch in channels:
        y = np.asarray(out[ch], dtype=float).copy()
        peak = float(np.max(np.abs(y))) or 1.0
        if noise:
            y = y + rng.normal(0.0, noise * peak, n)
        if outliers:
            y = np.where(bad, y + rng.choice([-1.0, 1.0], n) * outlier_size * peak, y)
        df[ch] = y
    return df
