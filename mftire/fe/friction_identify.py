"""Identification of the velocity part of the friction law from braking curves (thesis ch. 5).

Procedure (van der Steen 2010, section 5.3-5.4, Fig. 5.3):

1. Global friction mu_MF(kappa) = |Fx|/Fz of each braking curve at the identification load.
2. Divide by the global pressure part mu_p (Fx/Fz at wheel lock of a model run with the
   pressure-only law), giving mu_MFv(kappa).
3. mu_lock = mean of mu_MFv at |kappa| = 1 over the speeds (assumption ii of section 5.4).
4. Per speed: fit [mu_s, mu_m] of mu_v(kappa) = mu_s + (mu_m - mu_s) exp(-h^2 ln^2(|kappa|/kappa_max))
   (eq 5.5), h from mu_lock by eq 5.8, on equidistant kappa from the maximum of mu_MFv to 1,
   subject to 0 < mu_s < mu_lock < mu_m (eq 5.9).
5. mu_m linear in Vx (eq 5.10); refit mu_s with mu_m fixed (eq 5.11); mu_s quadratic in Vx (eq 5.12).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.optimize import least_squares

from mftire.errors import MftireInputError
from mftire.fe.config import TyreConfig
from mftire.fe.friction import h_from_mu_lock, mu_v_of_kappa
from mftire.fe.rolling_contact import solve

_EPS = 1e-4


@dataclass
class IdentifiedFriction:
    """Result of the chapter-5 identification (speeds in m/s)."""

    kappa_max: float  #: fixed peak location, Vmax = kappa_max Vx (eq 5.6)
    mu_p: float  #: global pressure part used to normalise mu_MF
    mu_lock: float  #: common locked-wheel velocity friction (eq 5.7)
    a1: float  #: mu_m = a1 Vx + a2 (eq 5.10) [s/m]
    a2: float
    a3: float  #: mu_s = a3 Vx^2 + a4 Vx + a5 (eq 5.12) [s^2/m^2]
    a4: float
    a5: float
    per_speed: pd.DataFrame = field(repr=False)  #: Vx, mu_s, mu_m (eq 5.9), mu_s_refit (eq 5.11), h, rms

    def friction_table(self) -> dict[str, object]:
        """The ``[friction]`` TOML table (velocity part) of a tyre file."""
        return {
            "mu_m": [self.a1, self.a2],
            "mu_s": [self.a3, self.a4, self.a5],
            "mu_lock": self.mu_lock,
            "kappa_max": self.kappa_max,
        }

    def to_toml(self) -> str:
        """TOML text: a ``[friction]`` table plus an ``[identification]`` record per speed."""
        ft = self.friction_table()
        lines = [
            "# velocity part identified by `mftire fe identify` (van der Steen 2010, ch. 5)",
            "[friction]",
            f"mu_m = [{ft['mu_m'][0]:.8g}, {ft['mu_m'][1]:.8g}]  # a1 [s/m], a2 (eq 5.10)",
            f"mu_s = [{ft['mu_s'][0]:.8g}, {ft['mu_s'][1]:.8g}, {ft['mu_s'][2]:.8g}]  # a3, a4, a5 (eq 5.12)",
            f"mu_lock = {self.mu_lock:.8g}  # h from eq 5.8 at every speed",
            f"kappa_max = {self.kappa_max:.8g}",
            "",
            "[identification]",
            f"mu_p = {self.mu_p:.8g}",
        ]
        for col in ("Vx", "mu_s", "mu_m", "mu_s_refit", "h", "rms"):
            vals = ", ".join(f"{v:.6g}" for v in self.per_speed[col])
            lines.append(f"{col} = [{vals}]")
        return "\n".join(lines) + "\n"

    def to_json(self) -> str:
        """JSON text with the same content as :meth:`to_toml`."""
        d = {"friction": self.friction_table(), "mu_p": self.mu_p,
             "per_speed": self.per_speed.to_dict(orient="list")}
        return json.dumps(d, indent=2)


def global_pressure_factor(tyre: TyreConfig, Fz: float, Vx: np.ndarray, P: float) -> float:
    """mu_p: Fx/Fz at wheel lock with the pressure-only friction law (mu_v = 1), thesis 5.3."""
    flat = tyre.updated({"friction.mu_m": (0.0, 1.0 + 1e-9), "friction.mu_s": (0.0, 0.0, 1.0),
                         "friction.h": 1.0, "friction.mu_lock": None})
    Vx = np.atleast_1d(np.asarray(Vx, dtype=float))
    res = solve(flat, np.full(Vx.size, Fz), Vx, np.full(Vx.size, P), np.zeros(Vx.size))
    return float(np.mean(np.abs(res.Fx) / Fz))


def _braking_curves(data: pd.DataFrame, Fz: float | None) -> tuple[float, dict[float, pd.DataFrame]]:
    needed = {"Fz", "kappa", "Vx", "Fx"}
    missing = needed - set(data.columns)
    if missing:
        raise MftireInputError(f"braking data lacks column(s): {', '.join(sorted(missing))}")
    df = data
    if "alpha" in df.columns:
        df = df[np.abs(df["alpha"]) < np.deg2rad(0.05)]
    if "kind" in df.columns:
        df = df[df["kind"].astype(str) == "braking"] if (df["kind"].astype(str) == "braking").any() else df
    df = df[df["kappa"] <= 0.0]
    if df.empty:
        raise MftireInputError("no braking rows (alpha = 0, kappa <= 0) in the input")
    loads = np.unique(np.round(df["Fz"].to_numpy(), 0))
    if Fz is None:
        Fz_sel = float(loads[len(loads) // 2])
    else:
        Fz_sel = float(loads[np.argmin(np.abs(loads - Fz))])
        if abs(Fz_sel - Fz) > 0.05 * Fz:
            raise MftireInputError(f"no braking curves near Fz = {Fz:.0f} N (loads present: {loads.tolist()})")
    df = df[np.abs(df["Fz"] - Fz_sel) < 0.5]
    curves = {float(v): g.sort_values("kappa", ascending=False) for v, g in df.groupby(np.round(df["Vx"], 2))}
    return Fz_sel, curves


def identify_velocity_law(
    data: pd.DataFrame,
    tyre: TyreConfig | None = None,
    *,
    Fz: float | None = None,
    P: float | None = None,
    kappa_max: float = 0.05,
    mu_p: float | None = None,
    n_points: int = 40,
) -> IdentifiedFriction:
    """Run the chapter-5 identification on braking curves at several speeds.

    ``data`` is a sweep table (columns Fz, kappa, Vx, Fx; alpha/kind used to keep pure braking).
    ``mu_p`` defaults to the pressure-only lock simulation of ``tyre`` (required then).
    """
    Fz_sel, curves = _braking_curves(data, Fz)
    if len(curves) < 3:
        raise MftireInputError(f"identification needs braking curves at >= 3 speeds (got {len(curves)})")
    speeds = np.array(sorted(curves))
    if mu_p is None:
        if tyre is None:
            raise MftireInputError("give mu_p or a tyre to compute it")
        p_use = float(P) if P is not None else tyre.size.nominal_pressure
        mu_p = global_pressure_factor(tyre, Fz_sel, speeds, p_use)
    if not mu_p > 0:
        raise MftireInputError(f"mu_p must be positive (got {mu_p})")
    # mu_MFv(|kappa|) on a common footing (steps 1-2)
    mu_curves = {}
    for v in speeds:
        g = curves[v]
        k = np.abs(g["kappa"].to_numpy())
        mu = np.abs(g["Fx"].to_numpy()) / g["Fz"].to_numpy() / mu_p
        order = np.argsort(k)
        k, mu = k[order], mu[order]
        if k.max() < 0.95:
            raise MftireInputError(f"braking curve at Vx = {v:g} m/s does not reach wheel lock (|kappa| = 1)")
        mu_curves[v] = (k, mu)
    mu_lock = float(np.mean([np.interp(1.0, k, mu) for k, mu in mu_curves.values()]))  # step 3
    rows = []
    for v in speeds:
        k, mu = mu_curves[v]
        k0 = k[np.argmax(mu)]
        kk = np.linspace(max(k0, 1e-3), 1.0, n_points)  # equidistant from the maximum to lock
        target = np.interp(kk, k, mu)

        def resid(x: np.ndarray, kk=kk, target=target) -> np.ndarray:
            h = h_from_mu_lock(x[0], x[1], mu_lock, kappa_max)  # eq 5.8
            return mu_v_of_kappa(kk, x[0], x[1], h, kappa_max) - target  # eq 5.5

        x0 = np.array([0.8 * mu_lock, max(target.max() * 1.1, mu_lock * 1.2)])
        sol = least_squares(resid, x0, bounds=([_EPS, mu_lock + _EPS], [mu_lock - _EPS, 10.0]))  # eq 5.9
        rows.append({"Vx": v, "mu_s": sol.x[0], "mu_m": sol.x[1],
                     "h": float(h_from_mu_lock(sol.x[0], sol.x[1], mu_lock, kappa_max)),
                     "rms": float(np.sqrt(np.mean(sol.fun**2))), "_kk": kk, "_t": target})
    per = pd.DataFrame(rows)
    a1, a2 = np.polyfit(per["Vx"], per["mu_m"], 1)  # eq 5.10
    refit = []
    for r in rows:
        mu_m = max(a1 * r["Vx"] + a2, mu_lock + 2 * _EPS)

        def resid_s(x: np.ndarray, r=r, mu_m=mu_m) -> np.ndarray:
            h = h_from_mu_lock(x[0], mu_m, mu_lock, kappa_max)
            return mu_v_of_kappa(r["_kk"], x[0], mu_m, h, kappa_max) - r["_t"]  # eq 5.11

        sol = least_squares(resid_s, [min(r["mu_s"], mu_lock - 2 * _EPS)], bounds=([_EPS], [mu_lock - _EPS]))
        refit.append(sol.x[0])
    per["mu_s_refit"] = refit
    a3, a4, a5 = np.polyfit(per["Vx"], per["mu_s_refit"], 2)  # eq 5.12
    per = per.drop(columns=["_kk", "_t"])[["Vx", "mu_s", "mu_m", "mu_s_refit", "h", "rms"]]
    return IdentifiedFriction(kappa_max=kappa_max, mu_p=float(mu_p), mu_lock=mu_lock,
                              a1=float(a1), a2=float(a2), a3=float(a3), a4=float(a4), a5=float(a5),
                              per_speed=per)
