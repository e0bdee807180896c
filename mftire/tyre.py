"""A thin object layer over the parameter file and the pure evaluator.

>>> import mftire
>>> tyre = mftire.load("tirfiles/MF61_255-55R20_mfeval-jl.tir")
>>> out = tyre.evaluate(Fz=4000.0, kappa=-0.1, alpha=0.0)
>>> round(float(out["Fx"]), 1)  # doctest: +SKIP
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, Union

import numpy as np

from mftire.input_checks import UNIT_LIMITS, check_input_types, check_keywords, warn_units
from mftire.iotools.tir import TirParameters, as_parameters, read_tir
from mftire.mf import kernel, pac2002
from mftire.mf.extensions import SECTION, ExtensionSet, parse_section
from mftire.mf.family import MODEL_CODES, PAC2002_CODE
from mftire.mf.kernel import FlatParameters
from mftire.mf.solver import (
    CHECKED_MODES,
    OUTPUT_NAMES,
    OUTPUT_UNITS,
    UnsupportedModelError,
    check_fittyp,
    evaluate_arrays,
    unsupported_message,
    valid_mode,
)
from mftire.parameters import with_defaults

if TYPE_CHECKING:  # pandas is imported by the table methods only (fast ``mftire info``)
    import pandas as pd


class MFResult(dict):
    """The 30 output channels by name (``out["Fx"]``), each an array.

    A plain ``dict`` of numpy arrays in MFeval's order, plus :meth:`to_frame`.
    """

    units = OUTPUT_UNITS

    def to_frame(self) -> pd.DataFrame:
        """All channels as a DataFrame (inputs are flattened to one row per point)."""
        import pandas as pd

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
        if isinstance(params, (str, os.PathLike)):
            raise TypeError(f"Tyre() takes parameters, not a file name: read {os.fspath(params)!r} with "
                            "mftire.load(path) or Tyre.from_file(path)")
        #: The parameters as a :class:`TirParameters` (a mapping is converted; its
        #: non-standard keys outside sections are kept in :attr:`flat` only).
        self.parameters: TirParameters = as_parameters(params, unknown="drop")
        self.flat: dict[str, float] = with_defaults(params.flat() if isinstance(params, TirParameters) else params)
        code = MODEL_CODES.get(self.parameters.model)
        if code is not None:  # internal model code of the evaluator, not the file's FITTYP (mftire.mf.family)
            self.flat["FITTYP"] = code
        if code == PAC2002_CODE:
            file_values = self.parameters.flat()
            pac2002.warn_unused(file_values)
            self.flat.update(pac2002.absent_terms(file_values))  # absent terms off (docs/pac2002.md)
            # the folded parameter set every pipeline evaluates (evaluator, fitter, diagnosis, FMU)
            self.flat = pac2002.prepare(self.flat)
        from mftire.input_checks import check_constants

        check_constants(self.flat, getattr(params, "path", None) or name,
                        self.parameters.sections.get(SECTION))  # the one parameter check (tir_checks)
        self.flat = FlatParameters(self.flat)  # a dict that counts its changes (the kernel's cache)
        ext = self.parameters.sections.get(SECTION)
        #: The ``[MFTIRE_EXTENSIONS]`` section (model extensions), or None.
        self.extensions: dict[str, Any] | None = dict(ext) if ext else None
        #: The validated extension terms (empty without a section).
        self.extension_set: ExtensionSet = parse_section(self.extensions)
        #: External input variables the extensions need (data columns such as ``temperature``).
        self.required_variables: list[str] = self.extension_set.external_variables
        #: Values a steady-state evaluation uses for extension variables it is not given: ``TH_TEMPERATURE``
        #: of ``[MFTIRE_THERMAL]`` [°C] for the variable of each temperature law that reads a thermal node
        #: (:mod:`mftire.mf.thermal_section`); empty without that section.
        self.variable_defaults: dict[str, float] = _variable_defaults(self)
        path = getattr(params, "path", None)
        self.name = name or (os.path.basename(str(path)) if path else "tyre")

    _point: _Point | None = None  # the latency path's state (see evaluate)

    def evaluate_frame(self, df: pd.DataFrame, mode: int = 111, name: str = "data") -> pd.DataFrame:
        """Evaluate at the rows of a table: the one way to evaluate a table.

        Inputs are taken from the columns by name (``Fz``, ``kappa``, ``alpha`` required;
        ``gamma``, ``phit``, ``Vx``, ``P``, ``omega`` optional; SI units), a column whose
        name differs only in letter case or by a same-unit alias (``fz``, ``slip_ratio``:
        :func:`mftire.iotools.sweeps.find_column`) also counts; the variables of the model
        extensions are taken from the columns of their names.  ``name`` labels the table in
        error messages (a missing column names the table and the column).

        Returns
        -------
        DataFrame
            The 30 channels of :data:`OUTPUT_NAMES`, with the index of ``df``.
        """
        import pandas as pd

        out = _frame_evaluate(self, df, mode, name)
        return pd.DataFrame({k: np.broadcast_to(out[k], (len(df),)) for k in OUTPUT_NAMES}, index=df.index)

    @classmethod
    def from_file(cls, path: str | os.PathLike, strict: bool = False) -> Tyre:
        """Read a ``.tir`` file (see :func:`mftire.read_tir`; ``strict`` makes its reading warnings errors);
        a broken file raises, a suspicious one warns (:mod:`mftire.iotools.tir_checks`)."""
        from mftire.iotools.tir_checks import checked

        return cls(checked(read_tir(path, strict=strict)))

    @property
    def fittyp(self) -> int | None:
        """The file's ``FITTYP`` (61, 62, 6 for MF 5.2, 5 for MF-Tyre 5.0, ...), None when the file has none
        (PAC2002, or a file whose ``PROPERTY_FILE_FORMAT`` names its version)."""
        return self.parameters.fittyp

    @property
    def format(self) -> str:
        """The file's format: ``'PAC2002'``, ``'MF_05'``, ``'FITTYP 61'``, ... (see ``TirParameters.format``)."""
        return self.parameters.format

    def __getitem__(self, key: str) -> float:
        return self.flat[key.upper()]

    def __repr__(self) -> str:
        return f"Tyre({self.name!r}, {self.format}, FNOMIN={self.flat['FNOMIN']:g} N)"

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
        channels: str | Sequence[str] | None = None,
        backend: str | None = None,
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
        channels : str or sequence of str, optional
            Only these outputs (names of :data:`mftire.mf.solver.OUTPUT_NAMES`), computing
            only what they need; default all 30.
        backend : {"auto", "kernel", "numpy"}, optional
            The compiled array kernel or the numpy reference (see :mod:`mftire.mf.kernel`);
            default: the kernel when it is built, unless ``MFTIRE_BACKEND=numpy``.
        **variables : array_like
            Extra inputs for the model extensions of the file's ``[MFTIRE_EXTENSIONS]``
            section (e.g. ``temperature=...``); a variable an extension needs but
            that is not given raises :class:`~mftire.errors.MftireInputError`.

        Returns
        -------
        MFResult
            The channels asked for (default the 30 of :data:`mftire.mf.solver.OUTPUT_NAMES`),
            arrays of the broadcast input shape (numpy scalars for scalar inputs).

        Notes
        -----
        One operating point given as numbers (``int``, ``float``, ``numpy.float64``), all
        channels and the kernel take a short path to one C call (a few microseconds; see
        :func:`mftire.mf.kernel.point_function`), with the same checks, warnings and numbers
        as arrays of one point.
        """
        # One operating point given as numbers, all channels, the kernel (``backend`` None,
        # "auto" with MFTIRE_BACKEND read and not "numpy", or "kernel"), a valid mode (any ``mode=``, ``P=``):
        # the latency path, with the semantics of the general path below (same checks, warnings,
        # numbers and types; tests/test_point_path.py).  Anything else takes the general path.
        if (
            channels is None
            and not variables
            and type(Fz) in _SCALARS
            and type(kappa) in _SCALARS
            and type(alpha) in _SCALARS
            and type(gamma) in _SCALARS
            and type(phit) in _SCALARS
            and type(Vx) in _OPTIONAL
            and type(P) in _OPTIONAL
            and type(omega) in _OPTIONAL
            and (mode in CHECKED_MODES or valid_mode(mode))
            and (
                backend == "kernel"
                if backend is not None and backend != "auto"
                else kernel._env is not None and kernel._env != "numpy"
            )
        ):
            pt, flat = self._point, self.flat
            if (
                pt is None
                or pt.flat is not flat
                or pt.version != flat.version
                or pt.ext is not self.extension_set
                or pt.lib is not kernel._lib
            ):
                pt = self._point = _point_state(self)
            if pt is not None:
                if not (-pt.alpha_limit <= alpha <= pt.alpha_limit and (Fz >= pt.fz_limit or Fz == 0.0)
                        and -pt.gamma_limit <= gamma <= pt.gamma_limit and (P is None or P >= pt.p_limit)
                        and (Vx is None or -pt.vx_limit <= Vx <= pt.vx_limit)):
                    warn_units(self, Fz, alpha, gamma, P, Vx)  # a unit warning is possible: the one check
                out = pt.evaluate(Fz, kappa, alpha, gamma, phit, Vx, P, omega, mode)
                if out is None:  # the C code refused the mode or FITTYP: the path that raises
                    out = MFResult(evaluate_arrays(flat, Fz, kappa, alpha, gamma, phit, Vx, P, omega, mode,
                                                   self.extension_set, None, None, backend))  # fmt: skip
                return out
        if self.flat.get("FITTYP") not in _EVALUATED_CODES:
            why = unsupported_message(self.parameters.get("FITTYP"))
            raise UnsupportedModelError(f"{self.name} ({self.format}): {why}")
        if self.variable_defaults:
            variables = {**{k: v for k, v in self.variable_defaults.items() if k not in variables}, **variables}
        if variables:
            check_keywords(variables, self.required_variables)
        check_input_types({"Fz": Fz, "kappa": kappa, "alpha": alpha, "gamma": gamma, "phit": phit, "Vx": Vx,
                           "P": P, "omega": omega, **variables})
        warn_units(self, Fz, alpha, gamma, P, Vx)
        out = evaluate_arrays(
            self.flat, Fz, kappa, alpha, gamma, phit, Vx, P, omega, mode, self.extension_set, variables or None,
            channels, backend,
        )  # fmt: skip
        return MFResult(out)


#: Model codes :meth:`Tyre.evaluate` evaluates (mftire.mf.family.MODEL_CODES); any other value of
#: ``flat["FITTYP"]`` (none, an unsupported FITTYP of a flat mapping) is refused with its own message.
_EVALUATED_CODES = frozenset(MODEL_CODES.values())
#: Input types of the latency path of :meth:`Tyre.evaluate` (other scalars, such as bool or
#: numpy.float32, and arrays take the general path).
_SCALARS = frozenset((float, int, np.float64))
_OPTIONAL = _SCALARS | {type(None)}


class _Point:
    """What :meth:`Tyre.evaluate` needs for scalar calls, prepared once per parameter set: valid
    while ``flat`` is the tyre's parameter dict at ``version``, ``ext`` its extension set and
    ``lib`` the kernel library in use."""

    __slots__ = ("flat", "version", "ext", "lib", "evaluate", "fz_limit", "alpha_limit", "gamma_limit", "p_limit",
                 "vx_limit")

    def __reduce__(self):  # a copied or unpickled tyre prepares its own (addresses, the library)
        return _no_point, ()


def _no_point() -> None:
    return None


def _point_state(tyre: Tyre) -> _Point | None:
    """The latency path's state for ``tyre``, or None when its calls take the general path (no
    kernel, a model the evaluator refuses, per-point parameters, extension variables)."""
    flat, ext = tyre.flat, tyre.extension_set
    if not isinstance(flat, FlatParameters) or ext.external_variables:
        return None
    if flat.get("FITTYP") not in _EVALUATED_CODES:
        return None
    try:
        check_fittyp(flat)
    except UnsupportedModelError:
        return None
    lib = kernel.load()
    evaluate = None if lib is None else kernel.point_function(flat, ext, MFResult)
    if evaluate is None:
        return None
    pt = _Point()
    pt.flat, pt.version, pt.ext, pt.lib, pt.evaluate = flat, flat.version, ext, lib, evaluate
    # warn_units can warn only outside these bounds (a NaN is outside too)
    pt.fz_limit, pt.alpha_limit = UNIT_LIMITS["Fz"] * flat["FNOMIN"], UNIT_LIMITS["alpha"]
    pt.gamma_limit, pt.p_limit, pt.vx_limit = UNIT_LIMITS["gamma"], UNIT_LIMITS["P"], UNIT_LIMITS["Vx"]
    return pt


def _variable_defaults(tyre: Tyre) -> dict[str, float]:
    """``Tyre.variable_defaults``: the thermal section's steady-state temperature for its laws' variables."""
    from mftire.mf.thermal_section import SECTION as THERMAL
    from mftire.mf.thermal_section import parse_thermal

    params = parse_thermal(tyre.parameters.sections.get(THERMAL))
    if params is None or params.temperature is None:
        return {}
    terms = {t.index: t for t in tyre.extension_set.terms}
    return {terms[n].variable: params.temperature for n in params.nodes if n in terms}


_FRAME_INPUTS = ("Fz", "kappa", "alpha", "gamma", "phit", "Vx", "P", "omega")
_FRAME_REQUIRED = ("Fz", "kappa", "alpha")


def _frame_evaluate(self: Tyre, df: pd.DataFrame, mode: int = 111, name: str = "data") -> MFResult:
    from mftire.errors import MftireInputError
    from mftire.iotools.sweeps import find_column

    kw: dict[str, np.ndarray] = {}
    for col in _FRAME_INPUTS:
        src = find_column(df.columns, col)
        if src is not None:
            kw[col] = df[src].to_numpy(dtype=float)
    missing = [c for c in _FRAME_REQUIRED if c not in kw]
    missing += [v for v in self.required_variables if v not in df.columns and v not in self.variable_defaults]
    if missing:
        from mftire.iotools.loaders import missing_columns_hint

        raise MftireInputError(
            f"{name}: missing column(s) {', '.join(missing)} (have: {', '.join(map(str, df.columns))})"
            + missing_columns_hint(df.columns, missing)
        )
    variables = {v: df[v].to_numpy(dtype=float) for v in self.required_variables if v in df.columns}
    return self.evaluate(**kw, mode=mode, **variables)


TyreLike = Union["Tyre", TirParameters, str, os.PathLike, Mapping[str, Any]]


def as_tyre(tyre: TyreLike) -> Tyre:
    """A :class:`Tyre` from a Tyre, a ``.tir`` path, a :class:`TirParameters` or a flat mapping:
    every entry point of mftire takes any of them."""
    if isinstance(tyre, Tyre):
        return tyre
    if isinstance(tyre, (str, os.PathLike)):
        return Tyre.from_file(tyre)
    if isinstance(tyre, (TirParameters, Mapping)):
        return Tyre(tyre)
    raise TypeError(f"expected a Tyre, a .tir path, TirParameters or a mapping, not {type(tyre).__name__}")


def load(path: str | os.PathLike) -> Tyre:
    """Load a ``.tir`` property file as a :class:`Tyre`."""
    return Tyre.from_file(path)


__all__ = ["MFResult", "OUTPUT_NAMES", "Tyre", "TyreLike", "as_tyre", "load"]
