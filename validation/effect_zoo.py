"""The effect zoo (issue 21): random campaigns with an undeclared effect, and the judge of a diagnosis.

:func:`draw` makes one campaign from a seed: a measured-like rig programme simulated with a Magic
Formula tyre, one effect (or none) that the plain MF does not hold, rig artefacts, identifier and
decoy columns, a held-out design, and the ground truth.  It models what users' data can hold; it
is independent of the diagnosis method (it reads nothing of :mod:`mftire.diagnosis`) and broader
than the method's catalogue of laws.  What it varies (each drawn independently from the seed):

* **effect family and target channel** (:data:`FAMILIES`): friction (LMUX/LMUY), slip stiffness
  (LKX/LKY), shape (LCX/LCY), curvature (LEX/LEY), horizontal and vertical shifts (LHX/LHY, LVX/LVY),
  the Mz trail (LTR) and residual torque (LRES), Fx/Fy offsets, and *input* errors: an effective
  pressure ``P·(1 + s·g)`` (e.g. the ideal-gas rise with temperature) while the logged ``P`` stays
  cold, a slip-angle offset, a camber offset;
* **law shape** g (:data:`SHAPES`): linear, quadratic, hinge (threshold), saturating, optimum, a
  two-level step (flags) and direction (hysteresis: a sign change between up and down sweeps);
* **variable**: a run-level constant (continuous or cycled levels), drifting within runs (a tread
  temperature that follows the friction power with a lag, wear that follows the friction energy, a
  track temperature drifting in time), a staircase in test order, a two-level flag, an MF input
  (speed, slip speed), the sweep direction, optionally times an MF input (load dfz, camber, speed,
  pressure, sign of the slip angle: an interaction);
* **effect size**: drawn as it shows, 2-25 noise sigmas (log-uniform; ``snr``: the effect's RMS on its
  most affected scored channel over that channel's noise), the physical size ``s`` following (at most 2x
  the family's largest size of :data:`FAMILIES`); an effect that cannot show on its target moves to another;
* **confounding**: loads tested in blocks or interleaved, staircases in test order, identifier
  columns that follow the effect (a file number per specimen), a variable that follows friction power;
* **held-out design**: an unseen level (interior band) of the variable, an unseen combination of a
  load with a level, new runs (scattered or the last of the programme), an interior load;
* **noise** (0.3-1.2 % of peak), **outliers** (0-2 % of rows), **missing or all-zero channels** (Mz, Mx, My);
* **identifier columns** (run, sweep, segment, row, file numbers) always, under varying names;
* **nulls** (a quarter of the draws): no effect, run-to-run friction scatter that no column
  explains, decoy columns drifting with time or load.

The tyre is one of :data:`TYRES`; the fit's start file is that tyre perturbed by a few per cent.

The runner (:func:`main`) fits the base MF to the training rows, runs :func:`mftire.diagnosis.diagnose`
on the training rows only, evaluates the held-out rows (outliers excluded) before and after, and the
**oracle ceiling**: a refit of the training rows with the generating law (shape and variable known,
its size and every MF coefficient fitted: an ``[MFTIRE_EXTENSIONS]`` ``linear`` term in the true g;
for input errors the fit and evaluation with the true inputs).  Scores (issue 21 "Done when"):

* *cause named first*: the cause the diagnosis names (the first of its ranking when it reports an
  effect, or ``DiagnosisResult.cause`` when it names a cause without a law) is the generating column
  or an accepted equivalent the draw documents (``accepted``: e.g. the friction energy or time for wear);
* *held-out cut* of the scored channels (Fx, Fy, Mz where measured; each channel's RMS normalised by its
  held-out peak, pooled): counted in draws whose ceiling cut is >= 70 %; success >= 50 %;
* *violation*: any scored channel's held-out RMS > 1.05 x before;
* *false finding*: a null draw where the diagnosis reports an effect or names a cause.

Run from the repository root::

    python validation/effect_zoo.py --draws 200 [--seed 0] [--jobs 1]
    python validation/effect_zoo.py --table-only      # rewrite the README table from the results file

Writes ``validation/effect_zoo_results.csv`` (one row per draw) and the table between the
``effect-zoo`` markers of ``validation/README.md``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from make_unanticipated_campaigns import (  # noqa: E402
    CHANNELS,
    FZ_WANDER,
    perturbed,
    rig_artefacts,
    sliding_power,
    thermal_tread_temp,
)

from mftire import Tyre, read_tir  # noqa: E402
from mftire.extensions import SECTION  # noqa: E402
from mftire.fe.measured import _smooth_noise  # noqa: E402
from mftire.iotools.tir import TirParameters  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
TYRES = (ROOT / "tirfiles" / "MF61_255-55R20_mfeval-jl.tir", ROOT / "mftire" / "data" / "default.tir")
RESULTS = ROOT / "validation" / "effect_zoo_results.csv"
README = ROOT / "validation" / "README.md"
MARK_BEGIN, MARK_END = "<!-- effect-zoo:begin -->", "<!-- effect-zoo:end -->"

NULL_FRACTION = 0.25  #: one draw in every block of four consecutive seeds is a null
SCORED = ("Fx", "Fy", "Mz")
WORSE = 1.05  #: a scored channel's held-out RMS above this x before is a violation
CEILING_MIN, CUT_MIN = 0.70, 0.50
SWEEP_TIME = {"braking": 12.0, "cornering": 20.0}  #: [s]
SWEEP_PAUSE, RUN_PAUSE, BLOCK_PAUSE = 8.0, 30.0, 240.0  #: [s]
#: ranges of the points of a braking sweep, of one way of a cornering sweep (drawn per campaign)
POINTS_BRAKING, POINTS_CORNERING = (11, 22), (8, 16)
KAPPA_END, ALPHA_MAX_DEG = -0.25, 10.0

#: family -> (target choices, size range [min, max] of |s|, the channels the effect acts on per target)
FAMILIES: dict[str, tuple[tuple[tuple[str, ...], ...], tuple[float, float]]] = {
    "friction": ((("LMUX",), ("LMUY",), ("LMUX", "LMUY")), (0.04, 0.25)),
    "stiffness": ((("LKX",), ("LKY",), ("LKX", "LKY")), (0.08, 0.35)),
    "shape": ((("LCX",), ("LCY",), ("LCX", "LCY")), (0.04, 0.15)),
    "curvature": ((("LEX",), ("LEY",)), (0.2, 0.8)),
    "horizontal_shift": ((("LHX",), ("LHY",)), (1.0, 4.0)),
    "vertical_shift": ((("LVX",), ("LVY",)), (0.5, 2.0)),
    "trail": ((("LTR",),), (0.1, 0.35)),
    "residual_torque": ((("LRES",),), (0.5, 3.0)),
    "offset": ((("FX_OFFSET",), ("FY_OFFSET",)), (0.005, 0.03)),
    "pressure_input": ((("P",),), (0.04, 0.15)),
    "slip_angle_offset": ((("alpha",),), (math.radians(0.1), math.radians(0.6))),
    "camber_offset": ((("gamma",),), (math.radians(0.5), math.radians(2.5))),
}
INPUT_FAMILIES = ("pressure_input", "slip_angle_offset", "camber_offset")
#: scaling factors a law keeps positive (factor >= 0.3): friction, stiffness, shape, trail
POSITIVE = frozenset({"LMUX", "LMUY", "LKX", "LKY", "LCX", "LCY", "LTR"})
SHAPES = ("linear", "quadratic", "hinge", "saturating", "optimum")
#: variable kinds and their probabilities
VARIABLE_KINDS = {"run_constant": 0.24, "staircase": 0.14, "flag": 0.12, "drift": 0.3, "mf_input": 0.1,
                  "direction": 0.1}  # fmt: skip
INTERACTIONS = ("dfz", "gamma", "Vx", "P", "sign_alpha")
NULL_KINDS = ("plain", "run_scatter", "decoys")
ID_NAMES = {"run": ("run", "run_no", "RUN"), "sweep": ("sweep", "sweep_no", "SWEEPNR"),
            "segment": ("segment", "seg"), "row": ("row", "row_no", "rownum"),
            "file": ("file_no", "file_id", "FILENR")}  # fmt: skip
RUN_VARIABLES = {"carcass_temp": (20.0, 60.0, 1), "road_temp": (10.0, 50.0, 1), "tread_depth": (2.0, 8.0, 2),
                 "rim_temp": (25.0, 70.0, 1), "hardness": (55.0, 75.0, 1)}  # fmt: skip
LEVEL_VARIABLES = {"tread_depth": (2.0, 8.0), "specimen_age": (0.0, 24.0), "compound_batch": (1.0, 5.0),
                   "conditioning_temp": (10.0, 50.0)}  # fmt: skip
FLAG_VARIABLES = ("wet", "new_tyre", "surface_b", "heater_on")
DECOYS = ("ambient_temp", "hub_temp", "humidity", "rig_oil_temp", "operator")


@dataclass
class ZooDraw:
    """One campaign of the zoo with its ground truth."""

    seed: int
    data: pd.DataFrame  #: the sweep table as a user has it (SI; identifiers, time, variable, decoys)
    holdout: np.ndarray  #: rows held out (never seen by the fit or the diagnosis)
    outlier: np.ndarray  #: rows with a spike (excluded from the held-out scores)
    clean: pd.DataFrame  #: noise-free channels of the generating tyre
    tyre_file: str  #: the generating plain .tir (repository-relative)
    start: TirParameters  #: start file of the base fit (the generating tyre perturbed)
    truth: dict  #: the ground truth (see :func:`draw`)
    law_g: np.ndarray | None  #: the generating law's per-row shape g (factor 1 + s·g; offset Fz·s·g)
    true_inputs: pd.DataFrame | None  #: the true MF inputs of an input-error draw
    zero_channels: tuple[str, ...] = ()
    sigma: dict = field(default_factory=dict)

    @property
    def train(self) -> pd.DataFrame:
        return self.data[~self.holdout].reset_index(drop=True)

    @property
    def identifier_columns(self) -> list[str]:
        return list(self.truth["identifiers"].values())


# --------------------------------------------------------------------------------------------
# programme


def _sweep_slips(kind: str, points: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(kappa, alpha, direction) of a sweep: braking 0 -> KAPPA_END, cornering -A -> +A -> -A.

    The direction is the sign of the rate of the swept slip, as the diagnosis's ``sweep_dir`` and the sweep
    analysis define it: a braking sweep to KAPPA_END < 0 is a decreasing sweep (−1), like the down half of a
    cornering sweep.  (Until 9dc3c2b it was +1, "|slip| increases", while cornering used the signed rate: one
    generator with two conventions, so a direction effect put the up-sweep offset on every braking sweep.)
    """
    if kind == "braking":
        k = KAPPA_END * np.linspace(0.0, 1.0, points[0]) ** 1.5
        return k, np.zeros(len(k)), np.full(len(k), float(np.sign(KAPPA_END)))  # the sign of dkappa/dt
    one = np.deg2rad(np.linspace(-ALPHA_MAX_DEG, ALPHA_MAX_DEG, points[1]))
    a = np.concatenate([one, one[-2::-1]])
    d = np.concatenate([np.ones(len(one)), -np.ones(len(one) - 1)])  # up, then down
    return np.zeros(len(a)), a, d


def _conditions(rng, tyre: TirParameters, need: str | None) -> tuple[list[dict], dict]:
    """Operating conditions: loads x (camber | speed | pressure levels), one factor at a time per load."""
    F0, P0 = float(tyre["FNOMIN"]), float(tyre["NOMPRES"])
    n_loads = int(rng.choice([3, 4]))
    loads = np.sort(rng.choice([0.4, 0.6, 0.8, 1.0, 1.2, 1.45], n_loads, replace=False)) * F0
    gammas = [0.0]
    if need == "gamma" or rng.random() < 0.25:
        gammas = [0.0, math.radians(2.0), math.radians(4.0)] if rng.random() < 0.5 else [
            math.radians(-3.0), 0.0, math.radians(3.0)]
    speeds = [16.7]
    if need == "Vx" or rng.random() < 0.3:
        speeds = list(rng.choice([8.0, 12.0, 16.7, 22.0, 28.0], int(rng.choice([2, 3])), replace=False))
    pressures = [P0]
    if need == "P" or rng.random() < 0.25:
        pressures = [0.85 * P0, P0, 1.15 * P0]
    conds = []
    # the factor the effect interacts with at every load; the others at two loads (one factor at a time)
    some = set(np.sort(rng.choice(len(loads), 2, replace=False)).tolist())
    for i, L in enumerate(loads):
        base = {"load": float(L), "gamma": 0.0, "Vx": float(speeds[0]), "P": P0}
        conds.append(base)
        if need == "gamma" or i in some:
            conds += [{**base, "gamma": g} for g in gammas if g != 0.0]
        if need == "Vx" or i in some:
            conds += [{**base, "Vx": float(v)} for v in speeds[1:]]
        if need == "P" or i in some:
            conds += [{**base, "P": p} for p in pressures if p != P0]
    return conds, {"loads": [float(x) for x in loads], "gammas": gammas, "speeds": [float(v) for v in speeds],
                   "pressures": pressures}  # fmt: skip


def _runs(rng, conds: list[dict], target_runs: int, blocked: bool) -> list[dict]:
    """The programme: each condition repeated to reach about ``target_runs`` runs; loads in blocks
    (ascending or in a random block order) or everything interleaved."""
    reps = max(2, int(round(target_runs / len(conds))))  # every condition at least twice
    runs = [dict(c) for c in conds for _ in range(reps)]
    if blocked:
        loads = sorted({r["load"] for r in runs})
        if rng.random() < 0.4:
            loads = list(rng.permutation(loads))
        out = []
        for b, L in enumerate(loads):
            block = [r for r in runs if r["load"] == L]
            for i in rng.permutation(len(block)):
                out.append({**block[i], "block": b})
        return out
    return [{**runs[i], "block": 0} for i in rng.permutation(len(runs))]


def _table(rng, runs: list[dict]) -> pd.DataFrame:
    """Inputs of every point: actual load (wander), slips, camber, speed, pressure, time, run, sweep."""
    pieces, t, prev_block, sweep = [], 0.0, None, 0
    points = (int(rng.integers(*POINTS_BRAKING)), int(rng.integers(*POINTS_CORNERING)))
    for i, r in enumerate(runs):
        if prev_block is not None:
            t += BLOCK_PAUSE if r["block"] != prev_block else RUN_PAUSE
        prev_block = r["block"]
        kinds = ("braking", "cornering") if rng.random() < 0.5 else ("cornering", "braking")
        for j, kind in enumerate(kinds):
            if j:
                t += SWEEP_PAUSE
            kappa, alpha, direction = _sweep_slips(kind, points)
            n = len(kappa)
            wander = np.clip(0.4 * FZ_WANDER * _smooth_noise(n, rng), -FZ_WANDER, FZ_WANDER)
            tt = t + np.linspace(0.0, SWEEP_TIME[kind], n)
            pieces.append(pd.DataFrame({
                "Fz": r["load"] * (1.0 + wander), "kappa": kappa, "alpha": alpha, "gamma": r["gamma"], "Vx": r["Vx"],
                "P": r["P"], "time": tt, "run": i, "block": r["block"], "sweep": sweep, "segment": j + 1,
                "kind": kind, "direction": direction, "Fz_set": r["load"]}))  # fmt: skip
            sweep += 1
            t = float(tt[-1])
    return pd.concat(pieces, ignore_index=True)


# --------------------------------------------------------------------------------------------
# the law


def shape_g(shape: str, z: np.ndarray, rng) -> tuple[np.ndarray, dict]:
    """The law's shape g(z) for z in about [0, 1] (the variable scaled to its campaign range)."""
    if shape == "linear":
        return 2.0 * z - 1.0, {}
    if shape == "quadratic":
        c = float(rng.uniform(0.0, 0.6))
        return ((z - c) / (1.0 - c)) ** 2, {"vertex": c}
    if shape == "hinge":
        z0 = float(rng.uniform(0.3, 0.7))
        return np.maximum(z - z0, 0.0) / (1.0 - z0), {"threshold": z0}
    if shape == "saturating":
        tau = float(rng.uniform(0.1, 0.4))
        return (1.0 - np.exp(-np.maximum(z, 0.0) / tau)) / (1.0 - np.exp(-1.0 / tau)), {"tau": tau}
    if shape == "optimum":
        zs, w = float(rng.uniform(0.3, 0.7)), float(rng.uniform(0.35, 0.6))
        return -(((z - zs) / w) ** 2), {"optimum": zs, "width": w}
    if shape in ("step", "direction"):
        return z, {}
    raise ValueError(shape)


def _scaled(v: np.ndarray) -> np.ndarray:
    lo, hi = np.nanpercentile(v, 2), np.nanpercentile(v, 98)
    return (v - lo) / (hi - lo) if hi > lo else np.zeros_like(v)


def _interaction_h(kind: str, table: pd.DataFrame, F0: float, P0: float) -> np.ndarray:
    if kind == "dfz":
        return 1.0 + 1.5 * (table.Fz.to_numpy() - F0) / F0
    if kind == "gamma":
        g = np.abs(table.gamma.to_numpy())
        return g / max(float(g.max()), 1e-9)
    if kind == "Vx":
        v = table.Vx.to_numpy()
        return v / float(v.mean())
    if kind == "P":
        return 1.0 + 4.0 * (table.P.to_numpy() - P0) / P0
    if kind == "sign_alpha":
        return np.sign(table.alpha.to_numpy())
    raise ValueError(kind)


# --------------------------------------------------------------------------------------------
# simulation


def _evaluate(tyre: TirParameters, table: pd.DataFrame, inputs: pd.DataFrame | None = None,
              targets: tuple[str, ...] = (), factor: np.ndarray | None = None) -> pd.DataFrame:
    """Clean channels of the plain tyre with per-row factor ``factor`` on ``targets`` (scaling factors, or
    FX/FY_OFFSET = Fz·(factor − 1)), at ``inputs`` (default: the table's)."""
    params = tyre.copy()
    kwargs = {}
    if targets and factor is not None:
        for k, v in {"EXT1_TARGET": " ".join(targets), "EXT1_FORM": "linear", "EXT1_VARIABLE": "zoo_g",
                     "EXT1_REF": 0.0, "EXT1_SCALE": 1.0, "EXT1_C1": 1.0}.items():  # fmt: skip
            params.set(k, v, section=SECTION)
        kwargs["zoo_g"] = np.asarray(factor, float) - 1.0
    x = table if inputs is None else inputs
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = Tyre(params).evaluate(x.Fz.to_numpy(float), x.kappa.to_numpy(float), x.alpha.to_numpy(float),
                                    x.gamma.to_numpy(float), 0.0, x.Vx.to_numpy(float), x.P.to_numpy(float),
                                    mode=111, **kwargs)  # fmt: skip
    return pd.DataFrame({ch: np.asarray(out[ch], float) for ch in CHANNELS}, index=table.index)


def _pick(rng, options):
    return options[int(rng.integers(len(options)))]


def _choose_kind(rng) -> str:
    names = list(VARIABLE_KINDS)
    return str(rng.choice(names, p=np.array(list(VARIABLE_KINDS.values())) / sum(VARIABLE_KINDS.values())))


def _assign_run_values(rng, table: pd.DataFrame, runs: list[dict], kind: str, truth: dict) -> np.ndarray | None:
    """Values of a run-level variable per row (None for the within-run kinds)."""
    n_runs = len(runs)
    if kind == "run_constant":
        name = _pick(rng, list(RUN_VARIABLES))
        lo, hi, dec = RUN_VARIABLES[name]
        if rng.random() < 0.5:  # continuous, one value per run
            per_run = np.round(rng.uniform(lo, hi, n_runs), dec)
        else:  # a few levels, cycled in a random order inside each load block
            k = int(rng.integers(3, 6))
            lv = np.round(np.linspace(lo, hi, k), dec)
            per_run = np.empty(n_runs)
            for b in sorted({r["block"] for r in runs}):
                idx = [i for i, r in enumerate(runs) if r["block"] == b]
                cyc = np.concatenate([rng.permutation(lv) for _ in range(len(idx) // k + 1)])
                per_run[idx] = cyc[: len(idx)]
        truth.update(variable=name, variable_kind="run_constant")
    elif kind == "staircase":
        name = _pick(rng, list(LEVEL_VARIABLES))
        lo, hi = LEVEL_VARIABLES[name]
        k = int(rng.integers(3, 6))
        lv = np.linspace(lo, hi, k)
        if rng.random() < 0.5:
            lv = lv[::-1]
        step = np.minimum(np.arange(n_runs) * k // n_runs, k - 1)  # contiguous in test order
        per_run = np.round(lv[step], 3)
        truth.update(variable=name, variable_kind="staircase", confounding=truth["confounding"] + ["test order"])
    elif kind == "flag":
        name = _pick(rng, FLAG_VARIABLES)
        if rng.random() < 0.6:  # interleaved, balanced
            per_run = rng.permutation(np.arange(n_runs) % 2).astype(float)
        else:  # in blocks of runs: the second half of the programme
            per_run = (np.arange(n_runs) >= n_runs // 2).astype(float)
            truth["confounding"] = truth["confounding"] + ["test order"]
        truth.update(variable=name, variable_kind="flag")
    else:
        return None
    return per_run[table.run.to_numpy()]


def draw(seed: int) -> ZooDraw:
    """One zoo campaign from ``seed`` (reproducible).  ``truth`` holds: ``is_null``, ``null_kind``,
    ``family``, ``targets``, ``channels`` (the channels the effect acts on), ``shape`` (+ ``shape_params``),
    ``variable`` (the generating column, or a derived quantity: ``Vs``, ``Vx``, ``sweep_dir``),
    ``variable_kind``, ``accepted`` (names that count as the right cause), ``interaction`` (MF input or
    None), ``size`` (s), ``snr`` (the effect's RMS over the noise sigma on its main channel),
    ``confounding``, ``holdout_design``, ``noise``, ``outlier_fraction``, ``identifiers``, ``decoys``,
    ``not_measured``, ``law_expressible`` (how the ceiling is refitted)."""
    rng = np.random.default_rng([21, seed])
    tyre_path = TYRES[int(rng.integers(len(TYRES)))]
    tyre = read_tir(tyre_path)
    F0, P0 = float(tyre["FNOMIN"]), float(tyre["NOMPRES"])
    # a quarter nulls, exactly: one seed of every four consecutive ones (4k .. 4k+3), which one drawn per block
    is_null = seed % 4 == int(np.random.default_rng([21, 4, seed // 4]).integers(4))
    truth: dict = {"is_null": is_null, "null_kind": None, "family": None, "targets": [], "channels": [],
                   "shape": None, "shape_params": {}, "variable": None, "variable_kind": None, "accepted": [],
                   "interaction": None, "size": 0.0, "snr": 0.0, "confounding": [], "tyre": str(
                       tyre_path.relative_to(ROOT))}  # fmt: skip
    family = None if is_null else str(_pick(rng, list(FAMILIES)))
    kind = None if is_null else _choose_kind(rng)
    if family in INPUT_FAMILIES and kind == "direction":
        kind = "run_constant"
    interaction = None
    if not is_null and kind in ("run_constant", "staircase", "drift", "flag") and rng.random() < 0.25:
        interaction = str(_pick(rng, INTERACTIONS))
    need = {"gamma": "gamma", "Vx": "Vx", "P": "P"}.get(interaction or "")
    if kind == "mf_input":
        need = "Vx"
    if family == "camber_offset":
        need = need or "gamma"
    conds, levels = _conditions(rng, tyre, need)
    blocked = bool(rng.random() < 0.6)
    if blocked:
        truth["confounding"].append("load blocks")
    runs = _runs(rng, conds, int(rng.integers(20, 30)), blocked)
    table = _table(rng, runs)
    n = len(table)
    plain = _evaluate(tyre, table)
    by_sweep = table.assign(run=table.sweep)  # the heat models cool in every pause, also between the sweeps of a run

    # the generating variable
    v = _assign_run_values(rng, table, runs, kind, truth) if kind else None
    if kind == "drift":
        which = _pick(rng, ("tread_temp", "wear", "track_temp"))
        if which == "tread_temp":  # follows the friction power with a lag (first-order heat model)
            heat, tau = float(rng.uniform(3e-3, 1.2e-2)), float(rng.uniform(40.0, 200.0))
            v = np.round(thermal_tread_temp(by_sweep, sliding_power(table, plain), ambient=float(rng.uniform(15, 35)),
                                            heat=heat, tau=tau), 2)  # fmt: skip
            truth.update(variable=_pick(rng, ("tread_temp", "TSTC", "surface_temp")), variable_kind="drift",
                         confounding=truth["confounding"] + ["follows friction power"])  # fmt: skip
        elif which == "wear":  # tread worn in proportion to the friction energy (Archard)
            e = np.cumsum(sliding_power(table, plain) * np.diff(table.time.to_numpy(), prepend=0.0))
            v = np.round(float(rng.uniform(6.0, 8.0)) - float(rng.uniform(1.0, 3.0)) * e / e.max(), 4)
            truth.update(variable=_pick(rng, ("tread_depth", "wear_mm")), variable_kind="drift",
                         accepted=["energy", "time"], confounding=truth["confounding"] + ["test order"])  # fmt: skip
        else:  # drifts in time (weather): a trend and a slow swing
            t = table.time.to_numpy()
            v = np.round(float(rng.uniform(10, 30)) + float(rng.uniform(8, 25)) * (t / t.max()) * rng.choice(
                [-1, 1]) + 3.0 * np.sin(2 * np.pi * t / float(rng.uniform(900, 3000))), 2)  # fmt: skip
            truth.update(variable="track_temp", variable_kind="drift",
                         confounding=truth["confounding"] + ["test order"])  # fmt: skip
    elif kind == "mf_input":
        if rng.random() < 0.5:
            v = table.Vx.to_numpy(float)
            truth.update(variable="Vx", variable_kind="mf_input", accepted=["Vx_set"])
        else:
            v = np.abs(table.Vx.to_numpy()) * np.sqrt(table.kappa.to_numpy() ** 2 + np.tan(table.alpha.to_numpy()) ** 2)
            truth.update(variable="Vs", variable_kind="mf_input")
    elif kind == "direction":
        v = table.direction.to_numpy(float)
        truth.update(variable="sweep_dir", variable_kind="direction", accepted=["direction"])
    if truth["variable"]:
        truth["accepted"] = [truth["variable"]] + [a for a in truth["accepted"] if a != truth["variable"]]

    # the law
    g = None
    if not is_null:
        shape = {"flag": "step", "direction": "direction"}.get(kind) or str(_pick(rng, SHAPES))
        z = v if kind in ("flag", "direction") else _scaled(v)
        g, sp = shape_g(shape, z, rng)
        if interaction:
            g = g * _interaction_h(interaction, table, F0, P0)
        g = np.asarray(g, float)
        truth.update(family=family, shape=shape, shape_params=sp, interaction=interaction)
    elif (nk := str(_pick(rng, NULL_KINDS))) == "run_scatter":  # friction scatter no column explains
        scatter = float(rng.uniform(0.01, 0.03))
        g = rng.standard_normal(len(runs))[table.run.to_numpy()] * scatter
        truth.update(null_kind=nk, targets=["LMUX", "LMUY"], size=scatter)
    else:
        truth["null_kind"] = nk

    noise = float(np.exp(rng.uniform(np.log(0.003), np.log(0.012))))
    outlier_fraction = float(_pick(rng, (0.0, 0.005, 0.01, 0.02)))
    true_inputs, clean = None, None
    if is_null:
        clean = plain if g is None else _evaluate(tyre, table, targets=("LMUX", "LMUY"), factor=1.0 + g)
    else:
        # the size as it shows: 2-25 noise sigmas (log-uniform) on the most affected scored channel
        snr_target = float(np.exp(rng.uniform(np.log(2.0), np.log(25.0))))
        u_size, sign = float(rng.uniform()), float(rng.choice([-1.0, 1.0]))

        def size(fam: str) -> float:
            lo, hi = FAMILIES[fam][1]
            s = float(np.exp(np.log(lo) + u_size * (np.log(hi) - np.log(lo))))
            if fam == "curvature":
                return -s  # E <= 1 (Pacejka 2012 eq 4.E14): the curvature is lowered
            return s if shape == "optimum" else sign * s

        def simulate(s: float, fam: str, targets: tuple[str, ...]):
            if fam in INPUT_FAMILIES:
                x = table.copy()
                col = targets[0]
                u = table[col].to_numpy(float)
                x[col] = u * (1.0 + s * g) if col == "P" else u + s * g  # effective pressure; angle offsets
                return _evaluate(tyre, table, inputs=x), x
            factor = 1.0 + s * g
            if set(targets) & POSITIVE:  # friction, stiffness, shape and trail stay positive
                factor = np.maximum(factor, 0.3)
            return _evaluate(tyre, table, targets=targets, factor=factor), None

        def snr_of(c: pd.DataFrame) -> float:
            best = 0.0
            for ch in SCORED:
                rows = _primary(table, ch)
                eff = float(np.sqrt(np.mean((c[ch] - plain[ch]).to_numpy()[rows] ** 2)))
                sig = noise * float(np.max(np.abs(c[ch])))
                if sig > 0:
                    best = max(best, eff / sig)
            return best

        # the drawn family's targets in a random order, then (only if none shows) the other families
        others = [str(f) for f in rng.permutation(list(FAMILIES)) if f != family]
        tries = [(fam, tuple(FAMILIES[fam][0][i])) for fam in [family, *others]
                 for i in rng.permutation(len(FAMILIES[fam][0]))]  # fmt: skip
        if kind == "direction":  # up and down sweeps are lateral: a law in the direction needs Fy or Mz
            tries = [(f, t) for f, t in tries if f not in INPUT_FAMILIES and not all(
                x.endswith("X") or x == "FX_OFFSET" for x in t)]  # fmt: skip
        for fam, targets in tries:  # the first on which the effect shows (a shift the tyre lacks does not)
            s = size(fam)
            cap = 2.0 * FAMILIES[fam][1][1]  # at most 2x the family's largest physical size
            clean, true_inputs = simulate(s, fam, targets)
            snr = snr_of(clean)
            for _ in range(2):  # scaled to the drawn visibility (the effect is not quite linear in s)
                if snr <= 0:
                    break
                s = float(np.clip(s * np.clip(snr_target / snr, 0.05, 20.0), -cap, cap))
                clean, true_inputs = simulate(s, fam, targets)
                snr = snr_of(clean)
            if snr >= 1.5:
                break
        if fam != family:
            truth["family_drawn"] = family
            family = fam
            truth["family"] = fam
        chans = [ch for ch in SCORED if np.max(np.abs((clean[ch] - plain[ch]).to_numpy())) > 1e-9 * (
            1 + np.max(np.abs(plain[ch].to_numpy())))]  # fmt: skip
        s = round(s, 6)
        truth.update(targets=list(targets), size=s, snr=round(snr, 2), channels=chans)
        if fam not in INPUT_FAMILIES and set(targets) & POSITIVE:
            g = (np.maximum(1.0 + s * g, 0.3) - 1.0) / s  # the law as applied (a factor kept positive)
        if family in INPUT_FAMILIES:
            truth["law_expressible"] = (f"input law ({targets[0]} corrected by the generating law): no "
                                        "[MFTIRE_EXTENSIONS] form; ceiling = fit and evaluation with the true inputs")
        else:
            truth["law_expressible"] = ("[MFTIRE_EXTENSIONS] linear term on " + " ".join(targets) +
                                        " in the true g of the generating variable (shape known, size fitted)")

    # the table a user has: rig artefacts, identifiers, variable, decoys
    data, outlier, sigma = rig_artefacts(table, clean, rng, noise=noise, outlier_fraction=outlier_fraction)
    zero, not_measured = [], {}
    for ch, p in (("Mz", 0.12), ("Mx", 0.3), ("My", 0.3)):
        if ch == "Mz" and truth["family"] in ("trail", "residual_torque"):
            continue
        if rng.random() < p:
            how = _pick(rng, ("zeros", "absent", "nan"))
            not_measured[ch] = how
            if how == "zeros":
                data[ch] = 0.0
            elif how == "absent":
                data = data.drop(columns=[ch])
            else:
                data[ch] = np.nan
            zero.append(ch)
    ids = {k: str(_pick(rng, names)) for k, names in ID_NAMES.items()}
    run0, sweep0, row0 = int(rng.integers(1, 400)), int(rng.integers(1, 2000)), int(rng.integers(0, 10000))
    run_ids = table.run.to_numpy() + run0
    per_file = int(rng.integers(4, 10))
    if truth["variable_kind"] == "staircase" and rng.random() < 0.5:  # one file per specimen / level
        file_ids = np.unique(v, return_inverse=True)[1] + 1
        truth["confounding"] = truth["confounding"] + [f"{ids['file']} follows {truth['variable']}"]
    else:
        file_ids = table.run.to_numpy() // per_file + 1
    user = pd.DataFrame({"Fz": data.Fz, "kappa": data.kappa, "alpha": data.alpha, "gamma": data.gamma, "Vx": data.Vx,
                         "P": data.P})  # fmt: skip
    for ch in CHANNELS:
        if ch in data.columns:
            user[ch] = data[ch].to_numpy()
    user["time"] = np.round(table.time.to_numpy(), 3)
    user[ids["run"]] = run_ids
    user[ids["sweep"]] = table.sweep.to_numpy() + sweep0
    user[ids["segment"]] = table.segment.to_numpy()
    user[ids["row"]] = np.arange(n) + row0
    user[ids["file"]] = file_ids
    if truth["variable"] and truth["variable_kind"] not in ("mf_input", "direction"):
        user[truth["variable"]] = v
    decoys = []
    n_decoys = int(rng.integers(1, 4)) + (1 if truth["null_kind"] == "decoys" else 0)
    for name in rng.permutation(DECOYS)[:n_decoys]:
        name = str(name)
        if name in user.columns:
            continue
        t = table.time.to_numpy()
        if name == "ambient_temp":  # drifts with time (and so with blocked loads)
            val = 18.0 + float(rng.uniform(5, 15)) * t / t.max() + rng.normal(0, 0.1, n)
        elif name == "hub_temp":  # follows the load with a lag
            fz = pd.Series(table.Fz_set.to_numpy() / F0).ewm(span=200).mean().to_numpy()
            val = 30.0 + 25.0 * fz + rng.normal(0, 0.2, n)
        elif name == "humidity":  # random per run
            val = rng.uniform(30, 80, len(runs))[table.run.to_numpy()]
        elif name == "rig_oil_temp":  # follows the friction power with a lag, like a temperature would
            val = thermal_tread_temp(by_sweep, sliding_power(table, plain), ambient=35.0, heat=2e-3, tau=400.0)
        else:  # operator: a two-level label per block of runs
            val = ((table.run.to_numpy() // int(rng.integers(3, 8))) % 2).astype(float)
        user[name] = np.round(val, 2)
        decoys.append(name)
    truth.update(holdout_design=None, noise=round(noise, 5), outlier_fraction=outlier_fraction, identifiers=ids,
                 decoys=decoys, not_measured=not_measured, rows=n, runs=len(runs), levels=levels)  # fmt: skip
    if is_null:
        truth["law_expressible"] = "no effect" if g is None else "run scatter: no column holds it"
    hold, design = _holdout(rng, table, runs, v if kind in ("run_constant", "staircase", "flag") else None, truth)
    truth["holdout_design"] = design
    truth["rows_heldout"] = int(hold.sum())
    return ZooDraw(seed, user, hold, outlier, clean, truth["tyre"], perturbed(read_tir(tyre_path), 1000 + seed),
                   truth, g if not is_null or truth["null_kind"] == "run_scatter" else None, true_inputs,
                   tuple(zero), sigma)  # fmt: skip


def _primary(table: pd.DataFrame, ch: str) -> np.ndarray:
    """Rows where ``ch`` is a primary response: Fx with longitudinal slip, Fy and Mz with a slip angle."""
    if ch == "Fx":
        return np.abs(table.kappa.to_numpy(float)) > 0.005
    return np.abs(table.alpha.to_numpy(float)) > math.radians(0.5)


def _holdout(rng, table: pd.DataFrame, runs: list[dict], v: np.ndarray | None, truth: dict) -> tuple[np.ndarray, str]:
    """Held-out rows (whole runs): an unseen level, an unseen combination, new runs or an interior load."""
    run = table.run.to_numpy()
    n_runs = len(runs)
    loads = sorted({r["load"] for r in runs})
    options = ["new_runs"] + (["interior_load"] if len(loads) >= 4 else [])  # 3 loads stay to fit load terms
    if v is not None and len(np.unique(v)) >= 3:
        options += ["unseen_level", "unseen_level"]
    if v is not None:
        options += ["unseen_combination"]
    design = str(_pick(rng, options))
    per_run = None if v is None else pd.Series(v).groupby(run).first().to_numpy()
    if design == "unseen_level":
        lv = np.unique(per_run)
        if len(lv) <= 6:
            held_runs = np.isin(per_run, [lv[int(rng.integers(1, len(lv) - 1))]])
        else:
            q = float(rng.uniform(0.3, 0.55))
            lo, hi = np.quantile(per_run, [q, q + 0.2])
            held_runs = (per_run >= lo) & (per_run <= hi)
    elif design == "unseen_combination":
        L = loads[int(rng.integers(1, len(loads)))]
        lv = np.unique(per_run)
        top = per_run >= (lv[-1] if len(lv) <= 2 else np.median(per_run))
        held_runs = np.array([r["load"] == L for r in runs]) & top
    elif design == "interior_load":
        L = loads[int(rng.integers(1, len(loads) - 1))]
        held_runs = np.array([r["load"] == L for r in runs])
    else:
        k = max(2, int(round(0.2 * n_runs)))
        if rng.random() < 0.5:
            held_runs = np.isin(np.arange(n_runs), rng.choice(n_runs, k, replace=False))
            design = "new_runs (scattered)"
        else:
            held_runs = np.arange(n_runs) >= n_runs - k
            design = "new_runs (last of the programme)"
    if design != "interior_load":  # every MF operating condition stays in training (the effect is tested)
        cond = [(r["load"], r["gamma"], r["Vx"], r["P"]) for r in runs]
        for i in np.flatnonzero(held_runs):
            if not any(cond[j] == cond[i] and not held_runs[j] for j in range(n_runs)):
                held_runs[i] = False
    if held_runs.sum() == 0 or held_runs.sum() >= n_runs - 2:  # fall back: new runs, scattered
        held_runs = np.isin(np.arange(n_runs), rng.choice(n_runs, max(2, n_runs // 5), replace=False))
        design = "new_runs (scattered)"
    return held_runs[run], design


# --------------------------------------------------------------------------------------------
# scoring


def channel_rms(y: np.ndarray, model: np.ndarray, rows: np.ndarray) -> float:
    r = (y - model)[rows]
    return float(np.sqrt(np.mean(r * r))) if rows.any() else float("nan")


def _frame_inputs(df: pd.DataFrame) -> pd.DataFrame:
    return df.drop(columns=[c for c in CHANNELS if c in df.columns])


def _fit(train: pd.DataFrame, start: TirParameters) -> TirParameters:
    from mftire.fitting import fit_tir

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fit_tir(train, start, progress=False).parameters


def _ceiling_model(d: ZooDraw, train_rows: np.ndarray) -> tuple[Tyre, pd.DataFrame]:
    """The refit of the training rows with the generating law, and the inputs to evaluate it at.

    Started from the generating tyre (the plain file and the law's true size), so that the refit finds the
    best the law's form reaches rather than a local minimum of the base fit; every MF coefficient and the
    law's size are refitted.  A scaling or offset law is an ``[MFTIRE_EXTENSIONS]`` ``linear`` term in the
    true per-row shape g (z = g·|s|, C1 = ±1 at the start, so the fitter's bounds on C1 allow up to twice the
    true size); an input law is the fit and evaluation with the true inputs."""
    t = d.truth
    fit_data = d.data.copy()
    for ch in d.zero_channels:
        if ch in fit_data.columns:
            fit_data = fit_data.drop(columns=[ch])
    params = read_tir(ROOT / d.tyre_file)
    if t["family"] in INPUT_FAMILIES:
        col = t["targets"][0]
        fit_data[col] = d.true_inputs[col].to_numpy()
    else:
        size = float(t["size"])
        for k, v in {"EXT1_TARGET": " ".join(t["targets"]), "EXT1_FORM": "linear", "EXT1_VARIABLE": "zoo_g",
                     "EXT1_REF": 0.0, "EXT1_SCALE": 1.0 / max(abs(size), 1e-9),
                     "EXT1_C1": 1.0 if size >= 0 else -1.0}.items():  # fmt: skip
            params.set(k, v, section=SECTION)
        fit_data["zoo_g"] = d.law_g
    tyre = Tyre(_fit(fit_data[train_rows], params))
    return tyre, fit_data


def _derived_for_eval(d: ZooDraw) -> pd.DataFrame:
    """The campaign with the quantities the diagnosis derives (sweep labels, slip speed, direction, ...),
    so that an extension in any of them can be evaluated on the held-out rows."""
    from mftire.diagnosis.candidates import derived_candidates, with_sweeps

    full = with_sweeps(d.data.reset_index(drop=True))
    for k, val in derived_candidates(full).items():
        if k not in full.columns:
            full[k] = val
    return full


#: An effect draw whose law shape g is this well explained by the set-point cells of the training rows (R²: it is
#: constant within every cell to a per cent of its variance) is aliased with the test conditions there: the
#: training data cannot tell the effect from a load or speed effect.
ALIASED_R2 = 0.99


def aliased_r2(d: ZooDraw) -> float:
    """R² of the generating law's shape g over the training rows explained by their set-point cells (each row at
    its nearest programme load, speed, pressure and camber): 1 when the effect is constant in every cell, so that
    the training data cannot tell it from a function of the set points (NaN for a null or an MF-input variable,
    which is a set point itself and which a law reads directly).  The oracle ceiling (:func:`_ceiling_model`)
    starts at the true law and keeps it on such a draw, so its ceiling says nothing of what the data identify."""
    t = d.truth
    if t["is_null"] or d.law_g is None or t["variable_kind"] == "mf_input":
        return float("nan")
    train = ~d.holdout
    g = np.asarray(d.law_g, float)[train]
    rows = d.data[train]
    cells = []
    for col, key in (("Fz", "loads"), ("Vx", "speeds"), ("P", "pressures"), ("gamma", "gammas")):
        levels = np.asarray(t["levels"].get(key) or [0.0], float)
        x = rows[col].to_numpy(float)
        cells.append(np.argmin(np.abs(x[:, None] - levels[None, :]), axis=1))
    _, cell = np.unique(np.column_stack(cells), axis=0, return_inverse=True)
    var = float(np.var(g))
    if not var > 0:
        return 1.0
    means = np.bincount(cell.ravel(), weights=g) / np.bincount(cell.ravel())
    return 1.0 - float(np.mean((g - means[cell.ravel()]) ** 2)) / var


def score_heldout(held: pd.DataFrame, before: pd.DataFrame, after: pd.DataFrame | None, truth: pd.DataFrame,
                  ceiling: pd.DataFrame | None, channels: list[str]) -> dict:
    """Held-out scores of the measured rows ``held`` (outliers already excluded) for the models ``before``
    (the base fit), ``after`` (the diagnosed model; None: it could not be evaluated), ``truth`` (noise-free)
    and ``ceiling``: per channel the RMS on its primary rows and the relative change after/before; pooled
    over the channels (each RMS normalised by the channel's held-out peak) the cut, the best cut (truth)
    and the ceiling cut; the worst change and whether it is a violation (> ``WORSE``)."""
    rec: dict = {}
    ssb = ssa = ssc = sst = 0.0
    worst = 0.0
    for ch in channels:
        rows = _primary(held, ch) & np.isfinite(held[ch].to_numpy(float))
        if rows.sum() < 5:
            continue
        y = held[ch].to_numpy(float)
        peak = float(np.max(np.abs(y[rows])))
        rb = channel_rms(y, before[ch].to_numpy(), rows)
        ra = channel_rms(y, after[ch].to_numpy(), rows) if after is not None else float("inf")
        rt = channel_rms(y, truth[ch].to_numpy(), rows)
        rec[f"rms_{ch}_before"], rec[f"rms_{ch}_after"], rec[f"rms_{ch}_truth"] = rb, ra, rt
        rec[f"change_{ch}"] = ra / rb - 1.0 if rb > 0 else 0.0
        worst = max(worst, rec[f"change_{ch}"])
        ssb += (rb / peak) ** 2
        ssa += (ra / peak) ** 2
        sst += (rt / peak) ** 2
        if ceiling is not None:
            rc = channel_rms(y, ceiling[ch].to_numpy(), rows)
            rec[f"rms_{ch}_ceiling"] = rc
            ssc += (rc / peak) ** 2
    rec["scored"] = " ".join(ch for ch in channels if f"rms_{ch}_before" in rec)
    rec["cut"] = 1.0 - math.sqrt(ssa / ssb) if ssb > 0 else float("nan")
    rec["best_cut"] = 1.0 - math.sqrt(sst / ssb) if ssb > 0 else float("nan")
    rec["ceiling_cut"] = (1.0 - math.sqrt(ssc / ssb)) if (ssb > 0 and ceiling is not None) else float("nan")
    rec["worst_change"] = worst
    rec["violation"] = bool(worst > WORSE - 1.0)
    return rec


def evaluate_draw(seed: int, n_perm: int = 99) -> dict:
    """Fit, diagnose and score draw ``seed``; one flat record."""
    from mftire.diagnosis.diagnose import diagnose

    t_start = time.perf_counter()
    d = draw(seed)
    t = d.truth
    rec: dict = {"seed": seed, "is_null": t["is_null"], "null_kind": t["null_kind"], "family": t["family"],
                 "targets": " ".join(t["targets"]), "shape": t["shape"], "variable": t["variable"],
                 "variable_kind": t["variable_kind"], "interaction": t["interaction"], "size": t["size"],
                 "snr": t["snr"], "confounding": "; ".join(t["confounding"]), "holdout_design": t["holdout_design"],
                 "noise": t["noise"], "outliers": t["outlier_fraction"], "rows": t["rows"],
                 "not_measured": " ".join(f"{k}:{v}" for k, v in t["not_measured"].items()), "tyre": t["tyre"],
                 "accepted": " ".join(t["accepted"]), "identifiers": " ".join(t["identifiers"].values())}  # fmt: skip
    rec["aliased_r2"] = aliased_r2(d)
    train_rows = ~d.holdout
    fit_data = d.data.drop(columns=[c for c in d.zero_channels if c in d.data.columns])
    base_params = _fit(fit_data[train_rows], d.start)
    base = Tyre(base_params)
    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = diagnose(d.train, base, n_perm=n_perm, seed=0, progress=False)
        err = None
    except Exception as exc:  # a crash is a result of the judge, not of the zoo
        res, err = None, f"{type(exc).__name__}: {exc}"
    rec["diagnose_s"] = round(time.perf_counter() - t0, 2)
    rec["error"] = err
    top = res.ranking[0] if res is not None and res.ranking else None
    rec["found_first"] = None if top is None else top.variable
    rec["top_significant"] = bool(top is not None and top.significant)
    rec["top_p"] = None if top is None else float(top.p_value)  # the ranking's permutation p-value of its first
    rec["significant"] = bool(res is not None and res.significant)
    # the cause the diagnosis names: the first of the ranking when it reports an effect, or the cause it
    # names without a law (``DiagnosisResult.cause`` where the method has it: "cause named, no law found")
    rec["cause"] = rec["found_first"] if rec["significant"] else getattr(res, "cause", None)
    finding = bool(res is not None and (res.significant or res.extended is not None or rec["cause"] is not None))
    rec["finding"] = finding  # an effect or a cause reported (on a null: a false finding)
    rec["law"], rec["law_ratio"] = None, None
    # the diagnosis's first message (why no law, or the law's own first note), for reading a run's failures
    msgs = [] if res is None else (res.significant and res.effect is not None and res.effect.messages) or res.messages
    rec["message"] = msgs[0][:400] if msgs else None
    if res is not None and res.effect is not None and res.extended is not None:
        e = res.effect
        rec["law"] = f"{' '.join(e.targets) or e.name} x {e.name} in {e.variable}"
        rec["law_ratio"] = float(e.heldout)  # its held-out-fold error over the control's (the selection's measure)
    rec["cause_named"] = bool(not t["is_null"] and rec["cause"] in t["accepted"])

    held = d.holdout & ~d.outlier
    hdf = d.data[held]
    before = base.evaluate_frame(_frame_inputs(hdf))
    after, rec["eval_error"] = before, None
    if finding and res.extended is not None:
        try:
            full = _derived_for_eval(d)
            need = [c for c in res.extended.required_variables if c not in hdf.columns]
            x = _frame_inputs(hdf).assign(**{c: full.loc[held, c].to_numpy() for c in need})
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                after = res.extended.evaluate_frame(x)
        except Exception as exc:
            rec["eval_error"] = f"{type(exc).__name__}: {exc}"
            after = None
    ceil_tyre, ceiling = None, None
    if not t["is_null"]:
        ceil_tyre, ceil_data = _ceiling_model(d, train_rows)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ceiling = ceil_tyre.evaluate_frame(_frame_inputs(ceil_data[held]))
    rec.update(score_heldout(hdf, before, after, d.clean[held], ceiling,
                             [ch for ch in SCORED if ch in hdf.columns and ch not in d.zero_channels]))
    rec["total_s"] = round(time.perf_counter() - t_start, 2)
    return rec


# --------------------------------------------------------------------------------------------
# the table


def headline(df: pd.DataFrame) -> dict:
    """The four rates of issue 21's "Done when" from per-draw records."""
    eff = df[~df.is_null.astype(bool)]
    nul = df[df.is_null.astype(bool)]
    ceil = eff[eff.ceiling_cut >= CEILING_MIN]
    return {
        "draws": len(df), "effect_draws": len(eff), "null_draws": len(nul),
        "cause_named_first": float(eff.cause_named.astype(bool).mean()) if len(eff) else float("nan"),
        "ceiling_draws": len(ceil),
        "cut_ge_50_where_ceiling_ge_70": float((ceil.cut >= CUT_MIN).mean()) if len(ceil) else float("nan"),
        "violations": int(df.violation.astype(bool).sum()),
        "false_findings_on_nulls": float(nul.finding.astype(bool).mean()) if len(nul) else float("nan"),
    }  # fmt: skip


def _pct(x: float) -> str:
    return "-" if x != x else f"{100 * x:.0f} %"


def table_markdown(df: pd.DataFrame, command: str) -> str:
    h = headline(df)
    commits = ", ".join(sorted(df["commit"].astype(str).unique())) if "commit" in df else "not recorded"
    days = ", ".join(sorted(df["date"].astype(str).unique())) if "date" in df else "date not recorded"
    lines = [MARK_BEGIN, "", f"Measured with `{command}` ({h['draws']} draws: {h['effect_draws']} with an effect, "
             f"{h['null_draws']} nulls; the diagnosis of commit {commits}; {days}; per-draw "
             "results in `validation/effect_zoo_results.csv`).", "",
             "| headline (issue 21 target) | measured |", "|---|---:|",
             f"| right cause named first (≥ 95 % of effect draws) | {_pct(h['cause_named_first'])} |",
             f"| held-out cut ≥ 50 % where the ceiling is ≥ 70 % (≥ 85 %; {h['ceiling_draws']} draws) | "
             f"{_pct(h['cut_ge_50_where_ceiling_ge_70'])} |",
             f"| draws with a scored channel > 5 % worse held out (0) | {h['violations']} |",
             f"| false findings on nulls (≤ 2 %) | {_pct(h['false_findings_on_nulls'])} |", "",
             "| family | draws | cause first | ceiling ≥ 70 % | cut ≥ 50 % of those | median cut | median ceiling | "
             "worse > 5 % | finding |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]  # fmt: skip
    df = df.assign(group=np.where(df.is_null.astype(bool), "null: " + df.null_kind.astype(str), df.family.astype(str)))
    for name, g in sorted(df.groupby("group"), key=lambda kv: (kv[0].startswith("null"), kv[0])):
        null = name.startswith("null")
        c = g[g.ceiling_cut >= CEILING_MIN]
        lines.append(f"| {name} | {len(g)} | {'-' if null else _pct(g.cause_named.astype(bool).mean())} | "
                     f"{'-' if null else len(c)} | {_pct((c.cut >= CUT_MIN).mean()) if len(c) else '-'} | "
                     f"{_pct(g.cut.median())} | {'-' if null else _pct(g.ceiling_cut.median())} | "
                     f"{int(g.violation.astype(bool).sum())} | {int(g.finding.astype(bool).sum())} |")  # fmt: skip
    eff = df[~df.is_null.astype(bool)]
    if "aliased_r2" not in eff:  # results written before the column: computed from the draws
        eff = eff.assign(aliased_r2=[aliased_r2(draw(int(x))) for x in eff.seed])
    alias = eff.aliased_r2.to_numpy(float) >= ALIASED_R2
    breakdowns = [(f" by {title}", sorted(eff.groupby(eff[key].astype(str).str.split(" ").str[0])))
                  for key, title in (("variable_kind", "variable kind"), ("holdout_design", "held-out design"))]
    breakdowns.append((", by what the training rows identify",
                       [(f"aliased with the set points (R² ≥ {ALIASED_R2})", eff[alias]), ("the others", eff[~alias])]))
    for title, groups in breakdowns:
        lines += ["", f"| effect draws{title} | draws | cause first | ceiling ≥ 70 % | cut ≥ 50 % of those | "
                  "worse > 5 % |", "|---|---:|---:|---:|---:|---:|"]  # fmt: skip
        for name, g in groups:
            c = g[g.ceiling_cut >= CEILING_MIN]
            cut = _pct((c.cut >= CUT_MIN).mean()) if len(c) else "-"
            lines.append(f"| {name} | {len(g)} | {_pct(g.cause_named.astype(bool).mean()) if len(g) else '-'} | "
                         f"{len(c)} | {cut} | {int(g.violation.astype(bool).sum())} |")
    lines += [""]
    if "identifiers" in df:
        ids = [set(str(x).split()) for x in df.identifiers]
        in_id = [str(c) in i for c, i in zip(df.get("cause", df.found_first), ids, strict=True)]
        law_id = [isinstance(law, str) and law.split(" in ")[-1] in i for law, i in zip(df.law, ids, strict=True)]
        lines.append(f"- A cause named in an identifier column (run, sweep, segment, row, file number): {sum(in_id)} "
                     f"draws; a law in one: {sum(law_id)}.")
    bad = df[df.violation.astype(bool)].sort_values("worst_change", ascending=False)
    if len(bad):
        worst = "; ".join(f"seed {int(r.seed)} {r.group}: {r.law} ({100 * r.worst_change:+.0f} %)"
                          for r in bad.head(8).itertuples())  # fmt: skip
        lines.append(f"- Worst held-out changes: {worst}.")
    if "error" in df and df.error.notna().any():
        e = df[df.error.notna()]
        lines.append(f"- The diagnosis raised an error on {len(e)} draw(s): "
                     + "; ".join(f"seed {int(r.seed)}: {str(r.error)[:60]}" for r in e.head(5).itertuples()) + ".")
    if "diagnose_s" in df:
        lines.append(f"- Time: diagnosis median {df.diagnose_s.median():.1f} s, max {df.diagnose_s.max():.0f} s; a "
                     f"whole draw (two fits, the diagnosis, scoring) {df.total_s.sum() / 60:.0f} min in all (wall "
                     "time, one process).")
    lines += ["", MARK_END]
    return "\n".join(lines)


def write_readme_table(df: pd.DataFrame, command: str, readme: Path = README) -> None:
    from mftire.iotools.atomic import write_text_atomic

    text = readme.read_text()
    block = table_markdown(df, command)
    if MARK_BEGIN in text and MARK_END in text:
        head, rest = text.split(MARK_BEGIN, 1)
        tail = rest.split(MARK_END, 1)[1]
        text = head + block + tail
    else:
        text = text.rstrip("\n") + "\n\n## Effect zoo (issue 21)\n\n" + block + "\n"
    write_text_atomic(readme, text)


def _worker(args: tuple[int, int]) -> dict:
    import os

    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    seed, n_perm = args
    try:
        with warnings.catch_warnings():  # the models' range warnings (clipped E, ...) are not the zoo's output
            warnings.simplefilter("ignore")
            return evaluate_draw(seed, n_perm)
    except Exception as exc:  # the zoo itself failed: report, do not stop the run
        return {"seed": seed, "zoo_error": f"{type(exc).__name__}: {exc}"}


def _commit() -> str:
    """The repository's commit (short hash, ``+dirty`` with uncommitted changes to mftire/): the method judged."""
    import subprocess

    def git(*a: str) -> str:
        return subprocess.run(["git", "-C", str(ROOT), *a], capture_output=True, text=True).stdout.strip()

    head = git("rev-parse", "--short", "HEAD") or "unknown"
    return head + ("+dirty" if git("status", "--porcelain", "--", "mftire") else "")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0, help="first seed (draws seed .. seed + draws - 1)")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--n-perm", type=int, default=99, help="permutations of the diagnosis' ranking test")
    ap.add_argument("--out", type=Path, default=RESULTS)
    ap.add_argument("--no-readme", action="store_true", help="do not write the table into validation/README.md")
    ap.add_argument("--table-only", action="store_true", help="rewrite the README table from --out")
    args = ap.parse_args(argv)
    command = f"python validation/effect_zoo.py --draws {args.draws}" + (f" --seed {args.seed}" if args.seed else "")
    if args.table_only:
        df = pd.read_csv(args.out)
        print(table_markdown(df, command))
        if not args.no_readme:
            write_readme_table(df, command)
        return 0
    seeds = [(s, args.n_perm) for s in range(args.seed, args.seed + args.draws)]
    records = []
    commit, day = _commit(), time.strftime("%Y-%m-%d")
    from mftire.iotools.atomic import atomic_path

    def save():
        df = pd.DataFrame(records).sort_values("seed")
        with atomic_path(args.out) as tmp:
            df.to_csv(tmp, index=False, float_format="%.5g")
        return df

    if args.jobs > 1:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(args.jobs) as pool:
            it = pool.map(_worker, seeds)
            for rec in it:
                records.append({**rec, "commit": commit, "date": day})
                _print_rec(rec)
                save()
    else:
        for s in seeds:
            rec = {**_worker(s), "commit": commit, "date": day}
            records.append(rec)
            _print_rec(rec)
            save()
    df = save()
    ok = df[df.get("zoo_error", pd.Series(index=df.index, dtype=object)).isna()] if "zoo_error" in df else df
    print(table_markdown(ok, command))
    print(json.dumps(headline(ok), indent=1))
    if not args.no_readme:
        write_readme_table(ok, command)
    return 0


def _print_rec(rec: dict) -> None:
    if "zoo_error" in rec:
        print(f"seed {rec['seed']}: ZOO ERROR {rec['zoo_error']}", flush=True)
        return
    what = f"null/{rec['null_kind']}" if rec["is_null"] else f"{rec['family']}/{rec['shape']} in {rec['variable']}"
    print(f"seed {rec['seed']:4d} {what:45s} found {str(rec['found_first']):14s} named={rec['cause_named']!s:5} "
          f"law={rec['law']} cut {_pct(rec['cut'])} ceiling {_pct(rec['ceiling_cut'])} "
          f"worst {rec['worst_change']:+.2f} "
          f"({rec['total_s']:.0f} s){' ERR ' + rec['error'] if rec['error'] else ''}", flush=True)


if __name__ == "__main__":
    sys.exit(main())
