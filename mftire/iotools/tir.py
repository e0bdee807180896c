r"""Read and write TYDEX-style ``.tir`` Magic Formula tyre property files.

:func:`read_tir` parses a file into a :class:`TirParameters` (ordered sections of
ordered ``KEY = value`` pairs, in SI units); :func:`write_tir` writes one back so
that ``read_tir(write_tir(read_tir(f)))`` equals ``read_tir(f)`` exactly (floats
are written with :func:`repr`, which round-trips every double bit for bit).

Accepted syntax
---------------
* ``[SECTION]`` headers and ``KEY = value`` lines, in any letter case (both are
  normalised to upper case), with any spacing or tabs, ``KEY=value`` too.
* Comments: a line starting with ``$`` or ``!``; text after ``$`` or ``!`` on a
  data line is kept as the key's description and written back.
* Values: numbers in any usual format (``1``, ``+3``, ``-.5``, ``1.``, ``1E3``,
  ``1.2e+03``, ``1.0D+03``, ``inf``, ``nan``), quoted strings (``'..'`` or
  ``".."``) and bare words (read as strings).  Integers stay :class:`int`.
* Blank lines, Windows/old-Mac line endings, a UTF-8 byte-order mark; non-UTF-8
  files are read as Latin-1.
* Sections and keys the reader does not know are kept and written back.  A section
  whose lines are not ``KEY = value`` lines is a table (e.g. ``[SHAPE]`` with a
  ``{radial width}`` header and rows of numbers) and is kept as a
  :class:`TirTable`.  A key/value section that appears twice is merged; a table
  section that appears twice is kept as a second table named ``NAME#2`` (written
  back as ``[NAME]``).
* Comment lines before the first section are kept (``header_comments``), except
  ``$-----`` separator lines; other full-line comments are dropped.

Writing
-------
Sections and keys are written in their order, one ``KEY = value $description``
per line (the file's own description, else the table's), floats with
:func:`repr`, strings quoted, ``[UNITS]`` in SI, with Windows (CRLF) line ends by
default: MFeval 4.0's reader drops the last character of every line, assuming it
is a carriage return, and the MFeval and ADAMS example files all use CRLF.

``FITTYP`` and ``PROPERTY_FILE_FORMAT``
--------------------------------------
No version is invented: the file must say which model it holds.  ``FITTYP`` in
``[MODEL]`` (5 MF-Tyre 5.0, 6 and 21 MF 5.2, 61 MF 6.1, 62 MF 6.2; an integral float or
a quoted number is accepted) decides when present; any other value raises
:class:`UnknownFittypError` with a hint (``52``: "an MF 5.2 file has FITTYP = 6").
Without ``FITTYP``, a ``PROPERTY_FILE_FORMAT`` that names the model
(:data:`FORMAT_MODELS`: ``'PAC2002'``, ``'MF_05'``, ``'MF_52'``, ``'MF_61'``, ``'MF6.2'``,
compared by :func:`format_token`) is enough; a generic one (``'USER'``, ``'MF-TYRE'``) or
none raises :class:`MissingFittypError`, another tyre model (``'PAC89'``, ``'PAC-TIME'``)
:class:`UnsupportedFormatError`.  A ``PROPERTY_FILE_FORMAT`` naming another equation set
than ``FITTYP`` is a :class:`TirWarning` (FITTYP decides).  ``TirParameters.fittyp`` is
the file's FITTYP or None, ``.format`` what the file says (``'FITTYP 61'``, ``'MF_05'``,
``'PAC2002'``, ``'MF_61'``), ``.model`` the equation set.

Units
-----
The values are converted to SI on read, per parameter, using the ``[UNITS]``
section and the unit column of :data:`mftire.parameters.PARAMETERS`.  After
reading, ``[UNITS]`` reports SI (non-SI entries are replaced by ``'meter'``,
``'newton'``, ``'radian'``, ``'kg'``, ``'second'``, ``'pascal'``; missing
entries of the first five are added).  An absent ``PRESSURE`` means
FORCE/LENGTH²; an absent ``[UNITS]`` means SI.

=========  ==================================================================
Quantity   Accepted unit names (case-insensitive) → SI factor
=========  ==================================================================
LENGTH     meter/metre/m 1; mm/millimeter 1e-3; cm/centimeter 1e-2;
           km 1e3; inch/in 0.0254; foot/ft 0.3048
FORCE      newton/N 1; kN/kilonewton 1e3; lbf/pound_force 4.4482216152605;
           kgf 9.80665
ANGLE      radian(s)/rad 1; deg/degree(s) π/180
MASS       kg/kilogram 1; gram/g 1e-3; tonne 1e3; lbm/lb/pound 0.45359237
TIME       second/s/sec 1; millisecond/ms 1e-3; minute/min 60; hour/h 3600
PRESSURE   pascal/Pa 1; kPa 1e3; MPa 1e6; bar 1e5; psi 6894.757…
=========  ==================================================================

The full list (also daN, kp, hPa, mbar, ...) is :data:`mftire.iotools.units.UNITS`, the
one unit table of mftire; names are matched after :func:`~mftire.iotools.units.normalise_unit`.

=====================================================  ==========  ===========
Parameters (see the table for the full list)           SI unit     Converted
=====================================================  ==========  ===========
UNLOADED_RADIUS, WIDTH, RIM_RADIUS, RIM_WIDTH,         m           yes
BOTTOM_OFFST, ELLIPS_MAX_STEP, ROAD_INCREMENT
FNOMIN, FZMIN, FZMAX                                   N           yes
VERTICAL_STIFFNESS, BOTTOM_STIFF, LONGITUDINAL_/       N/m         yes
LATERAL_STIFFNESS
VERTICAL_DAMPING                                       N·s/m       yes
YAW_STIFFNESS                                          N·m/rad     yes
NOMPRES, INFLPRES, PRESMIN, PRESMAX                    Pa          yes
IP, IP_NOM (PAC2002 ``[TIRE_CONDITIONS]``)             Pa          yes
MASS, BELT_MASS, MBELT                                 kg          yes
IXX, IYY, BELT_IXX, BELT_IYY                           kg·m²       yes
LONGVL, VXLOW                                          m/s         yes
GRAVITY                                                m/s²        yes
ALPMIN, ALPMAX, CAMMIN, CAMMAX                         rad         yes
HMAX_LOCAL, TIME_SWITCH_INTEG, DAMP_RESIDUAL,          s           yes
DAMP_VLOW
FREQ_LONG, FREQ_LAT, FREQ_YAW, FREQ_WINDUP             1/s (Hz)    yes
KPUMIN/KPUMAX, ratios, scaling factors and all MF      -           no
shape coefficients (Pxxx, Qxxx, Rxxx, Sxxx, Q_xxx,
PCFx, ...)
unknown keys                                           ?           no (warning)
=====================================================  ==========  ===========

MF shape coefficients are dimensionless or relate to angles in radians (e.g.
``PKY3`` in 1/rad) and are never converted: the Magic Formula is defined on SI
inputs, so a file that declares ``ANGLE = 'deg'`` still holds its coefficients
for angles in radians.  Conversions by rational factors are correctly rounded
(computed with :class:`fractions.Fraction`).

Errors
------
Every problem raises :class:`TirError` (a :class:`mftire.errors.MftireError`)
or one of its subclasses, with the file name, line number and offending text in
the message: :class:`MalformedLineError`, :class:`NonNumericValueError`,
:class:`UnknownUnitError`, :class:`UnknownFittypError`,
:class:`MissingFittypError`, :class:`UnsupportedFormatError`,
:class:`DuplicateKeyError` (a key twice in one section, under ``strict``),
:class:`EmptyFileError`.

Tolerated quirks of real files: a blank value (``KEY =``) or a non-numeric value on
a standard numeric key that the evaluator does not use (``MASS = kg``), and a blank value
on a key it uses that has a default (``INFLPRES =``, the ranges), are treated as absent,
with one :class:`TirWarning` per file naming every line; a blank or non-numeric value on
a required key (:func:`mftire.iotools.tir_checks.required_keys`), a blank force or moment
coefficient the evaluator uses (``tir_checks.COEFFICIENT_SECTIONS``), or text on a key the
evaluator uses (:data:`mftire.iotools.evaluator_keys.EVALUATOR_KEYS`), is an error.  A key given
twice in a section is a :class:`TirWarning` and the last value counts (as MFeval and
Chrono read files).  Adams's ``(COMMENTS)`` / ``{comment_string}`` / quoted-line blocks
inside a section are kept (``TirParameters.blocks``) and written back.
``read_tir(path, strict=True)`` makes every warning an error.
"""

from __future__ import annotations

import copy
import math
import os
import re
import warnings
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

from mftire.errors import MftireError
from mftire.iotools.atomic import write_text_atomic
from mftire.iotools.units import UNITS, exact_factor
from mftire.parameters import BY_KEY, OTHER_UNITS, STANDARD_SECTIONS, UNIT_DIMENSIONS

__all__ = [
    "DuplicateKeyError",
    "EmptyFileError",
    "FITTYP_MODELS",
    "FORMAT_MODELS",
    "FittypError",
    "MalformedLineError",
    "MissingFittypError",
    "NonNumericValueError",
    "TirError",
    "TirParameters",
    "TirTable",
    "TirWarning",
    "KNOWN_EXTRA_KEYS",
    "UnknownFittypError",
    "UnknownKeyError",
    "UnknownUnitError",
    "UnsupportedFormatError",
    "format_token",
    "format_tir",
    "parse_tir",
    "read_tir",
    "write_tir",
]

Value = float | int | str

#: FITTYP values the reader accepts, with the model they denote (21: MF 5.2 coefficients in an
#: MF-Tyre 6.0 file; MFeval and its ports evaluate 6 and 21 alike).
FITTYP_MODELS: dict[int, str] = {5: "MF-Tyre 5.0", 6: "MF 5.2", 21: "MF 5.2", 61: "MF 6.1", 62: "MF 6.2"}

#: ``PROPERTY_FILE_FORMAT`` spellings that name the model of a file without ``FITTYP``, compared
#: after :func:`format_token` (upper case; blanks, ``-``, ``_`` and ``.`` removed: ``'MF_05'``,
#: ``'mf-05'`` and ``'MF 05'`` are one token).
FORMAT_MODELS: dict[str, str] = {
    "PAC2002": "PAC2002", "PAC02": "PAC2002",
    "MF05": "MF-Tyre 5.0", "MF50": "MF-Tyre 5.0", "MFTYRE50": "MF-Tyre 5.0",
    "MF52": "MF 5.2", "MFTYRE52": "MF 5.2",
    "MF61": "MF 6.1", "MFTYRE61": "MF 6.1",
    "MF62": "MF 6.2", "MFTYRE62": "MF 6.2",
}  # fmt: skip
#: ``PROPERTY_FILE_FORMAT`` values that do not say which Magic Formula version a file holds (its
#: ``FITTYP`` does): TNO's MF-Tyre/MF-Swift exports, MFeval's ``'USER'``.
GENERIC_FORMATS = frozenset({"", "USER", "MFTYRE", "MFSWIFT", "TNO", "TNOMF", "MF", "DEFAULT", "MAGICFORMULA"})
#: ``PROPERTY_FILE_FORMAT`` values of other tyre models that share the ``.tir`` layout, not the equations.
OTHER_MODELS: dict[str, str] = {
    "PACTIME": "PAC-TIME", "PACMC": "PAC MC (motorcycle)", "PAC89": "Pacejka '89", "PAC94": "Pacejka '94",
    "FIALA": "Fiala", "UA": "UA tire", "FTIRE": "FTire", "5PT": "Adams 5.2.1",
}  # fmt: skip


def format_token(value: Any) -> str:
    """``PROPERTY_FILE_FORMAT`` compared as a token: upper case without blanks, ``-``, ``_``, ``.``."""
    return re.sub(r"[\s_.\-]", "", str(value).upper()) if isinstance(value, str) else ""


def _fittyp_number(value: Any) -> int | None:
    """The FITTYP as an int when it is one of :data:`FITTYP_MODELS`, else None."""
    if isinstance(value, float) and value.is_integer():
        value = int(value)
    return value if _is_number(value) and value in FITTYP_MODELS else None


# --------------------------------------------------------------------------- errors
class TirError(MftireError):
    """A ``.tir`` file could not be read or written.

    Attributes
    ----------
    path : str
        The file (or ``"<string>"``).
    line : int or None
        1-based line number of the offending line.
    text : str or None
        The offending line (stripped).
    reason : str
        The problem, without location.
    """

    def __init__(self, reason: str, path: Any = None, line: int | None = None, text: str | None = None):
        self.reason = reason
        self.path = "<string>" if path is None else str(path)
        self.line = line
        self.text = text
        where = self.path if line is None else f"{self.path}, line {line}"
        message = f"{where}: {reason}"
        if text is not None:
            message += f": {text!r}"
        super().__init__(message)


class MalformedLineError(TirError):
    """A line that is neither a comment, a section header, ``KEY = value`` nor a table row."""


class NonNumericValueError(TirError):
    """A standard numeric key has a value that is not a number."""


class UnknownUnitError(TirError):
    """A ``[UNITS]`` entry names a unit the reader cannot convert."""


class FittypError(TirError):
    """``FITTYP`` is missing or not a supported Magic Formula version."""


class UnknownFittypError(FittypError):
    """``FITTYP`` is not one of 5, 6, 21, 61, 62."""


class MissingFittypError(FittypError):
    """The file has no ``FITTYP`` and its ``PROPERTY_FILE_FORMAT`` does not imply a model."""


class UnsupportedFormatError(FittypError):
    """``PROPERTY_FILE_FORMAT`` names another tyre model (PAC-TIME, PAC89, Fiala, ...)."""


class UnknownKeyError(TirError):
    """A key of a standard section that looks like a misspelled standard key (strict reading)."""


class TirWarning(UserWarning):
    """A tolerated problem in a ``.tir`` file (``read_tir(..., strict=True)`` makes it a :class:`TirError`)."""


class DuplicateKeyError(TirError):
    """A key appears twice in the same section."""


class EmptyFileError(TirError):
    """The file holds no section and no parameter."""


# ----------------------------------------------------------------------- values
_INT_RE = re.compile(r"[+-]?\d+\Z")
_FLOAT_RE = re.compile(r"[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eEdD][+-]?\d+)?|inf(?:inity)?|nan)\Z", re.IGNORECASE)
_KEY_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_.\-]*\Z")
_SECTION_RE = re.compile(r"\[\s*([A-Za-z0-9_][A-Za-z0-9_ .\-]*?)\s*\]\s*(?:[$!].*)?\Z")
_SEPARATOR_RE = re.compile(r"\$-{3,}")
_TABLE_HEADER_RE = re.compile(r"\{([^{}]*)\}\s*(?:[$!].*)?\Z")
_BLOCK_RE = re.compile(r"\(\s*[A-Za-z_][A-Za-z0-9_ ]*\)\s*(?:[$!].*)?\Z")
_QUOTED_ROW_RE = re.compile(r"""(?:'[^']*'|"[^"]*")\s*(?:[$!].*)?\Z""")
_DECIMAL_COMMA_RE = re.compile(r"[+-]?\d*,\d+(?:[eEdD][+-]?\d+)?\Z")


def _parse_number(token: str) -> int | float | None:
    """Return the number ``token`` spells, or None."""
    if _INT_RE.match(token):
        number = int(token)
        if number == 0 and token.startswith("-"):
            return -0.0
        return number
    if _FLOAT_RE.match(token):
        return float(token.replace("d", "e").replace("D", "e"))
    return None


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _same_value(a: Any, b: Any) -> bool:
    """Equality of two parameter values, exact to the bit for floats (-0.0 != 0.0, nan == nan)."""
    if isinstance(a, str) or isinstance(b, str):
        return isinstance(a, str) and isinstance(b, str) and a == b
    if not (_is_number(a) and _is_number(b)):
        return a == b
    if isinstance(a, int) and isinstance(b, int):
        return a == b
    try:
        fa, fb = float(a), float(b)
    except OverflowError:
        return False
    if math.isnan(fa) or math.isnan(fb):
        return math.isnan(fa) and math.isnan(fb)
    return fa == fb and math.copysign(1.0, fa) == math.copysign(1.0, fb)


# --------------------------------------------------------------------- data model
@dataclass(eq=False)
class TirTable:
    """A table-like section, e.g. ``[SHAPE]`` with a ``{radial width}`` header.

    Attributes
    ----------
    columns : list of str or None
        Column names from the ``{...}`` header line, if any.
    rows : list of list of int or float
        The numbers of each row.
    """

    columns: list[str] | None = None
    rows: list[list[int | float]] = field(default_factory=list)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, TirTable):
            return NotImplemented
        return (
            self.columns == other.columns
            and len(self.rows) == len(other.rows)
            and all(
                len(r1) == len(r2) and all(_same_value(a, b) for a, b in zip(r1, r2, strict=True))
                for r1, r2 in zip(self.rows, other.rows, strict=True)
            )
        )


Section = dict[str, Value] | TirTable


def _base_name(section: str) -> str:
    """``"SHAPE#2"`` -> ``"SHAPE"``."""
    return section.split("#", 1)[0]


class TirParameters:
    """The parameters of one ``.tir`` file: ordered sections of ordered ``KEY: value``.

    Values are :class:`float`, :class:`int` or :class:`str`, in SI units once read
    by :func:`read_tir`.  Section and key names are upper case.

    Parameters
    ----------
    sections : mapping, optional
        ``{SECTION: {KEY: value}}`` (a :class:`TirTable` for a table section).
    path : str or path-like, optional
        The source file.

    Attributes
    ----------
    sections : dict
        ``{SECTION: {KEY: value} or TirTable}`` in file order.
    comments : dict
        ``{(SECTION, KEY): description}``, the inline ``$`` comments.
    header_comments : list of str
        Comment lines found before the first section.
    path : str or None
        The file the parameters were read from.
    """

    def __init__(self, sections: dict[str, Any] | None = None, path: Any = None) -> None:
        self.sections: dict[str, Section] = {}
        self.comments: dict[tuple[str, str], str] = {}
        self.header_comments: list[str] = []
        #: ``{SECTION: [lines]}``: free-text blocks inside a section, e.g. Adams's
        #: ``(COMMENTS)`` / ``{comment_string}`` / ``'text'`` lines; kept and written back.
        self.blocks: dict[str, list[str]] = {}
        self.path: str | None = None if path is None else str(path)
        for name, body in (sections or {}).items():
            name = name.upper()
            if isinstance(body, TirTable):
                self.sections[name] = copy.deepcopy(body)
            else:
                self.sections[name] = {}
                for key, value in body.items():
                    self.set(key, value, section=name)

    # ------------------------------------------------------------------ access
    def flat(self) -> dict[str, Value]:
        """Return ``{KEY: value}`` over all key/value sections.

        ``[UNITS]`` and table sections are left out (``MASS`` is both the mass unit
        and the tyre mass in ``[INERTIA]``).  A key found in several sections takes
        the value of its standard section, else of the first section holding it.

        Returns
        -------
        dict
        """
        out: dict[str, Value] = {}
        for body in self._value_sections():
            for key in body:
                if key not in out:
                    out[key] = self._lookup(key)[key]  # type: ignore[index]
        return out

    def _value_sections(self) -> Iterator[dict[str, Value]]:
        """The key/value sections in file order: every section but ``[UNITS]`` and the tables."""
        return (body for name, body in self.sections.items() if name != "UNITS" and not isinstance(body, TirTable))

    def section(self, name: str) -> Section:
        """Return the body of section ``name`` (KeyError if absent)."""
        return self.sections[name.upper()]

    def _lookup(self, key: str) -> Section | None:
        """The section body whose value of ``key`` (upper case) :meth:`flat` returns, or None; without building
        :meth:`flat` (a parameter is read thousands of times in a fit)."""
        p = BY_KEY.get(key)
        if p is not None and p.section != "UNITS":
            body = self.sections.get(p.section)
            if body is not None and not isinstance(body, TirTable) and key in body:
                return body  # the standard section wins
        return next((body for body in self._value_sections() if key in body), None)  # else the first

    def get(self, key: str, default: Any = None) -> Any:
        """Return the value of ``key`` (see :meth:`flat`) or ``default``."""
        k = key.upper()
        body = self._lookup(k)
        return default if body is None else body[k]

    def __getitem__(self, key: str) -> Value:
        k = key.upper()
        body = self._lookup(k)
        if body is None:
            raise KeyError(key)
        return body[k]

    def __contains__(self, key: object) -> bool:
        return isinstance(key, str) and self._lookup(key.upper()) is not None

    def keys(self) -> list[str]:
        """Return the keys of :meth:`flat`."""
        return list(self.flat())

    @property
    def fittyp(self) -> int | None:
        """The ``FITTYP`` of the file as an int, or None if absent (e.g. PAC2002) or not supported."""
        return _fittyp_number(self.get("FITTYP"))

    @property
    def model(self) -> str:
        """Model family: what the equations are.

        One of ``"MF 6.2"``, ``"MF 6.1"``, ``"MF 5.2"`` (FITTYP 6 or 21, or a
        ``PROPERTY_FILE_FORMAT`` such as ``'MF_52'``), ``"MF-Tyre 5.0"`` (FITTYP 5 or
        ``'MF_05'``), ``"PAC2002"`` or ``"unknown"``.  ``FITTYP`` decides when a file has one;
        else ``PROPERTY_FILE_FORMAT`` (:data:`FORMAT_MODELS`).
        """
        fittyp = self.fittyp
        if fittyp is not None:
            return FITTYP_MODELS[fittyp]
        return FORMAT_MODELS.get(format_token(self.get("PROPERTY_FILE_FORMAT")), "unknown")

    @property
    def format(self) -> str:
        """The format as the file states it, no version invented.

        ``"FITTYP 61"`` (``62``, ``6``, ``21``) for a file with a ``FITTYP``,
        ``"MF_05"`` for an MF-Tyre 5.0 file (``FITTYP = 5``), else the file's
        ``PROPERTY_FILE_FORMAT`` in upper case (``"PAC2002"``, ``"MF_05"``, ``"MF_61"``, ...)
        or ``"unknown"``.
        """
        fittyp = self.fittyp
        if fittyp == 5:
            return "MF_05"
        if fittyp is not None:
            return f"FITTYP {fittyp}"
        fmt = self.get("PROPERTY_FILE_FORMAT")
        return fmt.strip().upper() if isinstance(fmt, str) and fmt.strip() else "unknown"

    # ---------------------------------------------------------------- changing
    def set(self, key: str, value: Value, section: str | None = None) -> None:
        """Set ``key`` to ``value``.

        Parameters
        ----------
        key : str
            Parameter name (case-insensitive).
        value : float, int or str
            New value, in SI units.
        section : str, optional
            Section to put the key in (created if needed).  By default the key is
            updated where it already is; a new standard key goes to its standard
            section, and a new unknown key needs ``section``.
        """
        if not isinstance(key, str) or not _KEY_RE.match(key):
            raise ValueError(f"invalid .tir key {key!r}")
        if isinstance(value, bool) or not isinstance(value, (int, float, str)):
            raise TypeError(f"a .tir value must be a float, int or str, not {type(value).__name__}")
        key = key.upper()
        if section is None:
            holders = [
                n for n, b in self.sections.items() if isinstance(b, dict) and key in b and n != "UNITS"
            ]
            p = BY_KEY.get(key)
            if p is not None and p.section in holders:
                section = p.section
            elif holders:
                section = holders[0]
            elif p is not None:
                section = p.section
            else:
                raise ValueError(f"{key} is not a standard .tir key: give the section to put it in")
        section = section.upper()
        body = self.sections.get(section)
        if body is None:
            body = self._add_section(section)
        if isinstance(body, TirTable):
            raise ValueError(f"[{section}] is a table section")
        body[key] = value

    def _add_section(self, name: str) -> dict[str, Value]:
        """Create an empty key/value section, placed in standard order if it is standard."""
        body: dict[str, Value] = {}
        if name in STANDARD_SECTIONS:
            rank = STANDARD_SECTIONS.index(name)
            names = list(self.sections)
            at = len(names)
            for i, other in enumerate(names):
                if other in STANDARD_SECTIONS and STANDARD_SECTIONS.index(other) > rank:
                    at = i
                    break
            items = list(self.sections.items())
            items.insert(at, (name, body))
            self.sections = dict(items)
        else:
            self.sections[name] = body
        return body

    def copy(self) -> TirParameters:
        """Return a deep copy: every container new; the values (numbers and strings) are immutable and shared,
        which is what makes it fast (a fit copies its parameters often)."""
        new = object.__new__(type(self))
        new.__dict__.update({k: copy.deepcopy(v) for k, v in self.__dict__.items()
                             if k not in ("sections", "comments", "header_comments", "blocks")})  # fmt: skip
        new.sections = {name: copy.deepcopy(body) if isinstance(body, TirTable) else dict(body)
                        for name, body in self.sections.items()}  # fmt: skip
        new.comments = dict(self.comments)
        new.header_comments = list(self.header_comments)
        new.blocks = {name: list(lines) for name, lines in self.blocks.items()}
        return new

    # ------------------------------------------------------------------ compare
    def __eq__(self, other: object) -> bool:
        if not isinstance(other, TirParameters):
            return NotImplemented
        if set(self.sections) != set(other.sections):
            return False
        for name, body in self.sections.items():
            theirs = other.sections[name]
            if isinstance(body, TirTable) or isinstance(theirs, TirTable):
                if not (isinstance(body, TirTable) and isinstance(theirs, TirTable) and body == theirs):
                    return False
                continue
            if set(body) != set(theirs) or not all(_same_value(v, theirs[k]) for k, v in body.items()):
                return False
        return True

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        n = sum(len(b) for b in self.sections.values() if isinstance(b, dict))
        return f"<TirParameters {self.model} {n} keys in {len(self.sections)} sections from {self.path!r}>"


# --------------------------------------------------------------------- units
# The names and exact factors are those of mftire.iotools.units (one table for every reader).
_UNIT_FACTORS: dict[str, dict[str, Fraction]] = {
    q: UNITS[q.lower()] for q in ("LENGTH", "FORCE", "ANGLE", "MASS", "TIME", "PRESSURE")
}
_UNIT_QUANTITIES = ("LENGTH", "FORCE", "ANGLE", "MASS", "TIME", "PRESSURE")
_SI_NAMES = {
    "LENGTH": "meter",
    "FORCE": "newton",
    "ANGLE": "radian",
    "MASS": "kg",
    "TIME": "second",
    "PRESSURE": "pascal",
}


def _unit_factor(quantity: str, name: str) -> Fraction | None:
    return exact_factor(name, quantity.lower())


def _scale(value: int | float, factor: Fraction) -> float:
    """``value * factor``, correctly rounded for finite values; keeps the sign of zero."""
    if isinstance(value, float) and not math.isfinite(value):
        return value * float(factor)
    if value == 0:
        return float(value)
    try:
        return float(Fraction(value) * factor)
    except OverflowError:
        return math.copysign(math.inf, value)


# --------------------------------------------------------------------- reading
_NO_VALUE = "missing value after '='"


class _LineProblem(Exception):
    """Internal: a problem in one line, turned into a TirError with its location."""

    def __init__(self, cls: type[TirError], reason: str) -> None:
        super().__init__(reason)
        self.cls = cls
        self.reason = reason


def _split_value(rest: str) -> tuple[Value, bool, str | None]:
    """Parse the text after ``=``: return (value, was_quoted, comment)."""
    rest = rest.strip()
    if not rest or rest[0] in "$!":
        raise _LineProblem(MalformedLineError, _NO_VALUE)
    if rest[0] in "'\"":
        quote = rest[0]
        end = rest.find(quote, 1)
        if end == -1:
            raise _LineProblem(MalformedLineError, "unterminated quoted string")
        raw: str = rest[1:end]
        tail = rest[end + 1 :].strip()
        quoted = True
    else:
        m = re.search(r"[$!]", rest)
        raw = (rest[: m.start()] if m else rest).strip()
        tail = rest[m.start() :] if m else ""
        quoted = False
    comment = None
    if tail:
        if tail[0] not in "$!":
            raise _LineProblem(MalformedLineError, "unexpected text after the value")
        comment = tail[1:].strip()
    if quoted:
        return raw, True, comment
    number = _parse_number(raw)
    return (raw if number is None else number), False, comment


_CONTROL_RE = re.compile(r"[\x00-\x08\x0e-\x1f\x7f]")


def _decode(data: bytes) -> str:
    """The file's text: UTF-16 (with a byte-order mark, or ASCII text saved as UTF-16 without
    one, as some Windows editors do), else UTF-8, else Latin-1."""
    utf16 = None
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        utf16 = "utf-16"
    elif len(data) >= 4 and data[1::2][:64].count(0) > 24 and data[0::2][:64].count(0) == 0:
        utf16 = "utf-16-le"
    elif len(data) >= 4 and data[0::2][:64].count(0) > 24 and data[1::2][:64].count(0) == 0:
        utf16 = "utf-16-be"
    if utf16 is not None:
        try:
            text = data.decode(utf16)
            return text[1:] if text.startswith("\ufeff") else text
        except UnicodeDecodeError:
            pass
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        text = data.decode("latin-1")
    return text[1:] if text.startswith("\ufeff") else text


def parse_tir(text: str, path: Any = None, strict: bool = False) -> TirParameters:
    """Parse the text of a ``.tir`` file.

    Parameters
    ----------
    text : str
        File content.
    path : str or path-like, optional
        Name used in error messages and stored as ``path``.
    strict : bool, default False
        Make every :class:`TirWarning` a :class:`TirError` (see :func:`read_tir`).

    Returns
    -------
    TirParameters
        Values in SI units.

    Raises
    ------
    TirError
        On any problem (see the module docstring).
    """
    source = "<string>" if path is None else str(path)
    if text.startswith("\ufeff"):
        text = text[1:]
    lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
    params = TirParameters(path=path)
    where: dict[tuple[str, str], tuple[int, str]] = {}
    section_line: dict[str, tuple[int, str]] = {}
    current: str | None = None
    found_data = False

    def fail(cls: type[TirError], reason: str, lineno: int, line: str) -> TirError:
        return cls(reason, source, lineno, line)

    def tolerate(cls: type[TirError], key: str, reason: str, lineno: int, line: str, blank: bool) -> None:
        """A blank or non-numeric value.  Error on a required key (no sensible default), on a key
        the evaluator uses when the value is text, and under ``strict``; else a warning and the key
        is treated as absent (a blank on a key the evaluator uses takes its default)."""
        from mftire.iotools.evaluator_keys import evaluator_keys
        from mftire.iotools.tir_checks import COEFFICIENT_SECTIONS, required_keys

        used = key in evaluator_keys()
        p = BY_KEY.get(key)
        if key in required_keys():
            raise fail(cls, f"{reason} (the evaluator uses {key}, and it has no default)", lineno, line)
        if used and not blank:
            raise fail(cls, f"{reason} (the evaluator uses {key})", lineno, line)
        if used and p is not None and p.section in COEFFICIENT_SECTIONS:
            raise fail(cls, f"{reason} (the evaluator uses {key}: a coefficient of the force and moment "
                       "characteristic takes no default)", lineno, line)
        if strict:
            raise fail(cls, f"{reason} (strict reading)", lineno, line)
        default = None
        if used and p is not None:
            default = ("NOMPRES" if key == "INFLPRES" else repr(p.default) if isinstance(p.default, str)
                       else f"{p.default:g}" + ("" if p.unit == "-" else f" {p.unit}"))
        tolerated.append((lineno, reason, line, key, default))

    tolerated: list[tuple[int, str, str, str, str | None]] = []
    block: str | None = None  # the section whose free-text block (COMMENTS) is being read
    for lineno, raw in enumerate(lines, 1):
        line = raw.strip()
        if not line:
            continue
        if line[0] in "$!":
            if current is None and not _SEPARATOR_RE.match(line):
                params.header_comments.append(line)
            continue
        found_data = True
        if line[0] == "[":
            m = _SECTION_RE.match(line)
            if not m:
                raise fail(MalformedLineError, "malformed section header", lineno, line)
            name = m.group(1).upper()
            existing = params.sections.get(name)
            if isinstance(existing, TirTable):
                n = 2
                while f"{name}#{n}" in params.sections:
                    n += 1
                name = f"{name}#{n}"
                existing = None
            if existing is None:
                params.sections[name] = {}
                section_line[name] = (lineno, line)
            current = name
            block = None
            continue
        if current is None:
            raise fail(MalformedLineError, "data before the first [SECTION] header", lineno, line)
        body = params.sections[current]
        eq = line.find("=")
        is_pair = eq > 0 and not any(c in line[:eq] for c in "$!'\"{(")
        if is_pair:
            block = None
        elif block == current or (isinstance(body, dict) and _BLOCK_RE.match(line)):
            block = current  # "(COMMENTS)", "{comment_string}", "'text'": a free-text block, kept
            params.blocks.setdefault(current, []).append(line)
            continue
        elif (isinstance(body, TirTable) and not body.rows and body.columns is not None
              and _QUOTED_ROW_RE.match(line)):
            # a "{comment_string}" header with quoted rows: free text, not a table
            block = current
            params.sections[current] = {}
            params.blocks.setdefault(current, []).extend(["{" + " ".join(body.columns) + "}", line])
            continue
        if line[0] == "{":
            m = _TABLE_HEADER_RE.match(line)
            if not m:
                raise fail(MalformedLineError, "malformed table header", lineno, line)
            if isinstance(body, dict) and body:
                raise fail(MalformedLineError, f"table header inside key = value section [{current}]",
                           lineno, line)
            if isinstance(body, TirTable) and (body.columns is not None or body.rows):
                raise fail(MalformedLineError, f"second table header in section [{current}]", lineno, line)
            params.sections[current] = TirTable(columns=m.group(1).split(), rows=[])
            continue
        if not is_pair:
            if isinstance(body, dict) and body:
                raise fail(MalformedLineError, "expected KEY = value", lineno, line)
            cut = re.search(r"[$!]", line)
            tokens = (line[: cut.start()] if cut else line).split()
            numbers = [_parse_number(t) for t in tokens]
            if not tokens or any(v is None for v in numbers):
                reason = "expected KEY = value" if isinstance(body, dict) else "non-numeric table row"
                raise fail(MalformedLineError, reason, lineno, line)
            if isinstance(body, dict):
                body = params.sections[current] = TirTable()
            body.rows.append(numbers)  # type: ignore[arg-type]
            continue
        if isinstance(body, TirTable):
            raise fail(MalformedLineError, f"KEY = value line inside table section [{current}]", lineno, line)
        key = line[:eq].strip()
        if not _KEY_RE.match(key):
            raise fail(MalformedLineError, "invalid key name", lineno, line)
        key = key.upper()
        try:
            value, quoted, comment = _split_value(line[eq + 1 :])
        except _LineProblem as problem:
            if problem.reason != _NO_VALUE:
                raise fail(problem.cls, problem.reason, lineno, line) from None
            tolerate(problem.cls, key, f"{key} has no value", lineno, line, blank=True)
            continue
        p = BY_KEY.get(key)
        if current != "UNITS" and p is not None and p.unit != "str" and not _is_number(value):
            number = _parse_number(value.strip()) if quoted and isinstance(value, str) else None
            if number is None:
                text = value.strip() if isinstance(value, str) else ""
                hint = " (a decimal comma? write 0.85, not 0,85)" if _DECIMAL_COMMA_RE.match(text) else ""
                tolerate(NonNumericValueError, key, f"{key} needs a number{hint}", lineno, line, blank=not text)
                continue
            value = number
        if key in body:
            first, _ = where[(current, key)]
            same = _same_value(body[key], value)
            reason = (f"duplicate key {key} in [{_base_name(current)}] (first on line {first}"
                      + (", same value)" if same else f", value {body[key]!r}); the last value is used, as "
                         "MFeval's and Chrono's readers do"))
            if strict:
                raise fail(DuplicateKeyError, reason + " (strict reading)", lineno, line)
            warnings.warn(TirWarning(f"{source}, line {lineno}: {reason}: {line!r}"), stacklevel=3)
        body[key] = value
        where[(current, key)] = (lineno, line)
        if comment:
            params.comments[(current, key)] = comment

    if not found_data:
        raise EmptyFileError("empty file: no section and no parameter", source, max(len(lines), 1), "")
    if tolerated:
        _warn_tolerated(source, tolerated)

    _convert_units(params, where, section_line, source, strict)
    _check_fittyp(params, where, section_line, source, lines, strict)
    misspelled = _misspelled_keys(params, where)
    if misspelled and strict:
        lineno, line, reason = misspelled[0]
        raise fail(UnknownKeyError, reason + " (strict reading)", lineno, line)
    if misspelled:
        warnings.warn(TirWarning(f"{source}: " + "; ".join(f"line {n}: {r}" for n, _, r in misspelled)), stacklevel=3)
    return params


#: Keys outside the parameter table that real files carry (MF-Tyre/MF-Swift and Adams exports): never
#: reported as misspelled.
KNOWN_EXTRA_KEYS = frozenset({
    "FE_METHOD", "MFSAFE1", "MFSAFE2", "MFSAFE3", "BELT_DYNAMICS", "CONTACT_MODEL", "BOTTOMING_RADIUS",
    "DYNAMIC_STIFFNESS", "DYNAMIC_DAMPING", "LKG", "LCZ", "LIP", "PTX4", "QPX1", "PTY3", "QPZ1", "QPZ2", "MESSAGES",
    "LOCAL_SOLVER", "LOCAL_SOLVER_HP",
})  # fmt: skip


def _misspelled_keys(params: TirParameters, where: dict) -> list[tuple[int, str, str]]:
    """Keys of a standard section that are no key mftire knows but are one typo away from a key of
    that section (``LMUXX`` for ``LMUX``): ``(line number, line, reason)`` each.  Such a key is
    ignored, so the key meant silently takes its default; other unknown keys (vendor additions)
    are kept quietly."""
    import difflib

    section_keys: dict[str, list[str]] = {}
    for p in BY_KEY.values():
        section_keys.setdefault(p.section, []).append(p.key)
    out = []
    for (section, key), (lineno, line) in where.items():
        base = _base_name(section)
        if base not in section_keys or base == "MDI_HEADER" or key in BY_KEY or key in KNOWN_EXTRA_KEYS:
            continue
        close = difflib.get_close_matches(key, section_keys[base], n=1, cutoff=0.8)
        if close:
            body = params.sections.get(section)
            taken = isinstance(body, dict) and close[0] in body
            out.append((lineno, line, f"{key} in [{base}] is not a key mftire knows: did you mean {close[0]}? "
                        f"({key} is ignored" + ("" if taken else f"; {close[0]} takes its default") + ")"))
    return sorted(out)


def _warn_tolerated(source: str, tolerated: list[tuple[int, str, str, str, str | None]]) -> None:
    """One :class:`TirWarning` for every blank or non-numeric value of a file (each with its line)."""
    items = [f"line {n}: {reason}: {line!r}" for n, reason, line, _, _ in tolerated]
    keys = ", ".join(dict.fromkeys(k for *_, k, _ in tolerated))
    used = [f"{k} ({d})" for *_, k, d in tolerated if d is not None]
    text = (f"{source}: {len(items)} value(s) treated as absent ({keys}): " + "; ".join(items)
            + (f"; the evaluator uses the defaults of {', '.join(used)}" if used else ""))
    warnings.warn(TirWarning(text), stacklevel=4)


def _convert_units(params: TirParameters, where: dict, section_line: dict, source: str, strict: bool = False) -> None:
    """Convert every known dimensional value to SI and make ``[UNITS]`` report SI."""
    units = params.sections.get("UNITS")
    if isinstance(units, TirTable):
        lineno, line = section_line["UNITS"]
        raise MalformedLineError("[UNITS] must hold KEY = value lines", source, lineno, line)
    if units is None:
        units = params._add_section("UNITS")
    factors: dict[str, Fraction] = {}
    for quantity in _UNIT_QUANTITIES:
        name = units.get(quantity)
        if name is None:
            continue
        factor = _unit_factor(quantity, name) if isinstance(name, str) else None
        if factor is None:
            lineno, line = where[("UNITS", quantity)]
            raise UnknownUnitError(f"unknown {quantity.lower()} unit", source, lineno, line)
        factors[quantity] = factor
    #: the non-SI units the file declared (read by mftire.iotools.tir_checks for its hints)
    params.file_units = {q: units[q] for q, f in factors.items() if f != 1}
    for quantity in _UNIT_QUANTITIES[:5]:
        factors.setdefault(quantity, Fraction(1))
    factors.setdefault("PRESSURE", factors["FORCE"] / factors["LENGTH"] ** 2)

    if any(f != 1 for f in factors.values()):
        unconverted = []
        for name, body in params.sections.items():
            if name == "UNITS" or isinstance(body, TirTable):
                continue
            for key, value in body.items():
                if not _is_number(value):
                    continue
                p = BY_KEY.get(key)
                unit = p.unit if p is not None else OTHER_UNITS.get(key)
                if unit is None:
                    unconverted.append(key)
                    continue
                factor = Fraction(1)
                for quantity, power in UNIT_DIMENSIONS.get(unit, {}).items():
                    factor *= factors[quantity] ** power
                if factor != 1:
                    body[key] = _scale(value, factor)
        if unconverted and strict:
            raise TirError(f"non-SI [UNITS]; unknown keys left unconverted: {', '.join(unconverted)} "
                           "(strict reading)", source)
        if unconverted:
            warnings.warn(
                f"{source}: non-SI [UNITS]; unknown keys left unconverted: {', '.join(unconverted)}",
                stacklevel=3,
            )
    for quantity in _UNIT_QUANTITIES:
        if quantity in units:
            if factors[quantity] != 1:
                units[quantity] = _SI_NAMES[quantity]
        elif quantity != "PRESSURE":
            units[quantity] = _SI_NAMES[quantity]


def _fittyp_hint(value: Any) -> str:
    """A hint for a FITTYP that is not one of :data:`FITTYP_MODELS`."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        return ""
    if v in (52.0, 5.2, 520.0, 512.0):
        return "; an MF 5.2 file has FITTYP = 6 (or 21)"
    if v in (6.1, 6.2, 610.0, 620.0, 612.0):
        return f"; did you mean {61 if v in (6.1, 610.0, 612.0) else 62}?"
    if v in (5.0, 50.0, 500.0):
        return "; an MF-Tyre 5.0 file has FITTYP = 5"
    return ""


def _check_fittyp(params: TirParameters, where: dict, section_line: dict, source: str, lines: list,
                  strict: bool = False) -> None:
    """The file must say which model it holds: a supported ``FITTYP`` or a ``PROPERTY_FILE_FORMAT``
    naming one (:data:`FORMAT_MODELS`); no version is invented.  ``FITTYP`` decides when both are
    given; a ``PROPERTY_FILE_FORMAT`` naming another equation set is a :class:`TirWarning`."""
    fmt = params.get("PROPERTY_FILE_FORMAT")
    token = format_token(fmt)
    located = [(s, k) for (s, k) in where if k == "FITTYP"]
    if located:
        loc = ("MODEL", "FITTYP") if ("MODEL", "FITTYP") in where else located[0]
        lineno, line = where[loc]
        value = params.sections[loc[0]]["FITTYP"]  # type: ignore[index]
        fittyp = _fittyp_number(value)
        if fittyp is None:
            supported = "5 (MF-Tyre 5.0), 6 and 21 (MF 5.2), 61 (MF 6.1), 62 (MF 6.2)"
            raise UnknownFittypError(f"unsupported FITTYP {value!r} (supported: {supported}){_fittyp_hint(value)}",
                                     source, lineno, line)
        named = FORMAT_MODELS.get(token) or OTHER_MODELS.get(token)
        model = FITTYP_MODELS[fittyp]
        same = {named, model} <= {"PAC2002", "MF-Tyre 5.0"} or named == model  # one equation set (docs)
        reason = None
        if named is not None and not same:
            reason = (f"PROPERTY_FILE_FORMAT = {fmt!r} names {named}, but FITTYP = {fittyp} ({model}) "
                      f"decides: the file is evaluated as {model}")
        elif named is None and token not in GENERIC_FORMATS and fmt is not None:
            reason = (f"PROPERTY_FILE_FORMAT = {fmt!r} is not a format mftire knows ('USER', 'PAC2002', 'MF_05', "
                      f"'MF_52', 'MF_61', 'MF_62'); FITTYP = {fittyp} ({model}) decides")
        if reason is not None:  # an error when reading strictly, else a warning, at the PROPERTY_FILE_FORMAT line
            fline = next((where[k] for k in where if k[1] == "PROPERTY_FILE_FORMAT"), (lineno, line))
            if strict:
                raise FittypError(reason + " (strict reading)", source, fline[0], fline[1])
            warnings.warn(TirWarning(f"{source}, line {fline[0]}: {reason}"), stacklevel=4)
        return
    if token in FORMAT_MODELS:
        return
    if "MODEL" in section_line:
        lineno, line = section_line["MODEL"]
    else:
        lineno = next((i for i, t in enumerate(lines, 1) if t.strip()), 1)
        line = lines[lineno - 1].strip() if lines else ""
    floc = next((where[k] for k in where if k[1] == "PROPERTY_FILE_FORMAT"), None)
    if token in OTHER_MODELS:
        raise UnsupportedFormatError(
            f"PROPERTY_FILE_FORMAT = {fmt!r} is the {OTHER_MODELS[token]} tyre model, not a Magic Formula file "
            "mftire evaluates (MF 5.2, PAC2002, MF-Tyre 5.0, MF 6.1, MF 6.2)", source, *(floc or (lineno, line)))
    if fmt is not None and token not in GENERIC_FORMATS:
        lineno, line = floc or (lineno, line)
        raise MissingFittypError(
            f"no FITTYP, and PROPERTY_FILE_FORMAT = {fmt!r} is not a format mftire knows (known without FITTYP: "
            "'PAC2002', 'MF_05', 'MF_52', 'MF_61', 'MF_62')", source, lineno, line)
    said = f"PROPERTY_FILE_FORMAT = {fmt!r} does not name the version" if fmt is not None else "no PROPERTY_FILE_FORMAT"
    raise MissingFittypError(
        f"no FITTYP in [MODEL] and {said}: add FITTYP = 61 (MF 6.1), 62 (MF 6.2) or 6 (MF 5.2), or "
        "PROPERTY_FILE_FORMAT = 'PAC2002' / 'MF_05'", source, lineno, line)


def read_tir(path: str | os.PathLike[str], strict: bool = False) -> TirParameters:
    """Read a ``.tir`` tyre property file.

    Real-world files have quirks.  A blank value (``KEY =``) or a non-numeric value
    on a standard numeric key (``MASS = kg``) is tolerated when the evaluator does
    not use the key (:data:`mftire.iotools.evaluator_keys.EVALUATOR_KEYS`): a
    :class:`TirWarning` naming file, line and key, and the key is treated as absent.
    On a key the evaluator uses it is an error naming file, line and key.

    Parameters
    ----------
    path : str or path-like
        The file.
    strict : bool, default False
        Make every warning an error (tolerated values, unconverted unknown keys).

    Returns
    -------
    TirParameters
        The parameters, converted to SI units (m, N, rad, kg, s, Pa).

    Raises
    ------
    TirError
        If the file is malformed (message with file name, line and text).
    OSError
        If the file cannot be read.
    """
    data = Path(path).read_bytes()
    text = _decode(data)
    control = _CONTROL_RE.findall(text)
    if len(control) > max(4, len(text) // 20):  # a few may sit in a quoted value; many: a binary file
        line = text.count("\n", 0, text.index(control[0])) + 1
        raise TirError("binary data (control characters): not a text .tir file", os.fspath(path), line)
    return parse_tir(text, path=os.fspath(path), strict=strict)


# --------------------------------------------------------------------- writing
def _format_value(value: Any, key: str, section: str) -> str:
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise TirError(f"cannot write {type(value).__name__} value of {key} in [{section}]")
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, int):
        return str(value)
    if "\n" in value or "\r" in value:
        raise TirError(f"cannot write a line break in the string value of {key} in [{section}]")
    if "'" not in value:
        return f"'{value}'"
    if '"' not in value:
        return f'"{value}"'
    raise TirError(f"cannot write a string holding both quote characters ({key} in [{section}])")


def as_parameters(params: Any, unknown: str = "error") -> TirParameters:
    """A :class:`TirParameters` from a TirParameters, ``{SECTION: {KEY: value}}`` or a flat mapping.

    A flat mapping puts each standard key in its standard section; values that are
    mappings (or tables) become sections of that name, so ``{"PCX1": 1.6,
    "MFTIRE_EXTENSIONS": {"VS_DECAY": 0.1}}`` works.  A non-standard key outside a
    section raises (``unknown="error"``) or is left out (``unknown="drop"``).
    """
    if isinstance(params, TirParameters):
        return params
    if isinstance(params, Mapping):
        if all(isinstance(v, (Mapping, TirTable)) for v in params.values()):
            return TirParameters({k: (dict(v) if isinstance(v, Mapping) else v) for k, v in params.items()})
        out = TirParameters()
        for key, value in params.items():
            if isinstance(value, (Mapping, TirTable)):
                for k, v in (value.items() if isinstance(value, Mapping) else ()):
                    out.set(str(k).upper(), v, section=str(key).upper())
                if isinstance(value, TirTable):
                    out.sections[str(key).upper()] = value
            elif unknown == "drop" and str(key).upper() not in BY_KEY:
                continue
            else:
                out.set(str(key).upper(), value)
        return out
    raise TypeError(f"cannot write {type(params).__name__} as a .tir file")


def format_tir(params: TirParameters | Mapping[str, Any]) -> str:
    """Return the text of a ``.tir`` file holding ``params`` (SI units, ``\\n`` line ends).

    Parameters
    ----------
    params : TirParameters or mapping
        A :class:`TirParameters`, a ``{SECTION: {KEY: value}}`` mapping or a flat
        ``{KEY: value}`` mapping of standard keys (each put in its standard section).

    Returns
    -------
    str

    Raises
    ------
    TirError
        If a value cannot be written so that it reads back identically (a string
        for a numeric key, a non-SI ``[UNITS]`` entry, a bad key name, ...).
    """
    params = as_parameters(params)
    out: list[str] = [c if c[:1] in "$!" else "$" + c for c in params.header_comments]
    sections = list(params.sections.items())
    if "UNITS" not in params.sections:
        units: dict[str, Value] = {q: _SI_NAMES[q] for q in _UNIT_QUANTITIES[:5]}
        at = 1 if sections and sections[0][0] == "MDI_HEADER" else 0
        sections.insert(at, ("UNITS", units))
    for name, body in sections:
        base = _base_name(name)
        if not _SECTION_RE.match(f"[{base}]"):
            raise TirError(f"cannot write section name {base!r}")
        out.append("$" + "-" * max(3, 70 - len(base)) + base.lower())
        out.append(f"[{base}]")
        if isinstance(body, TirTable):
            if body.columns is not None:
                out.append("{" + " ".join(body.columns) + "}")
            for row in body.rows:
                out.append(" ".join(_format_value(v, "table row", base) for v in row))
            out.extend(params.blocks.get(name, []))
            continue
        for key, value in body.items():
            if not _KEY_RE.match(key) or key != key.upper():
                raise TirError(f"cannot write key {key!r} in [{base}]")
            p = BY_KEY.get(key)
            if base == "UNITS":
                if key in _UNIT_FACTORS and not (isinstance(value, str) and _unit_factor(key, value) == 1):
                    raise TirError(f"[UNITS] {key} = {value!r} is not SI; convert the values, set SI units")
            elif p is not None and p.unit != "str" and not _is_number(value):
                raise TirError(f"{key} in [{base}] needs a number, not {value!r}")
            text = f"{key:<25}= {_format_value(value, key, base)}"
            comment = params.comments.get((name, key))
            if comment is None and p is not None and p.section == base:
                comment = p.description
            if comment:
                text = f"{text:<50} ${comment.strip()}"
            out.append(text)
        out.extend(params.blocks.get(name, []))
    return "\n".join(out) + "\n"


def write_tir(
    params: TirParameters | Mapping[str, Any],
    path: str | os.PathLike[str],
    line_ending: str = "\r\n",
) -> None:
    """Write ``params`` to a ``.tir`` file, atomically.

    The text goes to a temporary file in the same directory, which then replaces
    ``path`` (:func:`os.replace`), so readers never see a half-written file.

    Parameters
    ----------
    params : TirParameters or mapping
        Parameters in SI units (as :func:`read_tir` returns them; see
        :func:`format_tir` for the mappings accepted).
    path : str or path-like
        Destination file.
    line_ending : str, default "\\r\\n"
        Windows line endings by default, like the MFeval and ADAMS example
        files: MFeval 4.0's reader drops the last character of every line,
        assuming it is a carriage return.

    Raises
    ------
    TirError
        If ``params`` cannot be written faithfully (see :func:`format_tir`).
    """
    write_text_atomic(path, format_tir(params), newline=line_ending)
