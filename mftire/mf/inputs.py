"""Input conditioning: limit checks, low-speed reduction and turn-slip spin.

This reproduces the input stage of the reference evaluator MFeval 4.0 so that the
force and moment equations see exactly the same operating point.  All arrays are
broadcast to one shape first.  Quantities prefixed ``u`` are the user's values
before any limit (but after negative loads are set to zero).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from mftire.mf.modes import Mode
from mftire.mf.spec import WARNINGS

#: Small number against singularities at zero speed (Pacejka 2012, eq 4.E6a).
EPSILON = 1e-6


class MFLimitWarning(UserWarning):
    """An input was outside the ``.tir`` ranges and was saturated (mode 1xx)."""


@dataclass
class Conditions:
    """Operating point after conditioning (SI units, ISO-W axes)."""

    Fz: np.ndarray  #: vertical load [N], >= 0, <= FZMAX with limits
    Fz_low: np.ndarray  #: Fz raised to FZMIN (limits only), used in some moments [N]
    kappa: np.ndarray  #: longitudinal slip [-], low-speed reduced and clipped
    alpha: np.ndarray  #: slip angle [rad], low-speed reduced and clipped
    gamma: np.ndarray  #: inclination angle [rad], clipped
    phit: np.ndarray  #: turn slip [1/m], conditioned
    P: np.ndarray  #: inflation pressure [Pa], clipped
    Vx: np.ndarray  #: forward speed of the contact centre [m/s] (never limited)
    uFz: np.ndarray  #: load as given (negative set to 0) [N]
    ukappa: np.ndarray  #: slip as given [-]
    ukappa_low: np.ndarray  #: slip as given with the low-speed reduction (output channel) [-]
    ualpha: np.ndarray  #: slip angle as given, 0 where Vx == 0 (output channel) [rad]
    ugamma: np.ndarray  #: inclination as given [rad]
    low_speed: np.ndarray  #: bool, |Vx| <= VXLOW with limits
    smooth: np.ndarray | float  #: low-speed smooth reduction factor, 1 where not low speed [-]
    omega: np.ndarray | None = None  #: wheel spin [rad/s]; None until estimated
    omega_given: bool = False
    phi: np.ndarray | None = None  #: turn-slip spin (Pacejka 2012 eq 4.76) [1/m]
    eps_gamma: np.ndarray | float = 0.0  #: camber reduction factor epsilon_gamma (eq 4.90) [-]


_WARNINGS = {w.name: w for w in WARNINGS}


def limit_message(kind: str, p) -> str:
    """The text of the limit warning ``kind`` (:data:`mftire.mf.spec.WARNINGS`) with the limit of ``p``."""
    w = _WARNINGS[kind]
    return w.text.format(limit=w.limit, value=p[w.limit])


def _warn(kind: str, p, stacklevel: int = 4) -> None:
    warnings.warn(limit_message(kind, p), MFLimitWarning, stacklevel=stacklevel)


def condition_inputs(
    p: dict,
    mode: Mode,
    Fz: np.ndarray,
    kappa: np.ndarray,
    alpha: np.ndarray,
    gamma: np.ndarray,
    phit: np.ndarray,
    Vx: np.ndarray,
    P: np.ndarray,
) -> Conditions:
    """Apply the reference evaluator's input stage.

    Parameters are the flat ``.tir`` dictionary ``p`` and broadcast float arrays.
    Returns a :class:`Conditions`; ``omega`` and ``phi`` are filled later by
    :func:`mftire.mf.solver.evaluate_arrays`.
    """
    Fz = np.where(Fz < 0.0, 0.0, Fz)  # negative loads mean lift-off
    uFz, ukappa, ualpha, ugamma, uVx = Fz, kappa, alpha, gamma, Vx
    ukappa_low = kappa
    Fz_low = Fz
    shape = Fz.shape
    low_speed = np.zeros(shape, dtype=bool)
    smooth = 1.0  # scalar unless some point is below VXLOW

    if mode.limits:
        VXLOW = p["VXLOW"]
        # MFeval departure: turn slip is scaled by cos(alpha) ("empirically discovered"
        # to match TNO).
        phit = phit * np.cos(alpha)
        low_speed = np.abs(Vx) <= VXLOW
        if low_speed.any():
            # Smooth (cosine) and linear reduction factors below VXLOW; 1 elsewhere.
            smooth = np.where(low_speed, 1.0 - 0.5 * (1.0 + np.cos(np.pi * Vx / VXLOW)), 1.0)
            linear = np.where(low_speed, np.abs(Vx / VXLOW), 1.0)
            ukappa_low = kappa * linear
            phit = phit * linear
            kappa = kappa * linear
        backwards = Vx < 0.0
        if backwards.any():
            phit = np.where(backwards, -phit, phit)
        # Slip angle is also reduced when |Vx| + |Vsy| < VXLOW.
        speed_sum = np.abs(Vx) + np.abs(np.tan(alpha) * Vx)
        low_alpha = speed_sum < VXLOW
        if low_alpha.any():
            alpha = np.where(low_alpha, alpha * (speed_sum / VXLOW), alpha)

        checks = (("alpha", "ALPMIN", "ALPMAX", "ALPHA"), ("gamma", "CAMMIN", "CAMMAX", "GAMMA"))
        clipped = {"alpha": alpha, "gamma": gamma}
        for name, lo_key, hi_key, kind in checks:
            v = clipped[name]
            lo, hi = p[lo_key], p[hi_key]
            if (v < lo).any():
                _warn(kind + "_LOW", p)
            if (v > hi).any():
                _warn(kind + "_HIGH", p)
            if (v < lo).any() or (v > hi).any():
                clipped[name] = np.clip(v, lo, hi)
        alpha, gamma = clipped["alpha"], clipped["gamma"]

        if (Fz > p["FZMAX"]).any():
            _warn("FZ_HIGH", p)
            Fz = np.where(Fz > p["FZMAX"], p["FZMAX"], Fz)
        if (Fz < p["FZMIN"]).any():
            _warn("FZ_LOW", p)
        Fz_low = np.where(Fz < p["FZMIN"], p["FZMIN"], Fz)
        if (P < p["PRESMIN"]).any():
            _warn("P_LOW", p)
        if (P > p["PRESMAX"]).any():
            _warn("P_HIGH", p)
        P = np.clip(P, p["PRESMIN"], p["PRESMAX"])
        if (kappa < p["KPUMIN"]).any():
            _warn("KAPPA_LOW", p)
        if (kappa > p["KPUMAX"]).any():
            _warn("KAPPA_HIGH", p)
        kappa = np.clip(kappa, p["KPUMIN"], p["KPUMAX"])
        if low_speed.any():
            _warn("LOW_SPEED", p, stacklevel=3)

    # MFeval departure: the reported slip angle is zero at exactly zero speed.
    standstill = uVx == 0.0
    if standstill.any():
        ualpha = np.where(standstill, 0.0, ualpha)
    return Conditions(
        Fz=Fz,
        Fz_low=Fz_low,
        kappa=kappa,
        alpha=alpha,
        gamma=gamma,
        phit=phit,
        P=P,
        Vx=uVx,
        uFz=uFz,
        ukappa=ukappa,
        ukappa_low=ukappa_low,
        ualpha=ualpha,
        ugamma=ugamma,
        low_speed=low_speed,
        smooth=smooth,
    )
