"""Measured-like campaigns: FE-surrogate sweeps with the artefacts of a real test.

A test rig or trailer does not deliver clean curves.  :func:`measured_campaign` runs
a programme of sweeps *in sequence* through the FE surrogate and adds:

* **Fz wander**: the load follows its set point only on average (smooth random
  variation along each sweep); forces respond to the actual load, and the recorded
  ``Fz`` is the actual load;
* **zero offsets**: every run starts with its own load-cell offsets on each channel;
* **drift**: the offsets drift linearly along the campaign;
* **noise**: Gaussian, a fraction of each channel's peak in the sweep;
* **time**: a ``time`` column (seconds, with pauses between runs) and a ``run`` id.

An optional *fade* law scales the tyre's friction level at the start of every run
from the friction energy dissipated so far (thermal fade or wear): the data then
contain an effect that the Magic Formula lacks.  Everything is reproducible from
``seed``.  The output is a sweep table (:mod:`mftire.iotools.sweeps`) plus ``kind``,
``load_fraction``, ``run`` and ``time``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from mftire.fe.config import TyreConfig
from mftire.fe.rolling_contact import solve
from mftire.fe.slip_sweeps import COMBINED_ALPHAS_DEG, Condition, free_rolling, rows_for, solve_points
from mftire.parallel import Executor

CHANNELS = ("Fx", "Fy", "Mz", "Mx", "My")


@dataclass(frozen=True)
class Artefacts:
    """Test artefacts added by :func:`measured_campaign` (all SI)."""

    noise: float = 0.01  #: Gaussian noise, fraction of the channel's peak in the sweep [-]
    fz_wander: float = 0.03  #: RMS of the load around its set point, fraction of the set point [-]
    #: RMS of the per-run zero offsets [N, N·m]
    offsets: Mapping[str, float] = field(
        default_factory=lambda: {"Fx": 20.0, "Fy": 20.0, "Mz": 1.0, "Mx": 4.0, "My": 1.0}
    )
    drift: float = 1.0  #: total offset drift over the campaign, in units of the offset RMS [-]
    point_time: float = 0.5  #: time per measured point [s]
    pause: float = 60.0  #: time between runs [s]


#: A fade law: friction level factor [-] from dissipated friction energy [J] and time [s].
FadeLaw = Callable[[float, float], float]


def thermal_fade(depth: float, energy_scale: float) -> FadeLaw:
    """Friction level 1 − depth·(1 − exp(−E/energy_scale)) of the energy E dissipated so far."""
    return lambda energy, time: 1.0 - depth * (1.0 - np.exp(-energy / energy_scale))


def _smooth_noise(n: int, rng: np.random.Generator, corr_points: float = 8.0) -> np.ndarray:
    """Zero-mean, unit-RMS, smoothly varying noise of ``n`` points (AR(1) filtered)."""
    a = np.exp(-1.0 / corr_points)
    e = rng.standard_normal(n + 50)
    x = np.empty_like(e)
    x[0] = e[0]
    for i in range(1, len(e)):
        x[i] = a * x[i - 1] + np.sqrt(1 - a * a) * e[i]
    x = x[50:]
    return (x - x.mean()) / (x.std() or 1.0)


def _forces(tyre: TyreConfig, pts: tuple[np.ndarray, ...]) -> list[np.ndarray]:
    """(Fx, Fy, Mz, Mx, My) at the points (Fz, Vx, P, omega, alpha, gamma)."""
    r = solve(tyre, *pts)
    return [r.Fx, r.Fy, r.Mz, r.Mx, r.My]


def measured_campaign(
    tyre: TyreConfig,
    jobs: Sequence[tuple[str, Condition]],
    artefacts: Artefacts | None = None,
    *,
    fade: FadeLaw | None = None,
    n_kappa: int = 40,
    n_alpha: int = 41,
    combined_alphas_deg: Sequence[float] = COMBINED_ALPHAS_DEG,
    seed: int = 0,
    executor: Executor | None = None,
) -> pd.DataFrame:
    """Run ``jobs`` in order as a measured test campaign (see the module docstring).

    Parameters
    ----------
    tyre : TyreConfig
        The FE-surrogate tyre.
    jobs : sequence of (kind, Condition)
        The test programme in the order it is driven; a job may repeat.
    artefacts : Artefacts, optional
        Default :class:`Artefacts`; ``Artefacts(noise=0, fz_wander=0, offsets={}, drift=0)``
        gives clean data.
    fade : callable, optional
        Friction level factor from (energy [J], time [s]) at the start of each run.
    executor : Executor, optional
        Runs the chunks of points when there is no fade (default: in this process); the
        result does not depend on it.
    """
    art = artefacts or Artefacts()
    rng = np.random.default_rng(seed)
    conds = sorted({(c.Fz, c.V, c.P, c.gamma) for _, c in jobs})
    arr = np.array(conds, dtype=float)
    w_free, _ = free_rolling(tyre, arr[:, 0], arr[:, 1], arr[:, 2], arr[:, 3])
    omega_free = {c: w for c, w in zip(conds, w_free, strict=True)}
    total_points = sum(len(rows_for(k, n_kappa, n_alpha, combined_alphas_deg)[0]) for k, _ in jobs)
    total_time = total_points * art.point_time + len(jobs) * art.pause
    drift_dir = {ch: rng.standard_normal() for ch in CHANNELS}

    runs = []
    t, energy = 0.0, 0.0
    for kind, c in jobs:
        kappa, alpha = rows_for(kind, n_kappa, n_alpha, combined_alphas_deg)
        n = len(kappa)
        level = 1.0 if fade is None else float(fade(energy, t))
        Fz = c.Fz * (1.0 + art.fz_wander * _smooth_noise(n, rng)) if art.fz_wander else np.full(n, c.Fz)
        # the run's random draws (offset, then noise, per channel), made before its forces are known
        z = {ch: (rng.standard_normal(), rng.standard_normal(n)) for ch in CHANNELS}
        omega = np.cos(alpha) * omega_free[(c.Fz, c.V, c.P, c.gamma)] * (1.0 + kappa)  # eqs 3.4, 5.15
        time = t + art.point_time * np.arange(n)
        pts = (Fz, np.full(n, c.V) * np.cos(alpha), np.full(n, c.P), omega, alpha, np.full(n, c.gamma))
        forces = None
        if fade is not None:  # the friction level of the next run depends on this run's forces
            tyre_run = tyre if level == 1.0 else tyre.updated({"friction.scale": tyre.friction.scale * level})
            forces = _forces(tyre_run, pts)
            # friction energy of this run: sliding power ~ |Fx Vsx| + |Fy Vsy| over the run time
            Vsx = kappa * c.V
            Vsy = np.tan(alpha) * c.V
            energy += float(np.sum(np.abs(forces[0] * Vsx) + np.abs(forces[1] * Vsy)) * art.point_time)
        runs.append((kind, c, kappa, alpha, Fz, time, z, pts, forces))
        t = float(time[-1]) + art.pause
    if fade is None:  # no run depends on another: one vectorised solve of all points (each point's
        # solution is independent of the batch, so this equals run-by-run solves bit for bit)
        allpts = np.array([np.concatenate([r[7][k] for r in runs]) for k in range(6)])
        split = np.cumsum([len(r[2]) for r in runs])[:-1]
        per_run = [np.split(f, split) for f in solve_points(tyre, allpts, executor=executor).T]
        runs = [(*r[:8], [f[i] for f in per_run]) for i, r in enumerate(runs)]

    pieces = []
    for run, (kind, c, kappa, alpha, Fz, time, z, _, forces) in enumerate(runs):
        df = pd.DataFrame({
            "Fz": Fz, "kappa": kappa, "alpha": alpha, "gamma": c.gamma, "Vx": c.V, "P": c.P,
            **dict(zip(CHANNELS, forces, strict=True)),
            "kind": kind, "load_fraction": c.Fz / tyre.load_index_load, "run": run, "time": time,
        })  # fmt: skip
        for ch in CHANNELS:
            y = df[ch].to_numpy(float)
            off = art.offsets.get(ch, 0.0) * z[ch][0]
            drift = art.drift * art.offsets.get(ch, 0.0) * drift_dir[ch] * (time / max(total_time, 1.0))
            noise = art.noise * np.max(np.abs(y)) * z[ch][1]
            df[ch] = y + off + drift + noise
        pieces.append(df)
    return pd.concat(pieces, ignore_index=True)
