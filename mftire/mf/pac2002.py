"""PAC2002: the MSC Adams implementation of MF-Tyre 5.2, and where it differs from MF 5.2.

PAC2002 property files (``PROPERTY_FILE_FORMAT = 'PAC2002'``, no ``FITTYP``) hold
the steady-state Magic Formula of Pacejka, *Tyre and Vehicle Dynamics*, 2nd ed.
(2006), §4.3.2, as documented in the MSC Adams/Tire help page "Using the PAC2002
Tire Model".  Their coefficients are in the ISO-W (TYDEX) sign convention used by
Adams (the STI interface converts to the W axes before the tyre model), the same
convention as MF 5.2 and MF 6.x files (e.g. ``PKY1 < 0``).

mftire evaluates a PAC2002 file with the MF 5.2 (FITTYP 6) code paths of
:mod:`mftire.mf` wherever the two formulations coincide.  The differences are
here, or are small branches marked ``is_pac2002`` in the channel modules:

=====================  ======================================================
camber scaling         gamma_x = gamma*LGAX, gamma_y = gamma*LGAY,
                       gamma_z = gamma*LGAZ (2006 eqs 4.E4, 4.E13, 4.E23,
                       4.E24, 4.E25, 4.E27-29, 4.E35, 4.E40, 4.E42-44,
                       4.E47): exactly folded into the coefficients they
                       multiply (:func:`prepare`)
LMUV                   lambda_mu* = lambda_mu/(1 + LMUV*Vs/V0) (eq 4.E7);
                       MF 5.2 as MFeval and MF 6.x use LMUV = 0
pure-slip Mz0          Mz0 = -t*Fy0 + Mzr with Fy0 at the actual camber
                       (2006 eqs 4.E31, 4.E32); MF 6.x uses Fy0 at gamma = 0
                       (:func:`mz0`); the residual torque carries cos(alpha)
                       once (eq 4.E36)
combined-slip Mz       F'y = Fy - SVyk with the same SVyk as Fy (eq 4.E74);
                       the trail is not multiplied by LFZO (eq 4.E73)
pressure keys          ``[TIRE_CONDITIONS]`` IP / IP_NOM and QPZ1, QPZ2, QPX1
                       of newer PAC2002 files are the MF 6.1 INFLPRES /
                       NOMPRES, PPZ1, PPZ2, PPMX1 (:func:`prepare`); LKYG is
                       MF 5.2's LKYC (camber terms of SHy, SVy)
moment arm s           R0*(SSZ1 + SSZ2*Fy/Fz0' + ...) with Fz0' = LFZO*FNOMIN
                       (eq 4.E76; MF 5.2 as MFeval uses FNOMIN), in
                       :func:`mftire.mf.aligning.mz_combined`
terms absent in 2006   PKY4 = 2 (the fixed "2" of eq 4.E25), and PKY5, PEY5,
                       RBX3, RBY4, QDZ10, QDZ11, QSX12-QSX14 = 0; the MF 6.2
                       vertical terms (Q_CAM*, Q_FYS*, Q_FCY2) = 0, so the
                       loaded radius is the closed-form root of the MF 6.1
                       equation (solver.py) instead of an iteration
absent coefficients    zero (the term is off), not MFeval's defaults
                       (:func:`absent_terms`)
QSY5..QSY8             not in the published PAC2002/MF 5.2 rolling-resistance
                       equation (eq 4.E70); nonzero values are ignored with a
                       warning
=====================  ======================================================

``TYRESIDE`` is not used: the file is evaluated as the tyre it describes (mirroring
for the other vehicle side is a mounting operation, as in MFeval).  The input stage
(limits, low-speed reduction below VXLOW), turn slip, effective rolling radius,
loaded radius, contact patch and relaxation lengths are the MF 5.2 ones.
See ``docs/pac2002.md`` for the full difference table.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from typing import Any

import numpy as np

from mftire.mf.aligning import AligningTerms, _trail_mf
from mftire.mf.basic import Basic
from mftire.mf.family import PAC2002_CODE
from mftire.mf.inputs import Conditions
from mftire.mf.lateral import PureLateral
from mftire.mf.modes import Mode
from mftire.parameters import PARAMETERS

__all__ = ["PAC2002_CODE", "PAC2002Warning", "absent_terms", "camber_folding", "mz0", "prepare", "warn_unused"]


class PAC2002Warning(UserWarning):
    """A PAC2002 parameter that the published PAC2002 equations do not use."""


#: Camber scaling factor -> (coefficient, power) pairs: the coefficient multiplies
#: gamma_i**power in the PAC2002 equations, so it is scaled by factor**power
#: ("abs": it multiplies |gamma_i|, scaled by |factor|).
_CAMBER_FOLD: dict[str, tuple[tuple[str, int | str], ...]] = {
    "LGAX": (("PDX3", 2),),  # eq 4.E13
    "LGAY": (
        ("PDY3", 2),  # eq 4.E23
        ("PEY4", 1),  # eq 4.E24
        ("PKY3", "abs"),  # eq 4.E25
        ("PHY3", 1),  # eq 4.E27 (2006 form)
        ("PVY3", 1),  # eq 4.E29
        ("PVY4", 1),  # eq 4.E29
    ),
    "LGAZ": (
        ("QHZ3", 1),  # eq 4.E35
        ("QHZ4", 1),  # eq 4.E35
        ("QBZ4", 1),  # eq 4.E40
        ("QBZ5", "abs"),  # eq 4.E40
        ("QDZ3", 1),  # eq 4.E42
        ("QDZ4", 2),  # eq 4.E42
        ("QEZ5", 1),  # eq 4.E44
        ("QDZ8", 1),  # eq 4.E47
        ("QDZ9", 1),  # eq 4.E47
    ),
}

#: MF 6.x terms that the 2006 (PAC2002) equations do not have, at their neutral value.
_ABSENT = {
    "PKY4": 2.0,  # eq 4.E25 (2006): sin(2*atan(...))
    "PKY5": 0.0,
    "PEY5": 0.0,
    "RBX3": 0.0,
    "RBY4": 0.0,
    "QDZ10": 0.0,
    "QDZ11": 0.0,
    "QSX12": 0.0,
    "QSX13": 0.0,
    "QSX14": 0.0,
    # MF 6.2 vertical terms: without them the MF 6.2 loaded-radius equation of the MF 5.2
    # path is the MF 6.1 one, whose closed-form root mftire uses for PAC2002
    "Q_FCY2": 0.0,
    "Q_CAM1": 0.0,
    "Q_CAM2": 0.0,
    "Q_CAM3": 0.0,
    "Q_FYS1": 0.0,
    "Q_FYS2": 0.0,
    "Q_FYS3": 0.0,
}

#: PAC2002 pressure keys -> the MF 6.1 keys of the shared equations.
_PRESSURE = {"IP": "INFLPRES", "IP_NOM": "NOMPRES", "QPZ1": "PPZ1", "QPZ2": "PPZ2", "QPX1": "PPMX1"}

#: PAC2002 names of MF 5.2 scaling factors: LKYG (camber stiffness, on the PHY3 and PVY3/PVY4 camber
#: terms of eqs 4.E27, 4.E29, as Chrono's ChPac02Tire applies it) is MF 5.2's LKYC.
_RENAMED = {"LKYG": "LKYC"}

_UNUSED_ROLLING = ("QSY5", "QSY6", "QSY7", "QSY8")

#: Coefficient sections whose absent keys are neutral (zero) in a PAC2002 or MF_05 file: the term is not
#: in the file's model version (an MF_05 file has no PDX3, REX1/2, REY1/2, RHY2, QBZ10, QSX4-11, QSY3-8;
#: the Sedan PAC2002 file of Chrono has no combined-slip coefficients), as Chrono's ChPac02Tire reads it.
#: MFeval's defaults (mftire.parameters, nonzero for e.g. RBX1, RCX1, QSY3, the turn-slip PDXP1) are the
#: values of another tyre; they stay the defaults of MF 5.2 / 6.x files, which MFeval evaluates.
_COEFFICIENT_SECTIONS = ("LONGITUDINAL_COEFFICIENTS", "LATERAL_COEFFICIENTS", "ALIGNING_COEFFICIENTS",
                         "OVERTURNING_COEFFICIENTS", "ROLLING_COEFFICIENTS", "TURNSLIP_COEFFICIENTS")
#: Divisors, for which zero is not neutral: an absent one keeps its default.
_DIVISORS = ("PKY2", "PTY2")


def absent_terms(file_values: Mapping[str, Any]) -> dict[str, float]:
    """Zero for every coefficient the file lacks whose default is not zero (see :data:`_COEFFICIENT_SECTIONS`).

    ``file_values`` are the file's own values (``TirParameters.flat()``).
    """
    return {
        p.key: 0.0
        for p in PARAMETERS
        if p.section in _COEFFICIENT_SECTIONS and p.unit != "str" and p.default != 0
        and p.key not in file_values and p.key not in _DIVISORS
    }


def camber_folding(p: dict) -> dict[str, float]:
    """The coefficients that absorb the camber scaling factors LGAX/LGAY/LGAZ.

    Returns ``{KEY: value}`` for every coefficient of :data:`_CAMBER_FOLD`:
    ``value = p[KEY] * factor**power``, so that the shared equations, which use the
    unscaled inclination, give exactly the PAC2002 result with gamma_i = gamma*LGAi.
    """
    out: dict[str, float] = {}
    for factor_key, coefficients in _CAMBER_FOLD.items():
        factor = float(p.get(factor_key, 1.0))
        for key, power in coefficients:
            scale = abs(factor) if power == "abs" else factor**power
            out[key] = float(p.get(key, 0.0)) * scale
    return out


def prepare(p: dict) -> dict:
    """The flat dict the shared MF 5.2 code paths evaluate as PAC2002.

    ``p`` is a flat parameter dict marked with :data:`PAC2002_CODE`; the result is a
    new dict (the input is not changed) with the camber scaling factors folded in,
    the MF 6.x-only terms neutral and the PAC2002 pressure keys mapped (see the
    module docstring).  ``LGAX``, ``LGAY`` and ``LGAZ`` are set to 1 once folded, so
    preparing twice gives the same dict.
    """
    q = dict(p)
    q.update(camber_folding(p))
    for key in _CAMBER_FOLD:
        q[key] = 1.0
    q.update(_ABSENT)
    for pac_key, mf_key in (_PRESSURE | _RENAMED).items():
        if pac_key in p:
            q[mf_key] = float(p[pac_key])
    q["FITTYP"] = PAC2002_CODE
    return q


def warn_unused(file_values: dict) -> None:
    """Warn about coefficients of a PAC2002 file that its equations do not use.

    ``file_values`` are the file's own values (``TirParameters.flat()``, not the
    defaults-filled dict: the MF 6.1 defaults of QSY7/QSY8 are not the file's).
    """
    unused = [k for k in _UNUSED_ROLLING if isinstance(file_values.get(k), (int, float)) and file_values[k] != 0]
    if unused:
        warnings.warn(
            f"PAC2002: {', '.join(unused)} are not part of the published PAC2002 rolling-resistance "
            "equation (Pacejka 2006 eq 4.E70) and are ignored.",
            PAC2002Warning,
            stacklevel=3,
        )


def mz0(
    p: dict, mode: Mode, c: Conditions, b: Basic, a: AligningTerms, lat: PureLateral
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """PAC2002 pure-slip aligning moment Mz0 = -t*Fy0 + Mzr.

    Pacejka 2006 eqs 4.E31-4.E36 as in the Adams PAC2002 documentation: the trail
    multiplies the pure lateral force at the actual inclination (``lat``), and the
    residual torque Mzr = Dr*cos(atan(Br*alpha_r))*cos(alpha) carries the cosine once
    (it is inside ``a.Dr`` of the shared :func:`~mftire.mf.aligning.aligning_terms`).
    cos(alpha') of the trail equals cos(alpha) for forward driving (eq 4.E6).

    Returns ``(Mz0 [N·m], t0 [m], Mzr0 [N·m])``.
    """
    t0 = _trail_mf(a.Dt, a.Ct, a.Bt, a.Et, a.alphat, b.alpha_prime) * c.smooth  # eq 4.E33
    Mzr0 = np.real(a.Dr * np.cos(a.Cr * np.arctan(a.Br * a.alphar))) * c.smooth  # eq 4.E36
    return -t0 * lat.Fy0 + Mzr0, t0, Mzr0  # eqs 4.E32, 4.E31
