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
        _check_constants(self.flat, getattr(params, "path", None))
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
        return cls(_checked(read_tir(path)))  # mftire.iotools.tir_checks: broken raises, suspicious warns

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
        if variables:
            _check_variables(variables, self.required_variables)
        _unit_check(self, Fz, alpha)
        out = evaluate_arrays(
            self.flat, Fz, kappa, alpha, gamma, phit, Vx, P, omega, mode, self.extensions, variables or None
        )
        return MFResult(out)


def load(path: str | os.PathLike) -> Tyre:
    """Load a ``.tir`` property file as a :class:`Tyre`."""
    return Tyre.from_file(path)


__all__ = ["MFResult", "OUTPUT_NAMES", "Tyre", "load"]


# ------------------------------------------------------------------ input and constant checks


def _checked(params: TirParameters) -> TirParameters:
    """Run the ``.tir`` sanity checks of :mod:`mftire.iotools.tir_checks` on a file just read:
    errors raise :class:`~mftire.iotools.tir_checks.TirCheckError` (one line naming the file),
    warnings are issued together as one :class:`~mftire.errors.MftireTirWarning`."""
    from mftire.iotools.tir_checks import check_parameters

    report = check_parameters(params)
    report.raise_errors()
    report.warn(stacklevel=4)
    return params


def _unit_check(tyre: Tyre, Fz, alpha) -> None:
    """One :class:`~mftire.errors.MftireUnitWarning` per tyre and cause for inputs that look
    like degrees (|alpha| > 1.5 rad) or kN (every Fz below 5 % of FNOMIN)."""
    import warnings

    from mftire.errors import MftireUnitWarning

    warned = tyre.__dict__.setdefault("_unit_warned", set())
    if "alpha" not in warned:
        top = _largest(alpha, absolute=True)
        if np.isfinite(top) and top > UNIT_LIMITS["alpha"]:
            warned.add("alpha")
            warnings.warn(f"slip angle alpha up to {top:g} rad ({np.degrees(top):.0f} deg): alpha is in radians; "
                          "values above 1.5 rad look like degrees (convert with numpy.deg2rad)",
                          MftireUnitWarning, stacklevel=3)  # fmt: skip
    if "Fz" not in warned:
        top = _largest(Fz, absolute=False)
        limit = UNIT_LIMITS["Fz"] * tyre.flat["FNOMIN"]
        if 0.0 < top < limit:
            warned.add("Fz")
            warnings.warn(f"every vertical load Fz is below {limit:g} N (5 % of FNOMIN = {tyre.flat['FNOMIN']:g} "
                          f"N; largest {top:g}): Fz is in newtons, the values look like kN (multiply by 1000)",
                          MftireUnitWarning, stacklevel=3)  # fmt: skip


def _largest(x, absolute: bool) -> float:
    """Largest (absolute) value of ``x`` ignoring NaN; 0 when there is none (fast for scalars)."""
    if isinstance(x, (int, float)):
        v = abs(x) if absolute else float(x)
        return v if v == v else 0.0
    a = np.asarray(x, dtype=float)
    if absolute:
        a = np.abs(a)
    return float(np.nanmax(a)) if a.size and not np.isnan(a).all() else 0.0


#: Thresholds of the unit warnings of :meth:`Tyre.evaluate`: |alpha| in rad, Fz as a fraction of FNOMIN.
UNIT_LIMITS = {"alpha": 1.5, "Fz": 0.05}
#: The keyword arguments of :meth:`Tyre.evaluate` besides the extension variables.
EVALUATE_ARGUMENTS = ("Fz", "kappa", "alpha", "gamma", "phit", "Vx", "P", "omega", "mode")


def _check_variables(given: Mapping[str, Any], required: list[str]) -> None:
    """Extra keyword arguments must be variables the tyre's extensions need; else a
    :class:`TypeError` with the likely intended name."""
    import difflib

    from mftire.iotools.sweeps import _ALIASES  # common names of the schema quantities (one table)

    extra = [k for k in given if k not in required]
    if not extra:
        return
    name = extra[0]
    known = [*EVALUATE_ARGUMENTS, *required]
    low = name.lower()
    guess = next((q for q, names in _ALIASES.items() if low in names and q in known), None)
    guess = guess or next((k for k in known if k.lower() == low), None)
    if guess is None:
        close = difflib.get_close_matches(name, known, n=1, cutoff=0.6)
        guess = close[0] if close else None
    msg = f"Tyre.evaluate() got an unexpected keyword argument {name!r}"
    if guess:
        msg += f"; did you mean {guess!r}?"
    msg += (f" (the tyre's extensions take: {', '.join(required)})" if required
            else " (this tyre has no model extensions, so no extra variables)")
    raise TypeError(msg)


def _check_constants(flat: Mapping[str, float], path: Any) -> None:
    """FNOMIN and UNLOADED_RADIUS scale every equation: they must be finite and positive."""
    from mftire.iotools.tir_checks import TirCheckError

    for key in ("FNOMIN", "UNLOADED_RADIUS"):
        v = flat[key]
        if not (np.isfinite(v) and v > 0):
            where = f"{path}: " if path else ""
            raise TirCheckError(f"{where}{key} = {v:g} must be > 0")
