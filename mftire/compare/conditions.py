"""Comparing ``.tir`` models without data: their curves over usual or given conditions, and a difference table.

``mftire compare --tir A.tir B.tir --output d`` (no ``--data`` / ``--fe``) draws every model's
braking, cornering and combined curves over a set of operating conditions and tabulates, per
condition and model (see :func:`characteristics`):

* ``Kxk`` [N]: longitudinal slip stiffness dFx/dκ at κ = 0, α = 0 (MF output ``Kxk``),
* ``Kya`` [N/rad]: cornering stiffness dFy/dα at α = 0, κ = 0 (MF output ``Kya``),
* ``mu_x_peak``, ``mu_y_peak`` [-]: peak |Fx|/Fz over κ ∈ [−0.3, 0.3] (α = 0) and peak |Fy|/Fz
  over α ∈ [−15°, 15°] (κ = 0),
* ``t0`` [m]: pneumatic trail at α = 0.5°, κ = 0 (MF output ``t``, near its α → 0 value),

and each one's difference to the first model in % (``d_<name>_pct``).

Conditions
----------
The usual conditions of the first model: loads 0.5, 1.0 and 1.5 × ``FNOMIN``, speed ``LONGVL``,
pressure ``NOMPRES`` (its inflation pressure), camber 0.  ``--conditions`` overrides any of them::

    --conditions loads=3000,4500,6000,speeds=40,80,pressures=2.0,2.4,cambers=0,-2

keys ``loads`` [N], ``speeds`` [km/h], ``pressures`` [bar], ``cambers`` [deg]; a value list runs
until the next ``key=``.  :func:`parse_conditions` validates it (unknown key, non-number,
negative or zero load, negative speed, non-positive pressure, |camber| > 15°: a clear error).
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd

from mftire.errors import MftireInputError
from mftire.tyre import Tyre

__all__ = ["Conditions", "parse_conditions", "usual_conditions", "design_sweeps", "characteristics",
           "CONDITION_KEYS"]

#: ``--conditions`` keys: (unit in the option, factor to SI, check, message).
CONDITION_KEYS: dict[str, tuple[str, float]] = {
    "loads": ("N", 1.0),
    "speeds": ("km/h", 1 / 3.6),
    "pressures": ("bar", 1e5),
    "cambers": ("deg", math.pi / 180),
}
_KAPPA_MAX = 0.3
_ALPHA_MAX = math.radians(15.0)
_COMBINED_ALPHAS = (math.radians(4.0), math.radians(-4.0))
_N = 61


@dataclass(frozen=True)
class Conditions:
    """Operating conditions of a no-data comparison (SI): every combination is one condition."""

    loads: tuple[float, ...]  #: Fz [N]
    speeds: tuple[float, ...]  #: Vx [m/s]
    pressures: tuple[float, ...]  #: P [Pa]
    cambers: tuple[float, ...]  #: γ [rad]

    def combinations(self) -> list[tuple[float, float, float, float]]:
        """``(Fz, Vx, P, γ)`` of every condition."""
        return list(itertools.product(self.loads, self.speeds, self.pressures, self.cambers))


def parse_conditions(text: str) -> dict[str, tuple[float, ...]]:
    """``"loads=3000,4500,speeds=40,80"`` -> ``{"loads": (3000.0, 4500.0), "speeds": (11.1, 22.2)}`` (SI).

    Raises :class:`MftireInputError` naming the offending part: empty text, a value before the
    first ``key=``, an unknown or repeated key, a key without values, a non-number, or a value out
    of range (loads > 0 N, speeds ≥ 0 km/h, pressures > 0 bar, |cambers| ≤ 15°).
    """
    known = ", ".join(f"{k} [{u}]" for k, (u, _) in CONDITION_KEYS.items())
    if not text or not text.strip():
        raise MftireInputError(f"--conditions is empty; give e.g. loads=3000,4500,speeds=60 (keys: {known})")
    out: dict[str, list[float]] = {}
    key = None
    for tok in (t.strip() for t in text.split(",")):
        if not tok:
            raise MftireInputError(f"--conditions {text!r}: an empty value (two commas in a row?)")
        if "=" in tok:
            key, _, tok = (s.strip() for s in tok.partition("="))
            key = key.lower()
            if key not in CONDITION_KEYS:
                import difflib

                close = difflib.get_close_matches(key, list(CONDITION_KEYS), n=1)
                hint = f" (did you mean {close[0]}?)" if close else ""
                raise MftireInputError(f"--conditions: unknown key {key!r}{hint}; known keys: {known}")
            if key in out:
                raise MftireInputError(f"--conditions: {key} given twice")
            out[key] = []
            if not tok:
                raise MftireInputError(f"--conditions: {key}= has no value")
        elif key is None:
            raise MftireInputError(f"--conditions {text!r}: {tok!r} comes before any key=; give e.g. loads={tok}")
        if not re.fullmatch(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?", tok):
            unit = CONDITION_KEYS[key][0]
            raise MftireInputError(f"--conditions: {key} value {tok!r} is not a number (plain numbers in {unit})")
        out[key].append(float(tok))
    si: dict[str, tuple[float, ...]] = {}
    for k, vals in out.items():
        unit, factor = CONDITION_KEYS[k]
        for v in vals:
            bad = ((k == "loads" and v <= 0) or (k == "speeds" and v < 0) or (k == "pressures" and v <= 0)
                   or (k == "cambers" and abs(v) > 15))  # fmt: skip
            if bad:
                rule = {"loads": "> 0 N", "speeds": "≥ 0 km/h", "pressures": "> 0 bar", "cambers": "within ±15°"}[k]
                raise MftireInputError(f"--conditions: {k} = {v:g} {unit} is out of range ({k} must be {rule})")
        si[k] = tuple(dict.fromkeys(v * factor for v in vals))
    return si


def usual_conditions(tyre: Tyre, overrides: Mapping[str, tuple[float, ...]] | None = None) -> Conditions:
    """Loads 0.5/1.0/1.5 × FNOMIN, speed LONGVL, pressure NOMPRES, camber 0 of ``tyre``, with ``overrides``
    (SI, from :func:`parse_conditions`) in their place."""
    from mftire.parameters import with_defaults

    p = with_defaults(tyre.parameters)
    f0 = float(p["FNOMIN"])
    base = {"loads": (0.5 * f0, f0, 1.5 * f0), "speeds": (float(p["LONGVL"]),),
            "pressures": (float(p.get("NOMPRES") or p.get("INFLPRES") or 220000.0),), "cambers": (0.0,)}
    base.update(overrides or {})
    return Conditions(**{k: tuple(float(v) for v in base[k]) for k in CONDITION_KEYS})


def design_sweeps(conditions: Conditions, n: int = _N) -> pd.DataFrame:
    """Inputs of the curves (SI sweep schema, no channels): per condition a braking κ sweep (α = 0), a
    cornering α sweep (κ = 0) and κ sweeps at α = ±4°; ``source`` is ``"conditions"``."""
    kap = np.linspace(-_KAPPA_MAX, _KAPPA_MAX, n)
    alp = np.linspace(-_ALPHA_MAX, _ALPHA_MAX, n)
    parts = []
    for fz, vx, p, g in conditions.combinations():
        common = {"Fz": fz, "gamma": g, "Vx": vx, "P": p, "phit": 0.0}
        parts.append(pd.DataFrame({"kappa": kap, "alpha": 0.0, **common}))
        parts.append(pd.DataFrame({"kappa": 0.0, "alpha": alp, **common}))
        for a in _COMBINED_ALPHAS:
            parts.append(pd.DataFrame({"kappa": kap, "alpha": a, **common}))
    df = pd.concat(parts, ignore_index=True)
    df["source"] = "conditions"
    df["origin"] = "design"
    return df[["Fz", "kappa", "alpha", "gamma", "Vx", "P", "phit", "source", "origin"]]


def characteristics(models: Mapping[str, Tyre], conditions: Conditions, mode: int = 111) -> pd.DataFrame:
    """Slip stiffness, cornering stiffness, peak µ and trail per condition and model, with differences
    to the first model (see the module docstring).

    Returns
    -------
    DataFrame
        ``Fz [N], Vx [m/s], P [Pa], gamma [rad], model, Kxk [N], Kya [N/rad], mu_x_peak, mu_y_peak, t0 [m]``
        and ``d_Kxk_pct, d_Kya_pct, d_mu_x_peak_pct, d_mu_y_peak_pct, d_t0_pct`` [%].
    """
    kap = np.linspace(-_KAPPA_MAX, _KAPPA_MAX, 241)
    alp = np.linspace(-_ALPHA_MAX, _ALPHA_MAX, 241)
    rows = []
    for fz, vx, p, g in conditions.combinations():
        for name, t in models.items():
            def ev(k, a, t=t, fz=fz, vx=vx, p=p, g=g):
                k, a = np.broadcast_arrays(np.atleast_1d(np.asarray(k, float)), np.atleast_1d(np.asarray(a, float)))
                n = k.size
                return t.evaluate(np.full(n, fz), k, a, np.full(n, g), Vx=np.full(n, vx), P=np.full(n, p),
                                  mode=mode)

            zero = ev(0.0, 0.0)
            fx = ev(kap, 0.0)["Fx"]
            fy = ev(0.0, alp)["Fy"]
            small = ev(0.0, math.radians(0.5))
            rows.append({"Fz": fz, "Vx": vx, "P": p, "gamma": g, "model": name,
                         "Kxk": float(zero["Kxk"][0]), "Kya": float(zero["Kya"][0]),
                         "mu_x_peak": float(np.max(np.abs(fx)) / fz), "mu_y_peak": float(np.max(np.abs(fy)) / fz),
                         "t0": float(small["t"][0])})
    df = pd.DataFrame(rows)
    first = next(iter(models))
    ref = df[df["model"] == first].set_index(["Fz", "Vx", "P", "gamma"])
    for c in ("Kxk", "Kya", "mu_x_peak", "mu_y_peak", "t0"):
        base = ref[c].reindex(pd.MultiIndex.from_frame(df[["Fz", "Vx", "P", "gamma"]])).to_numpy(float)
        with np.errstate(all="ignore"):
            df[f"d_{c}_pct"] = np.where(np.abs(base) > 0, 100.0 * (df[c].to_numpy(float) - base) / np.abs(base),
                                        np.nan)
    return df
