"""A thin object layer over the parameter file and the pure evaluator.

>>> import mftire
>>> tyre = mftire.load("tirfiles/MF61_255-55R20_mfeval-jl.tir")
>>> out = tyre.evaluate(Fz=4000.0, kappa=-0.1, alpha=0.0)
>>> round(float(out["Fx"]), 1)  # doctest: +SKIP
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from mftire.extensions import SECTION, required_variables
from mftire.iotools.tir import TirParameters, as_parameters, read_tir
from mftire.mf.solver import OUTPUT_NAMES, OUTPUT_UNITS, evaluate_arrays
from mftire.parameters import with_defaults


class MFResult(dict):
    """The 30 output channels by name (``out["Fx"]``), each an array.

    A plain ``dict`` of numpy arrays in MFeval's order, plus :meth:`to_frame`.
    """

    units = OUTPUT_UNITS

    def to_frame(self) -> pd.DataFrame:
        """All channels as a DataFrame (inputs are flattened to one row per point)."""
        return pd.DataFrame({k: np.ravel(v) for k, v in self.items()})


class Tyre:
    """A Magic Formula tyre: its ``.tir`` parameters and the evaluator.

    Parameters
    ----------
    params : TirParameters or Mapping
        Parameters as read by :func:`mftire.read_tir`, or a flat ``{KEY: value}``
        mapping in SI units.  Absent keys take MFeval's defaults
        (:data:`mftire.parameters.PARAMETERS`).
    name : str, optional
        A label (defaults to the file name).
    """

    def __init__(self, params: TirParameters | Mapping[str, Any], name: str | None = None) -> None:
        #: The parameters as a :class:`TirParameters` (a mapping is converted; its
        #: non-standard keys outside sections are kept in :attr:`flat` only).
        self.parameters: TirParameters = as_parameters(params, unknown="drop")
        self.flat: dict[str, float] = with_defaults(params)
        from mftire.input_checks import check_constants

        check_constants(self.flat, getattr(params, "path", None))
        ext = self.parameters.sections.get(SECTION)
        #: The ``[MFTIRE_EXTENSIONS]`` section (model extensions), or None.
        self.extensions: dict[str, Any] | None = dict(ext) if ext else None
        #: Extra input variables the extensions need (data columns such as ``temperature``).
        self.required_variables: list[str] = required_variables(self.extensions)
        path = getattr(params, "path", None)
        self.name = name or (os.path.basename(str(path)) if path else "tyre")

    @classmethod
    def from_file(cls, path: str | os.PathLike) -> Tyre:
        """Read a ``.tir`` file (see :func:`mftire.read_tir`)."""
        from mftire.iotools.tir_checks import checked

        return cls(checked(read_tir(path)))  # a broken file raises, a suspicious one warns

    @property
    def fittyp(self) -> int:
        """Magic Formula version number (61, 62, 6 for MF 5.2, ...)."""
        return int(self.flat["FITTYP"])

    def __getitem__(self, key: str) -> float:
        return self.flat[key.upper()]

    def __repr__(self) -> str:
        return f"Tyre({self.name!r}, FITTYP={self.fittyp}, FNOMIN={self.flat['FNOMIN']:g} N)"

    def evaluate(
        self,
        Fz,
        kappa,
        alpha,
        gamma=0.0,
        phit=0.0,
        Vx=None,
        P=None,
        omega=None,
        mode: int = 111,
        **variables,
    ) -> MFResult:
        """Steady-state forces and moments.

        Parameters
        ----------
        Fz : array_like
            Vertical load [N].
        kappa : array_like
            Longitudinal slip [-].
        alpha : array_like
            Slip angle [rad].
        gamma : array_like, default 0
            Inclination angle [rad].
        phit : array_like, default 0
            Turn slip [1/m].
        Vx : array_like, optional
            Forward speed [m/s]; default ``LONGVL``.
        P : array_like, optional
            Inflation pressure [Pa]; default ``INFLPRES``.
        omega : array_like, optional
            Wheel spin [rad/s]; estimated when not given.
        mode : int, default 111
            MFeval ``useMode`` (see :mod:`mftire.mf.modes`).
        **variables : array_like
            Extra inputs for the model extensions of the file's ``[MFTIRE_EXTENSIONS]``
            section (e.g. ``temperature=...``); a variable an extension needs but
            that is not given raises :class:`~mftire.errors.MftireInputError`.

        Returns
        -------
        MFResult
            The 30 channels of :data:`mftire.mf.solver.OUTPUT_NAMES`.
        """
        from mftire.input_checks import check_keywords, warn_units

        if variables:
            check_keywords(variables, self.required_variables)
        warn_units(self, Fz, alpha)
        out = evaluate_arrays(
            self.flat, Fz, kappa, alpha, gamma, phit, Vx, P, omega, mode, self.extensions, variables or None
        )
        return MFResult(out)


def load(path: str | os.PathLike) -> Tyre:
    """Load a ``.tir`` property file as a :class:`Tyre`."""
    return Tyre.from_file(path)


__all__ = ["MFResult", "OUTPUT_NAMES", "Tyre", "load"]
