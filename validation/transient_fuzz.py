"""Fuzz of the transient tyre FMU (issue 23): non-finite and absurd inputs never reach a state.

One instance of the transient FMU (FMI 2.0) in Co-Simulation and one in Model Exchange are driven
through ``n`` random input vectors each.  Each of the eight inputs is NaN, ±Inf, ±0, huge, tiny,
subnormal, a log-uniform magnitude of either sign (25 % / 20 %), or a value in the usual range (55 %);
``useMode`` cycles through all twelve modes.

* Co-Simulation: ``setReal`` of the inputs, ``doStep`` (step 0.1-10 ms), ``getReal`` of every output
  and of the states u, v.  Afterwards the instance runs a clean manoeuvre (1 s, combined slip) and its
  outputs are compared with those of a fresh instance running the same manoeuvre.
* Model Exchange: inputs and random finite states (|x| up to 10 m) set, ``getDerivatives`` and every
  output read.  Afterwards clean inputs and states: outputs and derivatives equal a fresh instance's.

Counted: vectors with any non-finite output, state or derivative (must be 0), the largest difference
after the fuzz, and the guard warnings logged.  Run::

    python validation/transient_fuzz.py [--n 100000] [--tir FILE] [--thermal]

``--thermal``: the transient FMU of a thermal ``.tir`` (``validation/thermal_block.py``'s, or ``--tir`` with a
``[MFTIRE_THERMAL]`` section): the inputs ``T_ambient``, ``T_road`` are fuzzed too, Model Exchange sets the three
node temperatures to random finite values (-100..300 °C) as well.  In Co-Simulation the node temperatures
remember the fuzz (minutes of thermal time constants), so there the check is that every output, state and
derivative stays finite, not the equality with a fresh instance.

(the test suite runs a reduced count: tests/test_transient_guards.py).
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_TIR = ROOT / "tests" / "data" / "tir" / "MagicFormula61_Parameters.tir"
NAMES = ("Fz", "Vx", "Vy", "omega", "gamma", "P", "muRoad", "yawRate")
THERMAL_NAMES = ("T_ambient", "T_road")
SPECIAL = np.array([np.nan, np.inf, -np.inf, 0.0, -0.0, 1e300, -1e300, 1e-300, -1e-300, 5e-324, 1e308, -1e308])
USUAL = {"Fz": (0.0, 12000.0), "Vx": (-5.0, 60.0), "Vy": (-5.0, 5.0), "omega": (-50.0, 200.0),
         "gamma": (-0.2, 0.2), "P": (1e5, 4e5), "muRoad": (0.2, 1.5), "yawRate": (-1.0, 1.0),
         "T_ambient": (-20.0, 50.0), "T_road": (-20.0, 70.0)}  # fmt: skip
MODES = (111, 112, 110, 121, 122, 120, 211, 212, 210, 221, 222, 220)


def fuzz_vectors(n: int, seed: int, names=NAMES) -> np.ndarray:
    """``n`` x len(names) inputs: 25 % special values, 20 % log-uniform magnitudes, 55 % usual range."""
    rng = np.random.default_rng(seed)
    out = np.empty((n, len(names)))
    for j, name in enumerate(names):
        lo, hi = USUAL[name]
        usual = rng.uniform(lo, hi, n)
        logmag = rng.choice([-1.0, 1.0], n) * 10.0 ** rng.uniform(-12, 12, n)
        special = rng.choice(SPECIAL, n)
        pick = rng.uniform(size=n)
        out[:, j] = np.where(pick < 0.25, special, np.where(pick < 0.45, logmag, usual))
    return out


class Instance:
    """One transient FMU instance through fmpy (``CS`` or ``ME``), messages collected."""

    def __init__(self, fmu: str | Path, interface: str) -> None:
        import fmpy
        from fmpy.fmi2 import FMU2Model, FMU2Slave

        from mftire.fmu.host import make_callbacks

        md = fmpy.read_model_description(str(fmu))
        self.unzip = fmpy.extract(str(fmu))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.outputs = [v.name for v in md.modelVariables if v.causality == "output"]
        self.messages: list = []
        cls, ident = (FMU2Slave, md.coSimulation) if interface == "CS" else (FMU2Model, md.modelExchange)
        self.f = cls(guid=md.guid, unzipDirectory=self.unzip, modelIdentifier=ident.modelIdentifier,
                     instanceName="fuzz")  # fmt: skip
        self.f.instantiate(callbacks=make_callbacks(self.messages))
        self.f.setupExperiment(startTime=0.0)
        self.f.enterInitializationMode()
        self.f.exitInitializationMode()
        if interface == "ME":
            self.f.enterContinuousTimeMode()
        self.interface = interface
        self.t = 0.0
        self.thermal = "T_ambient" in self.vr
        self.names = NAMES + THERMAL_NAMES if self.thermal else NAMES
        self.states = ("u", "v", "T_s", "T_b", "T_g") if self.thermal else ("u", "v")
        self.in_vrs = [self.vr[k] for k in self.names]
        self.out_vrs = [self.vr[k] for k in self.outputs] + [self.vr[k] for k in self.states]

    def step(self, inputs, h: float) -> np.ndarray:
        """CS: set the inputs, one doStep of h, the outputs and states."""
        self.f.setReal(self.in_vrs, list(inputs))
        self.f.doStep(currentCommunicationPoint=self.t, communicationStepSize=h)
        self.t += h
        return np.asarray(self.f.getReal(self.out_vrs))

    def probe(self, inputs, x) -> np.ndarray:
        """ME: set the inputs and states, the outputs and the derivatives."""
        self.f.setReal(self.in_vrs, list(inputs))
        import ctypes

        n = len(self.states)
        self.f.setContinuousStates((ctypes.c_double * n)(*map(float, x)), n)
        dx = (ctypes.c_double * n)()
        self.f.getDerivatives(dx, n)
        dx = np.asarray(dx[:])
        return np.concatenate([np.asarray(self.f.getReal(self.out_vrs)), dx])

    def close(self) -> None:
        self.f.terminate()
        self.f.freeInstance()
        shutil.rmtree(self.unzip, ignore_errors=True)


def clean_manoeuvre(n: int = 1000, thermal: bool = False) -> np.ndarray:
    """1 s at 1 ms of combined slip at 20 m/s (inputs in NAMES order; ``thermal``: then 22 °C ambient, 30 °C
    road)."""
    t = np.arange(n) * 1e-3
    Vx = 20.0 + 0.0 * t
    cols = [4000.0 + 500.0 * np.sin(8 * t), Vx, 0.6 * np.sin(5 * t), 1.05 * Vx / 0.31, 0.02 + 0.0 * t,
            2.2e5 + 0.0 * t, 0.9 + 0.0 * t, 0.1 * np.cos(3 * t)]  # fmt: skip
    if thermal:
        cols += [22.0 + 0.0 * t, 30.0 + 0.0 * t]
    return np.column_stack(cols)


def fuzz(fmu: str | Path, interface: str, n: int, seed: int = 23) -> dict:
    """Drive one instance through ``n`` vectors; returns the counts and the difference after the fuzz."""
    rng = np.random.default_rng(seed + 1)
    ins = Instance(fmu, interface)
    x = fuzz_vectors(n, seed, ins.names)
    bad = []
    block = n // len(MODES) + 1
    try:
        for i in range(n):
            if i % block == 0:
                ins.f.setInteger([ins.vr["useMode"]], [MODES[i // block]])
            if interface == "CS":
                y = ins.step(x[i], float(10.0 ** rng.uniform(-4, -2)))
            else:
                xs = rng.choice([-1.0, 1.0], 2) * 10.0 ** rng.uniform(-9, 1, 2)
                if ins.thermal:
                    xs = np.concatenate([xs, rng.uniform(-100.0, 300.0, 3)])  # node temperatures [degC]
                y = ins.probe(x[i], xs)
            if not np.isfinite(y).all():
                bad.append((i, x[i].tolist(), [ins.outputs[j] if j < len(ins.outputs) else j
                                               for j in np.flatnonzero(~np.isfinite(y))]))  # fmt: skip
        ins.f.setInteger([ins.vr["useMode"]], [111])
        # CS thermal: the node temperatures remember the fuzz (module docstring): finite outputs only
        diff = None if ins.thermal and interface == "CS" else after_fuzz_difference(fmu, ins)
        warnings = sum("not finite or out of range" in m for _, _, m in ins.messages)
        errors = sum(s >= 3 for s, _, _ in ins.messages)
    finally:
        ins.close()
    return {"interface": interface, "n": n, "bad": bad, "diff": diff, "guard_warnings": warnings, "errors": errors}


def after_fuzz_difference(fmu, ins: Instance) -> float:
    """Largest relative difference of every output between the fuzzed instance and a fresh one."""
    fresh = Instance(fmu, ins.interface)
    try:
        m = clean_manoeuvre(thermal=ins.thermal)
        worst = 0.0
        for k, u in enumerate(m):
            if ins.interface == "CS":
                a, b = ins.step(u, 1e-3), fresh.step(u, 1e-3)
                if k < len(m) - 100:
                    continue  # the fuzzed states are forgotten after ~60 relaxation lengths
            else:
                xs = (1e-3 * np.sin(k), 2e-3 * np.cos(k), *((45.0, 38.0, 30.0) if ins.thermal else ()))
                a, b = ins.probe(u, xs), fresh.probe(u, xs)
            worst = max(worst, float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1.0))))
        return worst
    finally:
        fresh.close()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100_000, help="vectors per interface")
    ap.add_argument("--tir", type=Path)
    ap.add_argument("--thermal", action="store_true", help="the thermal block (validation/thermal_block.py's .tir "
                    "unless --tir is given)")  # fmt: skip
    a = ap.parse_args(argv)
    from mftire.fmu.export import export_fmu

    tir = a.tir or DEFAULT_TIR
    if a.thermal and a.tir is None:
        import sys

        sys.path.insert(0, str(ROOT / "validation"))
        from thermal_block import thermal_tir

        tir = thermal_tir()
    with tempfile.TemporaryDirectory() as tmp:
        fmu = export_fmu(tir, Path(tmp) / "fuzz.fmu", transient=True)
        ok = True
        for interface in ("CS", "ME"):
            r = fuzz(fmu, interface, a.n)
            after = "not compared (thermal CS)" if r["diff"] is None else f"{r['diff']:.3g}"
            print(f"{interface}: {r['n']} vectors, {len(r['bad'])} with a non-finite output/state/derivative, "
                  f"{r['guard_warnings']} guard warnings logged, {r['errors']} errors; largest relative difference "
                  f"to a clean run after the fuzz {after}")  # fmt: skip
            ok &= not r["bad"] and (r["diff"] is None or r["diff"] <= 1e-12) and r["errors"] == 0
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
