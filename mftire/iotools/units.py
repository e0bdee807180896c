"""The unit table of mftire: every unit name any reader accepts, with its exact SI factor.

One table serves the ``.tir`` reader (``[UNITS]`` section, :mod:`mftire.iotools.tir`),
the sweep-table conversions (:mod:`mftire.iotools.sweeps`), the TYDEX reader and writer
(:mod:`mftire.iotools.tydex`) and the column checks of the fitter
(:mod:`mftire.iotools.loaders`).  Factors are exact rationals (:class:`fractions.Fraction`),
so a reader can convert with one correct rounding; ``float(factor)`` is the float factor.

Names are looked up after :func:`normalise_unit` (lower case; brackets, blanks, ``*``,
``·``, ``.``, ``-`` and ``×`` removed), so ``"N*m"``, ``"N.m"`` and ``"Nm"`` are one name, as
are ``"pound-force"`` and ``"poundforce"``.  A name may appear under several dimensions
(``lb`` is a force and a mass); the caller always says which dimension it wants.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from fractions import Fraction

from mftire.errors import MftireInputError

__all__ = [
    "SI_UNITS",
    "DIMENSIONS",
    "PLOT_UNITS",
    "UNITS",
    "normalise_unit",
    "is_known_unit",
    "exact_factor",
    "unit_factor",
]

#: The SI unit of each sweep-schema column (and of the extra channels the TYDEX reader names).
SI_UNITS: dict[str, str] = {
    "Fz": "N",
    "kappa": "-",
    "alpha": "rad",
    "gamma": "rad",
    "Vx": "m/s",
    "P": "Pa",
    "phit": "1/m",
    "Fx": "N",
    "Fy": "N",
    "Mz": "N.m",
    "Mx": "N.m",
    "My": "N.m",
    "meas_no": "-",
    "time": "s",
    "deflection": "m",
    "Re": "m",
    "Rl": "m",
    "omega": "rad/s",
}
#: Physical dimension of each schema column, used to check a unit makes sense.
DIMENSIONS: dict[str, str] = {
    "Fz": "force",
    "Fx": "force",
    "Fy": "force",
    "Mx": "moment",
    "My": "moment",
    "Mz": "moment",
    "kappa": "ratio",
    "alpha": "angle",
    "gamma": "angle",
    "Vx": "speed",
    "P": "pressure",
    "phit": "curvature",
    "meas_no": "count",
    "time": "time",
    "deflection": "length",
    "Re": "length",
    "Rl": "length",
    "omega": "angular_speed",
}
#: Axis-label form of the SI unit of each column: the unit names of :data:`SI_UNITS` (the FMI/SI names the
#: model spec uses, ``N.m``), with the product dot printed as ``·`` (``N·m``).
PLOT_UNITS: dict[str, str] = {c: u.replace(".", "·") for c, u in SI_UNITS.items()}

_PI = Fraction(math.pi)  # the float pi, exactly
_DEG = _PI / 180
_LBF = Fraction("4.4482216152605")  # N
_INCH = Fraction("0.0254")  # m
_FT = Fraction("0.3048")  # m
_KGF = Fraction("9.80665")  # N (standard gravity)
_RPM = 2 * _PI / 60

#: ``UNITS[dimension][normalised name]`` = exact factor to SI.
UNITS: dict[str, dict[str, Fraction]] = {}


def normalise_unit(unit: str | None) -> str:
    """Lower-case a unit string and drop brackets, blanks and multiplication signs."""
    if unit is None:
        return ""
    u = str(unit).strip()
    if len(u) >= 2 and u[0] in "[(" and u[-1] in "])":
        u = u[1:-1].strip()
    u = u.lower().replace("µ", "u").replace("²", "^2")
    if u in ("-", "--"):
        return "-"
    for ch in (" ", "*", "·", ".", "-", "×"):
        u = u.replace(ch, "")
    return u


def _add(dimension: str, table: Mapping[Iterable[str] | str, Fraction | int]) -> None:
    dim = UNITS.setdefault(dimension, {})
    for names, factor in table.items():
        for name in (names,) if isinstance(names, str) else names:
            key = name if name in ("", "-") else normalise_unit(name)
            if key in dim and dim[key] != factor:
                raise AssertionError(f"unit {name!r} listed twice for {dimension} with different factors")
            dim[key] = Fraction(factor)


_add("angle", {("rad", "radian", "radians"): 1, "mrad": Fraction(1, 1000),
               ("deg", "degree", "degrees", "°", "grd"): _DEG})
_add("ratio", {("", "-", "1", "none", "ratio", "frac", "unitless"): 1, ("%", "percent", "pct"): Fraction(1, 100)})
_add("speed", {"m/s": 1, ("km/h", "kmh", "kph", "km/hr"): Fraction(1000, 3600), "mph": Fraction("0.44704"),
               "mm/s": Fraction(1, 1000), "ft/s": _FT})
_add("pressure", {("pa", "pascal", "pascals", "n/m^2", "n/m2"): 1, "hpa": 100, "mbar": 100,
                  ("kpa", "kilopascal", "kilopascals"): 1000, "bar": 10**5,
                  ("mpa", "megapascal", "megapascals", "n/mm^2", "n/mm2"): 10**6, "psi": _LBF / _INCH**2})
_add("force", {("n", "newton", "newtons"): 1, ("kn", "kilonewton", "kilonewtons"): 1000, "dan": 10,
               "mn": Fraction(1, 1000), ("lbf", "lb", "pound_force", "poundforce", "pound-force"): _LBF,
               ("kgf", "kp", "kilogram_force", "kilogram-force"): _KGF})
_add("moment", {"nm": 1, "knm": 1000, "danm": 10, "nmm": Fraction(1, 1000),
                ("lbfft", "ftlbf", "ftlb", "lbft"): _LBF * _FT,
                ("lbfin", "inlbf"): _LBF * _INCH, ("kgfm", "kpm"): _KGF})
_add("length", {("m", "meter", "metre", "meters", "metres"): 1,
                ("mm", "millimeter", "millimetre", "millimeters", "millimetres"): Fraction(1, 1000),
                ("cm", "centimeter", "centimetre", "centimeters", "centimetres"): Fraction(1, 100),
                ("km", "kilometer", "kilometre", "kilometers", "kilometres"): 1000,
                ("in", "inch", "inches"): _INCH, ("ft", "foot", "feet"): _FT})
_add("mass", {("kg", "kilogram", "kilograms", "kilogramme"): 1, ("g", "gram", "grams", "gramme"): Fraction(1, 1000),
              ("tonne", "tonnes", "metric_ton"): 1000,
              ("lbm", "lb", "pound", "pounds", "pound_mass"): Fraction("0.45359237")})
_add("time", {("s", "sec", "second", "seconds"): 1,
              ("ms", "msec", "millisecond", "milliseconds"): Fraction(1, 1000),
              ("min", "minute", "minutes"): 60, ("h", "hr", "hour", "hours"): 3600})
_add("angular_speed", {("rad/s", "1/s"): 1, "deg/s": _DEG, ("rpm", "1/min", "u/min", "rev/min"): _RPM,
                       "rps": 2 * _PI})
_add("curvature", {("1/m", "rad/m"): 1, "1/mm": 1000, "1/km": Fraction(1, 1000)})
_add("count", {("", "-", "1", "none", "#", "no", "unitless"): 1})
# Temperatures convert to deg C (the unit of rig temperature channels), an affine map:
# value_C = value * factor + offset (:func:`unit_offset`).  The TYDEX reader only uses them to
# recognise a unit; it keeps temperature channels as read.
_add("temperature", {("degc", "°c", "c", "celsius", "k", "kelvin"): 1,
                     ("degf", "°f", "fahrenheit"): Fraction(5, 9)})
#: (normalised unit, dimension) -> additive offset after the factor (affine units only).
_OFFSETS: dict[tuple[str, str], float] = {
    **{(normalise_unit(u), "temperature"): -273.15 for u in ("k", "kelvin")},
    **{(normalise_unit(u), "temperature"): -32.0 * 5.0 / 9.0 for u in ("degf", "°f", "fahrenheit")},
}


def unit_offset(unit: str | None, dimension: str) -> float:
    """Additive offset of an affine unit (temperatures): ``value_SI = value * factor + offset``."""
    unit_factor(unit, dimension)  # raises on an unknown unit
    return _OFFSETS.get((normalise_unit(unit), dimension), 0.0)

_ANY: dict[str, set[str]] = {}
for _dim, _names in UNITS.items():
    for _name in _names:
        _ANY.setdefault(_name, set()).add(_dim)


def is_known_unit(unit: str | None) -> bool:
    """True when ``unit`` (e.g. ``"km/h"``, ``"deg C"``, ``"N*m"``) is a unit mftire knows."""
    key = normalise_unit(unit)
    return bool(key) and key in _ANY


def exact_factor(unit: str | None, dimension: str) -> Fraction | None:
    """Exact factor from ``unit`` to the SI unit of ``dimension``, or None when not a unit of it."""
    key = normalise_unit(unit)
    if dimension in ("ratio", "count") and key == "":
        return Fraction(1)
    return UNITS.get(dimension, {}).get(key)


def unit_factor(unit: str | None, dimension: str) -> float:
    """Factor that turns values in ``unit`` into the SI unit of ``dimension``.

    Parameters
    ----------
    unit : str
        Unit as written in a file, e.g. ``"deg"``, ``"km/h"``, ``"kN"``, ``"%"``, ``"N*m"``.
    dimension : str
        One of ``angle, ratio, speed, pressure, force, moment, length, mass, time,
        angular_speed, curvature, count``.

    Returns
    -------
    float
        ``value_SI = value * factor``.

    Raises
    ------
    MftireInputError
        When the unit is unknown or belongs to another dimension.
    """
    factor = exact_factor(unit, dimension)
    if factor is None:
        dims = _ANY.get(normalise_unit(unit), set())
        known = sorted(k for k in UNITS.get(dimension, {}) if k)
        what = "unknown unit" if not dims else f"unit of {'/'.join(sorted(dims))}, not {dimension},"
        raise MftireInputError(
            f"{what} {unit!r} for a {dimension} value; known {dimension} units: {', '.join(known)}"
        )
    return float(factor)
