"""Channel predictions for fitting, through the one model pipeline of :mod:`mftire.mf.solver`.

:class:`Model` binds the pipeline to fixed operating points: piece 1
(:func:`~mftire.mf.solver.prepare`: conditioning, extension variables) runs once, and
each evaluation for a parameter set ``q`` runs pieces 2 and 3 (scaling factors with
the model extensions, then only the channels asked for).  So the fitter's prediction
is :meth:`mftire.tyre.Tyre.evaluate` exactly, extensions included.

Limit checks are off while fitting (mode ``2x1``): the template's ranges (FZMAX,
ALPMAX ...) would otherwise clip measured operating points.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from mftire.mf.basic import basic
from mftire.mf.extensions import INPUT_TARGETS, ExtensionSet
from mftire.mf.modes import Mode
from mftire.mf.solver import Channels, channels, prepare, scaled

__all__ = ["Inputs", "Model", "fitting_mode", "predict", "predict_fx", "predict_fy", "predict_mz", "CHANNELS"]

CHANNELS = ("Fx", "Fy", "Mz", "Mx", "My")
#: The parameters :func:`mftire.mf.basic.basic` reads (eqs 4.E1-4.E8, the PAC2002 switch)
_BASIC_KEYS = ("FITTYP", "LFZO", "FNOMIN", "NOMPRES", "LMUV", "LONGVL", "LMUX", "LMUY")
_INPUTS = ("Fz", "kappa", "alpha", "gamma", "Vx", "P")


@dataclass
class Inputs:
    """Operating points (SI, 1-D arrays of equal length) and the extensions' external variables."""

    Fz: np.ndarray  #: vertical load [N]
    kappa: np.ndarray  #: longitudinal slip [-]
    alpha: np.ndarray  #: slip angle [rad]
    gamma: np.ndarray  #: inclination [rad]
    Vx: np.ndarray  #: forward speed [m/s]
    P: np.ndarray  #: inflation pressure [Pa]
    variables: dict[str, np.ndarray] = field(default_factory=dict)  #: external extension variables

    @classmethod
    def from_frame(cls, df, variables: Sequence[str] = ()) -> Inputs:
        """Take the schema columns of a sweep table, and the columns ``variables``."""
        return cls(*(df[c].to_numpy(dtype=float) for c in _INPUTS),
                   {v: df[v].to_numpy(dtype=float) for v in variables})  # fmt: skip

    def __len__(self) -> int:
        return int(self.Fz.size)


def fitting_mode(alpha_star: bool = False) -> Mode:
    """Mode used while fitting: combined slip, no turn slip, no input clipping (``211`` or ``221``),
    but curvature factors clipped to 1 as a fitted file evaluates in mode 1xx (eq 4.E14 ff.)."""
    return dataclasses.replace(Mode.from_code(221 if alpha_star else 211), curvature_limit=True)


class Model:
    """The model pipeline at fixed operating points ``x``.

    ``p`` supplies the never-fitted constants of piece 1; ``extensions`` are the terms of
    the tyre's ``[MFTIRE_EXTENSIONS]`` (their coefficients are read from each ``q``).
    """

    def __init__(self, p: Mapping[str, float], x: Inputs, mode: Mode, extensions: ExtensionSet | None = None):
        self.pre = prepare(p, x.Fz, x.kappa, x.alpha, x.gamma, 0.0, x.Vx, x.P, None, mode, x.variables or None)
        self.extensions = extensions
        self._basic: tuple[tuple, object] | None = None  # (values of _BASIC_KEYS, Basic) of the last evaluation

    def channels(self, q: Mapping[str, float], want: tuple[str, ...], given: Channels | None = None) -> Channels:
        """Pieces 2 and 3 for parameters ``q``: the channels ``want`` (see :func:`mftire.mf.solver.channels`)."""
        qq, offsets = scaled(q, self.extensions, self.pre, warn=False)
        if given is None and not any(k in offsets for k in INPUT_TARGETS):  # input laws change the conditions
            given = self._given_basic(qq)
        return channels(qq, self.pre, offsets, want, given)

    def _given_basic(self, qq: Mapping) -> Channels | None:
        """The basic quantities (eqs 4.E1-4.E8) of the last evaluation when the parameters they read are the
        same numbers (speed only: a fitter varies none of them).  None (computed afresh) with turn slip, whose
        spin makes the conditions depend on the parameters, or when one of them is an array (an extension)."""
        if self.pre.mode.turn_slip:
            return None
        key = tuple(qq.get(k) for k in _BASIC_KEYS)
        if not all(v is None or isinstance(v, (int, float, str)) for v in key):
            return None
        if self._basic is None or self._basic[0] != key:
            with np.errstate(all="ignore"):
                self._basic = (key, basic(qq, self.pre.mode, self.pre.c))
        return Channels(b=self._basic[1], c=self.pre.c)

    def predict(self, q: Mapping[str, float], channel: str) -> np.ndarray:
        """Model value of ``channel`` (one of :data:`CHANNELS`) [N or N·m]."""
        return np.real(getattr(self.channels(q, (channel,)), channel))


def predict(p: Mapping[str, float], x: Inputs, channel: str, mode: Mode, extensions: ExtensionSet | None = None):
    """Model value of ``channel`` (one of :data:`CHANNELS`) at ``x``."""
    return Model(p, x, mode, extensions).predict(p, channel)


def predict_fx(p: Mapping[str, float], x: Inputs, mode: Mode, extensions: ExtensionSet | None = None):
    """Fx [N]: Fx0 (eq 4.E9) weighted by Gxa (eq 4.E50)."""
    return predict(p, x, "Fx", mode, extensions)


def predict_fy(p: Mapping[str, float], x: Inputs, mode: Mode, extensions: ExtensionSet | None = None):
    """Fy [N]: Fy0 (eq 4.E19) weighted by Gyk plus SVyk (eq 4.E58)."""
    return predict(p, x, "Fy", mode, extensions)


def predict_mz(p: Mapping[str, float], x: Inputs, mode: Mode, extensions: ExtensionSet | None = None):
    """Mz [N·m]: −t·Fy′ + Mzr + s·Fx (eqs 4.E71, 4.E72)."""
    return predict(p, x, "Mz", mode, extensions)
