"""Generate the SIMULATED raw rig file ``mftire/data/simulated_ttc_run.dat.gz``.

The file ships inside the package (:func:`mftire.data.rig_run`), as the third data source
of ``mftire demo``; this generator is its only source and stays here.

**The file is simulated, not measured.**  It imitates a flat-track run file in the
TTC-style layout (tab-separated; title, channel and unit lines; channels ``ET V N SA IA
RL RE P FX FY FZ MX MZ NFX NFY RST TSTI TSTC TSTO AMBTMP SR``; metric units; SAE J670
axes, so FZ is negative), sampled at 100 Hz, so that the import -> fit -> diagnose
chain can be tested and demonstrated without the TTC data, whose licence forbids
redistribution.

Schedule (40 km/h, 260 kPa)
---------------------------
1. Roll-in at a light load, then a 60 s warm-up at FNOMIN, 0 deg inclination, slip
   angle swept +-8 deg at 1 Hz (a condition measured again later, so the importer drops
   it as warm-up), then unloading and a 12 s cool-down.
2. Cornering: at inclinations 0 and 2 deg, four loads each (0.4, 0.7, 1.0, 1.3 x FNOMIN,
   in a mixed order), slip angle swept +-12 deg as a 1 Hz triangle for 20 s, after a
   2.5 s load ramp and a 3 s dwell at zero slip; a 12 s cool-down at a light load with
   zero slip after every block.
3. Braking: at the four loads, slip ratio swept 0 -> -0.25 -> 0 (triangle, 2 s period)
   for 20 s at zero slip angle.

Tyre
----
Forces and moments are the steady-state Magic Formula of
``tirfiles/MF61_255-55R20_mfeval-jl.tir`` (``mftire.load`` and ``Tyre.evaluate``),
with the friction scaling factors LMUX = LMUY = g(T) set per sample from the tread
temperature T:

    g(T) = 1 - G_DROP * (1 - exp(-((T - T_OPT) / T_WIDTH)^2))

(a bell-shaped grip window, as rubber has around its optimum temperature; not the
polynomial form of mftire's ``friction_variable`` extension).  T follows a first-order
thermal model driven by friction power:

    C dT/dt = ETA * (|Fx * Vsx| + |Fy * Vsy|) + Q_ROLL - H * (T - T_amb),
    Vsx = -kappa * Vx,  Vsy = Vx * tan(alpha)      (slip velocities, Pacejka 2012 eqs 4.E5, 2.12/4.E3)

solved exactly per sample as a discrete first-order filter; the coupling (grip ->
force -> power -> temperature) is resolved by fixed-point iteration.  The surface
temperature channels are TSTC = T, TSTI = T + 1.5 K/deg x IA, TSTO = T - 1.2 K/deg x IA.

Rig artefacts: the load wanders 1 % around its set point, Gaussian sensor noise on
every channel (FX, FY 12 N; FZ 15 N; MX, MZ 1 N·m; SA, IA 0.02 deg; SR 0.001; V 0.05
km/h; P 0.3 kPa; temperatures 0.3 K), and a 0.5 % crosstalk of FZ into FY.

Run from the repository root:  ``python validation/make_rig_file.py [OUT]``;
``python validation/make_rig_file.py --chain OUT_DIR [PAIR_STEP]`` runs the demo's
import -> fit -> diagnose stage on the whole shipped file (or every PAIR_STEP-th pair of
sweeps) and prints its summary.  The
function :func:`simulate` returns the raw channels and the true (noise-free) state for
tests; :func:`template_for_fit` and :func:`heldout_rms` serve ``tests/test_rig_import.py``.
The import -> fit -> diagnose step of the demo is :func:`mftire.demo.rig_stage`.
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.signal import lfilter

ROOT = Path(__file__).resolve().parent.parent
TIR = ROOT / "tirfiles" / "MF61_255-55R20_mfeval-jl.tir"
OUT = ROOT / "mftire" / "data" / "simulated_ttc_run.dat.gz"

FS = 100.0  #: sample rate [Hz]
V_KMH = 40.0  #: rig speed [km/h]
P_KPA = 260.0  #: inflation pressure [kPa]
LOADS = (0.4, 0.7, 1.0, 1.3)  #: load levels [x FNOMIN]
INCLINATIONS = (0.0, 2.0)  #: [deg]
# thermal model
T_AMB = 25.0  #: ambient [deg C]
C_TH = 1500.0  #: heat capacity of the tread surface layer [J/K]
H_TH = 60.0  #: heat transfer to the surroundings [W/K]  (time constant C/H = 25 s)
ETA = 0.45  #: share of the friction power heating the tread surface [-]
Q_ROLL = 150.0  #: rolling-loss heating [W]
# grip window
G_DROP = 0.25
T_OPT = 85.0
T_WIDTH = 40.0
TITLE = ("SIMULATED rig data (not measured): mftire validation/make_rig_file.py, MF 6.1 "
         "tirfiles/MF61_255-55R20_mfeval-jl.tir with tread-temperature dependent grip, 100 Hz, SAE axes")  # fmt: skip


@dataclass
class Phase:
    """One phase of the schedule: duration, load/inclination ramps, slip angle and slip ratio programmes."""

    duration: float
    fz: tuple[float, float]  #: start and end load [N]
    ia: tuple[float, float]  #: start and end inclination [deg]
    sa: str = "zero"  #: "zero", "sweep8", "sweep12"
    sr: str = "zero"  #: "zero", "brake"


def grip(T: np.ndarray, drop: float = G_DROP) -> np.ndarray:
    """Friction scaling factor of the tread temperature [-]."""
    return 1.0 - drop * (1.0 - np.exp(-(((T - T_OPT) / T_WIDTH) ** 2)))


def _triangle(t: np.ndarray, period: float) -> np.ndarray:
    """Triangle wave of unit amplitude starting at 0 and rising."""
    ph = (t / period + 0.25) % 1.0
    return 4.0 * np.abs(ph - 0.5) - 1.0


def schedule(fnomin: float) -> list[Phase]:
    """The test programme (module docstring)."""
    light = 0.15 * fnomin
    ph: list[Phase] = [Phase(3.0, (light, light), (0, 0)), Phase(2.5, (light, fnomin), (0, 0)),
                       Phase(60.0, (fnomin, fnomin), (0, 0), sa="sweep8"), Phase(2.5, (fnomin, light), (0, 0)),
                       Phase(12.0, (light, light), (0, 0))]  # fmt: skip
    cur_fz, cur_ia = light, 0.0
    orders = {0.0: (1.0, 0.4, 1.3, 0.7), 2.0: (0.7, 1.3, 0.4, 1.0)}
    for ia in INCLINATIONS:
        for f in orders[ia]:
            fz = f * fnomin
            ph.append(Phase(2.5, (cur_fz, fz), (cur_ia, ia)))
            ph.append(Phase(3.0, (fz, fz), (ia, ia)))
            ph.append(Phase(20.0, (fz, fz), (ia, ia), sa="sweep12"))
            ph.append(Phase(2.5, (fz, light), (ia, ia)))
            ph.append(Phase(12.0, (light, light), (ia, ia)))
            cur_fz, cur_ia = light, ia
    for f in (0.7, 1.3, 0.4, 1.0):
        fz = f * fnomin
        ph.append(Phase(2.5, (cur_fz, fz), (cur_ia, 0.0)))
        ph.append(Phase(3.0, (fz, fz), (0.0, 0.0)))
        ph.append(Phase(20.0, (fz, fz), (0.0, 0.0), sr="brake"))
        ph.append(Phase(2.5, (fz, light), (0.0, 0.0)))
        ph.append(Phase(8.0, (light, light), (0.0, 0.0)))
        cur_fz, cur_ia = light, 0.0
    return ph


def simulate(seed: int = 0, tir: str | os.PathLike = TIR, g_drop: float = G_DROP) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Simulate the run (``g_drop=0``: the same run with a grip that does not depend on temperature).

    Returns
    -------
    raw : DataFrame
        The TTC channels as written to the file, in SI units (angles rad, temperatures
        deg C) and SAE axes, *before* rounding to the file's digits.
    true : DataFrame
        Noise-free ISO/SI state per sample: ``t, Fz, kappa, alpha, gamma, Vx, P, Fx,
        Fy, Mz, Mx, T, grip``.
    """
    import mftire

    tyre = mftire.load(tir)
    fnomin = tyre["FNOMIN"]
    rng = np.random.default_rng(seed)
    t_parts, fz_parts, ia_parts, sa_parts, sr_parts = [], [], [], [], []
    t0 = 0.0
    for ph in schedule(fnomin):
        n = int(round(ph.duration * FS))
        tl = np.arange(n) / FS
        u = tl / ph.duration
        t_parts.append(t0 + tl)
        fz_parts.append(ph.fz[0] + (ph.fz[1] - ph.fz[0]) * u)
        ia_parts.append(ph.ia[0] + (ph.ia[1] - ph.ia[0]) * u)
        sa_parts.append({"zero": 0.0 * tl, "sweep8": 8.0 * _triangle(tl, 1.0),
                         "sweep12": 12.0 * _triangle(tl, 1.0)}[ph.sa])  # fmt: skip
        sr_parts.append(-0.125 * (1.0 - np.cos(2 * np.pi * tl / 2.0)) if ph.sr == "brake" else 0.0 * tl)
        t0 += ph.duration
    t = np.concatenate(t_parts)
    n = t.size
    # the rig's load control wanders 1 % around the set point (smooth, ~2 s correlation)
    wander = lfilter([1 - np.exp(-1 / (2 * FS))], [1, -np.exp(-1 / (2 * FS))], rng.standard_normal(n))
    wander *= 0.01 / (np.std(wander) or 1.0)
    Fz = np.concatenate(fz_parts) * (1.0 + wander)
    ia = np.concatenate(ia_parts)
    sa_iso = -np.radians(np.concatenate(sa_parts))  # the file's SA is SAE: alpha_ISO = -SA
    kappa = np.concatenate(sr_parts)
    gamma = np.radians(ia)
    Vx = np.full(n, V_KMH / 3.6)
    P = np.full(n, P_KPA * 1e3)
    a = np.exp(-1.0 / (FS * C_TH / H_TH))  # exact discrete first-order filter, time constant C/H
    T = np.full(n, T_AMB)
    flat0 = dict(tyre.flat)
    for _ in range(6):  # fixed point: grip(T) -> forces -> friction power -> T
        g = grip(T, g_drop)
        tyre.flat.update(LMUX=flat0["LMUX"] * g, LMUY=flat0["LMUY"] * g)
        out = tyre.evaluate(Fz, kappa, sa_iso, gamma, Vx=Vx, P=P)
        # friction power |Fx Vsx| + |Fy Vsy|, Vsx = -kappa Vx (eq 4.E5), Vsy = tan(alpha) Vx (eq 2.12 / 4.E3)
        power = np.abs(out["Fx"] * (-kappa * Vx)) + np.abs(out["Fy"] * Vx * np.tan(sa_iso))
        target = T_AMB + (ETA * power + Q_ROLL) / H_TH
        # C dT/dt = ETA P + Q_ROLL - H (T - T_amb), exact for inputs held over a sample
        T_new, _ = lfilter([1 - a], [1, -a], target, zi=[a * T_AMB])
        converged = float(np.max(np.abs(T_new - T))) < 1e-3
        T = T_new
        if converged:
            break
    g = grip(T, g_drop)
    tyre.flat.update(LMUX=flat0["LMUX"] * g, LMUY=flat0["LMUY"] * g)
    out = tyre.evaluate(Fz, kappa, sa_iso, gamma, Vx=Vx, P=P)
    tyre.flat.update(LMUX=flat0["LMUX"], LMUY=flat0["LMUY"])
    true = pd.DataFrame({"t": t, "Fz": Fz, "kappa": kappa, "alpha": sa_iso, "gamma": gamma, "Vx": Vx, "P": P,
                         "Fx": out["Fx"], "Fy": out["Fy"], "Mz": out["Mz"], "Mx": out["Mx"], "T": T, "grip": g})

    def noise(scale: float) -> np.ndarray:
        return scale * rng.standard_normal(n)

    # ISO -> SAE (module docstring of mftire.iotools.rig): Fy, Fz, Mz, alpha change sign
    fz_sae = -Fz
    raw = pd.DataFrame({
        "ET": t,
        "V": V_KMH + noise(0.05),
        "N": out["omega"] * 60 / (2 * np.pi) + noise(0.5),
        "SA": -np.degrees(sa_iso) + noise(0.02),
        "IA": ia + noise(0.02),
        "RL": out["Rl"] * 100 + noise(0.02),
        "RE": out["Re"] * 100 + noise(0.02),
        "P": P_KPA + noise(0.3),
        "FX": out["Fx"] + noise(12.0),
        "FY": -out["Fy"] + 0.005 * fz_sae + noise(12.0),  # 0.5 % crosstalk of FZ into FY
        "FZ": fz_sae + noise(15.0),
        "MX": out["Mx"] + noise(1.0),
        "MZ": -out["Mz"] + noise(1.0),
        "RST": 30.0 + 0.3 * np.sin(2 * np.pi * t / 900.0) + noise(0.2),
        "TSTI": T + 1.5 * ia + noise(0.3),
        "TSTC": T + noise(0.3),
        "TSTO": T - 1.2 * ia + noise(0.3),
        "AMBTMP": T_AMB + noise(0.1),
        "SR": kappa + noise(0.001),
    })  # fmt: skip
    raw["NFX"] = raw["FX"] / raw["FZ"].abs()
    raw["NFY"] = raw["FY"] / raw["FZ"].abs()
    # to SI (the noise above is in the metric file units)
    raw["V"] /= 3.6
    raw["N"] *= 2 * np.pi / 60
    raw["SA"] = np.radians(raw["SA"])
    raw["IA"] = np.radians(raw["IA"])
    raw["RL"] /= 100.0
    raw["RE"] /= 100.0
    raw["P"] *= 1e3
    return raw, true


def make(path: str | os.PathLike = OUT, seed: int = 0) -> Path:
    """Simulate and write the gzipped TTC-style file; returns its path."""
    from mftire.iotools.rig import write_ttc

    raw, _ = simulate(seed)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_ttc(raw, path, units="metric", title=TITLE)
    return path


def template_for_fit(seed: int = 11, spread: float = 0.3):
    """Fit template: the generating tyre with every fitted coefficient perturbed by up to +-``spread``.

    The fit must find the coefficients again (as in ``tests/test_fit_recovery.py``);
    FNOMIN, NOMPRES, UNLOADED_RADIUS and the other constants a fit never changes are the
    generating tyre's, as a user's template holds the tested tyre's size and nominal values.
    """
    from mftire.fitting.stages import FITTED_KEYS
    from mftire.iotools.tir import read_tir
    from mftire.parameters import with_defaults

    true = read_tir(TIR)
    flat = with_defaults(true)
    rng = np.random.default_rng(seed)
    tmpl = true.copy()
    for key in sorted(FITTED_KEYS):
        if flat.get(key, 0.0):
            tmpl.set(key, float(flat[key] * (1.0 + rng.uniform(-spread, spread))))
    return tmpl


def heldout_rms(tyre, data: pd.DataFrame, variables: dict | None = None) -> dict[str, float]:
    """RMS error of Fx (braking rows) and Fy (cornering rows) in % of the data's peak |value|."""
    out = tyre.evaluate(data["Fz"].to_numpy(), data["kappa"].to_numpy(), data["alpha"].to_numpy(),
                        data["gamma"].to_numpy(), Vx=data["Vx"].to_numpy(), P=data["P"].to_numpy(),
                        **(variables or {}))  # fmt: skip
    res = {}
    for ch, rows in (("Fx", data["sweep_var"] == "kappa"), ("Fy", data["sweep_var"] == "alpha")):
        r = rows.to_numpy()
        if r.sum() < 5:
            continue
        y = data[ch].to_numpy()[r]
        res[ch] = float(100 * np.sqrt(np.mean((out[ch][r] - y) ** 2)) / np.max(np.abs(y)))
    return res


def chain(out_dir: str | os.PathLike, pair_step: int = 1) -> dict:
    """The demo's rig stage (:func:`mftire.demo.rig_stage`) on every ``pair_step``-th pair of
    sweeps of the shipped file (1: all 400 sweeps); returns its summary."""
    import warnings

    from mftire.demo import rig_stage

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return rig_stage(out_dir, pair_step=pair_step).summary


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--chain":  # --chain OUT_DIR [PAIR_STEP]
        import json

        summary = chain(sys.argv[2], int(sys.argv[3]) if len(sys.argv) > 3 else 1)
        print(json.dumps(summary, indent=1, default=float))
    else:
        target = make(sys.argv[1] if len(sys.argv) > 1 else OUT)
        print(f"wrote {target} ({os.path.getsize(target) / 1e6:.2f} MB), SIMULATED data")
