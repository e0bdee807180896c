"""Fast channel predictions for fitting: only the equations a stage needs.

Each function takes the flat parameter dictionary ``p`` (see
:func:`mftire.parameters.with_defaults`) and an :class:`Inputs` bundle of SI arrays and
returns the channel in SI units.  The full combined-slip model (mode ``2x1``: no
input limits, combined slip, no turn slip) is used for every channel, so the fitted
``.tir`` reproduces the data when evaluated the standard way; at pure slip it reduces to
the pure-slip equations (Gxa = Gyk = 1, SVyk = 0, eqs 4.E51, 4.E59, 4.E66).

Limit checks are off while fitting: the template's ranges (FZMAX, ALPMAX ...) would
otherwise clip measured operating points.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mftire.mf.aligning import aligning_terms, mz_combined
from mftire.mf.basic import basic
from mftire.mf.inputs import condition_inputs
from mftire.mf.lateral import fy0, fy_combined
from mftire.mf.longitudinal import fx0, fx_combined
from mftire.mf.modes import Mode
from mftire.mf.overturning import mx
from mftire.mf.rolling import my

__all__ = ["Inputs", "fitting_mode", "predict", "predict_fx", "predict_fy", "predict_mz", "CHANNELS"]

CHANNELS = ("Fx", "Fy", "Mz", "Mx", "My")


@dataclass
class Inputs:
    """Operating points (SI, 1-D arrays of equal length)."""

    Fz: np.ndarray  #: vertical load [N]
    kappa: np.ndarray  #: longitudinal slip [-]
    alpha: np.ndarray  #: slip angle [rad]
    gamma: np.ndarray  #: inclination [rad]
    Vx: np.ndarray  #: forward speed [m/s]
    P: np.ndarray  #: inflation pressure [Pa]

    @classmethod
    def from_frame(cls, df) -> Inputs:
        """Take the schema columns of a sweep table."""
        return cls(*(df[c].to_numpy(dtype=float) for c in ("Fz", "kappa", "alpha", "gamma", "Vx", "P")))

    def __len__(self) -> int:
        return int(self.Fz.size)


def fitting_mode(alpha_star: bool = False) -> Mode:
    """Mode used while fitting: no limits, combined slip, no turn slip (``211`` or ``221``)."""
    return Mode.from_code(221 if alpha_star else 211)


def _prepare(p: dict, x: Inputs, mode: Mode):
    z = np.zeros_like(x.Fz)
    c = condition_inputs(p, mode, x.Fz, x.kappa, x.alpha, x.gamma, z, x.Vx, x.P)
    return c, basic(p, mode, c)


def predict_fx(p: dict, x: Inputs, mode: Mode) -> np.ndarray:
    """Fx [N]: Fx0 (eq 4.E9) weighted by Gxa (eq 4.E50)."""
    with np.errstate(all="ignore"):
        c, b = _prepare(p, x, mode)
        Fx0, _, _ = fx0(p, mode, c, b)
        return fx_combined(p, mode, c, b, Fx0)


def predict_fy(p: dict, x: Inputs, mode: Mode) -> np.ndarray:
    """Fy [N]: Fy0 (eq 4.E19) weighted by Gyk plus SVyk (eq 4.E58)."""
    with np.errstate(all="ignore"):
        c, b = _prepare(p, x, mode)
        lat = fy0(p, mode, c, b, b.gamma_star, turn_slip=False)
        Fy, _, _ = fy_combined(p, mode, c, b, lat.Fy0, lat.muy, lat.zeta2)
        return Fy


def _forces(p: dict, x: Inputs, mode: Mode):
    c, b = _prepare(p, x, mode)
    Fx0, _, Kxk = fx0(p, mode, c, b)
    Fx = fx_combined(p, mode, c, b, Fx0)
    lat = fy0(p, mode, c, b, b.gamma_star, turn_slip=False)
    Fy, Gyk, _ = fy_combined(p, mode, c, b, lat.Fy0, lat.muy, lat.zeta2)
    return c, b, Fx, Kxk, lat, Fy, Gyk


def predict_mz(p: dict, x: Inputs, mode: Mode) -> np.ndarray:
    """Mz [N·m]: −t·Fy′ + Mzr + s·Fx (eqs 4.E71, 4.E72)."""
    with np.errstate(all="ignore"):
        c, b, Fx, Kxk, lat, Fy, Gyk = _forces(p, x, mode)
        terms = aligning_terms(p, mode, c, b, lat, Gyk)
        Mz, _, _ = mz_combined(p, mode, c, b, terms, Kxk, Fx, Fy, Gyk)
        return np.real(Mz)


def predict_mx(p: dict, x: Inputs, mode: Mode, Fy: np.ndarray | None = None) -> np.ndarray:
    """Mx [N·m] (draft eq 49); ``Fy`` from the model unless given."""
    with np.errstate(all="ignore"):
        c, b = _prepare(p, x, mode)
        if Fy is None:
            Fy = predict_fy(p, x, mode)
        return mx(p, c, b.dpi, Fy)


def predict_my(p: dict, x: Inputs, mode: Mode, Fx: np.ndarray | None = None) -> np.ndarray:
    """My [N·m] (Besselink 2010 eq A48); ``Fx`` from the model unless given."""
    with np.errstate(all="ignore"):
        c, _ = _prepare(p, x, mode)
        if Fx is None:
            Fx = predict_fx(p, x, mode)
        return my(p, c, Fx)


_PREDICT = {"Fx": predict_fx, "Fy": predict_fy, "Mz": predict_mz, "Mx": predict_mx, "My": predict_my}


def predict(p: dict, x: Inputs, channel: str, mode: Mode) -> np.ndarray:
    """Model value of ``channel`` (one of :data:`CHANNELS`) at ``x``."""
    return _PREDICT[channel](p, x, mode)
