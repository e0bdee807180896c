"""Simulated test campaigns with effects nobody anticipated (issue 11), with their truth.

Each case is a measured-like rig programme (pure braking sweeps kappa 0 -> -0.3, cornering
sweeps alpha -12 -> +12 -> -12 deg, three or four loads tested in blocks), simulated either
with the Magic Formula evaluator (the shipped MF 6.1 tyre ``tirfiles/MF61_255-55R20_mfeval-jl.tir``
with one term in ``[MFTIRE_EXTENSIONS]`` injecting the effect) or with the FE surrogate
(:mod:`mftire.fe`, with the friction level changed run by run), plus rig artefacts:

* load wander: the load follows its set point within +-2 % (smooth), the recorded ``Fz`` is
  the actual load and the forces respond to it;
* noise: Gaussian, :data:`NOISE` (0.6 %) of the channel's peak in the run (at least a fifth of
  0.6 % of its peak over the campaign);
* outliers: 1 % of the rows carry a spike of 10-30 noise sigmas on one of Fx, Fy, Mz;
* ``time`` [s] (a braking sweep lasts 15 s, a cornering sweep 24 s, 30 s between runs, 240 s
  between load blocks) and ``run``.

The reduced copies run the same programme with fewer points per sweep.

Written per case (``validation/data/unanticipated/<case>/``, and a smaller copy for tests in
``validation/data/unanticipated_reduced/<case>/``):

* ``sweeps.csv``: the sweep-table schema (``Fz, kappa, alpha, gamma, Vx, P, Fx, Fy, Mz, Mx, My``,
  SI) plus ``time``, ``run`` and the case's own columns;
* ``fitted.tir``: the plain MF 6.1 fit (:func:`mftire.fitting.fit_tir`) of the training rows
  (every row outside the held-out condition), started from the generating tyre's plain file
  with its main coefficients perturbed by a few per cent;
* ``expected.json``: what a diagnosis should find: ``effect``, ``variable``,
  ``scaling_factors``, ``family``, ``holdout`` (``{"column", "values"}``: rows whose column
  equals one of the values are held out), ``holdout_runs``, the generating term
  (``truth``), the noise sigma per channel, and the ``oracle`` held-out Fx+Fy RMS of the
  plain fit and of the truth (outlier rows excluded): the best cut any diagnosis can reach.

Cases (:data:`CASES`): ``stiffness_only``, ``curvature_shape``, ``interaction``,
``fade_blocked_load``, ``temperature_friction``, ``zero_channel_with_effect``,
``null_drifting_column``, ``null_plain``, ``null_fe`` (FE: no effect, but the MF fit's own model
error), and two FE-made effects whose MF form error dominates what any MF law can cut on the held-out
condition (``fade_blocked_load_fe``, ``sliding_speed_fe``; their ``oracle.ceiling_cut`` is the cut of
a refit with the generating law, which is the most an MF extension can reach).
Everything is reproducible (fixed seeds).
Run from the repository root::

    python validation/make_unanticipated_campaigns.py [NAME ...] [--reduced]

(``--reduced`` writes only the reduced copies; default both.)
"""

from __future__ import annotations

import argparse
import json
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from mftire import Tyre, read_tir
from mftire.extensions import SECTION
from mftire.fe.config import TyreConfig, load_tyre
from mftire.fe.measured import _smooth_noise
from mftire.fe.programmes import slip_speed_tyre
from mftire.fe.rolling_contact import solve
from mftire.fe.slip_sweeps import SWEEP_COLUMNS, free_rolling
from mftire.fe.template import mf_template
from mftire.fitting.fitter import fit_tir
from mftire.iotools.atomic import atomic_path, write_text_atomic
from mftire.iotools.tir import TirParameters, write_tir

ROOT = Path(__file__).resolve().parents[1]
TIR = ROOT / "tirfiles" / "MF61_255-55R20_mfeval-jl.tir"
OUT = ROOT / "validation" / "data" / "unanticipated"
OUT_REDUCED = ROOT / "validation" / "data" / "unanticipated_reduced"

CASES = ("stiffness_only", "curvature_shape", "interaction", "fade_blocked_load", "temperature_friction",
         "zero_channel_with_effect", "null_drifting_column", "null_plain", "null_fe", "fade_blocked_load_fe",
         "sliding_speed_fe")  # fmt: skip
#: Cases made only at full size (validation, not the tests' reduced copies).
FULL_ONLY = ("fade_blocked_load_fe", "sliding_speed_fe")
CHANNELS = ("Fx", "Fy", "Mz", "Mx", "My")
NOISE = 0.006  #: noise sigma, fraction of the channel's peak over the campaign [-]
OUTLIER_FRACTION = 0.01  #: rows with a spike on one channel [-]
FZ_WANDER = 0.02  #: load wander, most deviation from the set point [-]
SWEEP_TIME = {"braking": 15.0, "cornering": 24.0}  #: duration of a sweep [s]
RUN_PAUSE, BLOCK_PAUSE = 30.0, 240.0  #: pauses between runs, between load blocks [s]
KAPPA_END, ALPHA_MAX_DEG = -0.3, 12.0
#: (braking points, cornering points one way) of a sweep, full and reduced
POINTS = {False: (31, 25), True: (13, 9)}
#: MF coefficients perturbed (relative sigma) in the fit's start file
PERTURBED = ("PDX1", "PDY1", "PKX1", "PKY1", "PCX1", "PCY1", "PEX1", "PEY1", "PDX2", "PDY2", "QBZ1", "QDZ1")
PERTURBATION = 0.04
MODEL_TEXT = {
    "mf": "MF 6.1 (tirfiles/MF61_255-55R20_mfeval-jl.tir) with the extension term in 'truth'",
    "fe": "FE surrogate (mftire.fe, default tyre); 'truth' is the MF term that describes the effect",
}
FAMILY = {"LMUX": "friction", "LMUY": "friction", "LKX": "stiffness", "LKY": "stiffness",
          "LCX": "shape", "LCY": "shape", "LEX": "curvature", "LEY": "curvature"}  # fmt: skip


@dataclass(frozen=True)
class Run:
    """One sweep of the programme (set points; ``values``: the case's columns, constant in the run)."""

    kind: str  #: "braking" or "cornering"
    load: float  #: load set point [N]
    Vx: float  #: speed [m/s]
    block: int  #: load block (a longer pause before a new block)
    values: dict = field(default_factory=dict)


@dataclass
class Case:
    """A campaign: programme, truth, held-out condition and what a diagnosis should find."""

    name: str
    description: str
    runs: list[Run]
    model: str  #: "mf" (MF 6.1 + extension term) or "fe" (FE surrogate)
    extension: dict | None  #: the generating ``[MFTIRE_EXTENSIONS]`` term (the MF model of the effect)
    variable: str | None
    scaling_factors: list[str]
    holdout_column: str
    holdout_values: list[float]
    #: columns computed from the simulated table (name -> function(table, rng) -> values)
    derived: dict[str, Callable] = field(default_factory=dict)
    zero_channels: tuple[str, ...] = ()
    fe_tyre: TyreConfig | None = None
    #: FE friction level of a run from its index (FE cases; default 1)
    fe_level: Callable[[int], float] | None = None
    seed: int = 0
    #: MF set points the cause is confounded with across sweeps (the diagnosis must say so)
    confounded_with: tuple[str, ...] = ()


# --------------------------------------------------------------------------------------------
# the programme


def sweep_slips(kind: str, reduced: bool) -> tuple[np.ndarray, np.ndarray]:
    """(kappa, alpha) of one sweep: braking 0 -> -0.3 (clustered near 0), cornering -12 -> +12 -> -12 deg."""
    nk, na = POINTS[reduced]
    if kind == "braking":
        kappa = KAPPA_END * np.linspace(0.0, 1.0, nk) ** 1.5 + 0.0
        return kappa, np.zeros(nk)
    one_way = np.deg2rad(np.linspace(-ALPHA_MAX_DEG, ALPHA_MAX_DEG, na))
    alpha = np.concatenate([one_way, one_way[-2::-1]])
    return np.zeros(len(alpha)), alpha


def programme_table(case: Case, reduced: bool, P: float, rng: np.random.Generator) -> pd.DataFrame:
    """Inputs of every point of the programme: actual load (wander), slips, speed, time, run."""
    pieces, t, prev_block = [], 0.0, None
    for i, r in enumerate(case.runs):
        if prev_block is not None:
            t += BLOCK_PAUSE if r.block != prev_block else RUN_PAUSE
        prev_block = r.block
        kappa, alpha = sweep_slips(r.kind, reduced)
        n = len(kappa)
        wander = np.clip(0.4 * FZ_WANDER * _smooth_noise(n, rng), -FZ_WANDER, FZ_WANDER)
        time = t + np.linspace(0.0, SWEEP_TIME[r.kind], n)
        df = pd.DataFrame({"Fz": r.load * (1.0 + wander), "kappa": kappa, "alpha": alpha, "gamma": 0.0,
                           "Vx": r.Vx, "P": P, "time": time, "run": i})  # fmt: skip
        for k, v in r.values.items():
            df[k] = v
        pieces.append(df)
        t = float(time[-1])
    return pd.concat(pieces, ignore_index=True)


# --------------------------------------------------------------------------------------------
# the truth


def plain_tir() -> TirParameters:
    return read_tir(TIR)


def true_tyre(case: Case) -> Tyre:
    """The generating MF tyre of an MF case (the plain file plus the case's extension term)."""
    params = plain_tir()
    for k, v in (case.extension or {}).items():
        params.set(k, v, section=SECTION)
    return Tyre(params)


def case_columns(case: Case) -> list[str]:
    cols = {k for r in case.runs for k in r.values} | set(case.derived)
    return sorted(cols)


def mf_truth(case: Case, table: pd.DataFrame) -> pd.DataFrame:
    """Clean forces and moments of the rows of ``table`` from the generating MF tyre."""
    tyre = true_tyre(case)
    ext = case.extension or {}
    names = [v for k, v in ext.items() if k.endswith(("_VARIABLE", "_VARIABLE2"))]
    variables = {v: table[v].to_numpy(float) for v in names if v in table.columns and v not in SWEEP_COLUMNS}
    out = tyre.evaluate(table.Fz.to_numpy(float), table.kappa.to_numpy(float), table.alpha.to_numpy(float),
                        table.gamma.to_numpy(float), 0.0, table.Vx.to_numpy(float), table.P.to_numpy(float),
                        mode=111, **variables)  # fmt: skip
    return pd.DataFrame({ch: np.asarray(out[ch], float) for ch in CHANNELS}, index=table.index)


def fe_truth(case: Case, table: pd.DataFrame) -> pd.DataFrame:
    """Clean forces and moments of the rows of ``table`` from the FE surrogate, run by run.

    The wheel speed follows from free rolling at the run's set point (thesis eqs 2.53, 3.4,
    5.15: omega = cos(alpha)·omega_free·(1 + kappa)); the friction level of a run is
    ``case.fe_level(run)``.
    """
    tyre = case.fe_tyre
    out = pd.DataFrame(index=table.index, columns=list(CHANNELS), dtype=float)
    for run, rows in table.groupby("run", sort=False):
        r = case.runs[int(run)]
        P = float(rows.P.iloc[0])
        w_free, _ = free_rolling(tyre, np.array([r.load]), np.array([r.Vx]), np.array([P]))
        level = 1.0 if case.fe_level is None else float(case.fe_level(int(run)))
        tyre_run = tyre if level == 1.0 else tyre.updated({"friction.scale": tyre.friction.scale * level})
        kappa, alpha = rows.kappa.to_numpy(float), rows.alpha.to_numpy(float)
        omega = np.cos(alpha) * w_free[0] * (1.0 + kappa)
        res = solve(tyre_run, rows.Fz.to_numpy(float), r.Vx * np.cos(alpha), P, omega, alpha, 0.0)
        for ch in CHANNELS:
            out.loc[rows.index, ch] = np.asarray(getattr(res, ch), float)
    return out


def truth(case: Case, table: pd.DataFrame) -> pd.DataFrame:
    """Clean channels of the generating tyre at the stored inputs of ``table`` (any subset of rows)."""
    return fe_truth(case, table) if case.model == "fe" else mf_truth(case, table)


# --------------------------------------------------------------------------------------------
# the cases


def _fnomin() -> float:
    return float(plain_tir()["FNOMIN"])


def _blocked(loads, per_block: Callable[[int, float, np.random.Generator], list[Run]], rng) -> list[Run]:
    runs: list[Run] = []
    for b, load in enumerate(loads):
        runs += per_block(b, load, rng)
    return runs


def _levels_case(name, loads, levels, column, rng, Vx=16.6) -> list[Run]:
    """Per load block, every level of ``column`` in a fresh random order, braking and cornering."""

    def block(b, load, rng):
        order = rng.permutation(levels)
        return [Run(kind, load, Vx, b, {column: float(v)}) for v in order for kind in ("braking", "cornering")]

    return _blocked(loads, block, rng)


def thermal_tread_temp(table: pd.DataFrame, power: np.ndarray, *, ambient: float = 25.0, heat: float = 8e-3,
                       tau: float = 120.0) -> np.ndarray:  # fmt: skip
    """Tread temperature of a first-order thermal model driven by friction power [degC].

    dT/dt = heat·Pf/tau − (T − ambient)/tau, with Pf = |Fx·Vsx| + |Fy·Vsy| [W] the sliding power
    (Vsx = kappa·Vx, Vsy = tan(alpha)·Vx), integrated exactly per step (the power held over a
    step, the tyre cooling during the pauses between runs).
    """
    t, run = table.time.to_numpy(float), table.run.to_numpy()
    T = np.empty(len(t))
    temp = ambient
    for i in range(len(t)):
        if i:
            target = ambient + heat * (power[i - 1] if run[i] == run[i - 1] else 0.0)
            temp = target + (temp - target) * np.exp(-(t[i] - t[i - 1]) / tau)
        T[i] = temp
    return T


def sliding_power(table: pd.DataFrame, clean: pd.DataFrame) -> np.ndarray:
    vsx = table.kappa.to_numpy(float) * table.Vx.to_numpy(float)
    vsy = np.tan(table.alpha.to_numpy(float)) * table.Vx.to_numpy(float)
    return np.abs(clean.Fx.to_numpy(float) * vsx) + np.abs(clean.Fy.to_numpy(float) * vsy)


def make_case(name: str, reduced: bool = False) -> Case:
    """The definition of case ``name`` (the reduced programme is the same, with fewer points a sweep)."""
    rng = np.random.default_rng(CASES.index(name) + 11)
    F0 = _fnomin()
    loads4 = [f * F0 for f in (0.4, 0.75, 1.1, 1.45)]
    if name == "stiffness_only":
        levels = (20.0, 30.0, 40.0, 50.0, 60.0)
        runs = _levels_case(name, loads4, levels, "carcass_temp", rng)
        ext = {"EXT1_TARGET": "LKX LKY", "EXT1_FORM": "linear", "EXT1_VARIABLE": "carcass_temp",
               "EXT1_REF": 40.0, "EXT1_SCALE": 20.0, "EXT1_C1": -0.2}  # fmt: skip
        return Case(name, "slip stiffnesses LKX, LKY change linearly by -+20 % over carcass_temp 20..60 degC "
                    "(5 levels, shuffled within each load block); peak friction unchanged", runs, "mf", ext,
                    "carcass_temp", ["LKX", "LKY"], "carcass_temp", [60.0])  # fmt: skip
    if name == "curvature_shape":
        levels = (2.0, 3.5, 5.0, 6.5, 8.0)
        runs = _levels_case(name, loads4, levels, "tread_depth", rng)
        ext = {"EXT1_TARGET": "LCX LCY", "EXT1_FORM": "linear", "EXT1_VARIABLE": "tread_depth",
               "EXT1_REF": 5.0, "EXT1_SCALE": 3.0, "EXT1_C1": 0.15}  # fmt: skip
        return Case(name, "shape factors LCX, LCY change linearly by -+15 % over tread_depth 2..8 mm (five "
                    "specimens, tested interleaved in each load block)", runs, "mf", ext, "tread_depth",
                    ["LCX", "LCY"], "tread_depth", [6.5])  # fmt: skip
    if name == "interaction":
        speeds = (10.0, 15.0, 20.0, 25.0, 30.0)

        def block(b, load, rng):
            out = []
            for v in rng.permutation(speeds):
                for wet in (0.0, 1.0) if rng.random() < 0.5 else (1.0, 0.0):  # wet and dry interleaved
                    out += [Run(kind, load, float(v), b, {"wet": wet}) for kind in ("braking", "cornering")]
            return out

        runs = _blocked(loads4, block, rng)
        ext = {"EXT1_TARGET": "LMUX LMUY", "EXT1_FORM": "interaction", "EXT1_VARIABLE": "wet",
               "EXT1_REF": 0.0, "EXT1_SCALE": 1.0, "EXT1_VARIABLE2": "Vx", "EXT1_REF2": 0.0,
               "EXT1_SCALE2": 10.0, "EXT1_C1": -0.05, "EXT1_C2": -0.08}  # fmt: skip
        return Case(name, "grip loss on wet runs only, growing with speed: LMUX, LMUY x (1 - 0.05·wet - "
                    "0.08·wet·Vx/(10 m/s)); dry and wet runs interleaved at 10..30 m/s", runs, "mf", ext,
                    "wet", ["LMUX", "LMUY"], "Vx", [25.0])  # fmt: skip
    if name in ("fade_blocked_load", "fade_blocked_load_fe"):
        tyre = load_tyre(None)
        fe = name.endswith("_fe")
        unit = tyre.load_index_load if fe else _fnomin()
        fr = (0.4, 0.7, 1.0, 1.3)
        first = [(b, f) for b, f in enumerate(fr)]  # pass 1: loads ascending, two braking+cornering pairs each
        # pass 2: the 0.7 and 1.3 blocks repeated (time and load correlate, r = 0.77 over the runs)
        second = [(len(fr) + i, f) for i, f in enumerate((fr[1], fr[3]))]
        Vx = 60 / 3.6
        runs = [Run(k, f * unit, Vx, b) for b, f in first for _ in range(2) for k in ("braking", "cornering")]
        runs += [Run(k, f * unit, Vx, b) for b, f in second for k in ("braking", "cornering")]
        holdout = list(range(len(runs) - 4, len(runs) - 2))  # the repeated 0.7 block: far later than its first
        source = "FE surrogate; friction level (friction.scale)" if fe else "MF 6.1; friction LMUX, LMUY"
        case = Case(name, f"{source} fades with elapsed time: 1 - 0.15·(1 - exp(-t/tau)), tau = a third of the "
                    "programme; loads tested in ascending blocks (time correlates with load), then the 0.7 and "
                    "1.3 x FNOMIN blocks repeated; the repeated 0.7 block is held out", runs, "fe" if fe else "mf",
                    None, "time", ["LMUX", "LMUY"], "run", [float(i) for i in holdout],
                    fe_tyre=tyre if fe else None, confounded_with=("Fz_set",))  # fmt: skip
        # the times do not depend on the random numbers
        times = programme_table(case, reduced, 2e5, np.random.default_rng(0))
        mid = times.groupby("run").time.mean().to_numpy()
        tau = float(times.time.max()) / 3.0
        case.extension = {"EXT1_TARGET": "LMUX LMUY", "EXT1_FORM": "saturating", "EXT1_VARIABLE": "time",
                          "EXT1_REF": 0.0, "EXT1_SCALE": float(tau), "EXT1_C1": -0.15, "EXT1_C2": 1.0}  # fmt: skip
        if fe:
            case.fe_level = lambda run: 1.0 - 0.15 * (1.0 - np.exp(-mid[run] / tau))
            case.extension["note"] = "FE friction.scale, constant over a run at the run's mean time"
        return case
    if name == "temperature_friction":
        speeds = (12.0, 20.0, 28.0)

        def block(b, load, rng):
            out = []
            for v in rng.permutation(speeds):
                out += [Run(kind, load, float(v), b) for kind in ("braking", "cornering")]
            out += [Run(kind, load, float(speeds[0]), b) for kind in ("cornering", "braking")]
            return out

        runs = _blocked(loads4, block, rng)
        ext = {"EXT1_TARGET": "LMUX LMUY", "EXT1_FORM": "linear", "EXT1_VARIABLE": "tread_temp",
               "EXT1_REF": 50.0, "EXT1_SCALE": 50.0, "EXT1_C1": -0.25}  # fmt: skip
        case = Case(name, "friction LMUX, LMUY falls linearly with tread_temp (-25 % per 50 degC above 50 "
                    "degC), the tread temperature of a first-order thermal model driven by the sliding "
                    "power (rises along the sweeps, cools in the pauses)", runs, "mf", ext, "tread_temp",
                    ["LMUX", "LMUY"], "run", [])  # fmt: skip
        case.derived = {"tread_temp": lambda table, clean: thermal_tread_temp(table, sliding_power(table, clean))}
        return case
    if name in ("zero_channel_with_effect", "sliding_speed_fe"):
        fe = name.endswith("_fe")
        tyre = slip_speed_tyre(load_tyre(None)) if fe else None
        unit = tyre.load_index_load if fe else _fnomin()
        speeds = (8.0, 14.0, 20.0, 26.0, 32.0)
        fr = (0.4, 0.7, 1.0, 1.3)  # (free rolling of the FE tyre fails to converge at 1.45 x LI, 14 m/s)

        def block(b, f, rng):
            out = [Run("braking", f * unit, float(v), b) for v in rng.permutation(speeds)]
            out += [Run("cornering", f * unit, float(v), b) for v in rng.permutation(speeds[1::2])]
            return out

        runs = _blocked(fr, block, rng)
        if fe:
            return Case(name, "FE surrogate with friction depending on the local sliding speed (Savkoor law, "
                        "fixed Vmax = 1 m/s); braking at 8..32 m/s, cornering at 14 and 26 m/s", runs, "fe",
                        {"EXT1_TARGET": "LMUX LMUY", "EXT1_FORM": "decay", "EXT1_VARIABLE": "Vs",
                         "note": "FE sliding-speed friction law; the MF term that best describes it"},
                        "Vs", ["LMUX", "LMUY"], "Vx", [20.0], fe_tyre=tyre)  # fmt: skip
        ext = {"EXT1_TARGET": "LMUX LMUY", "EXT1_FORM": "decay", "EXT1_VARIABLE": "Vs", "EXT1_REF": 0.0,
               "EXT1_SCALE": 16.6, "EXT1_C1": 0.3}  # fmt: skip
        return Case(name, "MF 6.1 with friction decaying with the slip speed (LMUX, LMUY / (1 + 0.3·Vs/16.6 m/s), "
                    "the form of Pacejka 2012 eq 4.E7); braking at 8..32 m/s, cornering at 14 and 26 m/s; the "
                    "Mx channel was not measured and is stored as zeros", runs, "mf", ext, "Vs",
                    ["LMUX", "LMUY"], "Vx", [32.0], zero_channels=("Mx",))  # fmt: skip
    if name in ("null_drifting_column", "null_plain"):
        speeds = (16.6,) if name == "null_plain" else (12.0, 22.0)

        def block(b, load, rng):
            return [Run(kind, load, v, b) for _ in range(2) for v in speeds for kind in ("braking", "cornering")]

        runs = _blocked(loads4, block, rng)
        case = Case(name, "no effect: the plain MF 6.1 tyre", runs, "mf", None, None, [], "run", [])
        if name == "null_drifting_column":
            case.description = ("no effect; an irrelevant column ambient_temp drifts with time (18 -> 31 degC) "
                                "and so with the ascending load blocks")  # fmt: skip

            def ambient(table, clean):
                t = table.time.to_numpy(float)
                drift = 18.0 + 13.0 * t / t.max() + 0.8 * np.sin(2 * np.pi * t / 1800.0)
                return np.round(drift + 0.1 * np.random.default_rng(5).standard_normal(len(t)), 2)

            case.derived = {"ambient_temp": ambient}
        return case
    if name == "null_fe":
        tyre = load_tyre(None)
        li = tyre.load_index_load
        runs = [Run(k, f * li, 60 / 3.6, b) for b, f in enumerate((0.4, 0.7, 1.0, 1.3)) for _ in range(2)
                for k in ("braking", "cornering")]  # fmt: skip
        return Case(name, "no effect: the FE surrogate, whose curves the MF 6.1 fit matches only approximately",
                    runs, "fe", None, None, [], "run", [], fe_tyre=tyre)  # fmt: skip
    raise ValueError(f"unknown case {name!r}; choose from {', '.join(CASES)}")


def _finish_holdout(case: Case, table: pd.DataFrame) -> None:
    """Cases held out by run: the load block second from the bottom (a load between the trained ones)."""
    if case.holdout_column == "run" and not case.holdout_values:
        block_of_run = {i: r.block for i, r in enumerate(case.runs)}
        blocks = sorted({r.block for r in case.runs}, key=lambda b: min(r.load for r in case.runs if r.block == b))
        hold_block = blocks[1]
        case.holdout_values = [float(i) for i, b in block_of_run.items() if b == hold_block]


# --------------------------------------------------------------------------------------------
# simulate, fit, write


def simulate(case: Case, reduced: bool) -> tuple[pd.DataFrame, np.ndarray, dict[str, float]]:
    """The campaign table, its outlier mask and the noise sigma per channel."""
    rng = np.random.default_rng(1000 + CASES.index(case.name) + (500 if reduced else 0))
    P = float(case.fe_tyre.size.nominal_pressure if case.model == "fe" else plain_tir()["NOMPRES"])
    table = programme_table(case, reduced, P, rng)
    if case.derived:  # columns that depend on the simulated forces (of the tyre without the effect)
        base = truth(Case(case.name, "", case.runs, case.model, None, None, [], "", [], fe_tyre=case.fe_tyre), table)
        for col, fn in case.derived.items():
            table[col] = np.round(fn(table, base), 3)
    clean = truth(case, table)
    # noise sigma per channel: NOISE of its peak over the campaign ...
    sigma = {ch: NOISE * float(np.max(np.abs(clean[ch]))) for ch in CHANNELS}
    data = table.copy()
    for ch in CHANNELS:
        # ... and in a run NOISE of the channel's peak in the run, at least a fifth of the campaign's
        run_peak = clean[ch].abs().groupby(table.run).transform("max").to_numpy()
        run_sigma = np.maximum(NOISE * run_peak, 0.2 * sigma[ch])
        data[ch] = clean[ch].to_numpy() + run_sigma * rng.standard_normal(len(data))
    n_out = int(round(OUTLIER_FRACTION * len(data)))
    rows = rng.choice(len(data), n_out, replace=False)
    outlier = np.zeros(len(data), bool)
    outlier[rows] = True
    for i in rows:
        ch = ("Fx", "Fy", "Mz")[rng.integers(3)]
        data.loc[i, ch] += rng.choice((-1.0, 1.0)) * rng.uniform(10.0, 30.0) * sigma[ch]
    for ch in case.zero_channels:
        data[ch] = 0.0
    cols = SWEEP_COLUMNS + ["time", "run"] + [c for c in case_columns(case)]
    return data[cols], outlier, sigma


def holdout_mask(data: pd.DataFrame, column: str, values) -> np.ndarray:
    """Rows whose ``column`` equals one of ``values`` (to the CSV's 6 significant digits)."""
    v = data[column].to_numpy(float)
    return np.any(np.isclose(v[:, None], np.asarray(values, float)[None, :], rtol=1e-5, atol=1e-9), axis=1)


def start_file(case: Case, seed: int) -> TirParameters:
    """The generating tyre's plain file with its main coefficients perturbed by a few per cent."""
    params = mf_template(case.fe_tyre) if case.model == "fe" else plain_tir()
    rng = np.random.default_rng(seed)
    for key in PERTURBED:
        params.set(key, float(params[key]) * (1.0 + PERTURBATION * rng.standard_normal()))
    return params


def _rms_fx_fy(data: pd.DataFrame, model: pd.DataFrame) -> float:
    r = np.concatenate([(data.Fx - model.Fx).to_numpy(), (data.Fy - model.Fy).to_numpy()])
    return float(np.sqrt(np.mean(r * r)))


#: Start values of a generating law whose coefficients the FE case does not define.
_LAW_START = {"EXT1_REF": 0.0, "EXT1_SCALE": 16.6, "EXT1_C1": 0.1}


def ceiling_rms(case: Case, train: pd.DataFrame, fitted: TirParameters, held: pd.DataFrame) -> float:
    """Held-out Fx+Fy RMS of a refit of the training rows with the generating law (its form,
    variable and targets; coefficients fitted from the truth, or from :data:`_LAW_START`):
    the most an MF extension of that form can reach (the FE cases also carry MF form error)."""
    params = fitted.copy()
    for k, v in {**_LAW_START, **{k: v for k, v in case.extension.items() if k.startswith("EXT")}}.items():
        params.set(k, v, section=SECTION)
    tyre = Tyre(fit_tir(train, params, progress=False).parameters)
    names = [v for k, v in case.extension.items() if k.endswith(("_VARIABLE", "_VARIABLE2"))]
    out = tyre.evaluate_frame(held[[c for c in held.columns if c not in CHANNELS or c in names]])
    return _rms_fx_fy(held, out)


def make(name: str, reduced: bool) -> dict:
    case = make_case(name, reduced)
    data, outlier, sigma = simulate(case, reduced)
    _finish_holdout(case, data)
    hold = holdout_mask(data, case.holdout_column, case.holdout_values)
    if not hold.any() or hold.all():
        raise RuntimeError(f"{name}: the held-out condition selects {hold.sum()} of {len(hold)} rows")
    train = data[~hold].drop(columns=list(case.zero_channels))
    fit = fit_tir(train, start_file(case, 7 + CASES.index(name)), progress=False)
    fitted = Tyre(fit.parameters)
    held = data[hold & ~outlier]
    plain = fitted.evaluate(held.Fz.to_numpy(), held.kappa.to_numpy(), held.alpha.to_numpy(), held.gamma.to_numpy(),
                            0.0, held.Vx.to_numpy(), held.P.to_numpy(), mode=111)  # fmt: skip
    plain = pd.DataFrame({"Fx": plain["Fx"], "Fy": plain["Fy"]}, index=held.index)
    rms_fit, rms_true = _rms_fx_fy(held, plain), _rms_fx_fy(held, truth(case, held))
    rms_ceiling = ceiling_rms(case, train, fit.parameters, held) if case.extension else rms_true
    expected = {
        "case": name,
        "description": case.description,
        "effect": case.variable is not None,
        "variable": case.variable,
        "scaling_factors": case.scaling_factors,
        "family": FAMILY[case.scaling_factors[0]] if case.scaling_factors else None,
        "holdout": {"column": case.holdout_column, "values": case.holdout_values},
        "holdout_runs": sorted(int(r) for r in data.loc[hold, "run"].unique()),
        "model": MODEL_TEXT[case.model],
        "truth": case.extension,
        "not_measured": list(case.zero_channels),
        "confounded_with": list(case.confounded_with),
        "noise_sigma": {ch: round(s, 4) for ch, s in sigma.items()},
        "outlier_fraction": OUTLIER_FRACTION,
        "rows": len(data),
        "rows_heldout": int(hold.sum()),
        "oracle": {"holdout_rms_FxFy_fitted": round(rms_fit, 2), "holdout_rms_FxFy_truth": round(rms_true, 2),
                   "best_cut": round(1.0 - rms_true / rms_fit, 3),
                   "holdout_rms_FxFy_ceiling": round(rms_ceiling, 2),
                   "ceiling_cut": round(1.0 - rms_ceiling / rms_fit, 3),
                   "note": "RMS over the held-out Fx and Fy rows, outlier rows excluded; truth = the "
                           "generating model; fitted = fitted.tir; ceiling = a refit of the training rows "
                           "with the generating law (the most an MF extension of its form reaches)"},
    }  # fmt: skip
    folder = (OUT_REDUCED if reduced else OUT) / name
    folder.mkdir(parents=True, exist_ok=True)
    with atomic_path(folder / "sweeps.csv") as tmp:
        data.to_csv(tmp, index=False, float_format="%.6g")
    write_tir(fit.parameters, folder / "fitted.tir")
    write_text_atomic(folder / "expected.json", json.dumps(expected, indent=2) + "\n")
    print(
        f"{name}{' (reduced)' if reduced else ''}: {len(data)} rows, held out {hold.sum()}; held-out Fx+Fy "
        f"RMS fitted {rms_fit:.1f} N, truth {rms_true:.1f} N (best cut {1 - rms_true / rms_fit:.0%}), refit with "
        f"the generating law {rms_ceiling:.1f} N (ceiling cut {1 - rms_ceiling / rms_fit:.0%}) -> {folder}"
    )
    return expected


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="*", help=f"cases (default all): {', '.join(CASES)}")
    ap.add_argument("--reduced", action="store_true", help="write only the reduced copies (for CI)")
    args = ap.parse_args(argv)
    for name in args.names or CASES:
        if name not in CASES:
            ap.error(f"unknown case {name!r}; choose from {', '.join(CASES)}")
    warnings.simplefilter("ignore")
    for name in args.names or CASES:
        if name not in FULL_ONLY:
            make(name, True)
        if not args.reduced:
            make(name, False)


if __name__ == "__main__":
    main()
