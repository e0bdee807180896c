"""Generate SIMULATED rig runs for the thermal tyre (``mftire fit-thermal``, ``mftire replay``).

**The runs are simulated, not measured.**  Their temperatures come from a thermal model with more
structure than the three-node model mftire fits (:mod:`mftire.thermal`), so that a fit is not a
parameter echo:

* the tread is ``N_LAYERS`` conduction layers through its depth (surface layer first), then a
  carcass node and the inflation gas; the infrared sensors read the top layer;
* sliding friction power (Pacejka 2012 eqs 2.10–2.12: ``|Fx·Vsx| + |Fy·Vsy|``) heats the top
  layer (a share ``ETA_SLIP``; the rest goes into the road), rolling loss heats every layer and the
  carcass, and a force-dependent hysteresis ``∝ |Vx|·(Fx² + Fy²)/Fz`` heats the carcass;
* convection ``(H0 + H1·|V|^0.7)`` from the top layer (exponent 0.7, the fit assumes 0.8), sidewall
  convection from the carcass, contact conduction to the road;
* grip law with a threshold (no quadratic):
  ``LMUX, LMUY × 1 + A_GRIP·(T_s − 60) − B_GRIP·max(0, T_s − T_TH)``, of the top layer T_s;
* cornering and slip stiffness ``LKX, LKY × 1 − K_STIFF·(T_carcass − 40)``;
* the tyre is sealed: the gas law gives the pressure, which enters the MF's own pressure terms;
* sensor noise: FX, FY 12 N, FZ 15 N, MZ, MX 1 N·m, SA 0.005 deg, IA 0.02 deg, SR 0.0001, P 0.3 kPa,
  surface temperatures 0.5 K.  The slip channels are quieter than in ``make_rig_file.py``: a slip-ratio
  noise of 0.001 times a slip stiffness of ~1.5e5 N alone gives 150 N of Fx error, which would hide the
  temperature effect this run is for (the force errors of every model would sit on that floor).

Integration: backward Euler per sample of the layered chain (``scipy.linalg.solve_banded``); the
coupling temperature -> grip -> forces -> power -> temperature by fixed-point iteration.

Programmes (``PROGRAMMES``)
---------------------------
``warmup_loads``  a warm-up (slip angle swept +-6 deg at 40 km/h), then load steps (0.5, 1.0, 1.4 x
                  FNOMIN) each with a slip angle sweep and a braking sweep, at 40, 60 and 90 km/h;
``stint``         a stint of repeated cornering: laps of a 7 s corner at a steady slip angle
                  (3-5 deg), a 2 s braking zone, and a 6 s straight at 25 m/s.

``python validation/make_thermal_runs.py [OUT_DIR]`` writes ``thermal_run.dat.gz`` (the warm-up +
load steps programme followed by the stint, one continuous run), both programmes as separate files with
``--all``, and the true (noise-free) states as ``*_truth.csv.gz``.  Without ``OUT_DIR`` the run is the
shipped file ``mftire/data/simulated_thermal_run.dat.gz`` (in the package: ``mftire demo`` fits and
replays it; :func:`mftire.data.thermal_run`, the only copy) and the other files go to
``validation/data/thermal/``.  ``--check DIR`` runs the done-when measurement
(validation/README.md, "Thermal tyre").
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.linalg import solve_banded
from scipy.signal import lfilter

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # run from a source checkout
TIR = ROOT / "tirfiles" / "MF61_255-55R20_mfeval-jl.tir"
OUT = ROOT / "validation" / "data" / "thermal"
#: The shipped run (package data, the only copy; written by ``make()`` into the default OUT).
RUN = ROOT / "mftire" / "data" / "simulated_thermal_run.dat.gz"

FS = 10.0  #: sample rate [Hz]
T_AMB = 22.0  #: ambient [deg C]
T_ROAD = 30.0  #: road (drum) surface [deg C]
P_COLD_KPA = 230.0  #: cold set pressure (gauge) [kPa] at T_AMB
# the layered thermal model
N_LAYERS = 4  #: tread layers through the depth
C_TREAD = 6000.0  #: heat capacity of the whole tread [J/K] (split over the layers, thinnest on top)
LAYER_SHARE = (0.12, 0.22, 0.30, 0.36)  #: share of each layer, top first
G_LAYER = 260.0  #: conductance between adjacent layers [W/K]
C_CARCASS = 9000.0  #: [J/K]
G_TREAD_CARCASS = 120.0  #: bottom tread layer <-> carcass [W/K]
C_GAS = 120.0  #: [J/K]
G_CARCASS_GAS = 9.0  #: [W/K]
G_SIDEWALL = 10.0  #: carcass -> ambient [W/K]
H0, H1 = 8.0, 9.0  #: top layer -> air: H0 + H1·|V|^0.7 [W/K]
G_ROAD = 35.0  #: top layer -> road [W/K]
ETA_SLIP = 0.6  #: share of the friction power into the tread
ROLL = 0.012  #: rolling-loss coefficient (power ROLL·Fz·|V|), spread over layers and carcass
HYST = 0.012  #: hysteresis coefficient of the forces (power HYST·|V|·(Fx² + Fy²)/Fz) into the carcass
# the laws
A_GRIP, B_GRIP, T_TH = 0.0015, 0.006, 80.0
K_STIFF = 0.0035
#: The programmes and their sweep scale.
PROGRAMMES = ("warmup_loads", "stint")
TITLE = "SIMULATED rig data (not measured): mftire validation/make_thermal_runs.py, thermal MF 6.1, 10 Hz, SAE axes"


def grip(T_s):
    """Friction factor with a threshold: rises 0.15 %/K, falls 0.45 %/K above T_TH [-]."""
    return 1.0 + A_GRIP * (T_s - 60.0) - B_GRIP * np.maximum(0.0, T_s - T_TH)


def stiffness(T_c):
    """Cornering / slip stiffness factor of the carcass temperature [-]."""
    return 1.0 - K_STIFF * (T_c - 40.0)


def _triangle(t, period):
    ph = (t / period + 0.25) % 1.0
    return 4.0 * np.abs(ph - 0.5) - 1.0


def programme(name: str, fnomin: float) -> pd.DataFrame:
    """Set points per sample: ``t, Fz, V, alpha (ISO rad), kappa, ia (deg)``."""
    parts = []

    def seg(dur, fz, v, sa=lambda tl: 0 * tl, sr=lambda tl: 0 * tl, ia=0.0):
        tl = np.arange(int(round(dur * FS))) / FS
        fz0 = parts[-1]["Fz"][-1] if parts else fz
        ramp = np.clip(tl / 1.5, 0, 1)
        parts.append({"Fz": fz0 + (fz - fz0) * ramp, "V": np.full(tl.size, v), "SA": sa(tl), "kappa": sr(tl),
                      "IA": np.full(tl.size, ia)})  # fmt: skip

    if name == "warmup_loads":
        seg(5, 0.3 * fnomin, 11.1)
        seg(60, fnomin, 11.1, sa=lambda tl: 6.0 * _triangle(tl, 2.0))  # warm-up
        for v in (11.1, 16.7, 25.0):
            for f, ia in ((0.5, 0.0), (1.0, 2.0), (1.4, 0.0)):
                seg(4, f * fnomin, v, ia=ia)
                seg(16, f * fnomin, v, sa=lambda tl: 9.0 * _triangle(tl, 4.0), ia=ia)
                seg(3, f * fnomin, v, ia=ia)
                seg(10, f * fnomin, v, sr=lambda tl: -0.1 * (1 - np.cos(2 * np.pi * tl / 5.0)), ia=ia)
                seg(12, 0.3 * fnomin, v)  # cool-down
    elif name == "stint":
        for lap in range(12):
            sa_deg = (3.0, 4.0, 5.0)[lap % 3]
            seg(2, 1.2 * fnomin, 25.0, sr=lambda tl: -0.04 * np.sin(np.pi * tl / 2.0))
            seg(7, 1.3 * fnomin, 15.0, sa=lambda tl, a=sa_deg: a * np.sin(np.pi * np.minimum(tl, 7) / 7.0) ** 0.5,
                ia=2.0)  # fmt: skip
            seg(6, 0.9 * fnomin, 25.0, sr=lambda tl: 0.01 + 0 * tl)
        seg(30, 0.9 * fnomin, 25.0)  # in-lap: free rolling
    else:
        raise ValueError(f"unknown programme {name!r} (one of {', '.join(PROGRAMMES)})")
    cat = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    n = cat["Fz"].size
    return pd.DataFrame({"t": np.arange(n) / FS, "Fz": cat["Fz"], "V": cat["V"], "alpha": -np.radians(cat["SA"]),
                         "kappa": cat["kappa"], "ia": cat["IA"]})  # fmt: skip


def _layered(q_top, q_layers, q_carc, V, dt):
    """Integrate the layered chain (top layer .. bottom layer, carcass, gas); returns (n, N_LAYERS + 2)."""
    m = N_LAYERS + 2
    caps = np.array([C_TREAD * s for s in LAYER_SHARE] + [C_CARCASS, C_GAS])
    links = np.array([G_LAYER] * (N_LAYERS - 1) + [G_TREAD_CARCASS, G_CARCASS_GAS])  # link i: node i <-> i + 1
    n = q_top.size
    T = np.full(m, T_AMB)
    out = np.empty((n, m))
    out[0] = T
    for i in range(1, n):
        g_air = H0 + H1 * abs(V[i]) ** 0.7
        diag = caps / dt
        diag = diag.copy()
        diag[:-1] += links
        diag[1:] += links
        diag[0] += g_air + G_ROAD
        diag[N_LAYERS] += G_SIDEWALL
        ab = np.zeros((3, m))
        ab[0, 1:] = -links
        ab[1] = diag
        ab[2, :-1] = -links
        rhs = caps / dt * T
        rhs[:N_LAYERS] += q_layers[i] / N_LAYERS
        rhs[0] += q_top[i] + g_air * T_AMB + G_ROAD * T_ROAD
        rhs[N_LAYERS] += q_carc[i] + G_SIDEWALL * T_AMB
        T = solve_banded((1, 1), ab, rhs)
        out[i] = T
    return out


def simulate(name: str, seed: int = 0, tir=TIR) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Simulate a programme (or ``"run"``: warm-up + load steps, then the stint).

    Returns the raw TTC channels (SI, SAE axes, deg C; before the file's rounding) and the true
    state (ISO/SI: ``ET, Fz, kappa, alpha, gamma, Vx, P, Fx, Fy, Mz, T_top, T_carcass, T_gas,
    grip, stiffness``).
    """
    import mftire

    tyre = mftire.load(tir)
    fn = tyre["FNOMIN"]
    if name == "run":
        a, b = programme("warmup_loads", fn), programme("stint", fn)
        b["t"] += a["t"].iloc[-1] + 1.0 / FS
        sp = pd.concat([a, b], ignore_index=True)
    else:
        sp = programme(name, fn)
    rng = np.random.default_rng(seed)
    n = len(sp)
    wander = lfilter([1 - np.exp(-1 / (2 * FS))], [1, -np.exp(-1 / (2 * FS))], rng.standard_normal(n))
    wander *= 0.01 / (np.std(wander) or 1.0)
    Fz = sp["Fz"].to_numpy() * (1 + wander)
    V, kappa, alpha, gamma = sp["V"].to_numpy(), sp["kappa"].to_numpy(), sp["alpha"].to_numpy(), np.radians(sp["ia"])
    gamma = np.asarray(gamma)
    p_cold = P_COLD_KPA * 1e3
    atm = 101325.0
    flat0 = dict(tyre.flat)
    states = np.full((n, N_LAYERS + 2), T_AMB)
    for _ in range(30):
        g, k = grip(states[:, 0]), stiffness(states[:, N_LAYERS])
        P = (p_cold + atm) * (states[:, -1] + 273.15) / (T_AMB + 273.15) - atm
        tyre.flat.update(LMUX=flat0["LMUX"] * g, LMUY=flat0["LMUY"] * g, LKX=flat0["LKX"] * k, LKY=flat0["LKY"] * k)
        out = tyre.evaluate(Fz, kappa, alpha, gamma, Vx=V, P=P)
        power = np.abs(out["Fx"] * (-kappa * V)) + np.abs(out["Fy"] * V * np.tan(alpha))
        roll = ROLL * Fz * V
        hyst = HYST * V * (out["Fx"] ** 2 + out["Fy"] ** 2) / np.maximum(Fz, 1.0)
        new = _layered(ETA_SLIP * power, 0.5 * roll, 0.5 * roll + hyst, V, 1.0 / FS)
        change = np.max(np.abs(new - states))
        states = new
        if change < 1e-4:
            break
    tyre.flat.update({k: flat0[k] for k in ("LMUX", "LMUY", "LKX", "LKY")})
    T_top, T_c, T_g = states[:, 0], states[:, N_LAYERS], states[:, -1]
    t = sp["t"].to_numpy()
    true = pd.DataFrame({"ET": t, "Fz": Fz, "kappa": kappa, "alpha": alpha, "gamma": gamma, "Vx": V, "P": P,
                         "Fx": out["Fx"], "Fy": out["Fy"], "Mz": out["Mz"], "T_top": T_top, "T_carcass": T_c,
                         "T_gas": T_g, "grip": g, "stiffness": k})  # fmt: skip

    def noise(s):
        return s * rng.standard_normal(n)

    ia = np.degrees(gamma)
    raw = pd.DataFrame({
        "ET": t, "V": V * 3.6 + noise(0.05), "N": out["omega"] * 60 / (2 * np.pi) + noise(0.5),
        "SA": -np.degrees(alpha) + noise(0.005), "IA": ia + noise(0.02), "RL": out["Rl"] * 100 + noise(0.02),
        "RE": out["Re"] * 100 + noise(0.02), "P": P / 1e3 + noise(0.3), "FX": out["Fx"] + noise(12.0),
        "FY": -out["Fy"] + noise(12.0), "FZ": -Fz + noise(15.0), "MX": out["Mx"] + noise(1.0),
        "MZ": -out["Mz"] + noise(1.0), "RST": T_ROAD + noise(0.2),
        "TSTI": T_top + 1.5 * ia + noise(0.5), "TSTC": T_top + noise(0.5), "TSTO": T_top - 1.5 * ia + noise(0.5),
        "AMBTMP": T_AMB + noise(0.1), "SR": kappa + noise(0.0001),
    })  # fmt: skip
    raw["V"] /= 3.6
    raw["N"] *= 2 * np.pi / 60
    raw["SA"] = np.radians(raw["SA"])
    raw["IA"] = np.radians(raw["IA"])
    raw["RL"] /= 100.0
    raw["RE"] /= 100.0
    raw["P"] *= 1e3
    return raw, true


def make(out_dir=OUT, names=("run",), seed: int = 0) -> list[Path]:
    from mftire.iotools.rig import write_ttc

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for name in names:
        raw, true = simulate(name, seed)
        stem = "thermal_run" if name == "run" else f"thermal_{name}"
        p = RUN if name == "run" and out_dir.resolve() == OUT.resolve() else out_dir / f"{stem}.dat.gz"
        write_ttc(raw, p, units="metric", title=TITLE)
        true.to_csv(out_dir / f"{stem}_truth.csv.gz", index=False, float_format="%.6g")
        paths.append(p)
    return paths


def split_time(tir=TIR) -> float:
    """ET [s] at which the stint starts in the shipped run (the fit uses the rows before it)."""
    import mftire

    return float(len(programme("warmup_loads", mftire.load(tir)["FNOMIN"])) / FS)


def _rms(x) -> float:
    x = np.asarray(x, float)
    return float(np.sqrt(np.mean(x[np.isfinite(x)] ** 2)))


def check(work_dir, run=None, tir=TIR, quiet: bool = False) -> dict:
    """The done-when measurement on the shipped run (validation/README.md, "Thermal tyre").

    1. ``mftire fit-thermal RUN --tir TIR --output THERMAL.tir --fit-until SPLIT``;
    2. ``mftire replay RUN --tir THERMAL.tir --output replay.csv``, errors on ET > SPLIT;
    3. the same laws fed the measured temperature (mean IR) and the measured pressure, fitted on
       ET <= SPLIT (:func:`mftire.thermal.heldout.measured_temperature_model`);
    4. the isothermal fit: LMUX, LMUY, LKX, LKY of TIR refitted on ET <= SPLIT at the cold pressure
       (:func:`mftire.thermal.heldout.isothermal_fit`), written as ISO.tir and replayed
       (``mftire replay RUN --tir ISO.tir``).
    """
    import contextlib
    import io

    import mftire
    from mftire.cli import main
    from mftire.iotools.rig import read_ttc
    from mftire.iotools.tir import write_tir
    from mftire.thermal.thermal_fit import measured_surface

    work = Path(work_dir)
    work.mkdir(parents=True, exist_ok=True)
    run = Path(run or RUN)
    split = split_time(tir)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        rc1 = main(["fit-thermal", str(run), "--tir", str(tir), "--output", str(work / "THERMAL.tir"),
                    "--fit-until", f"{split:g}", "--force"])  # fmt: skip
        rc2 = main(["replay", str(run), "--tir", str(work / "THERMAL.tir"), "--output", str(work / "replay.csv"),
                    "--force"])  # fmt: skip
    assert rc1 == rc2 == 0, out.getvalue()
    df = read_ttc(run)
    held = df["ET"].to_numpy() > split
    fit = ~held
    rep = pd.read_csv(work / "replay.csv")
    ir = measured_surface(df)
    res = {"split_s": split, "surface_rms_K": _rms(rep["T_surface"][held] - ir[held]),
           "pressure_rms_kPa": _rms(rep["P_model"][held] - rep["P"][held]) / 1e3}  # fmt: skip
    for ch in ("Fx", "Fy"):
        res[f"{ch}_replay"] = _rms(rep[f"{ch}_model"][held] - rep[ch][held])
    # the two references (mftire.thermal.heldout, as mftire demo's thermal stage): the laws fed the measured
    # temperature and pressure; the isothermal fit, replayed with the command
    from mftire.thermal.heldout import evaluate_measured, isothermal_fit, measured_temperature_model

    dfit = df[fit].reset_index(drop=True)
    f = evaluate_measured(measured_temperature_model(mftire.load(tir), dfit), df)
    for ch in ("Fx", "Fy"):
        res[f"{ch}_measured_T"] = _rms(f[ch][held] - df[ch].to_numpy()[held])
    write_tir(isothermal_fit(mftire.load(tir), dfit), work / "ISO.tir")
    with contextlib.redirect_stdout(out):
        main(["replay", str(run), "--tir", str(work / "ISO.tir"), "--output", str(work / "replay_iso.csv"), "--force"])
    rep_iso = pd.read_csv(work / "replay_iso.csv")
    for ch in ("Fx", "Fy"):
        res[f"{ch}_isothermal"] = _rms(rep_iso[f"{ch}_model"][held] - rep_iso[ch][held])
        res[f"{ch}_ratio_to_measured_T"] = res[f"{ch}_replay"] / res[f"{ch}_measured_T"]
        res[f"{ch}_reduction_vs_isothermal_pct"] = 100 * (1 - res[f"{ch}_replay"] / res[f"{ch}_isothermal"])
        res[f"{ch}_measured_T_reduction_vs_isothermal_pct"] = 100 * (1 - res[f"{ch}_measured_T"]
                                                                     / res[f"{ch}_isothermal"])
    if not quiet:
        print(out.getvalue())
        for k, v in res.items():
            print(f"{k:40s} {v:10.3f}")
    return res


if __name__ == "__main__":
    if sys.argv[1:2] == ["--check"]:
        check(sys.argv[2] if len(sys.argv) > 2 else "thermal_check")
        sys.exit(0)
    args = sys.argv[1:]
    names = ("run", *PROGRAMMES) if "--all" in args else ("run",)
    args = [a for a in args if a != "--all"]
    for p in make(args[0] if args else OUT, names):
        print(p, f"{p.stat().st_size / 1e3:.0f} kB")
