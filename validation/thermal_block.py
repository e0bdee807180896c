"""The thermal block of the transient FMU against ``mftire.transient.simulate(..., thermal=True)`` (issue 22).

The shipped thermal ``.tir`` (``validation/data/thermal/thermal_tyre.tir``, the ``mftire fit-thermal`` result
of the shipped run: a grip law on the surface node, a stiffness law on the bulk node; :func:`shipped_tir`) is
exported with ``mftire export-fmu --transient`` (FMI 2 and FMI 3) and driven along a stint of the shipped thermal
run (``mftire.data.thermal_run()``: its load, speed, slip angle, slip ratio, camber, ambient and road
temperature, as wheel kinematics ``Vy = Vx·tan(alpha)``, ``omega = Vx·(1 + kappa)/R0``):

* **Model Exchange**: the FMU's derivatives (``fmi2GetDerivatives`` / ``fmi3GetContinuousStateDerivatives``
  through fmpy) integrated by the same integrator and tolerances as :func:`mftire.transient.simulate` (LSODA):
  the largest difference of the node temperatures, the pressure and the forces over the stint, relative to the
  channel's largest magnitude;
* **Co-Simulation**: ``doStep`` at 1 ms against its Python mirror (:class:`mftire.transient.TransientStepper`).

``python validation/thermal_block.py [SECONDS]`` runs it on the first SECONDS (default 60) of the held-out
stint (ET > 470 s) and prints the differences; ``tests/test_thermal_block.py`` runs a reduced case.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # run from a source checkout
TIR = ROOT / "tirfiles" / "MF61_255-55R20_mfeval-jl.tir"
RUN = ROOT / "validation" / "data" / "thermal" / "thermal_run.dat.gz"  #: where the run was before mftire.data
SHIPPED_TIR = ROOT / "validation" / "data" / "thermal" / "thermal_tyre.tir"
#: Channels compared.
CHANNELS = ("T_surface", "T_bulk", "T_gas", "P_hot", "Fx", "Fy", "Mz")
#: Initial node temperatures of the comparisons [°C] (a tyre already warm).
T0 = (45.0, 38.0, 30.0)


def thermal_tir():
    """The test's thermal tyre: a quadratic grip law (LMUX, LMUY) on the surface node and a linear stiffness
    law (LKX, LKY) on the bulk node, the default thermal parameters with a light surface layer."""
    from mftire.iotools.tir import read_tir
    from mftire.mf.thermal_section import SECTION, ThermalParameters
    from mftire.thermal.thermal_fit import with_default_laws
    from mftire.tyre import Tyre

    tp = with_default_laws(read_tir(TIR), 60.0)
    tp.sections["MFTIRE_EXTENSIONS"].update({"EXT1_C1": -0.1, "EXT1_C2": -0.05, "EXT2_C1": -0.05})
    tp.sections[SECTION] = ThermalParameters(nodes={1: "surface", 2: "bulk"}, cap_surface=800.0,
                                             cap_gas=60.0).section()  # fmt: skip
    return Tyre(tp, name="thermal.tir")


def shipped_tir():
    """The shipped thermal ``.tir`` (``mftire fit-thermal`` of the shipped run), else :func:`thermal_tir`."""
    from mftire.tyre import load

    return load(SHIPPED_TIR) if SHIPPED_TIR.is_file() else thermal_tir()


def stint(start: float = 470.0, seconds: float = 60.0) -> dict[str, np.ndarray]:
    """Wheel kinematics and conditions along ``seconds`` of the shipped run from ET = ``start`` (10 Hz),
    time from 0."""
    df = _read_run()
    df = df[(df["ET"] >= start) & (df["ET"] <= start + seconds)].reset_index(drop=True)
    t = df["ET"].to_numpy(float) - float(df["ET"].iloc[0])
    Vx = df["Vx"].to_numpy(float)
    R0 = 0.3499  # about UNLOADED_RADIUS of the file: omega of the run's slip ratio (a kinematic input)
    return {"t": t, "Fz": df["Fz"].to_numpy(float), "Vx": Vx, "Vy": Vx * np.tan(df["alpha"].to_numpy(float)),
            "omega": Vx * (1.0 + df["kappa"].to_numpy(float)) / R0, "gamma": df["gamma"].to_numpy(float),
            "T_ambient": df["AMBTMP"].to_numpy(float), "T_road": df["RST"].to_numpy(float)}  # fmt: skip


def _read_run():
    """The shipped thermal run (``mftire.data.thermal_run()`` where the package ships it, else the file of
    ``validation/data/thermal/``)."""
    from mftire.iotools.rig import read_ttc

    try:
        from mftire.data import thermal_run
    except ImportError:
        return read_ttc(RUN)
    return read_ttc(thermal_run())


def _instance(fmu_path, kind: str):
    import fmpy
    from fmpy.fmi2 import FMU2Model, FMU2Slave
    from fmpy.fmi3 import FMU3Model, FMU3Slave

    md = fmpy.read_model_description(str(fmu_path))
    unzip = fmpy.extract(str(fmu_path))
    v3 = md.fmiVersion.startswith("3")
    me = kind == "ME"
    ident = (md.modelExchange if me else md.coSimulation).modelIdentifier
    cls = {(False, True): FMU2Model, (False, False): FMU2Slave, (True, True): FMU3Model,
           (True, False): FMU3Slave}[(v3, me)]  # fmt: skip
    fmu = cls(guid=md.instantiationToken if v3 else md.guid, unzipDirectory=unzip, modelIdentifier=ident,
              instanceName="thermal")  # fmt: skip
    fmu.instantiate()
    vr = {v.name: v.valueReference for v in md.modelVariables}
    return fmu, vr, v3


def _set(fmu, vr, v3, values: dict[str, float]) -> None:
    names = list(values)
    refs = [vr[n] for n in names]
    (fmu.setFloat64 if v3 else fmu.setReal)(refs, [float(values[n]) for n in names])


def _get(fmu, vr, v3, names) -> list[float]:
    return list((fmu.getFloat64 if v3 else fmu.getReal)([vr[n] for n in names]))


def _init(fmu, vr, v3, T0) -> None:
    start = dict(zip(("TH_T_INIT_SURFACE", "TH_T_INIT_BULK", "TH_T_INIT_GAS"), T0, strict=True))
    if v3:
        fmu.enterInitializationMode(startTime=0.0)
    else:
        fmu.setupExperiment(startTime=0.0)
    _set(fmu, vr, v3, start)
    if not v3:
        fmu.enterInitializationMode()
    fmu.exitInitializationMode()


_INPUTS = ("Fz", "Vx", "Vy", "omega", "gamma", "T_ambient", "T_road")


def fmu_model_exchange(fmu_path, s: dict[str, np.ndarray], T0=T0, rtol: float = 1e-8, atol: float = 1e-12):
    """The FMU in Model Exchange along the stint ``s``, integrated as :func:`mftire.transient.simulate` does
    (LSODA, ``max_step`` the sample interval, inputs interpolated linearly): ``{channel: array}``."""
    from scipy.integrate import solve_ivp

    fmu, vr, v3 = _instance(fmu_path, "ME")
    t = s["t"]
    try:
        _init(fmu, vr, v3, T0)
        if v3:
            fmu.enterContinuousTimeMode()
        else:
            fmu.enterEventMode()
            fmu.newDiscreteStates()
            fmu.enterContinuousTimeMode()
        n = 5
        xs = np.zeros(n)
        (fmu.getContinuousStates)(xs.ctypes.data_as(_dptr()), n)
        dx = np.zeros(n)

        def inputs_at(tt):
            return {k: float(np.interp(tt, t, s[k])) for k in _INPUTS}

        def rhs(tt, x):
            fmu.setTime(tt)
            _set(fmu, vr, v3, inputs_at(tt))
            x = np.ascontiguousarray(x, dtype=float)
            fmu.setContinuousStates(x.ctypes.data_as(_dptr()), n)
            if v3:
                fmu.getContinuousStateDerivatives(dx.ctypes.data_as(_dptr()), n)
            else:
                fmu.getDerivatives(dx.ctypes.data_as(_dptr()), n)
            return dx.copy()

        sol = solve_ivp(rhs, (t[0], t[-1]), xs.copy(), method="LSODA", t_eval=t, rtol=rtol, atol=atol,
                        max_step=float(np.min(np.diff(t))))  # fmt: skip
        assert sol.success, sol.message
        out = {k: np.empty(t.size) for k in CHANNELS}
        for i, tt in enumerate(t):
            fmu.setTime(tt)
            _set(fmu, vr, v3, inputs_at(tt))
            x = np.ascontiguousarray(sol.y[:, i])
            fmu.setContinuousStates(x.ctypes.data_as(_dptr()), n)
            for k, val in zip(CHANNELS, _get(fmu, vr, v3, CHANNELS), strict=True):
                out[k][i] = val
        return out
    finally:
        fmu.terminate()
        fmu.freeInstance()


def _dptr():
    import ctypes

    return ctypes.POINTER(ctypes.c_double)


def fmu_co_simulation(fmu_path, s: dict[str, np.ndarray], H: float = 1e-3, T0=T0, tyre=None):
    """The FMU in Co-Simulation at steps ``H`` (inputs interpolated linearly, held over each step) and its Python
    mirror :class:`mftire.transient.TransientStepper` of ``tyre`` (the FMU's; default :func:`shipped_tir`):
    ``(fmu, python)``, each ``{channel: array}`` at the stint's sample times, and the wall time of the FMU's
    steps [s]."""
    import warnings

    from mftire.transient import TransientStepper, TransientTyre

    fmu, vr, v3 = _instance(fmu_path, "CS")
    t = s["t"]
    steps = int(round((t[-1] - t[0]) / H))
    every = max(int(round((t[1] - t[0]) / H)), 1)
    model = TransientTyre(shipped_tir() if tyre is None else tyre, thermal=True)
    py = TransientStepper(model, (0.0, 0.0, *T0))
    a = {k: [] for k in CHANNELS}
    b = {k: [] for k in CHANNELS}
    wall = 0.0
    try:
        _init(fmu, vr, v3, T0)
        for k in range(steps):
            tt = t[0] + k * H
            ins = {n: float(np.interp(tt, t, s[n])) for n in _INPUTS}
            w0 = time.perf_counter()
            _set(fmu, vr, v3, ins)
            fmu.doStep(tt, H) if not v3 else fmu.doStep(currentCommunicationPoint=tt, communicationStepSize=H)
            got = _get(fmu, vr, v3, CHANNELS)
            wall += time.perf_counter() - w0
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                ref = py.step(H, **ins)
            if (k + 1) % every == 0:
                for c, val in zip(CHANNELS, got, strict=True):
                    a[c].append(val)
                    b[c].append(ref[c])
    finally:
        fmu.terminate()
        fmu.freeInstance()
    return {k: np.array(v) for k, v in a.items()}, {k: np.array(v) for k, v in b.items()}, wall


def differences(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> dict[str, float]:
    """Largest |a − b| of each channel over its largest |b| (at least 1)."""
    return {k: float(np.max(np.abs(a[k] - b[k])) / max(float(np.max(np.abs(b[k]))), 1.0)) for k in CHANNELS}


def main(seconds: float = 60.0) -> int:
    import tempfile
    import warnings

    from mftire.fmu.export import export_fmu
    from mftire.transient import simulate

    tyre = shipped_tir()
    s = stint(seconds=seconds)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = simulate(tyre, s["t"], **{k: s[k] for k in _INPUTS if k not in ("T_ambient", "T_road")},
                       thermal=True, T_ambient=s["T_ambient"], T_road=s["T_road"], T0=T0)  # fmt: skip
    print(f"simulate(thermal=True): {seconds:g} s of the stint in {time.perf_counter() - t0:.1f} s wall; "
          f"T_surface {ref['T_surface'].min():.1f}..{ref['T_surface'].max():.1f} degC")
    worst = 0.0
    with tempfile.TemporaryDirectory() as d:
        for v in (2, 3):
            path = export_fmu(tyre, Path(d) / f"thermal{v}.fmu", fmi_version=v, transient=True)
            me = differences(fmu_model_exchange(path, s), {k: ref[k].to_numpy() for k in CHANNELS})
            worst = max(worst, *me.values())
            print(f"FMI {v} ME vs simulate: " + ", ".join(f"{k} {x:.1e}" for k, x in me.items()))
            a, b, wall = fmu_co_simulation(path, s, tyre=tyre)
            cs = differences(a, b)
            print(f"FMI {v} CS (1 ms) vs TransientStepper: " + ", ".join(f"{k} {x:.1e}" for k, x in cs.items()))
            print(f"FMI {v} CS: {seconds / wall:.0f}x real time at 1 kHz through fmpy (set 7 inputs, doStep, "
                  f"get {len(CHANNELS)} outputs)")
    print(f"largest ME difference: {worst:.2e} (done when <= 1e-6)")
    return 0 if worst <= 1e-6 else 1


if __name__ == "__main__":
    sys.exit(main(float(sys.argv[1]) if len(sys.argv) > 1 else 60.0))
