"""Transient tyre: wheel kinematics in, relaxation-length slip dynamics, standstill.

A single-contact-point transient slip model (Pacejka, *Tire and Vehicle Dynamics*,
3rd ed. 2012, ch. 7: §7.2.1 linear contact-point model, §7.2.2 its semi-non-linear
form with the steady-state Magic Formula evaluated at the transient slips, §7.3
enhanced model with the low-speed damping), with the MF 6.1 relaxation lengths
sigma_kappa = |Kxk/Cx| and sigma_alpha = |Kya/Cy| (Besselink et al. 2010 eq 19,
:mod:`mftire.mf.relaxation`).

Inputs (ISO-W axes, SI): ``Fz``, the wheel-centre velocity ``Vx``, ``Vy`` (y to the
left), the wheel spin ``omega``, ``gamma``, ``P``, ``muRoad`` and ``yawRate``.
States ``x = (u, v)`` [m]: the longitudinal and lateral slip deflections of the
contact point, scaled so that the transient slips are ``kappa' = u/sigma_kappa`` and
``tan(alpha') = v/sigma_alpha`` (``v`` is minus the physical lateral deflection in
ISO axes, because Kya < 0).

State equations (Pacejka 2012 §7.2.1, contact-point lag ``dv/dt + |Vx|·v/sigma = slip
velocity``; §7.2.2/§7.3, the relaxation length follows the slope of the force characteristic,
so the carcass deflection stays within sliding force / carcass stiffness), with a deflection
limiter (mftire addition, inactive below the limits)::

    du/dt = r_x·(-Vsx - A_x·u/sigma_kappa),   Vsx = Vx - omega·Re      (slip velocity, eq 2.5)
    dv/dt = r_y·( Vsy - A_y·v/sigma_alpha),   Vsy = Vy                 (eq 2.12, ISO sign)
    A_x = |Vx| + G·|Vsx|·max(0, |u|/(sigma_kappa·K_lim) - 1)²
    r_x = 1/max(sech²(kappa'/kappa_s), TR_SIGMA_MIN/sigma_kappa),  kappa_s = mu_x·Fz·|sin(pi/2·C_x)|/Kxk

The carcass deflection is u_c = sigma_kappa·kappa_s·tanh(kappa'/kappa_s) (|u_c| < F_sl/C_x, F_sl the sliding
force D_x·sin(pi/2·C_x), the Magic Formula's asymptote, Pacejka 2012 §4.3.2),
its rate du_c/dt = -Vsx - A_x·kappa' (the lag of the linear model); the slip state relaxes with
the local relaxation length sigma_kappa·sech²(kappa'/kappa_s).  Lateral likewise.

Outputs: the steady-state Magic Formula at the transient slips, with the low-speed
model below ``VXLOW`` (see ``docs/transient.md``)::

    kappa_t = (u + w·tau_x·du/dt) / sigma_kappa          (§7.3 low-speed damping)
    alpha_t = atan((v + w·tau_y·dv/dt) / sigma_alpha)
    w = (1 + cos(pi·min(|Vx|/VXLOW, 1)))/2              (1 at standstill, 0 at VXLOW)

The Magic Formula is evaluated rolling forward at ``max(|Vx|, VXLOW⁺)``, VXLOW⁺ the
next double above VXLOW (no slip reduction: the relaxation model replaces MFeval's
low-speed slip reduction, whose factors are all 1 at VXLOW);
the rolling offsets of Fx, Fy, Mz fade out with ``w`` (their zero-slip values are
subtracted times ``w``), My changes sign smoothly with ``Vx``.  At standstill the
tyre is therefore a damped spring: Fx = Cx·(u + tau_x·du/dt) in the linear range.

The same equations are compiled into the transient FMU (``mftire export-fmu
--transient``, ``mftire/mf/c/mf_transient.c``); the constants of
:data:`CONSTANTS` are its tunable parameters (one table for both).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from mftire.errors import MftireInputError
from mftire.iotools.tir_checks import value_errors
from mftire.mf.modes import Mode
from mftire.mf.solver import evaluate_arrays

if TYPE_CHECKING:
    from mftire.tyre import Tyre

#: Constants of the transient model: (name, default, unit, description).  They are the
#: tunable parameters of the transient FMU too (written into its C header).
CONSTANTS: tuple[tuple[str, float, str, str], ...] = (
    ("TR_TAU_X", 0.01, "s", "Low-speed damping time constant, longitudinal (damping = Cx*tau)"),
    ("TR_TAU_Y", 0.01, "s", "Low-speed damping time constant, lateral (damping = Cy*tau)"),
    ("TR_KAPPA_LIM", 1.0, "-", "Transient slip |u/sigma_kappa| beyond which the deflection limiter acts"),
    ("TR_TANALPHA_LIM", 1.0, "-", "Transient |tan alpha| = |v/sigma_alpha| beyond which the limiter acts"),
    ("TR_LIM_GAIN", 100.0, "-", "Gain of the deflection limiter (slip overshoot ~ 1/sqrt(gain))"),
    ("TR_SIGMA_MIN", 1e-3, "m", "Lower bound of the relaxation lengths (lift-off, Fz = 0)"),
    ("TR_SAT", 1.0, "-", "Factor on the saturation slip F_slide/K of the carcass deflection (0: linear relaxation)"),
    ("TR_CS_STEP", 1e-4, "s", "Largest internal step of the Co-Simulation integrator (non-linear range)"),
)

#: Relative change of the local relaxation length over a Co-Simulation step below which the step is
#: taken as one exact exponential step (else sub-steps of at most TR_CS_STEP).
CS_LINEAR_TOL = 0.01

#: Default constants by name.
DEFAULT_CONSTANTS: dict[str, float] = {name: value for name, value, _, _ in CONSTANTS}

#: Kinematic inputs: (name, unit, description, default) -- default a .tir key, a number, or
#: ``FREE_ROLLING`` (the spin of free rolling at LONGVL under FNOMIN, :func:`input_defaults`).
INPUTS: tuple[tuple[str, str | None, str, str | float], ...] = (
    ("Fz", "N", "Vertical load (negative: lift-off, treated as 0)", "FNOMIN"),
    ("Vx", "m/s", "Longitudinal velocity of the wheel centre (W axes)", "LONGVL"),
    ("Vy", "m/s", "Lateral velocity of the wheel centre (W axes, ISO: y to the left)", 0.0),
    ("omega", "rad/s", "Wheel spin speed (default: free rolling at LONGVL, FNOMIN)", "FREE_ROLLING"),
    ("gamma", "rad", "Inclination (camber) angle", 0.0),
    ("P", "Pa", "Inflation pressure (NaN or <= 0: INFLPRES)", "INFLPRES"),
    ("muRoad", None, "Road friction factor, multiplies LMUX and LMUY", 1.0),
    ("yawRate", "rad/s", "Yaw rate of the wheel (turn slip, used when useMode ends in 2)", 0.0),
)

FREE_ROLLING = "FREE_ROLLING"


def input_defaults(flat: Mapping[str, float]) -> dict[str, float]:
    """Default of every input for the flat parameters ``flat``: the file's FNOMIN, LONGVL,
    INFLPRES; omega of free rolling there (omega = LONGVL/Re, Re as MFeval estimates it);
    0; muRoad 1."""
    out = {}
    for name, _, _, d in INPUTS:
        if d == FREE_ROLLING:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                ev = evaluate_arrays(dict(flat), flat["FNOMIN"], 0.0, 0.0, 0.0, 0.0, flat["LONGVL"], None, None, 111)
            out[name] = float(ev["omega"])
        else:
            out[name] = float(flat[d]) if isinstance(d, str) else float(d)
    return out


#: Transient outputs ahead of the steady-state channels (name, unit, description).
TRANSIENT_OUTPUTS: tuple[tuple[str, str | None, str], ...] = (
    ("kappa_t", None, "Transient longitudinal slip (incl. low-speed damping)"),
    ("alpha_t", "rad", "Transient slip angle (incl. low-speed damping)"),
)

#: State names (FMU local variables with their derivatives ``der(u)``, ``der(v)``).
STATES: tuple[tuple[str, str], ...] = (
    ("u", "Longitudinal slip deflection of the contact point (kappa' = u/sigma_kappa)"),
    ("v", "Lateral slip deflection of the contact point (tan alpha' = v/sigma_alpha)"),
)

#: Steady-state channels published by the FMU under another name than the evaluator's.
_FMU_NAME = {"Fz": "Fz_out", "2a": "a2", "2b": "b2"}


#: The outputs that come first (the FMU's order), then every steady-state channel of the evaluator.
FIRST_OUTPUTS = ("Fx", "Fy", "Mz", "Mx", "My", "kappa_t", "alpha_t")


@dataclass
class Kinematics:
    """Input-only quantities of one operating point (arrays or floats)."""

    Vx: np.ndarray  #: wheel-centre forward velocity [m/s]
    Vsx: np.ndarray  #: longitudinal slip velocity Vx - omega*Re [m/s]
    Vsy: np.ndarray  #: lateral slip velocity [m/s]
    sigx: np.ndarray  #: relaxation length sigma_kappa [m]
    sigy: np.ndarray  #: relaxation length sigma_alpha [m]
    slx: np.ndarray  #: slip where the longitudinal deflection saturates, sliding force / Kxk (0: none) [-]
    sly: np.ndarray  #: tan(alpha) where the lateral deflection saturates, sliding force / |Kya| (0: none) [-]
    w: np.ndarray  #: low-speed weight (1 at standstill, 0 from VXLOW) [-]
    My_sign: np.ndarray  #: smooth sign of the rolling-resistance moment [-]
    zero: dict  #: steady-state outputs at zero slip (offsets, Re, sigma)
    args: dict  #: evaluator arguments except the slips


def _sliding(C: float) -> float:
    """Sliding force over peak force: the Magic Formula's asymptote y_a = D·sin(pi/2·C) over D (Pacejka 2012
    §4.3.2), for 0 < C < 2; 1 otherwise."""
    return abs(math.sin(0.5 * math.pi * C)) if 0.0 < C < 2.0 else 1.0


def _sat_slip(mu, Fz, K) -> np.ndarray:
    """Slip at which the carcass deflection saturates: force mu·Fz over the slip stiffness |K|
    (0 where not positive and finite: no saturation)."""
    with np.errstate(all="ignore"):
        q = np.abs(np.asarray(mu, dtype=float)) * np.asarray(Fz, dtype=float) / np.abs(np.asarray(K, dtype=float))
    return np.where(np.isfinite(q) & (q > 0.0), q, 0.0)


def _slope_factor(q, qs, smin):
    """1/max(sech²(q/qs), smin): how much faster than the linear lag the slip state q relaxes where the
    characteristic (slip stiffness K, peak mu·Fz) flattens; 1 where qs = 0.  sech² = 4t/(1+t)², t = exp(-2|x|)
    (no overflow)."""
    q, qs = np.asarray(q, dtype=float), np.asarray(qs, dtype=float)
    with np.errstate(all="ignore"):
        t = np.exp(-2.0 * np.abs(q / np.where(qs > 0.0, qs, 1.0)))
        s = np.where(qs > 0.0, 4.0 * t / ((1.0 + t) * (1.0 + t)), 1.0)
    return 1.0 / np.maximum(s, smin)


def _clean(x, fill: float) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    return np.where(np.isnan(x), fill, x)


class TransientTyre:
    """The transient model of one tyre (:class:`mftire.tyre.Tyre`), mode and constants.

    Parameters
    ----------
    tyre : Tyre
    mode : int
        ``useMode`` of the steady-state evaluation (default 111).
    constants : mapping, optional
        Overrides of :data:`DEFAULT_CONSTANTS`.
    """

    def __init__(self, tyre: Tyre, mode: int = 111, constants: Mapping[str, float] | None = None) -> None:
        Mode.from_code(mode)
        unknown = sorted(set(constants or {}) - set(DEFAULT_CONSTANTS))
        if unknown:
            raise MftireInputError(f"unknown transient constant(s) {', '.join(unknown)}")
        if tyre.extensions:
            raise MftireInputError(f"{tyre.name}: the transient model does not support [MFTIRE_EXTENSIONS] yet")
        self.tyre = tyre
        self.mode = int(mode)
        self.constants = {**DEFAULT_CONSTANTS, **{k: float(v) for k, v in (constants or {}).items()}}
        bad = value_errors(self.constants)  # the bounds of mftire.parameters.PARAMETER_LIMITS (TR_SAT >= 0, ...)
        if bad:
            raise MftireInputError(f"transient constant {bad[0]}")
        self._p = dict(tyre.flat)
        self._mu_cache: dict[float, dict] = {}

    def defaults(self) -> dict[str, float]:
        """Default value of every input (see :func:`input_defaults`)."""
        return input_defaults(self._p)

    def _params(self, mu: float) -> dict:
        # muRoad multiplies LMUX and LMUY (as the FMU's mf_eval.c basic()).
        if mu == 1.0:
            return self._p
        p = self._mu_cache.get(mu)
        if p is None:
            p = dict(self._p)
            p["LMUX"] = p["LMUX"] * mu
            p["LMUY"] = p["LMUY"] * mu
            if len(self._mu_cache) < 64:
                self._mu_cache[mu] = p
        return p

    def _eval(self, kin_args: dict, kappa, alpha) -> dict:
        a = kin_args
        keys = ("Fz", "gamma", "phit", "Vx", "P", "omega")
        mu = np.asarray(a["mu"], dtype=float)
        if mu.ndim == 0 or np.all(mu == mu.flat[0]):
            p = self._params(float(mu.flat[0]) if mu.size else 1.0)
            return evaluate_arrays(p, a["Fz"], kappa, alpha, *(a[k] for k in keys[1:]), self.mode)
        # friction varying over the points: one evaluation per distinct value
        keys = tuple(k for k in keys if a[k] is not None)  # omega None: free rolling (estimated)
        arrs = np.broadcast_arrays(mu, kappa, alpha, *(a[k] for k in keys))
        res: dict[str, np.ndarray] = {}
        for m in np.unique(arrs[0]):
            sel = arrs[0] == m
            rest = dict(zip(keys[1:], (x[sel] for x in arrs[4:]), strict=True))
            o = evaluate_arrays(self._params(float(m)), arrs[3][sel], arrs[1][sel], arrs[2][sel], rest["gamma"],
                                rest["phit"], rest["Vx"], rest["P"], rest.get("omega"), self.mode)  # fmt: skip
            for k, val in o.items():
                res.setdefault(k, np.zeros(arrs[0].shape))[sel] = val
        return res

    def kinematics(
        self,
        Fz: ArrayLike | None = None,
        Vx: ArrayLike = 0.0,
        Vy: ArrayLike = 0.0,
        omega: ArrayLike | None = 0.0,
        gamma: ArrayLike = 0.0,
        P: ArrayLike | None = None,
        muRoad: ArrayLike = 1.0,
        yawRate: ArrayLike = 0.0,
    ) -> Kinematics:
        """Slip velocities, relaxation lengths, low-speed weights and zero-slip offsets.

        ``Fz`` and ``P`` default to the file's ``FNOMIN`` and ``INFLPRES``, the others to a
        wheel at rest (0; ``muRoad`` 1).  ``omega=None`` means free rolling (Python only).
        Inputs broadcast against each other.
        """
        p, c = self._p, self.constants
        Fz = _clean(p["FNOMIN"] if Fz is None else Fz, 0.0)
        P = np.asarray(p["INFLPRES"] if P is None else P, dtype=float)
        free_rolling = omega is None
        Vx, Vy, omega, gamma = (_clean(v, 0.0) for v in (Vx, Vy, 0.0 if free_rolling else omega, gamma))
        mu, yawRate = _clean(muRoad, 1.0), _clean(yawRate, 0.0)
        vxlow = p["VXLOW"]
        absVx = np.abs(Vx)
        # evaluation speed: forward, never below VXLOW; the floor is the next double above VXLOW so that the
        # Magic Formula stays out of its low-speed mode (|Vx| <= VXLOW, whose factors are all 1 at VXLOW)
        Vev = np.maximum(absVx, np.nextafter(vxlow, np.inf))
        phit = -yawRate / np.sqrt(Vev**2 + Vy**2)  # turn slip phi_t = -psi_dot/V (Pacejka 2012 eq 4.75)
        omega_ev = None if free_rolling else np.where(omega == 0.0, 1e-300, omega)  # a true 0: not "estimate"
        args = dict(Fz=Fz, gamma=gamma, phit=phit, Vx=Vev, P=P, omega=omega_ev, mu=mu)
        zero = self._eval(args, 0.0, 0.0)
        if free_rolling:  # Python only: omega = Vx/Re, no longitudinal slip velocity
            Vsx = np.zeros(np.broadcast(Vx, zero["Re"]).shape)
        else:
            Vsx = Vx - omega * zero["Re"]  # longitudinal slip velocity (Pacejka 2012 eq 2.5 / 4.E5)
        sigx = np.maximum(zero["sigmax"], c["TR_SIGMA_MIN"])  # Besselink 2010 eq 19
        sigy = np.maximum(zero["sigmay"], c["TR_SIGMA_MIN"])  # Besselink 2010 eq 19
        r = np.minimum(absVx / vxlow, 1.0)
        w = 0.5 * (1.0 + np.cos(np.pi * r))  # low-speed weight (cosine, as MFeval's VXLOW reduction)
        My_sign = np.sin(0.5 * np.pi * np.clip(Vx / vxlow, -1.0, 1.0))
        # sliding force D·|sin(pi/2·C)| (the asymptote of the Magic Formula, Pacejka 2012 §4.3.2) over the slip
        # stiffness; C = PCX1·LCX (eq 4.E11), PCY1·LCY (eq 4.E21)
        slx = c["TR_SAT"] * _sat_slip(zero["mux"] * _sliding(p["PCX1"] * p["LCX"]), zero["Fz"], zero["Kxk"])
        sly = c["TR_SAT"] * _sat_slip(zero["muy"] * _sliding(p["PCY1"] * p["LCY"]), zero["Fz"], zero["Kya"])
        return Kinematics(Vx=Vx, Vsx=Vsx, Vsy=Vy, sigx=sigx, sigy=sigy, slx=slx, sly=sly, w=w, My_sign=My_sign,
                          zero=zero, args=args)  # fmt: skip

    def lag(self, kin: Kinematics, u: ArrayLike, v: ArrayLike):
        """Carcass deflection rates (du_c/dt, dv_c/dt) and the factors (r_x, r_y) with which the slip
        states relax faster than the linear lag (du/dt = r_x·du_c/dt)."""
        c = self.constants
        gx = np.maximum(np.abs(u) / (kin.sigx * c["TR_KAPPA_LIM"]) - 1.0, 0.0)  # deflection limiter
        gy = np.maximum(np.abs(v) / (kin.sigy * c["TR_TANALPHA_LIM"]) - 1.0, 0.0)
        Ax = np.abs(kin.Vx) + c["TR_LIM_GAIN"] * np.abs(kin.Vsx) * gx * gx
        Ay = np.abs(kin.Vx) + c["TR_LIM_GAIN"] * np.abs(kin.Vsy) * gy * gy
        dcu = -kin.Vsx - Ax * (u / kin.sigx)  # Pacejka 2012 §7.2.1: du/dt + |Vx|/sigma_kappa*u = -Vsx
        dcv = kin.Vsy - Ay * (v / kin.sigy)  # Pacejka 2012 §7.2.1: dv/dt + |Vx|/sigma_alpha*v = Vsy (ISO sign)
        rx = _slope_factor(u / kin.sigx, kin.slx, c["TR_SIGMA_MIN"] / kin.sigx)
        ry = _slope_factor(v / kin.sigy, kin.sly, c["TR_SIGMA_MIN"] / kin.sigy)
        return dcu, dcv, rx, ry

    def rates(self, kin: Kinematics, u: ArrayLike, v: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """State derivatives (du/dt, dv/dt) for the kinematics ``kin`` and deflections ``u``, ``v``."""
        dcu, dcv, rx, ry = self.lag(kin, u, v)
        # slope of the characteristic: local relaxation length sigma·sech² (Pacejka 2012 §7.2.2/§7.3)
        return rx * dcu, ry * dcv

    def derivatives(self, x: ArrayLike, **inputs: ArrayLike) -> np.ndarray:
        """``[du/dt, dv/dt]`` at state ``x = (u, v)`` and the inputs (see :data:`INPUTS`)."""
        kin = self.kinematics(**inputs)
        return np.array(self.rates(kin, x[0], x[1]), dtype=float)

    def outputs_from(self, kin: Kinematics, u: ArrayLike, v: ArrayLike) -> dict[str, np.ndarray]:
        """All outputs (FMU names) at the kinematics ``kin`` and deflections ``u``, ``v``."""
        c = self.constants
        du, dv, _, _ = self.lag(kin, u, v)  # damping on the carcass deflection rate
        kappa_t = (u + kin.w * c["TR_TAU_X"] * du) / kin.sigx  # transient slip with low-speed damping (§7.3)
        alpha_t = np.arctan((v + kin.w * c["TR_TAU_Y"] * dv) / kin.sigy)  # tan alpha' = v/sigma_alpha (§7.2.1)
        ss = self._eval(kin.args, kappa_t, alpha_t)
        z = kin.zero
        out = {_FMU_NAME.get(k, k): np.asarray(val, dtype=float) for k, val in ss.items()}
        out["Fx"] = ss["Fx"] - kin.w * z["Fx"]  # rolling offsets fade out below VXLOW
        out["Fy"] = ss["Fy"] - kin.w * z["Fy"]
        out["Mz"] = ss["Mz"] - kin.w * z["Mz"]
        out["My"] = ss["My"] * kin.My_sign  # rolling resistance opposes the rolling direction
        out["kappa_t"] = np.asarray(kappa_t, dtype=float)
        out["alpha_t"] = np.asarray(alpha_t, dtype=float)
        names = (*FIRST_OUTPUTS, *(k for k in out if k not in FIRST_OUTPUTS))
        return {k: np.broadcast_to(out[k], np.shape(out["Fx"])) for k in names}

    def outputs(self, x: ArrayLike, **inputs: ArrayLike) -> dict[str, np.ndarray]:
        """All outputs at state ``x = (u, v)`` and the inputs."""
        return self.outputs_from(self.kinematics(**inputs), x[0], x[1])


def _signal(value, t: np.ndarray, name: str) -> Callable[[float], float]:
    """A function of time from a scalar, an array on ``t`` (linear interpolation) or a callable."""
    if callable(value):
        return value
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        v = float(arr)
        return lambda _t: v
    if arr.shape != t.shape:
        raise MftireInputError(f"simulate: input {name} has {arr.size} values but t has {t.size}")
    return lambda tt: float(np.interp(tt, t, arr))


def simulate(
    tyre: Tyre,
    t: ArrayLike,
    Fz=None,
    Vx=None,
    Vy=0.0,
    omega=None,
    gamma=0.0,
    P=None,
    muRoad=1.0,
    yawRate=0.0,
    *,
    mode: int = 111,
    x0=(0.0, 0.0),
    constants: Mapping[str, float] | None = None,
    method: str = "LSODA",
    rtol: float = 1e-8,
    atol: float = 1e-12,
    max_step: float | None = None,
) -> pd.DataFrame:
    """Simulate the transient tyre over the time points ``t`` with :func:`scipy.integrate.solve_ivp`.

    Every input may be a scalar, an array on ``t`` (interpolated linearly) or a callable
    of time.  ``Fz``, ``Vx`` and ``P`` default to the file's ``FNOMIN``, ``LONGVL`` and
    ``INFLPRES``; ``omega`` defaults to free rolling (omega = Vx/Re, no longitudinal slip velocity -- a
    convenience of the Python model; the FMU's ``omega`` input is the wheel spin, 0 =
    locked).

    Returns a DataFrame indexed by ``t`` with the FMU's output names (``Fx, Fy, Mz,
    Mx, My, kappa_t, alpha_t, ...``) and the states ``u``, ``v``.
    """
    from scipy.integrate import solve_ivp

    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.size < 2 or np.any(np.diff(t) <= 0):
        raise MftireInputError("simulate: t must be an increasing 1-D array of at least two times")
    model = TransientTyre(tyre, mode, constants)
    d = model.defaults()
    given = dict(Fz=Fz, Vx=Vx, Vy=Vy, omega=omega, gamma=gamma, P=P, muRoad=muRoad, yawRate=yawRate)
    sig = {k: _signal(d[k] if v is None else v, t, k) for k, v in given.items() if not (k == "omega" and v is None)}

    free = {} if "omega" in sig else {"omega": None}

    def inputs_at(tt):
        return {**{k: f(tt) for k, f in sig.items()}, **free}

    def rhs(tt, x):
        kin = model.kinematics(**inputs_at(tt))
        return [float(r) for r in model.rates(kin, x[0], x[1])]

    step = max_step if max_step is not None else float(np.min(np.diff(t)))
    sol = solve_ivp(rhs, (t[0], t[-1]), list(map(float, x0)), method=method, t_eval=t, rtol=rtol, atol=atol,
                    max_step=step)  # fmt: skip
    if not sol.success:
        raise MftireInputError(f"simulate: the ODE solver failed: {sol.message}")
    u, v = sol.y
    ins = {**{k: np.array([f(tt) for tt in t]) for k, f in sig.items()}, **free}
    out = model.outputs_from(model.kinematics(**ins), u, v)
    frame = pd.DataFrame({k: np.asarray(val, dtype=float) for k, val in out.items()}, index=pd.Index(t, name="t"))
    frame["u"], frame["v"] = u, v
    return frame


def _equilibrium(f: float, sig: float, lim: float, absVx: float, Vs: float, G: float) -> float | None:
    """Equilibrium of ds/dt = r·(f - A(s)·s/sig), A(s) = |Vx| + G·|Vs|·max(0, |s|/L - 1)², L = sig·lim: the
    state the held inputs drive s to, monotonically; None when there is none.  Beyond the limit, bisection on
    [L, L·(1 + 1/sqrt(G·lim))] (60 halvings; as mt_transient.c)."""
    L, c = sig * lim, abs(f) * sig
    if f == 0.0:
        return 0.0 if (absVx > 0.0 or G * abs(Vs) > 0.0) else None
    if absVx * L >= c:
        return f * sig / absVx  # within the limit: the linear lag's steady state
    if not (G * abs(Vs) > 0.0) or not (lim > 0.0):
        return None
    lo, hi = L, L * (1.0 + 1.0 / math.sqrt(G * lim))
    if absVx > 0.0 and c / absVx < hi:
        hi = c / absVx
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        gm = mid / L - 1.0
        if (absVx + G * abs(Vs) * gm * gm) * mid < c:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi) if f > 0.0 else -0.5 * (lo + hi)


def _step1(s: float, sig: float, A: float, r: float, f: float, h: float, s_eq: float | None) -> float:
    """Exact solution over ``h`` of ds/dt = r·(f - A·s/sig) with r, A, f frozen (exponential Euler), not carried
    past the equilibrium ``s_eq`` of the unfrozen equation (the true solution never crosses it)."""
    a = r * A / sig
    ah = a * h
    phi = h if ah < 1e-12 else -math.expm1(-ah) / a
    y = s * math.exp(-ah) + r * f * phi
    if s_eq is not None and (y - s_eq) * (s - s_eq) < 0.0:
        y = s_eq
    return y


def step_exact(model: TransientTyre, kin: Kinematics, u: float, v: float, h: float) -> tuple[float, float]:
    """One exponential-Euler step of length ``h`` (the FMU's Co-Simulation sub-step).

    The rates A_x, A_y and slope factors r_x, r_y are frozen at the start of the step; each state moves
    monotonically towards the steady state of the frozen equation and is not carried past the equilibrium
    of the full equation (:func:`_equilibrium`), so the step is stable for any ``h`` and never chatters.
    For constant inputs in the linear range (limiter idle, r = 1) it is the exact solution of the lag.
    """
    c = model.constants
    sigx, sigy = float(kin.sigx), float(kin.sigy)
    Vsx, Vsy, absVx = float(kin.Vsx), float(kin.Vsy), abs(float(kin.Vx))
    gx = max(abs(u) / (sigx * c["TR_KAPPA_LIM"]) - 1.0, 0.0)
    gy = max(abs(v) / (sigy * c["TR_TANALPHA_LIM"]) - 1.0, 0.0)
    rx = float(_slope_factor(u / sigx, kin.slx, c["TR_SIGMA_MIN"] / sigx))
    ry = float(_slope_factor(v / sigy, kin.sly, c["TR_SIGMA_MIN"] / sigy))
    G = c["TR_LIM_GAIN"]
    ex = _equilibrium(-Vsx, sigx, c["TR_KAPPA_LIM"], absVx, Vsx, G)
    ey = _equilibrium(Vsy, sigy, c["TR_TANALPHA_LIM"], absVx, Vsy, G)
    un = _step1(u, sigx, absVx + G * abs(Vsx) * gx * gx, rx, -Vsx, h, ex)
    vn = _step1(v, sigy, absVx + G * abs(Vsy) * gy * gy, ry, Vsy, h, ey)
    return un, vn


def _r_flat(s0: float, s1: float, sig, qs, smin: float) -> bool:
    """Whether the slope factor r stays within CS_LINEAR_TOL along the monotone path from s0 to s1 (r depends
    on |s| only and is smallest, 1, at 0: a path through 0 includes r = 1)."""
    r0 = float(_slope_factor(s0 / float(sig), qs, smin))
    r1 = float(_slope_factor(s1 / float(sig), qs, smin))
    lo = min(r0, r1) if s0 * s1 > 0.0 else float(_slope_factor(0.0, qs, smin))
    return max(r0, r1) - lo <= CS_LINEAR_TOL * lo


def advance(model: TransientTyre, kin: Kinematics, u: float, v: float, H: float) -> tuple[float, float]:
    """Advance ``(u, v)`` by ``H`` with the inputs held: the FMU's Co-Simulation step.

    One exponential step (:func:`step_exact`) when it stays in the linear range: the limiter idle
    over the step and the slope factors along the step within :data:`CS_LINEAR_TOL` of each other.
    Else ``ceil(H/TR_CS_STEP)`` equal sub-steps.  Every (sub-)step is stable for any length.
    A result that is not finite (cannot happen with guarded inputs) keeps the state.
    """
    c = model.constants
    if not H > 0.0:
        return u, v
    un, vn = step_exact(model, kin, u, v, H)
    # the frozen step moves each state monotonically from start to end: the limiter is idle over the step
    # when both ends are within the limit
    ulim, vlim = float(kin.sigx) * c["TR_KAPPA_LIM"], float(kin.sigy) * c["TR_TANALPHA_LIM"]
    if max(abs(u), abs(un)) <= ulim and max(abs(v), abs(vn)) <= vlim:
        smx, smy = c["TR_SIGMA_MIN"] / float(kin.sigx), c["TR_SIGMA_MIN"] / float(kin.sigy)
        if _r_flat(u, un, kin.sigx, kin.slx, smx) and _r_flat(v, vn, kin.sigy, kin.sly, smy):
            return (un, vn) if math.isfinite(un) and math.isfinite(vn) else (u, v)
    n = max(int(math.ceil(H / c["TR_CS_STEP"] - 1e-9)), 1)
    x0 = (u, v)
    for _ in range(n):
        u, v = step_exact(model, kin, u, v, H / n)
    return (u, v) if math.isfinite(u) and math.isfinite(v) else x0


#: Physical bounds of the inputs (finite values beyond are saturated; the FMU's mt_guard_inputs):
#: name -> (low, high); Fz and P bounds are factors of the file's FZMAX and PRESMAX.
INPUT_BOUNDS: dict[str, tuple[float, float]] = {
    "Fz": (-math.inf, 3.0), "Vx": (-200.0, 200.0), "Vy": (-200.0, 200.0), "omega": (-2000.0, 2000.0),
    "gamma": (-1.55, 1.55), "P": (-math.inf, 3.0), "muRoad": (1e-3, 10.0), "yawRate": (-100.0, 100.0),
}  # fmt: skip


def guard_inputs(flat: Mapping[str, float], inputs: Mapping[str, float],
                 held: dict[str, float]) -> tuple[dict[str, float], list[str]]:  # fmt: skip
    """The transient model's input guard (the FMU's ``mt_guard_inputs``, same rules).

    A non-finite input (NaN, ±Inf) is replaced by its last good value ``held[name]``; a finite value
    beyond :data:`INPUT_BOUNDS` is saturated to the bound; |x| < 1e-30 is 0 (silently).  ``held`` is
    updated with the values used.
    Returns the values to use and the names of the inputs replaced or saturated.
    """
    out, bad = {}, []
    for name, _, _, _ in INPUTS:
        x = float(inputs.get(name, held[name]))
        lo, hi = INPUT_BOUNDS[name]
        if name == "Fz":
            hi *= flat["FZMAX"] if flat.get("FZMAX", 0.0) > 0.0 else flat["FNOMIN"]
        elif name == "P":
            hi *= flat["PRESMAX"] if flat.get("PRESMAX", 0.0) > 0.0 else flat["INFLPRES"]
        if abs(x) < 1e-30:
            x = 0.0 * x  # tiny and subnormal: 0 (1/x would overflow; P = 0: INFLPRES)
        if not math.isfinite(x):
            x = held[name]
            bad.append(name)
        elif x < lo or x > hi:
            x = min(max(x, lo), hi)
            bad.append(name)
        held[name] = out[name] = x
    return out, bad


class TransientStepper:
    """The transient tyre stepped as the Co-Simulation FMU steps it (Python mirror of ``fmi2DoStep``).

    ``step(H, **inputs)`` guards the inputs (:func:`guard_inputs`, a warning for each one replaced),
    advances the states with the inputs held (:func:`advance`) and returns the outputs at the new state.
    """

    def __init__(self, model: TransientTyre, x0=(0.0, 0.0)) -> None:
        self.model = model
        self.x = (float(x0[0]), float(x0[1]))
        self.held = model.defaults()
        self.time = 0.0

    def set_inputs(self, **inputs: float) -> Kinematics:
        """Guarded kinematics of ``inputs`` (omitted inputs keep their last value)."""
        vals, bad = guard_inputs(self.model._p, inputs, self.held)
        if bad:
            msg = "not finite or out of range: the last good value is held (non-finite) or the bound used"
            warnings.warn(f"t={self.time:.17g}: transient tyre input(s) {', '.join(bad)} {msg}", stacklevel=3)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return self.model.kinematics(**vals)

    def step(self, H: float, **inputs: float) -> dict[str, float]:
        kin = self.set_inputs(**inputs)
        self.x = advance(self.model, kin, self.x[0], self.x[1], H)
        self.time += H
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out = self.model.outputs_from(kin, self.x[0], self.x[1])
        return {k: float(v) for k, v in out.items()}


__all__ = [
    "CONSTANTS",
    "CS_LINEAR_TOL",
    "INPUT_BOUNDS",
    "TransientStepper",
    "guard_inputs",
    "DEFAULT_CONSTANTS",
    "INPUTS",
    "Kinematics",
    "STATES",
    "TransientTyre",
    "advance",
    "input_defaults",
    "FIRST_OUTPUTS",
    "simulate",
    "step_exact",
]
