"""Sanity checks of a ``.tir`` file on load: completeness and physics.

:func:`check_parameters` classifies the sections of the file's Magic Formula
version (``FITTYP``) and checks the values in SI units (after the ``[UNITS]``
conversion of :mod:`mftire.iotools.tir`).  :func:`mftire.load` runs it on every
file: errors raise :class:`TirCheckError` (one line naming the file), warnings are
issued together as one :class:`~mftire.errors.MftireTirWarning`.  ``mftire info``
prints the whole report; ``mftire info --strict`` exits 1 on warnings.

Sections
--------
============================  ===========  ==========================================
section                       MF 5.2/PAC   MF 6.1 / 6.2 (FITTYP 61, 62)
============================  ===========  ==========================================
DIMENSION, VERTICAL,          required     required
LONGITUDINAL_, LATERAL_,
ALIGNING_COEFFICIENTS
OVERTURNING_, ROLLING_        optional     optional
COEFFICIENTS, SCALING_
COEFFICIENTS, the four
``*_RANGE`` sections
OPERATING_CONDITIONS,         not used     optional
INFLATION_PRESSURE_RANGE
others (INERTIA, STRUCTURAL,  not checked  not checked (used by other use modes)
CONTACT_PATCH, TURNSLIP_...)
============================  ===========  ==========================================

A missing *required* section is an error; a missing *optional* one is a warning
that lists the keys that take default values.  ``FNOMIN`` is a required key
(a missing ``UNLOADED_RADIUS`` is a warning: MFeval's default is used and the moments scale
with it), and the pure-slip core coefficients (:data:`CORE_KEYS`) of a
present coefficient section must be there too: their absence usually means a
truncated or hand-cut file.

Physical checks
---------------
* errors: ``FNOMIN`` > 0, ``UNLOADED_RADIUS`` > 0, ``WIDTH`` and ``RIM_RADIUS`` ≥ 0,
  every numeric value finite (a ``nan``/``inf`` coefficient);
* warnings: ``FNOMIN`` within :data:`PLAUSIBLE` ``["FNOMIN"]``, ``UNLOADED_RADIUS``,
  ``NOMPRES`` and ``INFLPRES`` within their plausible ranges, ``RIM_RADIUS`` below
  ``UNLOADED_RADIUS``, ``FZMIN`` < ``FZMAX``, ``VERTICAL_STIFFNESS`` > 0 (radii, contact patch
  and relaxation lengths divide by it), non-zero ``PCX1``/``PDX1`` and ``PCY1``/``PDY1`` (a zero
  makes Fx or Fy vanish: a file fitted for USE_MODE 2 or 1, or a broken one).  When a value is out of range and the
  file declares non-SI ``[UNITS]``, or a power-of-ten factor would make it
  plausible, the message says so (e.g. ``LENGTH = 'inch'`` with metre values).
"""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from mftire.errors import MftireInputError, MftireTirWarning
from mftire.parameters import (  # the one table of limits lives with the keys (mftire.parameters)
    COEFFICIENT_MAX,
    EXPONENT_KEYS,
    EXPONENT_MAX,
    FRICTION_DFZ,
    MU_MAX,
    PARAMETER_LIMITS,
    PARAMETERS,
    RANGE_PAIRS,
    Limit,
)

#: Sections every file needs.
REQUIRED_SECTIONS = ("DIMENSION", "VERTICAL", "LONGITUDINAL_COEFFICIENTS", "LATERAL_COEFFICIENTS",
                     "ALIGNING_COEFFICIENTS")
#: Sections whose absence is a warning (every FITTYP).
OPTIONAL_SECTIONS = ("OVERTURNING_COEFFICIENTS", "ROLLING_COEFFICIENTS", "SCALING_COEFFICIENTS",
                     "VERTICAL_FORCE_RANGE", "LONG_SLIP_RANGE", "SLIP_ANGLE_RANGE", "INCLINATION_ANGLE_RANGE")
#: Further optional sections of MF 6.1 / 6.2 (pressure terms).
OPTIONAL_SECTIONS_6X = ("OPERATING_CONDITIONS", "INFLATION_PRESSURE_RANGE")
#: Keys a file must give (no default is a sensible guess).
REQUIRED_KEYS = ("FNOMIN",)
#: Keys whose absence is a warning: MFeval's default is used, and the message says what scales with it.
WARN_MISSING = {
    "UNLOADED_RADIUS": "Fx and Fy do not depend on it, but Mz (trail, residual torque), Mx, My, the radii, the "
                       "contact patch and the relaxation lengths scale with it",
}
#: Pure-slip core coefficients of each coefficient section (present in MF 5.2, 6.1 and 6.2).
CORE_KEYS = {
    "LONGITUDINAL_COEFFICIENTS": ("PCX1", "PDX1", "PKX1"),
    "LATERAL_COEFFICIENTS": ("PCY1", "PDY1", "PKY1"),
    "ALIGNING_COEFFICIENTS": ("QBZ1", "QCZ1", "QDZ1"),
}


#: Sections of the force and moment coefficients: a blank value there is an error (the characteristic would
#: take another tyre's value); a blank operating condition, range, dimension or stiffness takes its default.
COEFFICIENT_SECTIONS = ("LONGITUDINAL_COEFFICIENTS", "LATERAL_COEFFICIENTS", "ALIGNING_COEFFICIENTS",
                        "OVERTURNING_COEFFICIENTS", "ROLLING_COEFFICIENTS", "TURNSLIP_COEFFICIENTS")


def required_keys() -> frozenset[str]:
    """Keys without which a file cannot be evaluated: :data:`REQUIRED_KEYS` and the core coefficients
    (:data:`CORE_KEYS`).  A blank or non-numeric value on one of them is a reading error
    (:func:`mftire.iotools.tir.read_tir`)."""
    return frozenset(REQUIRED_KEYS).union(*CORE_KEYS.values())


#: Aligning-moment coefficients whose zeros make Mz vanish: trail peak (eq 4.E42), residual torque peak
#: (eq 4.E47, MF 6.1 adds QDZ10/11) and the Fx moment arm s (eq 4.E76).
ZERO_MZ = ("QDZ1", "QDZ2", "QDZ6", "QDZ7", "QDZ8", "QDZ9", "QDZ10", "QDZ11", "SSZ1", "SSZ2", "SSZ3", "SSZ4")
#: Plausible ranges (SI) of the constants, for any road or rig tyre from a bicycle to an aircraft.
PLAUSIBLE = {
    "FNOMIN": (50.0, 5e5),  # N
    "UNLOADED_RADIUS": (0.05, 2.5),  # m
    "NOMPRES": (2e4, 5e6),  # Pa (0.2 .. 50 bar)
    "INFLPRES": (2e4, 5e6),  # Pa
}
#: Shape and peak factors whose zero makes a pure-slip force vanish (Fx0 = Dx·sin(Cx·…), eqs 4.E9–4.E11;
#: Fy0 likewise, eqs 4.E19–4.E22): force, keys, what is missing, the USE_MODE that omits it.
ZERO_PEAK = {"Fx": ("Fx", ("PCX1", "PDX1"), "longitudinal", 2), "Fy": ("Fy", ("PCY1", "PDY1"), "lateral", 1)}
_UNITS = {"FNOMIN": "N", "UNLOADED_RADIUS": "m", "NOMPRES": "Pa", "INFLPRES": "Pa"}
_QUANTITY = {"FNOMIN": ("FORCE",), "UNLOADED_RADIUS": ("LENGTH",), "NOMPRES": ("PRESSURE", "FORCE", "LENGTH"),
             "INFLPRES": ("PRESSURE", "FORCE", "LENGTH")}


#: Known values of the string keys (a warning otherwise; they do not change the numbers).
TYRESIDES = ("LEFT", "RIGHT", "SYMMETRIC", "UNKNOWN")


def _show(v: Any) -> str:
    """A number as the user wrote it (no ``np.float64(...)``)."""
    return f"{float(v):g}" if _number(v) or hasattr(v, "__float__") else repr(v)


def value_errors(flat: Mapping[str, Any]) -> list[str]:
    """The errors of :data:`PARAMETER_LIMITS`, :data:`RANGE_PAIRS`, :data:`MU_MAX`, :data:`COEFFICIENT_MAX`
    for flat SI values (absent keys are not checked); one string per problem.  The extension coefficients
    are checked one layer up (:func:`mftire.input_checks.extension_errors`: they need the model's forms)."""
    out: list[str] = []
    failed: set[str] = set()
    for lim in PARAMETER_LIMITS:  # the first bound a key fails is reported
        v = flat.get(lim.key)
        if lim.key not in failed and _number(v) and math.isfinite(float(v)) and not lim.holds(float(v)):
            failed.add(lim.key)
            out.append(f"{lim.key} = {_show(v)} must be {lim.op} {lim.bound:g} ({lim.why})")
    for lo_key, hi_key, unit in RANGE_PAIRS:
        lo, hi = flat.get(lo_key), flat.get(hi_key)
        if _number(lo) and _number(hi) and math.isfinite(float(lo)) and math.isfinite(float(hi)) and lo >= hi:
            u = f" {unit}" if unit != "-" else ""
            out.append(f"{lo_key} = {_show(lo)}{u} is not below {hi_key} = {_show(hi)}{u} (inverted range: "
                       "mode 1xx would clip every input to one value)")
    for force, (d1, d2, scale) in (("Fx", ("PDX1", "PDX2", "LMUX")), ("Fy", ("PDY1", "PDY2", "LMUY"))):
        a, b, lam = flat.get(d1), flat.get(d2, 0.0), flat.get(scale, 1.0)
        if not (_number(a) and _number(b) and _number(lam)):
            continue
        mu = max(abs((float(a) + float(b) * d) * float(lam)) for d in FRICTION_DFZ)
        if math.isfinite(mu) and mu > MU_MAX:
            out.append(f"peak friction of {force} {mu:.3g} ({d1} = {_show(a)}, {d2} = {_show(b)}, {scale} = "
                       f"{_show(lam)}) is far beyond rubber (limit {MU_MAX:g}; eqs 4.E13, 4.E23)")
    huge = [k for k, v in flat.items() if k in _BOUNDED_KEYS and _number(v) and math.isfinite(float(v))
            and abs(float(v)) > (EXPONENT_MAX if k in EXPONENT_KEYS else COEFFICIENT_MAX)]
    if huge:
        out.append(f"{', '.join(f'{k} = {_show(flat[k])}' for k in huge[:4])}"
                   + (f" and {len(huge) - 4} more" if len(huge) > 4 else "")
                   + f": beyond any Magic Formula coefficient (|value| <= {COEFFICIENT_MAX:g}, exponents "
                   f"{', '.join(EXPONENT_KEYS)} <= {EXPONENT_MAX:g}); a channel would overflow")
    return out


#: Keys of the force and moment coefficients and the scaling factors (:data:`COEFFICIENT_MAX`).
_BOUNDED_KEYS = frozenset(p.key for p in PARAMETERS if p.section in (*COEFFICIENT_SECTIONS, "SCALING_COEFFICIENTS")
                          and p.unit != "str")


class TirCheckError(MftireInputError):
    """A ``.tir`` file that cannot be used: a required section or key missing, a non-physical value."""


@dataclass
class CheckReport:
    """What :func:`check_parameters` found."""

    source: str
    fittyp: int | None = None
    errors: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    #: ``{SECTION: [keys taking their default]}`` for the standard keys of the file's version.
    defaulted: dict[str, list[str]] = field(default_factory=dict)
    #: The file's model (``TirParameters.model``), when known.
    model: str = ""

    @property
    def ok(self) -> bool:
        return not self.errors

    def exit_code(self, strict: bool = False) -> int:
        """2 with errors, 1 with warnings under ``strict``, else 0."""
        return 2 if self.errors else 1 if (strict and self.warnings) else 0

    def format(self) -> str:
        """The report as text (used by ``mftire info``)."""
        lines = ["checks:"]
        lines += [f"  error: {m}" for m in self.errors]
        lines += [f"  warning: {m}" for m in self.warnings]
        if not self.errors and not self.warnings:
            lines.append("  all passed")
        if self.defaulted:
            lines.append("keys taking default values:" if self.model not in ("PAC2002", "MF-Tyre 5.0") else
                         "keys taking default values (a coefficient absent from a PAC2002 or MF_05 file is zero, "
                         "mftire.mf.pac2002.absent_terms):")
            for sec, keys in self.defaulted.items():
                lines.append(f"  [{sec}] {', '.join(keys)}")
        return "\n".join(lines)

    def raise_errors(self, strict: bool = False) -> None:
        """Raise :class:`TirCheckError` (one line) on errors, and on warnings under ``strict``."""
        problems = self.errors + (self.warnings if strict else [])
        if problems:
            more = f" (and {len(problems) - 1} more problem(s); see mftire info)" if len(problems) > 1 else ""
            raise TirCheckError(f"{self.source}: {problems[0]}{more}")

    def warn(self, stacklevel: int = 2) -> None:
        """Issue the warnings as one :class:`MftireTirWarning`."""
        if self.warnings:
            warnings.warn(f"{self.source}: " + "; ".join(self.warnings), MftireTirWarning, stacklevel=stacklevel + 1)


def _fittyp(flat: Mapping[str, Any]) -> int | None:
    v = flat.get("FITTYP")
    try:
        return int(v) if v is not None else None
    except (TypeError, ValueError):
        return None


def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _unit_hint(key: str, value: float, file_units: Mapping[str, str]) -> str:
    declared = [f"{q} = {file_units[q]!r}" for q in _QUANTITY[key] if q in file_units]
    if declared:
        return f"; check [UNITS] ({', '.join(declared)}): the values may be in other units"
    lo, hi = PLAUSIBLE[key]
    for power in (3, -3, 2, -2, 5, -5, 6, -6):
        if lo <= value * 10.0**power <= hi:
            return f"; a factor 1e{power} would make it plausible: check [UNITS] or the value's unit"
    return ""


def check_parameters(params: Any, source: str | None = None, sections: bool | None = None) -> CheckReport:
    """Check a :class:`~mftire.iotools.tir.TirParameters` (or a flat mapping).

    ``sections``: check the section layout (default: when ``params`` was read from a
    file, i.e. has a ``path``).  Returns a :class:`CheckReport`; raises nothing.
    """
    path = getattr(params, "path", None)
    source = source or (str(path) if path else "tyre parameters")
    secs = getattr(params, "sections", None)
    if hasattr(params, "flat") and callable(params.flat):
        flat = params.flat()
    else:
        flat = {str(k).upper(): v for k, v in dict(params).items()}
    fittyp = _fittyp(flat)
    rep = CheckReport(os.fspath(source), fittyp, model=str(getattr(params, "model", "") or ""))
    if sections is None:
        sections = bool(path) and secs is not None

    model = getattr(params, "model", None) or ({61: "MF 6.1", 62: "MF 6.2"}.get(fittyp, ""))
    if sections and secs is not None:
        present = {s for s, body in secs.items() if isinstance(body, Mapping)}
        mf6x = model in ("MF 6.1", "MF 6.2")
        missing = [s for s in REQUIRED_SECTIONS if s not in present]
        order = [s for s in secs]
        if missing:
            truncated = order and all(s not in present for s in REQUIRED_SECTIONS[REQUIRED_SECTIONS.index(missing[0]):])
            rep.errors.append(f"required section(s) {', '.join(f'[{s}]' for s in missing)} missing"
                              + (" (is the file truncated?)" if truncated else ""))
        optional = OPTIONAL_SECTIONS + (OPTIONAL_SECTIONS_6X if mf6x else ())
        # a missing optional section whose keys the file gives elsewhere (e.g. one [RANGE] section) is fine
        opt_missing = [s for s in optional if s not in present and any(
            p.key not in flat for p in PARAMETERS if p.section == s and p.mfeval and p.unit != "str")]
        if opt_missing:
            keys = [p.key for p in PARAMETERS if p.section in opt_missing and p.mfeval and p.unit != "str"
                    and p.key not in flat]
            shown = ", ".join(keys[:8]) + (f" and {len(keys) - 8} more" if len(keys) > 8 else "")
            rep.warnings.append(f"optional section(s) {', '.join(f'[{s}]' for s in opt_missing)} missing; "
                                f"{len(keys)} key(s) take default values ({shown})")
        for s in present:
            if s in CORE_KEYS and not secs[s]:
                rep.errors.append(f"section [{s}] is empty (is the file truncated?)")
            elif s in CORE_KEYS:
                lost = [k for k in CORE_KEYS[s] if k not in secs[s]]
                if lost:
                    rep.errors.append(f"[{s}] lacks the core coefficient(s) {', '.join(lost)} "
                                      "(is the file truncated?)")
        for key in REQUIRED_KEYS:
            home = next(p.section for p in PARAMETERS if p.key == key)
            if key not in flat and home in present:
                rep.errors.append(f"required key {key} missing in [{home}]")
        for key, scaled in WARN_MISSING.items():
            home = next(p for p in PARAMETERS if p.key == key)
            if key not in flat:
                rep.warnings.append(f"{key} missing: MFeval's default {home.default:g} {home.unit} is used; {scaled}")
        std = {p.key: p for p in PARAMETERS if p.mfeval and p.unit != "str"}
        for key, p in std.items():
            if key == "FITTYP" and flat.get("FITTYP") is None:  # the file names its format instead
                continue
            if key not in flat and p.section in present and (mf6x or p.section not in OPTIONAL_SECTIONS_6X):
                rep.defaulted.setdefault(p.section, []).append(key)
        for s in opt_missing:
            keys = [p.key for p in PARAMETERS if p.section == s and p.mfeval and p.unit != "str" and p.key not in flat]
            if keys:
                rep.defaulted[s] = keys

    # physics, on the file's values in SI (defaults where absent)
    bad = [k for k, v in flat.items() if _number(v) and not math.isfinite(float(v))]
    if bad:
        rep.errors.append(f"non-finite value(s): {', '.join(f'{k} = {flat[k]}' for k in bad[:6])}"
                          + (f" and {len(bad) - 6} more" if len(bad) > 6 else ""))
    file_units = getattr(params, "file_units", None) or {}
    rep.errors += value_errors(flat)
    odd, hints = [], []
    for key, (lo, hi) in PLAUSIBLE.items():
        v = flat.get(key)
        if not _number(v) or not math.isfinite(float(v)) or v <= 0:
            continue
        if not lo <= v <= hi:
            odd.append(f"{key} = {v:.4g} {_UNITS[key]} (expected {lo:g} .. {hi:g})")
            hint = _unit_hint(key, float(v), file_units)
            if hint and hint not in hints:
                hints.append(hint)
    if odd:
        rep.warnings.append("implausible after unit conversion: " + ", ".join(odd) + "".join(hints))
    r0, rim = flat.get("UNLOADED_RADIUS"), flat.get("RIM_RADIUS")
    if _number(r0) and _number(rim) and 0 < r0 <= rim:
        rep.warnings.append(f"RIM_RADIUS = {rim:g} m is not below UNLOADED_RADIUS = {r0:g} m")
    side = flat.get("TYRESIDE")
    if isinstance(side, str) and side.strip().upper() not in TYRESIDES:
        rep.warnings.append(f"TYRESIDE = {side!r} is not one of {', '.join(TYRESIDES)}")
    kz = flat.get("VERTICAL_STIFFNESS")
    if _number(kz) and math.isfinite(float(kz)) and kz <= 0:
        rep.warnings.append(f"VERTICAL_STIFFNESS = {kz:g} N/m: the deflection, the loaded and effective rolling "
                            "radii, the contact patch and the relaxation lengths divide by it and come out "
                            "NaN or infinite")
    if "QDZ1" in flat and all(not _number(flat.get(k)) or flat[k] == 0 for k in ZERO_MZ):
        rep.warnings.append(f"{', '.join(k for k in ZERO_MZ if k in flat)} = 0: Mz is identically zero (the file "
                            "has no aligning-moment characteristic)")
    for force, keys, kind, mode in (ZERO_PEAK["Fx"], ZERO_PEAK["Fy"]):
        zero = [k for k in (*keys, f"LMU{force[1].upper()}") if _number(flat.get(k)) and flat[k] == 0]
        if zero:
            rep.warnings.append(f"{' = '.join(zero)} = 0: {force} is identically zero (the file has no {kind} "
                                f"characteristic, as a fit for USE_MODE {mode} has)")
    return rep


def checked(params: Any) -> Any:
    """Check a file just read (:func:`check_parameters`): errors raise :class:`TirCheckError`
    (one line naming the file), warnings are issued as one :class:`MftireTirWarning`.
    Returns ``params``; :meth:`mftire.Tyre.from_file` (and so :func:`mftire.load`) calls it."""
    report = check_parameters(params)
    report.raise_errors()
    report.warn(stacklevel=4)
    return params


def check_tyre(tyre: Any) -> CheckReport:
    """:func:`check_parameters` of a :class:`mftire.Tyre`'s parameters."""
    return check_parameters(tyre.parameters, source=getattr(tyre.parameters, "path", None) or tyre.name)


__all__ = ["COEFFICIENT_SECTIONS", "CORE_KEYS", "CheckReport", "Limit", "MU_MAX",
           "OPTIONAL_SECTIONS", "OPTIONAL_SECTIONS_6X", "PARAMETER_LIMITS", "PLAUSIBLE", "RANGE_PAIRS",
           "REQUIRED_KEYS", "REQUIRED_SECTIONS", "TirCheckError", "WARN_MISSING", "ZERO_MZ", "check_parameters",
           "check_tyre", "checked", "required_keys", "value_errors", "COEFFICIENT_MAX"]
