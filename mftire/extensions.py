"""Model extensions: documented, physically motivated terms MF 6.1/6.2 lacks.

An extension is stored in a ``.tir`` section of our own, ``[MFTIRE_EXTENSIONS]``,
under fixed keys; other MF tools ignore the section, and a file without it is a
plain MF file.  Our evaluator, fitter and FMU export read it.

Friction-type extensions scale the friction scaling factors of the Magic Formula,
exactly where the book puts friction modifications (Pacejka 2012 eqs 4.E7, 4.E8:
lambda_mu* and lambda_mu'), so they act on the peak forces (Dx, Dy), the
vertical shifts, the trail (Bt) and the residual torque (Dr), and leave the slip
stiffnesses alone.  Offset-type extensions add a force or moment.

=========================  ========  ==============================================  ============================
name                       variable  term                                            keys
=========================  ========  ==============================================  ============================
``slip_speed_friction``    Vs        mu × 1/(1 + c·Vs/LONGVL)  (eq 4.E7, LMUV)         VS_DECAY
``slip_speed_peak``        Vs        mu × (1 + A·(S(Vs) − S(0.1·LONGVL)))/(1 + ...),   VS_PEAK_GAIN, VS_PEAK_SPEED,
                                     S = exp(−h²·ln²(Vs/Vpk)) (Savkoor-type, thesis    VS_PEAK_WIDTH
                                     eq 2.2, normalised at Vs = 0.1·LONGVL)
``speed_friction``         Vx        mu × (1 + c1·u + c2·u²), u = |Vx|/LONGVL − 1      VX_FRIC1, VX_FRIC2
``fade``                   any       mu × (1 − a·(1 − exp(−max(v, 0)/tau)))            FADE_VARIABLE, FADE_DEPTH,
                                     (thermal or wear fade with time, energy, ...)     FADE_SCALE
``friction_variable``      any       mu × (1 + c1·z + c2·z²), z = (v − ref)/scale      FVAR_VARIABLE, FVAR_REF,
                                     (e.g. temperature sensitivity of rubber); v        FVAR_SCALE, FVAR_C1, FVAR_C2,
                                     clipped to [FVAR_MIN, FVAR_MAX], the fitted range   FVAR_MIN, FVAR_MAX
``load_friction``          Fz        mu × (1 + c·dfz²)  (load sensitivity beyond PDX2, LOAD_MU2
                                     PDY2)
``rolling_resistance``     —         Fx − c·Fz·sign(Vx)  (free-rolling offset)         RR_FX
``asymmetry``              sign α    muy × (1 + a·sign(alpha)); Fy + b·Fz              ASYM_MUY, ASYM_FY
                                     (tread asymmetry; ply-steer)
``generic``                any       channel × (1 + c1·z + c2·z² + c3·z³), v clipped   GEN_CHANNEL, GEN_VARIABLE,
                                     to [GEN_MIN, GEN_MAX]; NOT PHYSICS: a labelled     GEN_REF, GEN_SCALE, GEN_C1..3,
                                     smooth correction                                  GEN_MIN, GEN_MAX
=========================  ========  ==============================================  ============================

The inflation-pressure effect needs no section of its own: it is the standard
MF 6.1 pressure terms (PPX1–PPX4, PPY1–PPY5, PPZ1, PPZ2, PPMX1), refitted when a
``.tir`` has none.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from mftire.errors import MftireInputError

#: The ``.tir`` section that holds the extension parameters.
SECTION = "MFTIRE_EXTENSIONS"


@dataclass(frozen=True)
class Extension:
    """One entry of the extension library."""

    name: str
    description: str
    keys: tuple[str, ...]  #: numeric keys (defaults: neutral values in :data:`NEUTRAL`)
    variable_key: str | None = None  #: string key naming the data variable, if any
    fixed_variable: str | None = None  #: the variable it depends on when fixed (Vs, Vx, Fz, ...)
    physical: bool = True


LIBRARY: dict[str, Extension] = {
    e.name: e
    for e in (
        Extension("slip_speed_friction", "friction decaying with slip speed (Pacejka 2012 eq 4.E7)",
                  ("VS_DECAY",), fixed_variable="Vs"),
        Extension("slip_speed_peak", "Savkoor-type friction peak in slip speed (van der Steen 2010 eq 2.2)",
                  ("VS_PEAK_GAIN", "VS_PEAK_SPEED", "VS_PEAK_WIDTH"), fixed_variable="Vs"),
        Extension("speed_friction", "friction depending on forward speed", ("VX_FRIC1", "VX_FRIC2"),
                  fixed_variable="Vx"),
        Extension("fade", "thermal or wear fade of friction with a cumulative variable",
                  ("FADE_DEPTH", "FADE_SCALE"), variable_key="FADE_VARIABLE"),
        Extension("friction_variable", "friction depending on a measured variable (e.g. temperature)",
                  ("FVAR_REF", "FVAR_SCALE", "FVAR_C1", "FVAR_C2", "FVAR_MIN", "FVAR_MAX"),
                  variable_key="FVAR_VARIABLE"),
        Extension("load_friction", "quadratic load sensitivity of friction", ("LOAD_MU2",), fixed_variable="Fz"),
        Extension("rolling_resistance", "free-rolling longitudinal force offset (rolling resistance)", ("RR_FX",)),
        Extension("asymmetry", "left/right asymmetry: tread asymmetry of lateral friction and ply-steer offset",
                  ("ASYM_MUY", "ASYM_FY"), fixed_variable="sign_alpha"),
        Extension("generic", "generic smooth correction (not a physical model)",
                  ("GEN_REF", "GEN_SCALE", "GEN_C1", "GEN_C2", "GEN_C3", "GEN_MIN", "GEN_MAX"),
                  variable_key="GEN_VARIABLE",
                  physical=False),
    )
}  # fmt: skip

#: Value of each numeric key at which its extension has no effect.
NEUTRAL: dict[str, float] = {
    "VS_DECAY": 0.0, "VS_PEAK_GAIN": 0.0, "VS_PEAK_SPEED": 1.0, "VS_PEAK_WIDTH": 0.5,
    "VX_FRIC1": 0.0, "VX_FRIC2": 0.0, "FADE_DEPTH": 0.0, "FADE_SCALE": 1.0,
    "FVAR_REF": 0.0, "FVAR_SCALE": 1.0, "FVAR_C1": 0.0, "FVAR_C2": 0.0, "FVAR_MIN": -1e300, "FVAR_MAX": 1e300,
    "LOAD_MU2": 0.0,
    "RR_FX": 0.0, "ASYM_MUY": 0.0, "ASYM_FY": 0.0,
    "GEN_REF": 0.0, "GEN_SCALE": 1.0, "GEN_C1": 0.0, "GEN_C2": 0.0, "GEN_C3": 0.0, "GEN_MIN": -1e300, "GEN_MAX": 1e300,
}  # fmt: skip

#: Variables an extension may use that the evaluator derives from its own inputs.
BUILTIN_VARIABLES = ("Fz", "kappa", "alpha", "gamma", "Vx", "P", "Vs", "sign_alpha", "sign_kappa")

#: Input names of the evaluator that a data variable may not take.
RESERVED_VARIABLES = ("phit", "omega", "mode")

#: Channels a generic correction may act on.
GENERIC_CHANNELS = ("Fx", "Fy", "Mz", "Mx", "My")


def active_extensions(section: Mapping[str, object] | None) -> list[str]:
    """Names of the extensions a ``[MFTIRE_EXTENSIONS]`` section switches on.

    An extension is active when any of its numeric keys is present (string keys
    alone do not activate it).
    """
    if not section:
        return []
    keys = {str(k).upper() for k in section}
    return [e.name for e in LIBRARY.values() if keys & set(e.keys)]


def required_variables(section: Mapping[str, object] | None) -> list[str]:
    """Data variables (input columns) the active extensions need besides the MF inputs."""
    out = []
    sec = {str(k).upper(): v for k, v in (section or {}).items()}
    for name in active_extensions(sec):
        ext = LIBRARY[name]
        if ext.variable_key:
            var = sec.get(ext.variable_key)
            if not isinstance(var, str) or not var:
                raise MftireInputError(f"[{SECTION}] {name}: {ext.variable_key} must name the input variable")
            if var in RESERVED_VARIABLES:
                raise MftireInputError(
                    f"[{SECTION}] {ext.variable_key} = {var!r}: that name is an input of the evaluator; "
                    "name the data variable differently"
                )
            if var not in BUILTIN_VARIABLES and var not in out:
                out.append(var)
    return out


def builtin_variables(Fz, kappa, alpha, gamma, Vx, P) -> dict[str, np.ndarray]:
    """The variables of :data:`BUILTIN_VARIABLES` from the (conditioned) MF inputs."""
    return {
        "Fz": Fz, "kappa": kappa, "alpha": alpha, "gamma": gamma, "Vx": Vx, "P": P,
        "Vs": np.abs(Vx) * np.sqrt(kappa**2 + np.tan(alpha) ** 2),  # slip speed
        "sign_alpha": np.sign(alpha), "sign_kappa": np.sign(kappa),
    }  # fmt: skip


@dataclass
class ExtensionTerms:
    """What the active extensions do at an operating point."""

    mux: np.ndarray | float = 1.0  #: factor on lambda_mux* [-]
    muy: np.ndarray | float = 1.0  #: factor on lambda_muy* [-]
    dFx: np.ndarray | float = 0.0  #: added longitudinal force [N]
    dFy: np.ndarray | float = 0.0  #: added lateral force [N]
    generic: tuple[str, np.ndarray] | None = None  #: (channel, factor) of a generic correction


def _value(sec: Mapping[str, object], key: str) -> float:
    v = sec.get(key, NEUTRAL[key])
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise MftireInputError(f"[{SECTION}] {key} = {v!r} must be a number")
    return float(v)


def _variable(name: str, variables: Mapping[str, np.ndarray], where: str) -> np.ndarray:
    if name not in variables:
        raise MftireInputError(
            f"{where} needs the input variable '{name}': pass it as a keyword argument or an input column"
        )
    return np.asarray(variables[name], dtype=float)


def _savkoor(v, v_peak: float, h: float):
    """Savkoor bell exp(−h²·ln²(v/v_peak)), 0..1 (van der Steen 2010 eq 2.2 shape)."""
    return np.exp(-(h**2) * np.log(np.maximum(v, 1e-9) / v_peak) ** 2)


def extension_terms(
    sec: Mapping[str, object] | None,
    p: Mapping[str, float],
    Fz: np.ndarray,
    kappa: np.ndarray,
    alpha: np.ndarray,
    gamma: np.ndarray,
    Vx: np.ndarray,
    P: np.ndarray,
    variables: Mapping[str, np.ndarray] | None = None,
) -> ExtensionTerms | None:
    """Evaluate the active extensions.

    Parameters
    ----------
    sec : mapping
        The ``[MFTIRE_EXTENSIONS]`` section (upper-case keys).
    p : mapping
        Flat MF parameters (FNOMIN, LFZO, LONGVL are used).
    Fz, kappa, alpha, gamma, Vx, P : ndarray
        Conditioned load [N], slip [-], slip angle [rad], inclination [rad], forward
        speed [m/s] and pressure [Pa].
    variables : mapping, optional
        Extra input arrays by name (e.g. ``{"temperature": ...}``), broadcast to Fz.
        The names of :data:`BUILTIN_VARIABLES` always come from the MF inputs.

    Returns
    -------
    ExtensionTerms or None
        None when no extension is active.
    """
    names = active_extensions(sec)
    if not names:
        return None
    sec = {str(k).upper(): v for k, v in sec.items()}  # type: ignore[union-attr]
    variables = {**(variables or {}), **builtin_variables(Fz, kappa, alpha, gamma, Vx, P)}
    t = ExtensionTerms()
    V0 = p["LONGVL"]
    mu = np.ones(np.shape(Fz))
    for name in names:
        where = f"[{SECTION}] {name}"
        if name == "slip_speed_friction":
            Vs = np.abs(Vx) * np.sqrt(kappa**2 + np.tan(alpha) ** 2)
            mu = mu / (1.0 + _value(sec, "VS_DECAY") * Vs / V0)  # Pacejka 2012 eq 4.E7
        elif name == "slip_speed_peak":
            Vs = np.abs(Vx) * np.sqrt(kappa**2 + np.tan(alpha) ** 2)
            A, Vpk, h = (_value(sec, k) for k in ("VS_PEAK_GAIN", "VS_PEAK_SPEED", "VS_PEAK_WIDTH"))
            Vpk = max(abs(Vpk), 1e-6)
            mu = mu * (1.0 + A * _savkoor(Vs, Vpk, h)) / (1.0 + A * _savkoor(0.1 * V0, Vpk, h))
        elif name == "speed_friction":
            u = np.abs(Vx) / V0 - 1.0
            mu = mu * (1.0 + _value(sec, "VX_FRIC1") * u + _value(sec, "VX_FRIC2") * u**2)
        elif name == "fade":
            v = _variable(str(sec["FADE_VARIABLE"]), variables, where)
            tau = max(abs(_value(sec, "FADE_SCALE")), 1e-12)
            mu = mu * (1.0 - _value(sec, "FADE_DEPTH") * (1.0 - np.exp(-np.maximum(v, 0.0) / tau)))
        elif name == "friction_variable":
            v = _variable(str(sec["FVAR_VARIABLE"]), variables, where)
            v = np.minimum(np.maximum(v, _value(sec, "FVAR_MIN")), _value(sec, "FVAR_MAX"))  # fitted range
            z = (v - _value(sec, "FVAR_REF")) / _value(sec, "FVAR_SCALE")
            mu = mu * (1.0 + _value(sec, "FVAR_C1") * z + _value(sec, "FVAR_C2") * z**2)
        elif name == "load_friction":
            Fz0p = p["LFZO"] * p["FNOMIN"]
            dfz = (Fz - Fz0p) / Fz0p  # eq 4.E2a
            mu = mu * (1.0 + _value(sec, "LOAD_MU2") * dfz**2)
        elif name == "rolling_resistance":
            t.dFx = t.dFx - _value(sec, "RR_FX") * Fz * np.sign(Vx)
        elif name == "asymmetry":
            t.muy = t.muy * (1.0 + _value(sec, "ASYM_MUY") * np.sign(alpha))
            t.dFy = t.dFy + _value(sec, "ASYM_FY") * Fz
        elif name == "generic":
            channel = str(sec.get("GEN_CHANNEL", "Fx"))
            if channel not in GENERIC_CHANNELS:
                raise MftireInputError(f"{where}: GEN_CHANNEL must be one of {', '.join(GENERIC_CHANNELS)}")
            v = _variable(str(sec.get("GEN_VARIABLE", "")), variables, where)
            v = np.minimum(np.maximum(v, _value(sec, "GEN_MIN")), _value(sec, "GEN_MAX"))  # fitted range
            z = (v - _value(sec, "GEN_REF")) / _value(sec, "GEN_SCALE")
            t.generic = (channel, 1.0 + _value(sec, "GEN_C1") * z + _value(sec, "GEN_C2") * z**2
                         + _value(sec, "GEN_C3") * z**3)  # fmt: skip
    t.mux = t.mux * mu
    t.muy = t.muy * mu
    return t
