"""Tyre design parameters of the FE surrogate: dataclasses, TOML loading, validation.

The file format is TOML with one table per physical concern (``[size]``,
``[vertical]``, ``[patch]``, ``[carcass]``, ``[tread]``, ``[friction]``,
``[rolling_resistance]``, ``[grid]``); see ``mftire/fe/data/default_tyre.toml``
for the documented default.  All values are SI (m, N, Pa, s, rad) unless a key
name says otherwise (``rim_diameter_in``).

Every check raises :class:`mftire.errors.MftireInputError` with a message that
names the offending parameter as ``section.key``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import tomllib

from mftire.errors import MftireInputError

G_ACC = 9.80665  # standard gravity [m/s^2]

#: ETRTO / ISO 4000-1 load-index table (index -> load capacity in kg).
LOAD_INDEX_KG: dict[int, float] = {
    70: 335, 71: 345, 72: 355, 73: 365, 74: 375, 75: 387, 76: 400, 77: 412, 78: 425, 79: 437,
    80: 450, 81: 462, 82: 475, 83: 487, 84: 500, 85: 515, 86: 530, 87: 545, 88: 560, 89: 580,
    90: 600, 91: 615, 92: 630, 93: 650, 94: 670, 95: 690, 96: 710, 97: 730, 98: 750, 99: 775,
    100: 800, 101: 825, 102: 850, 103: 875, 104: 900, 105: 925, 106: 950, 107: 975, 108: 1000,
    109: 1030, 110: 1060,
}


@dataclass(frozen=True)
class SizeParams:
    """Tyre size and ratings."""

    section_width: float = 0.205  #: section width [m]
    aspect_ratio: float = 0.55  #: section height / section width [-]
    rim_diameter_in: float = 16.0  #: rim diameter [inch]
    unloaded_radius: float | None = None  #: override of the size-derived free radius [m]
    tread_width: float = 0.160  #: width of the tread (contact-capable) [m]
    load_index: int = 91  #: ISO load index
    load_index_load: float | None = None  #: override of the load-index load [N]
    nominal_pressure: float = 2.2e5  #: nominal inflation pressure [Pa]
    max_load_fraction: float = 1.6  #: model range: Fz <= this x load-index load [-]
    min_pressure_fraction: float = 0.5  #: model range: P >= this x nominal [-]
    max_pressure_fraction: float = 1.8  #: model range: P <= this x nominal [-]


@dataclass(frozen=True)
class VerticalParams:
    """Vertical stiffness, free radius growth and belt rolling radius (Pacejka 2012 ch. 4.3 / App. 3)."""

    cz0: float = 220e3  #: vertical stiffness at nominal pressure, zero speed [N/m]
    pfz1: float = 0.7  #: pressure sensitivity of the vertical stiffness [-]
    qv2: float = 0.10  #: linear speed stiffening of Cz per v0 [-]
    qv1: float = 0.0015  #: centrifugal growth of the free radius per (V/v0)^2 [-]
    v0: float = 16.67  #: reference speed [m/s]
    dr_v: float = 0.008  #: saturating speed growth of the belt radius [m] (fitted to Table 5.1)
    v_r: float = 8.2  #: speed scale of that growth [m/s]
    d_re: float = 0.34  #: MF-Swift effective-rolling-radius shape D [-]
    b_re: float = 20.0  #: MF-Swift effective-rolling-radius shape B [-]
    f_re: float = 0.0  #: MF-Swift effective-rolling-radius shape F [-]
    q_fcy: float = 0.15  #: loss of vertical stiffness with (Fy/Fz_LI)^2 (loaded radius only) [-]


@dataclass(frozen=True)
class PatchParams:
    """Contact-patch size, pressure shape and tread layout."""

    q_a: float = 0.68  #: contact half-length factor, a = q_a * sqrt(2 R rho) [-]
    width_drop: float = 0.30  #: relative loss of contact width at zero deflection [-]
    width_rho: float = 0.008  #: deflection scale of the width growth [m]
    pressure_exponent: float = 2.5  #: longitudinal pressure shape (1 - |xi|^n) [-]
    shoulder0: float = 0.05  #: shoulder/centre load bias at nominal pressure and 0.8 LI [-]
    shoulder_pressure: float = 1.5  #: extra shoulder bias per relative under-inflation [-]
    shoulder_load: float = 0.25  #: extra shoulder bias per load fraction above 0.8 [-]
    end_rounding: float = 0.15  #: shortening of the outermost rows, (1 - c eta^4) [-]
    lateral_shift: float = 0.5  #: pressure-centre shift as a fraction of the lateral carcass deflection [-]
    camber_shift: float = 3.0  #: lateral load transfer per rad of camber [-]
    groove_centres: tuple[float, ...] = (-0.055, -0.015, 0.025)  #: groove centre lines y [m]
    groove_width: float = 0.009  #: width of each circumferential groove [m]


@dataclass(frozen=True)
class CarcassParams:
    """Carcass (belt on sidewall) compliances."""

    cx: float = 450e3  #: longitudinal stiffness [N/m]
    cy: float = 150e3  #: lateral stiffness [N/m]
    cpsi: float = 7000.0  #: yaw (torsional) stiffness at the load-index load [N·m/rad]
    cpsi_load: float = 0.5  #: relative growth of cpsi per load fraction [-]
    pressure_sensitivity: float = 0.5  #: relative growth of cy, cpsi per relative overpressure [-]
    camber_reduction: float = 0.6  #: epsilon_gamma, camber spin reduction of a radial tyre [-]
    plysteer: float = 0.0  #: built-in residual slip angle (ply-steer) [rad]


@dataclass(frozen=True)
class TreadParams:
    """Tread element (brush) stiffness per unit contact area."""

    kx: float = 9.0e7  #: longitudinal shear stiffness per area [N/m^3]
    ky: float = 6.0e7  #: lateral shear stiffness per area [N/m^3]
    damping_time: float = 2.0e-4  #: Kelvin-Voigt time constant c/k of the tread rubber [s]


@dataclass(frozen=True)
class FrictionParams:
    """Van der Steen (2010) friction law, eq 2.46 with the velocity part of ch. 5."""

    p0: float = 0.5e6  #: reference pressure [Pa] (eq 4.2)
    k: float = 0.5  #: pressure exponent [-] (eq 4.2)
    plimit: float = 0.2e6  #: lower limit of the pressure term [Pa] (eq 2.46)
    mu_m: tuple[float, float] = (-0.0020, 1.05)  #: (a1 [s/m], a2): mu_m = a1 Vx + a2 (eq 5.10)
    mu_s: tuple[float, float, float] = (-1.0e-4, 0.0, 0.62)  #: (a3, a4, a5): eq 5.12, Vx in m/s
    h: float | None = None  #: fixed width parameter h [-]; or give mu_lock instead
    mu_lock: float | None = 0.72  #: common locked-wheel mu_v; h then follows from eq 5.8 at every speed
    kappa_max: float = 0.05  #: Vmax = kappa_max * Vx (eq 5.6/5.13)
    #: fixed sliding speed of peak friction [m/s] (Savkoor's law with a constant Vmax, thesis
    #: eq 2.2) instead of kappa_max * Vx; needs a fixed ``h``.  Friction then depends on the
    #: local sliding speed itself, not on the slip ratio.
    v_max: float | None = None
    scale: float = 1.0  #: overall friction level (road surface, fade) multiplying mu_s and mu_m [-]
    gamma_crit_fraction: float = 0.01  #: regularisation gamma_crit = this * Vx (thesis 3.5.2)
    max_speed: float = 70.0  #: speeds up to which the law is checked/used [m/s]


@dataclass(frozen=True)
class RollingResistanceParams:
    """Hysteresis rolling resistance: f_r = eta_h(V) * rho / (4 a)."""

    hysteresis_loss: float = 0.15  #: fraction of the deflection energy lost per passage [-]
    speed_linear: float = 0.05  #: growth of eta_h per v0 [-]
    speed_quartic: float = 0.01  #: growth of eta_h per (V/v0)^4 [-]


@dataclass(frozen=True)
class GridParams:
    """Discretisation and solver controls."""

    nx: int = 40  #: elements along the contact length
    ny: int = 15  #: rows across the contact width
    carcass_tol: float = 1e-5  #: convergence tolerance on the carcass state [rad, m, -]
    carcass_maxiter: int = 60  #: maximum carcass iterations
    relaxation: float = 0.8  #: under-relaxation of the carcass update [-]
    newton_iter: int = 8  #: local return-mapping iterations per element (at most)
    #: an element's return map stops once a Newton step is <= newton_tol max(s, gamma_crit); 0 runs all iterations
    newton_tol: float = 1e-10


@dataclass(frozen=True)
class TyreConfig:
    """Complete FE-surrogate tyre description."""

    name: str = "default 205/55 R16 91 passenger tyre"
    size: SizeParams = field(default_factory=SizeParams)
    vertical: VerticalParams = field(default_factory=VerticalParams)
    patch: PatchParams = field(default_factory=PatchParams)
    carcass: CarcassParams = field(default_factory=CarcassParams)
    tread: TreadParams = field(default_factory=TreadParams)
    friction: FrictionParams = field(default_factory=FrictionParams)
    rolling_resistance: RollingResistanceParams = field(default_factory=RollingResistanceParams)
    grid: GridParams = field(default_factory=GridParams)

    # ---- derived quantities -------------------------------------------------
    @property
    def unloaded_radius(self) -> float:
        """Free (unloaded, standstill) radius R0 [m] from the size designation."""
        s = self.size
        if s.unloaded_radius is not None:
            return float(s.unloaded_radius)
        return 0.5 * s.rim_diameter_in * 0.0254 + s.section_width * s.aspect_ratio

    @property
    def load_index_load(self) -> float:
        """Load-index load capacity [N]."""
        s = self.size
        if s.load_index_load is not None:
            return float(s.load_index_load)
        return LOAD_INDEX_KG[s.load_index] * G_ACC

    @property
    def max_load(self) -> float:
        """Largest vertical load the model accepts [N]."""
        return self.size.max_load_fraction * self.load_index_load

    def updated(self, changes: Mapping[str, Any]) -> TyreConfig:
        """Return a validated copy with ``{"section.key": value}`` changes applied."""
        data = to_dict(self)
        for dotted, value in changes.items():
            section, _, key = dotted.partition(".")
            if key:
                if section not in data or key not in data[section]:
                    raise MftireInputError(f"unknown tyre parameter {dotted!r}")
                data[section][key] = value
            else:
                if section not in data:
                    raise MftireInputError(f"unknown tyre parameter {dotted!r}")
                data[section] = value
        # h and mu_lock are alternatives: setting one clears the other
        if "friction.h" in changes and "friction.mu_lock" not in changes and changes["friction.h"] is not None:
            data["friction"]["mu_lock"] = None
        if "friction.mu_lock" in changes and "friction.h" not in changes and changes["friction.mu_lock"] is not None:
            data["friction"]["h"] = None
        return from_dict(data)


_SECTIONS: dict[str, type] = {
    "size": SizeParams,
    "vertical": VerticalParams,
    "patch": PatchParams,
    "carcass": CarcassParams,
    "tread": TreadParams,
    "friction": FrictionParams,
    "rolling_resistance": RollingResistanceParams,
    "grid": GridParams,
}


def to_dict(tyre: TyreConfig) -> dict[str, Any]:
    """Nested plain-dict form of a tyre (the TOML layout)."""
    out: dict[str, Any] = {"name": tyre.name}
    for sec in _SECTIONS:
        out[sec] = dataclasses.asdict(getattr(tyre, sec))
    return out


def _coerce(section: str, cls: type, raw: Mapping[str, Any]) -> Any:
    fields = {f.name: f for f in dataclasses.fields(cls)}
    kwargs: dict[str, Any] = {}
    for key, value in raw.items():
        if key not in fields:
            raise MftireInputError(f"unknown tyre parameter '{section}.{key}'")
        default = fields[key].default
        try:
            if isinstance(default, tuple) or isinstance(value, list | tuple):
                kwargs[key] = tuple(float(v) for v in value)
            elif key in ("nx", "ny", "carcass_maxiter", "newton_iter", "load_index"):
                if float(value) != int(value):
                    raise ValueError
                kwargs[key] = int(value)
            elif value is None:
                kwargs[key] = None
            else:
                kwargs[key] = float(value)
        except (TypeError, ValueError):
            raise MftireInputError(
                f"tyre parameter '{section}.{key}' must be numeric (got {value!r})"
            ) from None
    return cls(**kwargs)


def from_dict(data: Mapping[str, Any]) -> TyreConfig:
    """Build and validate a :class:`TyreConfig` from the nested TOML layout."""
    unknown = set(data) - set(_SECTIONS) - {"name"}
    if unknown:
        raise MftireInputError(f"unknown tyre section(s): {', '.join(sorted(unknown))}")
    kwargs: dict[str, Any] = {}
    for sec, cls in _SECTIONS.items():
        raw = dict(data.get(sec, {}))
        if sec == "friction" and "h" in raw and "mu_lock" not in raw:
            raw["mu_lock"] = None  # fixed h given: no mu_lock
        if sec == "friction" and "mu_lock" in raw and "h" not in raw:
            raw["h"] = None  # mu_lock given: h follows from eq 5.8
        kwargs[sec] = _coerce(sec, cls, raw)
    tyre = TyreConfig(name=str(data.get("name", "unnamed tyre")), **kwargs)
    validate(tyre)
    return tyre


def default_tyre_path() -> Path:
    """Path of the shipped default tyre file."""
    return Path(str(resources.files("mftire.fe") / "data" / "default_tyre.toml"))


def load_tyre(source: str | Path | None = None) -> TyreConfig:
    """Load a tyre: ``None``/``"default"`` gives the shipped tyre, else a TOML file path."""
    if source is None or str(source) == "default":
        path = default_tyre_path()
    else:
        path = Path(source)
    if not path.is_file():
        raise MftireInputError(f"tyre file not found: {path}")
    try:
        with path.open("rb") as fh:
            data = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise MftireInputError(f"cannot parse tyre file {path}: {exc}") from None
    return from_dict(data)


def _positive(name: str, value: float | None) -> None:
    if value is None or not math.isfinite(value) or value <= 0.0:
        raise MftireInputError(f"tyre parameter '{name}' must be positive and finite (got {value!r})")


def _nonneg(name: str, value: float) -> None:
    if not math.isfinite(value) or value < 0.0:
        raise MftireInputError(f"tyre parameter '{name}' must be >= 0 (got {value!r})")


def _in_range(name: str, value: float, lo: float, hi: float) -> None:
    if not math.isfinite(value) or not lo <= value <= hi:
        raise MftireInputError(f"tyre parameter '{name}' must lie in [{lo}, {hi}] (got {value!r})")


def validate(tyre: TyreConfig) -> None:
    """Check physical admissibility; raise MftireInputError naming the parameter."""
    s, v, pa, c, t, f, rr, g = (
        tyre.size, tyre.vertical, tyre.patch, tyre.carcass, tyre.tread,
        tyre.friction, tyre.rolling_resistance, tyre.grid,
    )
    for name in ("section_width", "aspect_ratio", "rim_diameter_in", "tread_width", "nominal_pressure",
                 "max_load_fraction", "min_pressure_fraction", "max_pressure_fraction"):
        _positive(f"size.{name}", getattr(s, name))
    if s.unloaded_radius is not None:
        _positive("size.unloaded_radius", s.unloaded_radius)
    if s.load_index_load is not None:
        _positive("size.load_index_load", s.load_index_load)
    elif s.load_index not in LOAD_INDEX_KG:
        raise MftireInputError(f"tyre parameter 'size.load_index' {s.load_index} is not in the load-index table")
    if s.tread_width >= 1.2 * s.section_width:
        raise MftireInputError("tyre parameter 'size.tread_width' must be smaller than the section width")
    if s.min_pressure_fraction >= 1.0 or s.max_pressure_fraction <= 1.0:
        raise MftireInputError("tyre parameters 'size.min/max_pressure_fraction' must bracket 1")
    for name in ("cz0", "v0", "v_r", "b_re"):
        _positive(f"vertical.{name}", getattr(v, name))
    for name in ("pfz1", "qv2", "qv1", "dr_v", "d_re", "f_re", "q_fcy"):
        _nonneg(f"vertical.{name}", getattr(v, name))
    _positive("patch.q_a", pa.q_a)
    _in_range("patch.width_drop", pa.width_drop, 0.0, 0.9)
    _positive("patch.width_rho", pa.width_rho)
    _in_range("patch.pressure_exponent", pa.pressure_exponent, 1.0, 10.0)
    _in_range("patch.end_rounding", pa.end_rounding, 0.0, 0.8)
    _nonneg("patch.groove_width", pa.groove_width)
    _in_range("patch.lateral_shift", pa.lateral_shift, 0.0, 0.95)
    for name in ("cx", "cy", "cpsi"):
        _positive(f"carcass.{name}", getattr(c, name))
    _nonneg("carcass.cpsi_load", c.cpsi_load)
    _in_range("carcass.camber_reduction", c.camber_reduction, 0.0, 1.0)
    _in_range("carcass.plysteer", c.plysteer, -0.05, 0.05)
    _positive("tread.kx", t.kx)
    _positive("tread.ky", t.ky)
    _nonneg("tread.damping_time", t.damping_time)
    _positive("friction.p0", f.p0)
    _in_range("friction.k", f.k, 0.0, 0.95)
    _positive("friction.plimit", f.plimit)
    _in_range("friction.kappa_max", f.kappa_max, 1e-4, 0.5)
    _positive("friction.scale", f.scale)
    if f.v_max is not None:
        _positive("friction.v_max", f.v_max)
        if f.h is None:
            raise MftireInputError("tyre parameter 'friction.v_max' needs a fixed 'friction.h' (not mu_lock)")
    _in_range("friction.gamma_crit_fraction", f.gamma_crit_fraction, 1e-5, 0.2)
    _positive("friction.max_speed", f.max_speed)
    if (f.h is None) == (f.mu_lock is None):
        raise MftireInputError("give exactly one of 'friction.h' and 'friction.mu_lock'")
    if f.h is not None:
        _positive("friction.h", f.h)
    if len(f.mu_m) != 2:
        raise MftireInputError("tyre parameter 'friction.mu_m' must be [a1, a2]")
    if len(f.mu_s) != 3:
        raise MftireInputError("tyre parameter 'friction.mu_s' must be [a3, a4, a5]")
    speeds = np.linspace(0.0, f.max_speed, 71)
    mu_m = f.mu_m[0] * speeds + f.mu_m[1]
    mu_s = f.mu_s[0] * speeds**2 + f.mu_s[1] * speeds + f.mu_s[2]
    if np.any(mu_s <= 0.0):
        vbad = speeds[np.argmax(mu_s <= 0.0)]
        raise MftireInputError(f"tyre parameter 'friction.mu_s' gives mu_s <= 0 at Vx = {vbad:.1f} m/s")
    if np.any(mu_m <= mu_s):
        vbad = speeds[np.argmax(mu_m <= mu_s)]
        raise MftireInputError(
            f"tyre parameters 'friction.mu_m' < 'friction.mu_s' at Vx = {vbad:.1f} m/s "
            "(the peak friction mu_m must exceed the static friction mu_s)"
        )
    if f.mu_lock is not None and np.any((f.mu_lock <= mu_s) | (f.mu_lock >= mu_m)):
        raise MftireInputError("tyre parameter 'friction.mu_lock' must lie between mu_s and mu_m (eq 5.9)")
    _nonneg("rolling_resistance.hysteresis_loss", rr.hysteresis_loss)
    _nonneg("rolling_resistance.speed_linear", rr.speed_linear)
    _nonneg("rolling_resistance.speed_quartic", rr.speed_quartic)
    if g.nx < 8 or g.ny < 5:
        raise MftireInputError("tyre parameters 'grid.nx' >= 8 and 'grid.ny' >= 5 are required")
    _positive("grid.carcass_tol", g.carcass_tol)
    _in_range("grid.relaxation", g.relaxation, 0.05, 1.0)
    _nonneg("grid.newton_tol", g.newton_tol)
    if g.carcass_maxiter < 1 or g.newton_iter < 2:
        raise MftireInputError("tyre parameters 'grid.carcass_maxiter' >= 1 and 'grid.newton_iter' >= 2")


def check_operating_range(tyre: TyreConfig, Fz: np.ndarray, Vx: np.ndarray, P: np.ndarray) -> None:
    """Reject loads, speeds and pressures outside the model's range (MftireInputError)."""
    Fz, Vx, P = (np.asarray(a, dtype=float) for a in (Fz, Vx, P))
    for name, arr in (("Fz", Fz), ("Vx", Vx), ("P", P)):
        if not np.all(np.isfinite(arr)):
            raise MftireInputError(f"operating point {name} contains NaN or inf")
    if np.any(Fz <= 0.0):
        raise MftireInputError(f"Fz must be positive (got {Fz.min():.6g} N)")
    if np.any(Fz > tyre.max_load):
        raise MftireInputError(
            f"Fz = {Fz.max():.6g} N exceeds the model's range: at most size.max_load_fraction "
            f"{tyre.size.max_load_fraction:g} x load-index load = {tyre.max_load:.0f} N"
        )
    if np.any(Vx <= 0.1) or np.any(Vx > tyre.friction.max_speed):
        raise MftireInputError(
            f"Vx must lie in (0.1, {tyre.friction.max_speed:g}] m/s (got {Vx.min():.6g}..{Vx.max():.6g})"
        )
    pn = tyre.size.nominal_pressure
    lo, hi = tyre.size.min_pressure_fraction * pn, tyre.size.max_pressure_fraction * pn
    if np.any(P < lo) or np.any(P > hi):
        raise MftireInputError(
            f"P must lie in [{lo:.0f}, {hi:.0f}] Pa for this tyre (got {P.min():.6g}..{P.max():.6g} Pa)"
        )
