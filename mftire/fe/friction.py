"""Local rubber-road friction law of van der Steen (2010).

mu(p, v) = mu_p(p) * mu_v(v)                                      (thesis eq 5.1)
mu_p(p)  = (max(p, plimit) / p0)^(-k)                              (eq 4.2, with plimit of eq 2.46)
mu_v(v)  = mu_s + (mu_m - mu_s) exp(-h^2 ln^2(v / Vmax))           (eq 2.2 / 5.2)

with the speed dependence of chapter 5: ``Vmax = kappa_max * Vx`` (eq 5.13),
``mu_m = a1 Vx + a2`` (eq 5.10), ``mu_s = a3 Vx^2 + a4 Vx + a5`` (eq 5.12) and,
optionally, ``h`` from the locked-wheel friction ``mu_lock`` (eq 5.8).

The logarithm is the natural one throughout (consistent with the Jacobian of
thesis appendix A); ``h`` from eq 5.8 is computed in the same base, so the
curve shape is base-independent.  Units: p in Pa, v in m/s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from mftire.fe.config import FrictionParams

_TINY_V = 1e-12  # guard against log(0) [m/s]


def pressure_factor(p: ArrayLike, p0: float, k: float, plimit: float) -> np.ndarray:
    """Pressure part mu_p = (max(p, plimit)/p0)^-k (thesis eqs 4.2 and 2.46). p, p0, plimit in Pa."""
    return (np.maximum(np.asarray(p, dtype=float), plimit) / p0) ** (-k)


def velocity_factor(
    v: ArrayLike, mu_s: ArrayLike, mu_m: ArrayLike, h: ArrayLike, v_max: ArrayLike
) -> np.ndarray:
    """Velocity part mu_v(v) (Savkoor, thesis eq 2.2/5.2). v, v_max in m/s; v -> 0 gives mu_s."""
    v = np.maximum(np.asarray(v, dtype=float), _TINY_V)
    L = np.log(v / v_max)
    return mu_s + (np.asarray(mu_m) - mu_s) * np.exp(-np.asarray(h) ** 2 * L * L)


def velocity_factor_and_slope(
    v: np.ndarray, mu_s: np.ndarray, dmu: np.ndarray, h2: np.ndarray, v_max: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """mu_v and d mu_v / dv [s/m] with ``dmu = mu_m - mu_s`` and ``h2 = h^2`` (thesis app. A, A.4/A.11)."""
    v = np.maximum(v, _TINY_V)
    L = np.log(v / v_max)
    E = np.exp(-h2 * L * L)
    return mu_s + dmu * E, dmu * E * (-2.0 * h2 * L) / v


def mu_m_of_speed(Vx: ArrayLike, a1: float, a2: float) -> np.ndarray:
    """Peak friction mu_m(Vx) = a1 Vx + a2 (thesis eq 5.10), Vx in m/s."""
    return a1 * np.asarray(Vx, dtype=float) + a2


def mu_s_of_speed(Vx: ArrayLike, a3: float, a4: float, a5: float) -> np.ndarray:
    """Static friction mu_s(Vx) = a3 Vx^2 + a4 Vx + a5 (thesis eq 5.12), Vx in m/s."""
    Vx = np.asarray(Vx, dtype=float)
    return a3 * Vx**2 + a4 * Vx + a5


def h_from_mu_lock(mu_s: ArrayLike, mu_m: ArrayLike, mu_lock: ArrayLike, kappa_max: float) -> np.ndarray:
    """Width parameter h from the locked-wheel friction (thesis eq 5.8), natural log.

    h^2 = ln((mu_m - mu_s)/(mu_lock - mu_s)) / ln^2(kappa_max); requires mu_s < mu_lock < mu_m.
    """
    mu_s, mu_m, mu_lock = (np.asarray(a, dtype=float) for a in (mu_s, mu_m, mu_lock))
    ratio = (mu_m - mu_s) / (mu_lock - mu_s)
    return np.sqrt(np.log(ratio) / np.log(kappa_max) ** 2)


def mu_v_of_kappa(kappa: ArrayLike, mu_s: ArrayLike, mu_m: ArrayLike, h: ArrayLike, kappa_max: float) -> np.ndarray:
    """Global-slip form of the velocity part, mu_v(|kappa|) (thesis eq 5.5, kappa_max of eq 5.6)."""
    return velocity_factor(np.abs(np.asarray(kappa, dtype=float)), mu_s, mu_m, h, kappa_max)


@dataclass(frozen=True)
class VelocityLaw:
    """Per-operating-point velocity-law coefficients (arrays broadcastable with the batch)."""

    mu_s: np.ndarray  #: static friction [-]
    mu_m: np.ndarray  #: peak friction [-]
    h: np.ndarray  #: width parameter [-]
    v_max: np.ndarray  #: sliding speed of peak friction [m/s]
    gamma_crit: np.ndarray  #: regularisation slip speed [m/s]


def velocity_law(params: FrictionParams, Vx: ArrayLike) -> VelocityLaw:
    """Speed-dependent coefficients of the law at forward speed(s) Vx [m/s] (eqs 5.8, 5.10, 5.12, 5.13)."""
    Vx = np.asarray(Vx, dtype=float)
    mu_m = mu_m_of_speed(Vx, *params.mu_m)
    mu_s = mu_s_of_speed(Vx, *params.mu_s)
    if params.mu_lock is not None:
        h = h_from_mu_lock(mu_s, mu_m, params.mu_lock, params.kappa_max)
    else:
        h = np.full_like(Vx, float(params.h))
    if params.v_max is None:
        v_max = params.kappa_max * Vx  # eq 5.13
    else:
        v_max = np.full_like(Vx, float(params.v_max))  # constant Vmax, eq 2.2
    gamma_crit = params.gamma_crit_fraction * Vx  # thesis 3.5.2: 1 % of the forward speed
    scale = params.scale  # overall friction level
    return VelocityLaw(mu_s=scale * mu_s, mu_m=scale * mu_m, h=h, v_max=v_max, gamma_crit=gamma_crit)


def friction_coefficient(p: ArrayLike, v: ArrayLike, Vx: ArrayLike, params: FrictionParams) -> np.ndarray:
    """Local friction coefficient mu(p, v) at forward speed Vx (thesis eq 2.46 with 5.13). SI units."""
    law = velocity_law(params, Vx)
    return pressure_factor(p, params.p0, params.k, params.plimit) * velocity_factor(
        v, law.mu_s, law.mu_m, law.h, law.v_max
    )


def regularised_shear(
    p: ArrayLike, slip: ArrayLike, Vx: ArrayLike, params: FrictionParams
) -> np.ndarray:
    """Shear-stress magnitude of the regularised law [Pa] (thesis eqs 2.47-2.49).

    tau = mu p |gamma|/gamma_crit below gamma_crit (stick penalty), mu p above (slip).
    """
    law = velocity_law(params, Vx)
    slip = np.abs(np.asarray(slip, dtype=float))
    mu = pressure_factor(p, params.p0, params.k, params.plimit) * velocity_factor(
        slip, law.mu_s, law.mu_m, law.h, law.v_max
    )
    return mu * np.asarray(p, dtype=float) * np.minimum(slip / law.gamma_crit, 1.0)
