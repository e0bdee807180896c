"""The one model pipeline, and the 30 output channels of the reference evaluator MFeval.

The evaluation runs in three cacheable pieces, which the evaluator, the fitter, the
bands, the diagnosis and the comparison all call (none rebuilds the equations):

1. :func:`prepare` -- input checks, conditioning (limits, low speed), wheel spin and
   effective rolling radius, and the variables the model extensions read.  Depends
   on the inputs and on never-fitted constants only (FNOMIN, LONGVL, ranges, Q_RE0 ...).
2. :func:`scaled` -- the effective parameters: the file's scaling factors times the
   extension terms of ``[MFTIRE_EXTENSIONS]`` (:mod:`mftire.mf.extensions`).
3. :func:`channels` -- the Magic Formula equations by channel, computing only what
   is asked for; :func:`outputs` assembles MFeval's 30 channels.

:func:`evaluate_arrays` chains them.  :class:`mftire.tyre.Tyre` is the object layer.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from mftire.errors import MftireError, MftireInputError
from mftire.mf import kernel, pac2002, spec, turnslip
from mftire.mf.aligning import aligning_terms, mz0, mz_combined, zero_camber_lateral
from mftire.mf.basic import basic, increments
from mftire.mf.extensions import ExtensionSet, apply_input_laws, builtin_variables, parse_section
from mftire.mf.family import PAC2002_CODE, is_pac2002
from mftire.mf.inputs import Conditions, MFLimitWarning, condition_inputs
from mftire.mf.lateral import fy0, fy_combined
from mftire.mf.longitudinal import fx0, fx_combined
from mftire.mf.modes import Mode
from mftire.mf.overturning import mx
from mftire.mf.relaxation import relaxation
from mftire.mf.rolling import my
from mftire.mf.vertical import contact_patch, effective_rolling_radius, loaded_radius_61, loaded_radius_62

#: The 30 outputs, in the order and with the meaning of MFeval's output matrix
#: (:data:`mftire.mf.spec.OUTPUTS`, the order the compiled kernel writes them in).
OUTPUT_NAMES: tuple[str, ...] = kernel.OUTPUTS

#: Units of the outputs (SI, one spelling: :data:`mftire.mf.spec.OUTPUTS`).
OUTPUT_UNITS: dict[str, str] = {o.name: o.unit for o in spec.OUTPUTS}

#: FITTYP values the evaluator handles: 61 (MF 6.1), 62 (MF 6.2) and 6 (MF 5.2, as MFeval); PAC2002 has
#: its own model code (:data:`mftire.mf.spec.FAMILIES`).
EVALUATED_FITTYP = tuple(int(f.code) for f in spec.FAMILIES if f.code != PAC2002_CODE)


class UnsupportedModelError(MftireError):
    """The property file describes a model version the evaluator does not evaluate."""


def unsupported_message(fittyp) -> str:
    """Why parameters with this ``FITTYP`` (None or 0: absent) are not evaluated."""
    shown = int(fittyp) if isinstance(fittyp, float) and fittyp.is_integer() else fittyp
    evaluated = ("mftire evaluates MF 6.1 (FITTYP 61), MF 6.2 (62), MF 5.2 (6, 21), MF-Tyre 5.0 (5) and PAC2002 "
                 "property files")
    if shown in (None, 0):
        return f"the parameters have no FITTYP and their PROPERTY_FILE_FORMAT names no known model: {evaluated}."
    return f"FITTYP {shown} is not evaluated: {evaluated}."


_NAN_TEXT = next(w.text for w in spec.WARNINGS if w.input is not None)  # fill 0.0 (P: INFLPRES, silently)


def _clean(name: str, x: np.ndarray, fill: float) -> np.ndarray:
    """Replace NaN (and infinite values, treated as NaN) by ``fill`` with a warning (documented input policy)."""
    bad = ~np.isfinite(x)
    if bad.any():
        warnings.warn(_NAN_TEXT.format(n=int(bad.sum()), input=name), MFLimitWarning, stacklevel=4)
        x = np.where(bad, fill, x)
    return x


def check_fittyp(p: Mapping[str, float]) -> None:
    """Raise :class:`UnsupportedModelError` unless the evaluator handles ``p['FITTYP']``."""
    fittyp = p.get("FITTYP")
    if fittyp not in EVALUATED_FITTYP and fittyp != PAC2002_CODE:
        raise UnsupportedModelError(unsupported_message(fittyp))


@dataclass
class Prepared:
    """Piece 1 of the pipeline: the conditioned operating points (see :func:`prepare`)."""

    mode: Mode
    c: Conditions  #: conditioned inputs; ``omega`` filled
    dpi: np.ndarray  #: normalised pressure increment [-] (eq 4.E2b)
    Re: np.ndarray  #: effective rolling radius [m]
    Romega: np.ndarray  #: free radius at the wheel spin [m]
    variables: dict[str, np.ndarray]  #: external extension variables (data columns)
    shape: tuple[int, ...]
    builtin: dict[str, np.ndarray] | None = None  #: builtin variables, computed when first needed

    def all_variables(self, p: Mapping[str, float]) -> dict[str, np.ndarray]:
        """External and builtin variables (:data:`mftire.mf.extensions.BUILTIN_VARIABLES`)."""
        if self.builtin is None:
            with np.errstate(all="ignore"):
                self.builtin = builtin_variables(p, self.c)
        return {**self.variables, **self.builtin}


def prepare(p: Mapping[str, float], Fz, kappa, alpha, gamma, phit, Vx, P, omega, mode: int | Mode,
            variables: Mapping[str, object] | None) -> Prepared:  # fmt: skip
    """Piece 1: validate, broadcast and condition the inputs (arguments as :func:`evaluate_arrays`, every one
    given: the defaults are :func:`evaluate_arrays`'s).

    NaN inputs are replaced by 0 (pressure: ``INFLPRES``) with an
    :class:`~mftire.mf.inputs.MFLimitWarning`; out-of-range values are clipped in modes 1xx.
    """
    check_fittyp(p)
    m = mode if isinstance(mode, Mode) else Mode.from_code(mode)
    if Vx is None:
        Vx = p["LONGVL"]
    names = list((variables or {}).keys())
    try:
        arrays = np.broadcast_arrays(
            *(np.asarray(v, dtype=float) for v in (Fz, kappa, alpha, gamma, phit, Vx)),
            *(np.asarray(variables[k], dtype=float) for k in names),
        )
    except (ValueError, TypeError) as exc:
        raise MftireInputError(f"inputs cannot be broadcast together or are not numeric: {exc}") from None
    shape = arrays[0].shape
    external = {k: _clean(k, np.array(a, dtype=float), 0.0) for k, a in zip(names, arrays[6:], strict=True)}
    Fz, kappa, alpha, gamma, phit, Vx = (
        _clean(n, np.array(a, dtype=float), 0.0)
        for n, a in zip(("Fz", "kappa", "alpha", "gamma", "phit", "Vx"), arrays[:6], strict=True)
    )
    if P is None:
        P = np.full(shape, float(p["INFLPRES"]))
    else:
        P = np.broadcast_to(np.asarray(P, dtype=float), shape)
        P = np.where(~np.isfinite(P) | (P <= 0.0), float(p["INFLPRES"]), P)
    if omega is not None:
        omega = np.broadcast_to(np.asarray(omega, dtype=float), shape)
        omega = None if not np.any(omega) else _clean("omega", np.array(omega), 0.0)
    with np.errstate(all="ignore"):
        c = condition_inputs(p, m, Fz, kappa, alpha, gamma, phit, Vx, P)
        _, _, dpi = increments(p, c.Fz, c.P)  # eq 4.E2b
        Re, Romega, c.omega = effective_rolling_radius(p, c, dpi, omega)
    return Prepared(m, c, dpi, Re, Romega, external, shape)


def scaled(
    p: Mapping[str, float], extensions: ExtensionSet | None, pre: Prepared, warn: bool = True
) -> tuple[dict, dict[str, np.ndarray]]:
    """Piece 2: effective parameters ``(q, offsets)`` (see :meth:`ExtensionSet.scale`).

    Without extensions ``q`` is ``p`` itself and ``offsets`` is empty.  Extension
    coefficients (``EXTn_C1`` ...) are taken from ``p`` when it holds them, so a fitter
    can vary them like any coefficient.  In modes 1xx the extension variables are clamped to the
    ranges their terms were fitted on, with an :class:`~mftire.mf.inputs.MFLimitWarning` when ``warn``.
    """
    if not extensions:
        return p, {}
    with np.errstate(all="ignore"):
        return extensions.scale(p, pre.all_variables(p), limits=pre.mode.limits, warn=warn)


@dataclass
class Channels:
    """Piece 3: the Magic Formula channels and their intermediate terms (None: not computed)."""

    b: object = None  #: :class:`mftire.mf.basic.Basic`
    c: Conditions | None = None  #: conditions with the turn-slip spin of this parameter set
    Fx0: np.ndarray | None = None
    mux: np.ndarray | None = None
    Kxk: np.ndarray | None = None
    Fx: np.ndarray | None = None
    lat: object = None  #: :class:`mftire.mf.lateral.PureLateral`
    Fy: np.ndarray | None = None
    Gyk: np.ndarray | None = None
    lat0: object = None  #: pure lateral force at zero camber for the trail term (eq 4.E74)
    Mz: np.ndarray | None = None
    t: np.ndarray | None = None
    Mzr: np.ndarray | None = None
    Mx: np.ndarray | None = None
    My: np.ndarray | None = None


#: What each channel needs computed first: the whole forces of its group, then itself (mftire.mf.spec.GROUPS).
_NEEDS = {g.channel: (*g.forces, g.channel) if g.channel not in g.forces else g.forces
          for g in spec.GROUPS if g.channel}  # fmt: skip


def channels(
    q: Mapping[str, float],
    pre: Prepared,
    offsets: Mapping[str, np.ndarray] | None = None,
    want: tuple[str, ...] = ("Fx", "Fy", "Mz", "Mx", "My"),
    given: Channels | None = None,
) -> Channels:
    """Piece 3: the channels ``want`` (and what they need) for effective parameters ``q``.

    ``given`` holds terms computed before with the same ``q`` for the force equations
    (a fitter that varies only aligning coefficients passes the forces, and the
    zero-camber lateral force of eq 4.E74, once computed).
    """
    todo: set[str] = set()
    for w in want:
        todo.update(_NEEDS[w])
    m = pre.mode
    out = dataclasses.replace(given) if given is not None else Channels()
    offsets = offsets or {}
    with np.errstate(all="ignore"):
        if out.b is None:
            c = apply_input_laws(pre.c, offsets)  # input laws of the model extensions (alpha, gamma, P)
            if m.turn_slip:
                phi, eps_gamma = turnslip.turn_slip_spin(q, c)
                c = dataclasses.replace(c, phi=phi, eps_gamma=eps_gamma)
            out.c = c
            out.b = basic(q, m, c)
        c, b = out.c, out.b
        if "Fx" in todo and out.Fx is None:
            z1 = turnslip.zeta1(q, b.dfz, c.kappa, c.phi) if m.turn_slip else 1.0
            out.Fx0, out.mux, out.Kxk = fx0(q, m, c, b, z1)  # eq 4.E9
            Fx = fx_combined(q, m, c, b, out.Fx0) if m.combined else out.Fx0  # eq 4.E50
            if "FX_OFFSET" in offsets:
                Fx = Fx + c.Fz * offsets["FX_OFFSET"]
            out.Fx = Fx
        if "Fy" in todo and out.Fy is None:
            out.lat = fy0(q, m, c, b, b.gamma_star, turn_slip=m.turn_slip)  # eq 4.E19
            Fy, out.Gyk, _ = fy_combined(q, m, c, b, out.lat.Fy0, out.lat.muy, out.lat.zeta2)  # eq 4.E58
            Fy = Fy if m.combined else out.lat.Fy0
            if "FY_OFFSET" in offsets:
                Fy = Fy + c.Fz * offsets["FY_OFFSET"]
            out.Fy = Fy
        if "Mz" in todo:
            terms = aligning_terms(q, m, c, b, out.lat, out.Gyk)  # eqs 4.E33-4.E47
            if m.combined:
                if out.lat0 is None:  # kept in ``given`` by a fitter of aligning coefficients
                    out.lat0 = zero_camber_lateral(q, m, c, b, out.lat)
                out.Mz, out.t, out.Mzr = mz_combined(
                    q, m, c, b, terms, out.Kxk, out.Fx, out.Fy, out.Gyk, out.lat, out.lat0
                )
            else:
                if is_pac2002(q):  # PAC2002: pure-slip Mz0 with Fy0 at the actual camber (docs/pac2002.md)
                    out.Mz, out.t, out.Mzr = pac2002.mz0(q, m, c, b, terms, out.lat)
                else:
                    out.Mz, out.t, out.Mzr = mz0(q, m, c, b, terms)
        if "Mx" in todo:
            out.Mx = mx(q, c, b.dpi if "P_FACTOR" in offsets else pre.dpi, out.Fy)
        if "My" in todo:
            out.My = my(q, c, out.Fx)
    return out


#: The :func:`channels` each output needs (outputs of no group are conditioned inputs, Re and omega).
CHANNEL_NEEDS: dict[str, tuple[str, ...]] = {
    o.name: g.channels for o in spec.OUTPUTS for g in spec.GROUPS if o.group == g.name and g.channels
}


_OUTPUT_BY_NAME = {o.name: o for o in spec.OUTPUTS}
_GROUP_OUTPUTS = {g.name: {o.name for o in spec.OUTPUTS if o.group == g.name} for g in spec.GROUPS}


def output_names(channels: str | Sequence[str] | None) -> tuple[str, ...]:
    """The outputs asked for by ``channels`` of :func:`evaluate_arrays` (None: all 30), checked."""
    if channels is None:
        return OUTPUT_NAMES
    names = (channels,) if isinstance(channels, str) else tuple(channels)
    bad = [k for k in names if k not in OUTPUT_UNITS]
    if bad:
        raise ValueError(f"unknown output channel(s) {', '.join(map(repr, bad))}; the channels are "
                         f"{', '.join(OUTPUT_NAMES)}")  # fmt: skip
    return tuple(dict.fromkeys(names))


def outputs(
    q: Mapping[str, float], pre: Prepared, ch: Channels, names: tuple[str, ...] = OUTPUT_NAMES
) -> dict[str, np.ndarray]:
    """MFeval's channels ``names`` (default all of :data:`OUTPUT_NAMES`) from a :class:`Channels`
    holding what they need (:data:`CHANNEL_NEEDS`)."""
    c, m, dpi = ch.c, pre.mode, pre.dpi
    shape = pre.shape
    want = set(names)
    rho = Rl = Cz = a = bw = Cx = Cy = sigmax = sigmay = instKya = muy = None
    with np.errstate(all="ignore"):
        if "muy" in want:
            muy = np.abs(ch.lat.muy) if m.limits else ch.lat.muy
        if want & _GROUP_OUTPUTS["RAD"]:
            if q["FITTYP"] == 61:
                rho, Rl, Cz = loaded_radius_61(q, c, dpi, c.omega, pre.Romega, ch.Fx, ch.Fy)
            else:
                rho, Rl, Cz = loaded_radius_62(q, c, dpi, c.omega, pre.Romega, ch.Fx, ch.Fy)
        if want & _GROUP_OUTPUTS["PATCH"]:
            a, bw = contact_patch(q, c, dpi)
            a, bw = 2.0 * a, 2.0 * bw
        if want & _GROUP_OUTPUTS["RELAX"]:
            Cx, Cy, sigmax, sigmay = relaxation(q, c, ch.Kxk, ch.lat.Kya)
        if "instKya" in want:
            # along the slip angle as given (conditioned, before an input law's offset), as the C kernel stores it
            fy_flat, al_flat = np.broadcast_to(ch.Fy, shape).ravel(), np.broadcast_to(pre.c.alpha, shape).ravel()
            if fy_flat.size > 1:
                d = np.diff(fy_flat) / np.diff(al_flat)
                instKya = np.append(d, d[-1]).reshape(shape)
            else:
                instKya = np.zeros(shape)
    lat = ch.lat
    # the values by the C model's names (MFOutputs members, and the conditioned inputs), then each output
    # as mftire.mf.spec.OUTPUTS says
    fields = {
        "Fx": ch.Fx, "Fy": ch.Fy, "Fz": c.uFz, "Mx": ch.Mx, "My": ch.My, "Mz": ch.Mz, "Re": pre.Re, "rho": rho,
        "a2": a, "t": ch.t, "mux": ch.mux, "muy": muy, "omega": c.omega, "Rl": Rl, "b2": bw, "Mzr": ch.Mzr,
        "Cx": Cx, "Cy": Cy, "Cz": Cz, "Kya": lat.Kya if lat is not None else None, "sigmax": sigmax,
        "sigmay": sigmay, "Kxk": ch.Kxk,
    }  # fmt: skip
    out = {o.name: fields[o.field] if o.field is not None and o.cond is None else getattr(c, o.cond)
           for o in _OUTPUT_BY_NAME.values() if o.name in want}  # fmt: skip
    out["instKya"] = instKya
    if shape == ():  # scalar inputs: numpy scalars (as the kernel path)
        return {k: np.float64(np.real(out[k])) for k in names}
    return {k: np.broadcast_to(np.real(out[k]), shape).astype(float, copy=False) for k in names}


def evaluate_arrays(
    p: Mapping[str, float],
    Fz,
    kappa,
    alpha,
    gamma=0.0,
    phit=0.0,
    Vx=None,
    P=None,
    omega=None,
    mode: int = 111,
    extensions: Mapping[str, object] | ExtensionSet | None = None,
    variables: Mapping[str, object] | None = None,
    channels: str | Sequence[str] | None = None,
    backend: str | None = None,
) -> dict[str, np.ndarray]:
    """Steady-state Magic Formula outputs for broadcast inputs (the three pieces chained).

    The compiled array kernel (:mod:`mftire.mf.kernel`) evaluates when it is available;
    this numpy pipeline is the reference it agrees with to 1e-12 and the fallback.

    Parameters
    ----------
    p : dict
        Flat parameter dictionary with every standard key (see
        :func:`mftire.parameters.with_defaults`).
    Fz : array_like
        Vertical load [N].  Negative values are set to 0 (lift-off).
    kappa : array_like
        Longitudinal slip [-] (−1 = locked wheel).
    alpha : array_like
        Slip angle [rad].
    gamma : array_like
        Inclination angle [rad].
    phit : array_like
        Turn slip [1/m] (used in modes x x2).
    Vx : array_like, optional
        Forward speed [m/s]; default ``LONGVL``.
    P : array_like, optional
        Inflation pressure [Pa]; default ``INFLPRES``.  Values <= 0 also mean
        ``INFLPRES`` (as the reference's all-zero pressure column).
    omega : array_like, optional
        Wheel spin [rad/s]; estimated from kappa, Vx and Re when not given (or all zero).
    mode : int
        Three-digit ``useMode`` (see :mod:`mftire.mf.modes`).
    extensions : ExtensionSet or mapping, optional
        The ``[MFTIRE_EXTENSIONS]`` terms (see :mod:`mftire.mf.extensions`).
    variables : dict, optional
        External input arrays the extensions read, by name (e.g. ``temperature``).
    channels : str or sequence of str, optional
        The outputs to compute (names of :data:`OUTPUT_NAMES`); default all 30.  Only
        what they need is computed.
    backend : {"auto", "kernel", "numpy"}, optional
        ``"numpy"`` forces this numpy pipeline, ``"kernel"`` the compiled kernel (an error
        when it is not built); default ``"auto"``: the kernel when available, unless the
        environment variable ``MFTIRE_BACKEND`` is ``numpy``.

    Returns
    -------
    dict
        The channels asked for (default the 30 of :data:`OUTPUT_NAMES`), each an array
        of the broadcast shape (a numpy scalar for scalar inputs).
    """
    if p.get("FITTYP") == PAC2002_CODE and not isinstance(p, kernel.FlatParameters):
        p = pac2002.prepare(p)  # idempotent: a Tyre's flat parameters are prepared already
    ext = extensions if isinstance(extensions, ExtensionSet) else parse_section(extensions)
    names = output_names(channels)
    if not isinstance(mode, Mode) and kernel.use_kernel(backend):
        check_fittyp(p)
        if mode not in CHECKED_MODES:
            Mode.from_code(mode)  # raises for a bad mode, as prepare()
            CHECKED_MODES.add(mode)
        out = kernel.evaluate(p, Fz, kappa, alpha, gamma, phit, Vx, P, omega, mode, ext, variables, names)
        if out is not None:
            return out
    pre = prepare(p, Fz, kappa, alpha, gamma, phit, Vx, P, omega, mode, variables)
    q, offsets = scaled(p, ext, pre)
    want = tuple(dict.fromkeys(w for k in names for w in CHANNEL_NEEDS.get(k, ())))
    return outputs(q, pre, _channels(q, pre, offsets, want=want), names)


_channels = channels
#: The useMode codes found valid so far (:func:`valid_mode` adds to it; the latency path of
#: :meth:`mftire.Tyre.evaluate` reads it before calling the check).
CHECKED_MODES: set = set()


def valid_mode(mode) -> bool:
    """Whether ``mode`` is a valid three-digit ``useMode`` given as an ``int`` (checked once per code, then
    remembered): the latency path of :meth:`mftire.Tyre.evaluate` serves any valid mode from its first call."""
    if mode in CHECKED_MODES:
        return True
    if type(mode) is not int:
        return False
    try:
        Mode.from_code(mode)
    except MftireError:
        return False
    CHECKED_MODES.add(mode)
    return True
