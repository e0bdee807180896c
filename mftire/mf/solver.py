"""Assemble the 30 output channels of the reference evaluator MFeval.

:func:`evaluate_arrays` is the pure, vectorised core: a flat parameter dictionary
in, a dictionary of arrays out.  :class:`mftire.tyre.Tyre` is the object layer.
"""

from __future__ import annotations

import warnings

import numpy as np

from mftire.errors import MftireError, MftireInputError
from mftire.extensions import extension_terms
from mftire.mf import pac2002, turnslip
from mftire.mf.aligning import aligning_terms, mz0, mz_combined
from mftire.mf.basic import basic
from mftire.mf.family import PAC2002_CODE
from mftire.mf.inputs import MFLimitWarning, condition_inputs, turn_slip_spin
from mftire.mf.lateral import fy0, fy_combined
from mftire.mf.longitudinal import fx0, fx_combined
from mftire.mf.modes import Mode
from mftire.mf.overturning import mx
from mftire.mf.relaxation import relaxation
from mftire.mf.rolling import my
from mftire.mf.vertical import contact_patch, effective_rolling_radius, loaded_radius_61, loaded_radius_62

#: The 30 outputs, in the order and with the meaning of MFeval's output matrix.
OUTPUT_NAMES: tuple[str, ...] = (
    "Fx", "Fy", "Fz", "Mx", "My", "Mz", "kappa", "alpha", "gamma", "phit", "Vx", "P", "Re", "rho",
    "2a", "t", "mux", "muy", "omega", "Rl", "2b", "Mzr", "Cx", "Cy", "Cz", "Kya", "sigmax", "sigmay",
    "instKya", "Kxk",
)  # fmt: skip

#: Units of the outputs.
OUTPUT_UNITS: dict[str, str] = {
    "Fx": "N", "Fy": "N", "Fz": "N", "Mx": "N*m", "My": "N*m", "Mz": "N*m", "kappa": "-", "alpha": "rad",
    "gamma": "rad", "phit": "1/m", "Vx": "m/s", "P": "Pa", "Re": "m", "rho": "m", "2a": "m", "t": "m",
    "mux": "-", "muy": "-", "omega": "rad/s", "Rl": "m", "2b": "m", "Mzr": "N*m", "Cx": "N/m", "Cy": "N/m",
    "Cz": "N/m", "Kya": "N/rad", "sigmax": "m", "sigmay": "m", "instKya": "N/rad", "Kxk": "N",
}  # fmt: skip

#: FITTYP values the evaluator handles: 61 (MF 6.1), 62 (MF 6.2) and 6 (MF 5.2, as MFeval).
EVALUATED_FITTYP = (6, 61, 62)


class UnsupportedModelError(MftireError):
    """The property file describes a model version the evaluator does not evaluate."""


def unsupported_message(fittyp) -> str:
    """Why parameters with this ``FITTYP`` (None or 0: absent) are not evaluated."""
    shown = int(fittyp) if isinstance(fittyp, float) and fittyp.is_integer() else fittyp
    evaluated = "mftire evaluates MF 6.1 (FITTYP 61), MF 6.2 (62), MF 5.2 (6) and PAC2002 property files"
    if shown in (None, 0):
        return f"the parameters have no FITTYP (and are not a PAC2002 file): {evaluated}."
    if shown == 5:
        return (
            f"FITTYP 5 is not evaluated: MF_05 / MF-Tyre 5.0 files can be read and written, but the MF-Tyre 5.0 "
            f"equations are not public in a form that can be verified; {evaluated}."
        )
    return f"FITTYP {shown} is not evaluated: {evaluated}."


def _clean(name: str, x: np.ndarray, fill: float) -> np.ndarray:
    """Replace NaN by ``fill`` with a warning (documented input policy)."""
    bad = np.isnan(x)
    if bad.any():
        warnings.warn(
            f"{int(bad.sum())} NaN value(s) in input '{name}' replaced by {fill}.", MFLimitWarning, stacklevel=4
        )
        x = np.where(bad, fill, x)
    return x


def evaluate_arrays(
    p: dict,
    Fz,
    kappa,
    alpha,
    gamma=0.0,
    phit=0.0,
    Vx=None,
    P=None,
    omega=None,
    mode: int = 111,
    extensions: dict | None = None,
    variables: dict | None = None,
) -> dict[str, np.ndarray]:
    """Steady-state Magic Formula outputs for broadcast inputs.

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
    extensions : dict, optional
        The ``[MFTIRE_EXTENSIONS]`` section (see :mod:`mftire.extensions`).
    variables : dict, optional
        Extra input arrays the extensions need, by name (e.g. ``temperature``).

    NaN inputs are replaced by 0 (pressure: ``INFLPRES``) with an
    :class:`~mftire.mf.inputs.MFLimitWarning`.

    Returns
    -------
    dict
        The 30 channels of :data:`OUTPUT_NAMES`, each an array of the broadcast shape.
    """
    fittyp = p.get("FITTYP")
    if fittyp == PAC2002_CODE:
        p = pac2002.prepare(p)
    elif fittyp not in EVALUATED_FITTYP:
        raise UnsupportedModelError(unsupported_message(fittyp))
    m = Mode.from_code(mode)
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
    variables = {k: _clean(k, np.array(a, dtype=float), 0.0) for k, a in zip(names, arrays[6:], strict=True)}
    arrays = arrays[:6]
    Fz, kappa, alpha, gamma, phit, Vx = (np.array(a, dtype=float) for a in arrays)
    Fz = _clean("Fz", Fz, 0.0)
    kappa = _clean("kappa", kappa, 0.0)
    alpha = _clean("alpha", alpha, 0.0)
    gamma = _clean("gamma", gamma, 0.0)
    phit = _clean("phit", phit, 0.0)
    Vx = _clean("Vx", Vx, 0.0)
    if P is None:
        P = np.full(shape, float(p["INFLPRES"]))
    else:
        P = np.broadcast_to(np.asarray(P, dtype=float), shape)
        P = np.where(np.isnan(P) | (P <= 0.0), float(p["INFLPRES"]), P)
    if omega is not None:
        omega = np.broadcast_to(np.asarray(omega, dtype=float), shape)
        omega = None if not np.any(omega) else _clean("omega", np.array(omega), 0.0)

    with np.errstate(all="ignore"):
        return _evaluate(p, m, Fz, kappa, alpha, gamma, phit, Vx, P, omega, extensions, variables)


def _evaluate(
    p, m: Mode, Fz, kappa, alpha, gamma, phit, Vx, P, omega, extensions=None, variables=None
) -> dict[str, np.ndarray]:
    c = condition_inputs(p, m, Fz, kappa, alpha, gamma, phit, Vx, P)
    ext = extension_terms(extensions, p, c.Fz, c.kappa, c.alpha, c.gamma, c.Vx, c.P, variables) if extensions else None
    dpi = (c.P - p["NOMPRES"]) / p["NOMPRES"]  # eq 4.E2b
    Re, Romega, c.omega = effective_rolling_radius(p, c, dpi, omega)
    if m.turn_slip:
        c.phi, c.eps_gamma = turn_slip_spin(p, c)
    b = basic(p, m, c, ext.mux, ext.muy) if ext else basic(p, m, c)

    z1 = turnslip.zeta1(p, b.dfz, c.kappa, c.phi) if m.turn_slip else 1.0
    Fx0, mux, Kxk = fx0(p, m, c, b, z1)
    lat = fy0(p, m, c, b, b.gamma_star, turn_slip=m.turn_slip)
    Fy_comb, Gyk, _ = fy_combined(p, m, c, b, lat.Fy0, lat.muy, lat.zeta2)
    terms = aligning_terms(p, m, c, b, lat, Gyk)
    if m.combined:
        Fx = fx_combined(p, m, c, b, Fx0)
        Fy = Fy_comb
        Mz, t, Mzr = mz_combined(p, m, c, b, terms, Kxk, Fx, Fy, Gyk, lat)
    else:
        Fx, Fy = Fx0, lat.Fy0
        Mz, t, Mzr = mz0(p, m, c, b, terms)
    generic = ext.generic if ext is not None else None
    if ext is not None:
        Fx = Fx + ext.dFx
        Fy = Fy + ext.dFy
        if generic is not None and generic[0] in ("Fx", "Fy", "Mz"):
            Fx, Fy, Mz = (v * generic[1] if n == generic[0] else v for n, v in (("Fx", Fx), ("Fy", Fy), ("Mz", Mz)))
    Mx = mx(p, c, dpi, Fy)
    My = my(p, c, Fx)
    if generic is not None and generic[0] in ("Mx", "My"):
        Mx, My = (v * generic[1] if n == generic[0] else v for n, v in (("Mx", Mx), ("My", My)))
    muy = np.abs(lat.muy) if m.limits else lat.muy

    if p["FITTYP"] == 61:
        rho, Rl, Cz = loaded_radius_61(p, c, dpi, c.omega, Romega, Fx, Fy)
    else:
        rho, Rl, Cz = loaded_radius_62(p, c, dpi, c.omega, Romega, Fx, Fy)
    a, bw = contact_patch(p, c, dpi)
    Cx, Cy, sigmax, sigmay = relaxation(p, c, Kxk, lat.Kya)

    shape = Fz.shape
    fy_flat, al_flat = Fy.ravel(), c.alpha.ravel()
    if fy_flat.size > 1:
        d = np.diff(fy_flat) / np.diff(al_flat)
        instKya = np.append(d, d[-1]).reshape(shape)
    else:
        instKya = np.zeros(shape)

    out = {
        "Fx": Fx, "Fy": Fy, "Fz": c.uFz, "Mx": Mx, "My": My, "Mz": Mz, "kappa": c.ukappa_low,
        "alpha": c.ualpha, "gamma": c.ugamma, "phit": c.phit, "Vx": c.Vx, "P": c.P, "Re": Re, "rho": rho,
        "2a": 2.0 * a, "t": t, "mux": mux, "muy": muy, "omega": c.omega, "Rl": Rl, "2b": 2.0 * bw,
        "Mzr": Mzr, "Cx": Cx, "Cy": Cy, "Cz": Cz, "Kya": lat.Kya, "sigmax": sigmax, "sigmay": sigmay,
        "instKya": instKya, "Kxk": Kxk,
    }  # fmt: skip
    return {k: np.broadcast_to(np.real(out[k]), shape).astype(float, copy=False) for k in OUTPUT_NAMES}
