"""Slip sweeps and the thesis's test campaign, in the project's sweep-table schema.

* Free rolling is found per (Fz, V, P) as the zero of the wheel torque T(omega) by the
  secant scheme of thesis eq 2.53 (scipy.optimize.newton without derivative, vectorised
  over all operating conditions at once).  re = V / omega_free (eq 2.51/5.14).
* Braking: kappa from 0 to -1 with kappa = (omega - omega_free)/omega_free (eq 5.15).
* Cornering: alpha from -12 to +12 deg at Vx = V cos(alpha), Vy = V sin(alpha) and
  omega_alpha = cos(alpha) omega_free (eqs 3.2-3.4, Table 3.1).
* Combined: a kappa sweep (relative to omega_alpha) at each alpha in {0, +-3, +-5, +-8} deg.

Tables have SI columns ``Fz, kappa, alpha, gamma, Vx, P, Fx, Fy, Mz, Mx, My``; ``Vx`` is
the travel-speed setpoint V (the TYDEX RUNSPEED), alpha and gamma are in rad.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.optimize import newton

from mftire.errors import MftireInputError
from mftire.fe import carcass as cc
from mftire.fe.config import TyreConfig, check_operating_range
from mftire.fe.rolling_contact import solve
from mftire.iotools.atomic import write_text_atomic
from mftire.parallel import Executor
from mftire.progress import reporter

SWEEP_COLUMNS = ["Fz", "kappa", "alpha", "gamma", "Vx", "P", "Fx", "Fy", "Mz", "Mx", "My"]
FREE_ROLLING_COLUMNS = ["Vx", "Fz", "load_fraction", "P", "omega", "re"]
KINDS = ("braking", "cornering", "combined")
COMBINED_ALPHAS_DEG = (0.0, -3.0, 3.0, -5.0, 5.0, -8.0, 8.0)
KMH = 1.0 / 3.6


def kappa_grid(n: int, kappa_end: float = -1.0) -> np.ndarray:
    """Slip points from 0 to ``kappa_end``, quadratically clustered near free rolling."""
    if n < 2:
        raise MftireInputError("a slip sweep needs at least 2 points")
    return kappa_end * np.linspace(0.0, 1.0, n) ** 2 + 0.0  # + 0.0 turns -0.0 into 0.0


def alpha_grid(n: int, alpha_max_deg: float = 12.0) -> np.ndarray:
    """Slip angles from -alpha_max to +alpha_max [rad]."""
    if n < 2:
        raise MftireInputError("a slip-angle sweep needs at least 2 points")
    return np.deg2rad(np.linspace(-alpha_max_deg, alpha_max_deg, n))


def free_rolling(
    tyre: TyreConfig, Fz: np.ndarray, V: np.ndarray, P: np.ndarray, gamma: np.ndarray | float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """Free-rolling wheel speed omega_free [rad/s] and re = V/omega_free [m] (zero wheel torque).

    Secant iteration on T(omega) = 0 (thesis eq 2.53) started from the belt radius
    (eq 2.51 with r_b); vectorised over the conditions.
    """
    Fz, V, P, gamma = (np.atleast_1d(np.asarray(a, dtype=float)) for a in np.broadcast_arrays(Fz, V, P, gamma))
    Fz, V, P, gamma = (a.ravel().copy() for a in (Fz, V, P, gamma))
    check_operating_range(tyre, Fz, V, P)
    r_b = cc.belt_rolling_radius(tyre, Fz, V, P)
    w0 = V / r_b

    def torque(omega: np.ndarray) -> np.ndarray:
        return solve(tyre, Fz, V, P, omega, 0.0, gamma).wheel_torque

    omega = newton(torque, w0 * (1.0 - 2e-3), x1=w0, tol=1e-9 * float(np.max(w0)), maxiter=50)
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    return omega, V / omega


@dataclass(frozen=True)
class _SolveChunk:
    """Forces of one chunk of points (a picklable task for :class:`~mftire.parallel.Executor`)."""

    tyre: TyreConfig

    def __call__(self, pts: np.ndarray) -> np.ndarray:
        r = solve(self.tyre, *pts)
        return np.column_stack([r.Fx, r.Fy, r.Mz, r.Mx, r.My])


def solve_points(
    tyre: TyreConfig,
    pts: np.ndarray,
    *,
    chunk: int = 2000,
    executor: Executor | None = None,
    report: Callable[[str], None] | None = None,
) -> np.ndarray:
    """Forces (n, 5) = (Fx, Fy, Mz, Mx, My) at the points ``pts``, rows (Fz, Vx, P, omega, alpha, gamma).

    The points are solved in vectorised chunks of at most ``chunk`` points, of equal size and a
    multiple of the workers of ``executor`` in number (default: in this process), so that the
    workers finish together.  A point's solution depends on that point alone (the carcass and
    return-map iterations stop per point and per element), so the result is bit for bit the same
    for every chunk size and executor.
    """
    n = pts.shape[1]
    workers = 1 if executor is None or executor.scheduler else executor.workers
    n_chunks = workers * max(1, -(-n // (max(chunk, 1) * workers)))
    size = max(1, -(-n // n_chunks))
    bounds = [(start, min(start + size, n)) for start in range(0, n, size)]
    chunks = (np.ascontiguousarray(pts[:, a:b]) for a, b in bounds)  # contiguous: the same SIMD paths everywhere
    res = np.zeros((n, 5))
    for (start, stop), r in zip(bounds, (executor or Executor()).imap(_SolveChunk(tyre), chunks), strict=True):
        res[start:stop] = r
        if report is not None:
            report(f"solved {stop}/{n} slip points")
    return res


@dataclass(frozen=True)
class Condition:
    """One operating condition of a sweep (setpoints)."""

    Fz: float
    V: float
    P: float
    gamma: float = 0.0


def rows_for(kind: str, n_kappa: int, n_alpha: int, alphas_comb: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """(kappa, alpha) points of one sweep of the given kind."""
    if kind == "braking":
        k = kappa_grid(n_kappa)
        return k, np.zeros_like(k)
    if kind == "cornering":
        a = alpha_grid(n_alpha)
        return np.zeros_like(a), a
    if kind == "combined":
        k = kappa_grid(n_kappa)
        a = np.deg2rad(np.asarray(alphas_comb, dtype=float))
        kk, aa = np.meshgrid(k, a)
        return kk.ravel(), aa.ravel()
    raise MftireInputError(f"unknown sweep kind {kind!r} (use braking, cornering or combined)")


def run_sweeps(
    tyre: TyreConfig,
    jobs: Sequence[tuple[str, Condition]],
    *,
    n_kappa: int = 50,
    n_alpha: int = 49,
    combined_alphas_deg: Sequence[float] = COMBINED_ALPHAS_DEG,
    chunk: int = 2000,
    progress: bool | None = None,
    executor: Executor | None = None,
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Run a list of (kind, condition) sweeps; returns (sweep table, free-rolling table).

    The free-rolling speed of every distinct condition is found first, all conditions at once
    (secant scheme).  The slip points of all sweeps are then solved in vectorised chunks of
    ``chunk`` points, run by ``executor`` (default: in this process); the chunks and each
    point's solution do not depend on the executor, so neither does the table (bit for bit).
    """
    say = reporter(progress, "mftire fe")
    conds = sorted({(c.Fz, c.V, c.P, c.gamma) for _, c in jobs})
    if not conds:
        raise MftireInputError("no sweeps requested")
    arr = np.array(conds, dtype=float)
    check_operating_range(tyre, arr[:, 0], arr[:, 1], arr[:, 2])
    say.update(f"free rolling for {len(conds)} conditions")
    omega_free, re = free_rolling(tyre, arr[:, 0], arr[:, 1], arr[:, 2], arr[:, 3])
    lookup = {c: (w, r) for c, w, r in zip(conds, omega_free, re, strict=True)}
    free_tab = pd.DataFrame({
        "Vx": arr[:, 1], "Fz": arr[:, 0], "load_fraction": arr[:, 0] / tyre.load_index_load,
        "P": arr[:, 2], "omega": omega_free, "re": re,
    })[FREE_ROLLING_COLUMNS]
    pieces = []
    for kind, c in jobs:
        kap, alp = rows_for(kind, n_kappa, n_alpha, combined_alphas_deg)
        w_free, _ = lookup[(c.Fz, c.V, c.P, c.gamma)]
        pieces.append(pd.DataFrame({
            "Fz": c.Fz, "kappa": kap, "alpha": alp, "gamma": c.gamma, "Vx": c.V, "P": c.P,
            "omega": np.cos(alp) * w_free * (1.0 + kap),  # eqs 3.4 and 5.15
            "kind": kind,
        }))
    table = pd.concat(pieces, ignore_index=True)
    pts = np.array(table[["Fz", "Vx", "P", "omega", "alpha", "gamma"]].to_numpy(dtype=float).T, order="C")  # a copy
    pts[1] *= np.cos(pts[4])  # Vx = V cos(alpha), eq 3.2
    res = solve_points(tyre, pts, chunk=chunk, executor=executor, report=say.update)
    say.done()
    table[["Fx", "Fy", "Mz", "Mx", "My"]] = res
    table["load_fraction"] = table["Fz"] / tyre.load_index_load
    table = table.drop(columns="omega")
    return table[SWEEP_COLUMNS + ["kind", "load_fraction"]], free_tab


def sweep(
    tyre: TyreConfig,
    kind: str,
    Fz: Sequence[float] | float,
    V: Sequence[float] | float,
    P: Sequence[float] | float,
    gamma: float = 0.0,
    *,
    n_kappa: int = 50,
    n_alpha: int = 49,
    combined_alphas_deg: Sequence[float] = COMBINED_ALPHAS_DEG,
    progress: bool | None = None,
) -> pd.DataFrame:
    """One kind of sweep at every combination of the given loads [N], speeds [m/s], pressures [Pa]."""
    if kind not in KINDS:
        raise MftireInputError(f"unknown sweep kind {kind!r} (use braking, cornering or combined)")
    jobs = [(kind, Condition(float(f), float(v), float(p), float(gamma)))
            for f in np.atleast_1d(Fz) for v in np.atleast_1d(V) for p in np.atleast_1d(P)]
    table, _ = run_sweeps(tyre, jobs, n_kappa=n_kappa, n_alpha=n_alpha,
                          combined_alphas_deg=combined_alphas_deg, progress=progress)
    return table[SWEEP_COLUMNS]


def campaign_jobs(tyre: TyreConfig, quick: bool = False) -> list[tuple[str, Condition]]:
    """The thesis's programme: 0.4/0.8/1.2 LI; braking at 20..100 km/h; cornering and combined at
    60 km/h; nominal pressure and +-0.5 bar.  ``quick`` keeps 20/60/100 km/h braking and the
    pressure variations for braking only."""
    li = tyre.load_index_load
    pn = tyre.size.nominal_pressure
    loads = [0.4 * li, 0.8 * li, 1.2 * li]
    pressures = [pn, pn - 0.5e5, pn + 0.5e5]
    speeds = [20.0, 60.0, 100.0] if quick else [20.0, 40.0, 60.0, 80.0, 100.0]
    jobs: list[tuple[str, Condition]] = []
    for p in pressures:
        for f in loads:
            for v in speeds:
                if quick and p != pn and v != 60.0:
                    continue
                jobs.append(("braking", Condition(f, v * KMH, p)))
            for kind in ("cornering", "combined"):
                if quick and p != pn:
                    continue
                jobs.append((kind, Condition(f, 60.0 * KMH, p)))
    return jobs


def campaign(
    tyre: TyreConfig, quick: bool = False, progress: bool | None = None, executor: Executor | None = None
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Run the full (or quick) campaign; returns (sweeps, free_rolling) tables.

    ``executor`` runs the chunks of slip points (default: in this process; see :func:`run_sweeps`).
    """
    if quick:
        return run_sweeps(tyre, campaign_jobs(tyre, True), n_kappa=14, n_alpha=17,
                          combined_alphas_deg=(0.0, -5.0, 5.0), progress=progress, executor=executor)
    return run_sweeps(tyre, campaign_jobs(tyre, False), n_kappa=50, n_alpha=49, progress=progress,
                      executor=executor)


def write_csv_atomic(df: pd.DataFrame, path: str | os.PathLike[str]) -> Path:
    """Write a table as CSV atomically (see :mod:`mftire.iotools.atomic`), creating the folder."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(path, df.to_csv(index=False))
    return Path(path)
