"""Checks of what reaches :meth:`mftire.Tyre.evaluate` (issue 14: unit and name slips).

* :func:`check_keywords`: a keyword argument that is neither an input of
  ``evaluate`` nor a variable the tyre's model extensions read is a :class:`TypeError`
  with the likely intended name ("did you mean 'Vx'?"), from the aliases of
  :mod:`mftire.iotools.sweeps` and :func:`difflib.get_close_matches`.
* :func:`warn_units`: slip angles above 1.5 rad (degrees?) or every load below 5 % of
  FNOMIN (kN?) give one :class:`~mftire.errors.MftireUnitWarning` per tyre and cause,
  in every use mode.
* :func:`check_constants`: the constants that would make a channel non-finite or absurd
  (:data:`mftire.iotools.tir_checks.PARAMETER_LIMITS`), for every way a tyre is made.
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

#: Thresholds of the unit warnings: |alpha| and |gamma| in rad, Fz as a fraction of FNOMIN, P in Pa
#: (below: bar, psi or kPa), |Vx| in m/s (above: km/h or mm/s?).
UNIT_LIMITS = {"alpha": 1.5, "Fz": 0.05, "gamma": 1.0, "P": 2e4, "Vx": 250.0}
#: The keyword arguments of :meth:`mftire.Tyre.evaluate` besides the extension variables.
EVALUATE_ARGUMENTS = ("Fz", "kappa", "alpha", "gamma", "phit", "Vx", "P", "omega", "mode", "channels", "backend")


def warn_units(tyre: Any, Fz, alpha, gamma=0.0, P=None, Vx=None) -> None:
    """One :class:`~mftire.errors.MftireUnitWarning` per tyre and cause, in every use mode, for inputs
    that look like the wrong unit or sign: degrees (|alpha| > 1.5 rad, |gamma| > 1 rad), kN (every Fz
    below 5 % of FNOMIN), the SAE sign (every Fz of a batch negative or zero, some below -5 % of FNOMIN:
    not a lift-off; one point alone may be a wheel lifting), bar/psi/kPa (every P below 0.2 bar),
    km/h or mm/s (|Vx| above 250 m/s).  In modes 1xx the limits then clip, with their own warning."""
    warned = tyre.__dict__.setdefault("_unit_warned", set())

    def warn(cause: str, message: str) -> None:
        warned.add(cause)
        warnings.warn(message, MftireUnitWarning, stacklevel=4)

    for name, label in (("alpha", "slip angle alpha"), ("gamma", "inclination gamma")):
        if name in warned:
            continue
        top = _largest(alpha if name == "alpha" else gamma, absolute=True)
        lim = UNIT_LIMITS[name]
        if math.isfinite(top) and top > lim:  # a float: math is ~20x faster
            deg = f"{math.degrees(top):.0f} deg" if top < 1e300 else "beyond any angle"
            warn(name, f"{label} up to {top:g} rad ({deg}): {name} is in radians; values above {lim:g} rad look "
                       "like degrees (convert with numpy.deg2rad)")
    if "Fz" not in warned or "Fz-sign" not in warned:
        top = _largest(Fz, absolute=False)
        limit = UNIT_LIMITS["Fz"] * tyre.flat["FNOMIN"]
        if "Fz" not in warned and 0.0 < top < limit:
            warn("Fz", f"every vertical load Fz is below {limit:g} N (5 % of FNOMIN = {tyre.flat['FNOMIN']:g} "
                       f"N; largest {top:g}): Fz is in newtons, the values look like kN (multiply by 1000)")
        elif "Fz-sign" not in warned and top <= 0.0 and np.size(Fz) > 1 and _largest(Fz, absolute=True) > limit:
            warn("Fz-sign", "every vertical load Fz is negative or zero: in ISO/TYDEX W axes a load on the road is "
                            "positive (SAE files record it as negative: multiply by -1); negative loads mean "
                            "lift-off and give zero forces")
    if P is not None and "P" not in warned:
        top = _largest(P, absolute=False)
        if 0.0 < top < UNIT_LIMITS["P"]:
            from mftire.iotools.units import unit_factor  # the one unit table

            unit = "bar" if top < 15.0 else "psi" if top < 100.0 else "kPa"
            warn("P", f"every inflation pressure P is below {UNIT_LIMITS['P']:g} Pa (largest {top:g}): P is in "
                      f"pascals, the values look like {unit} (multiply by {unit_factor(unit, 'pressure'):.6g})")
    if Vx is not None and "Vx" not in warned:
        top = _largest(Vx, absolute=True)
        if top > UNIT_LIMITS["Vx"]:
            warn("Vx", f"speed Vx up to {top:g} m/s: Vx is in m/s; values above {UNIT_LIMITS['Vx']:g} m/s "
                       "(900 km/h) look like km/h or mm/s, and far beyond it the rolling resistance overflows")


def _largest(x, absolute: bool) -> float:
    """Largest (absolute) finite value of ``x`` (NaN and infinite values are treated as NaN, replaced
    with their own warning); 0 when there is none (fast for scalars)."""
    if isinstance(x, (int, float)):
        v = abs(x) if absolute else float(x)
        return v if math.isfinite(v) else 0.0
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError):  # not numbers: the evaluator's own check says so (MftireInputError)
        return 0.0
    a = a[np.isfinite(a)] if a.size else a
    if absolute:
        a = np.abs(a)
    return float(np.max(a)) if a.size else 0.0


def check_input_types(values: Mapping[str, Any]) -> None:
    """Refuse inputs that would become silent numbers: ``None`` (for an input without a default),
    booleans, complex numbers, dates and times, ragged sequences, masked arrays with masked points, and
    pandas objects whose indexes
    differ (they would be combined by position).  :class:`TypeError` / :class:`ValueError` saying why."""
    indexed: list[tuple[str, Any]] = []
    for name, v in values.items():
        if v is None:
            if name in ("Vx", "P", "omega"):
                continue  # None: the default (LONGVL, INFLPRES, estimated)
            raise TypeError(f"{name} is None: give a number or an array (in SI units)")
        if isinstance(v, (bool, np.bool_)):
            raise TypeError(f"{name} = {v!r} is a boolean, not a number (in SI units)")
        if isinstance(v, (complex, np.complexfloating)):
            raise TypeError(f"{name} = {v!r} is a complex number; give a real one (in SI units)")
        if isinstance(v, np.ma.MaskedArray):
            if np.ma.getmaskarray(v).any():
                raise ValueError(f"{name} is a masked array with {int(np.ma.getmaskarray(v).sum())} masked "
                                 f"point(s): drop them, or pass {name}.filled(numpy.nan) (NaN inputs are replaced "
                                 "by 0 with a warning)")
            continue
        index = getattr(v, "index", None)
        if index is not None and hasattr(v, "to_numpy") and hasattr(index, "equals"):
            indexed.append((name, index))
        if isinstance(v, (list, tuple)):
            try:
                v = np.asarray(v)
            except (TypeError, ValueError):
                raise ValueError(f"{name} is a ragged sequence (rows of different lengths): give a number or "
                                 "an array of one shape") from None
        dtype = getattr(v, "dtype", None)
        kind = getattr(dtype, "kind", None)
        if kind == "b":
            raise TypeError(f"{name} holds booleans, not numbers (in SI units)")
        if kind == "c":
            raise TypeError(f"{name} holds complex numbers; give real ones (in SI units)")
        if kind in ("M", "m") or isinstance(v, (np.datetime64, np.timedelta64)) or _is_datetime(v):
            raise TypeError(f"{name} holds dates or times, not numbers (in SI units)")
        if kind == "O":
            for x in np.asarray(v).ravel():
                if x is None or isinstance(x, (bool, np.bool_)) or _is_datetime(x) or \
                        isinstance(x, (np.datetime64, np.timedelta64)):
                    raise TypeError(f"{name} holds {type(x).__name__} values, not numbers (in SI units)")
    for (n1, i1), (n2, i2) in zip(indexed, indexed[1:], strict=False):
        if len(i1) == len(i2) and not i1.equals(i2):
            raise ValueError(f"{n1} and {n2} are pandas objects with different indexes; they would be combined "
                             "by position: align them (Series.align, reindex) or pass .to_numpy()")


def _is_datetime(x: Any) -> bool:
    import datetime

    return isinstance(x, (datetime.date, datetime.time, datetime.timedelta))


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


def check_constants(flat: Mapping[str, float], path: Any = None, extensions: Mapping[str, Any] | None = None) -> None:
    """The one parameter check of every consumer (:func:`mftire.iotools.tir_checks.value_errors`:
    FNOMIN, UNLOADED_RADIUS, NOMPRES, LFZO, LONGVL ... finite and in range, ranges not inverted,
    friction within rubber's, extension coefficients not absurd); the first problem raises
    :class:`~mftire.iotools.tir_checks.TirCheckError`."""
    from mftire.iotools.tir_checks import value_errors

    where = f"{path}: " if path else ""
    for key in ("FNOMIN", "UNLOADED_RADIUS"):
        v = flat[key]
        if not np.isfinite(v):
            raise TirCheckError(f"{where}{key} = {float(v):g} must be > 0")
    errors = value_errors(flat) + extension_errors(extensions)
    if errors:
        more = f" (and {len(errors) - 1} more problem(s); see mftire info)" if len(errors) > 1 else ""
        raise TirCheckError(f"{where}{errors[0]}{more}")


#: An extension coefficient beyond this multiple of its form's fitting bounds is absurd
#: (:data:`mftire.mf.extensions.FORMS`; e.g. C1 = 1e300 gives forces of 1e304 N).
EXTENSION_BOUND_FACTOR = 1e3


def extension_errors(section: Mapping[str, Any] | None) -> list[str]:
    """Absurd terms of an ``[MFTIRE_EXTENSIONS]`` section: a coefficient beyond
    :data:`EXTENSION_BOUND_FACTOR` times its form's fitting bounds, a zero ``SCALE``."""
    if not section:
        return []
    from mftire.errors import MftireInputError
    from mftire.mf.extensions import SECTION, parse_section

    try:
        ext = parse_section(section)
    except MftireInputError:
        return []  # the section's own errors are raised where it is parsed
    out = []
    for t in ext.terms:
        for key in t.coefficient_keys:
            v = t.numbers.get(key, 0.0)
            lo, hi = t.bounds(key)
            limit = EXTENSION_BOUND_FACTOR * max(abs(lo), abs(hi), 1.0)
            if isinstance(v, (int, float)) and math.isfinite(float(v)) and abs(float(v)) > limit:
                out.append(f"[{SECTION}] {key} = {float(v):g} is absurd for a {t.form.name} term (fitting bounds "
                           f"{lo:g} .. {hi:g}; limit |{key}| <= {limit:g})")
        scale = t.numbers.get(t.key("SCALE"))
        if isinstance(scale, (int, float)) and float(scale) == 0.0:
            out.append(f"[{SECTION}] {t.key('SCALE')} = 0: z = (u - REF)/SCALE divides by it")
    return out


__all__ = ["EVALUATE_ARGUMENTS", "EXTENSION_BOUND_FACTOR", "UNIT_LIMITS", "check_constants", "check_input_types",
           "check_keywords", "extension_errors", "warn_units"]
