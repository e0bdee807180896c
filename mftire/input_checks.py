"""Checks of what reaches :meth:`mftire.Tyre.evaluate` (issue 14: unit and name slips).

* :func:`check_keywords`: a keyword argument that is neither an input of
  ``evaluate`` nor a variable the tyre's model extensions read is a :class:`TypeError`
  with the likely intended name ("did you mean 'Vx'?"), from the aliases of
  :mod:`mftire.iotools.sweeps` and :func:`difflib.get_close_matches`.
* :func:`warn_units`: slip angles above 1.5 rad (degrees?) or every load below 5 % of
  FNOMIN (kN?) give one :class:`~mftire.errors.MftireUnitWarning` per tyre and cause,
  in every use mode.
* :func:`check_constants`: FNOMIN and UNLOADED_RADIUS must be finite and positive
  (every equation divides by them).
"""

from __future__ import annotations

import difflib
import math
import warnings
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from mftire.errors import MftireUnitWarning
from mftire.iotools.tir_checks import TirCheckError

#: Thresholds of the unit warnings: |alpha| in rad, Fz as a fraction of FNOMIN.
UNIT_LIMITS = {"alpha": 1.5, "Fz": 0.05}
#: The keyword arguments of :meth:`mftire.Tyre.evaluate` besides the extension variables.
EVALUATE_ARGUMENTS = ("Fz", "kappa", "alpha", "gamma", "phit", "Vx", "P", "omega", "mode", "channels", "backend")


def warn_units(tyre: Any, Fz, alpha) -> None:
    """One :class:`~mftire.errors.MftireUnitWarning` per tyre and cause for inputs that look
    like degrees (|alpha| > 1.5 rad) or kN (every Fz below 5 % of FNOMIN)."""
    warned = tyre.__dict__.setdefault("_unit_warned", set())
    if "alpha" not in warned:
        top = _largest(alpha, absolute=True)
        if math.isfinite(top) and top > UNIT_LIMITS["alpha"]:  # a float: math is ~20x faster
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
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError):  # not numbers: the evaluator's own check says so (MftireInputError)
        return 0.0
    if absolute:
        a = np.abs(a)
    return float(np.nanmax(a)) if a.size and not np.isnan(a).all() else 0.0


def check_keywords(given: Mapping[str, Any], required: Sequence[str]) -> None:
    """Extra keyword arguments must be variables the tyre's extensions need; else a
    :class:`TypeError` with the likely intended name."""
    from mftire.iotools.sweeps import COLUMN_ALIASES  # common names of the schema quantities (one table)

    extra = [k for k in given if k not in required]
    if not extra:
        return
    name = extra[0]
    known = [*EVALUATE_ARGUMENTS, *required]
    low = name.lower()
    guess = next((q for q, names in COLUMN_ALIASES.items() if low in names and q in known), None)
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


def check_constants(flat: Mapping[str, float], path: Any = None) -> None:
    """FNOMIN and UNLOADED_RADIUS scale every equation: they must be finite and positive."""
    for key in ("FNOMIN", "UNLOADED_RADIUS"):
        v = flat[key]
        if not (np.isfinite(v) and v > 0):
            where = f"{path}: " if path else ""
            raise TirCheckError(f"{where}{key} = {v:g} must be > 0")


__all__ = ["EVALUATE_ARGUMENTS", "UNIT_LIMITS", "check_constants", "check_keywords", "warn_units"]
