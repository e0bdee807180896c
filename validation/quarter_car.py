"""Quarter-car braking stop and standstill hold on the transient tyre (issue 23).

A quarter car (400 kg, wheel inertia 1.2 kg·m²) brakes from 30 m/s on one transient tyre.  The
brake torque is ramped to 3,000 N·m (the wheel locks) or to 1,200 N·m (it does not), and held after
the stop.  The tyre is coupled in two ways, with the same fixed-step master:

* ``fmu``: the transient FMU (``mftire export-fmu --transient``) in Co-Simulation through fmpy;
* ``libcosim``: the same FMU in the Open Simulation Platform's co-simulation engine (``libcosimpy``,
  when installed: an override manipulator sets the inputs, a last-value observer reads the outputs);
* ``python``: :class:`mftire.transient.TransientStepper`, the Python mirror of its ``fmi2DoStep``.

The master is what a co-simulation master does at a communication step h: set the tyre's inputs
(Fz, Vx, omega), ``doStep(t, h)``, read Fx and Re, then integrate the vehicle explicitly
(m·dV/dt = Fx, I·domega/dt = -Fx·Re - T_brake).  The brake is a dry friction torque with sticking
(Karnopp): it holds the wheel at omega = 0 while the tyre's torque |Fx·Re| is within the brake torque,
and a wheel whose spin would change sign within the step is stopped there.

Measured: the travel after the first standstill (largest distance from the stopping point) and the
drift over the last 3 s of the hold.  A second case parks the car (brake 1,200 N·m) on a 20 % slope
from rest: drift over the last 3 s.  Run::

    python validation/quarter_car.py [--tir FILE] [--output quarter_car.png] [--steps 1,10]

It prints the table of validation/README.md and writes the figure.
"""

from __future__ import annotations

import argparse
import math
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_TIR = ROOT / "tests" / "data" / "tir" / "MagicFormula61_Parameters.tir"


@dataclass(frozen=True)
class QuarterCar:
    m: float = 400.0  #: mass on the wheel [kg]
    I: float = 1.2  #: wheel spin inertia [kg m^2]
    g: float = 9.81
    V0: float = 30.0  #: initial speed [m/s]
    t_brake: float = 0.2  #: brake ramp start [s]
    ramp: float = 0.3  #: ramp duration [s]
    t_end: float = 10.0  #: end of the run [s]
    grade: float = 0.0  #: road slope (tan), down-hill forward [-]


class FMUTyre:
    """The transient FMU in Co-Simulation through fmpy (inputs Fz, Vx, omega; outputs Fx, Re)."""

    def __init__(self, fmu: str | Path) -> None:
        import fmpy
        from fmpy.fmi2 import FMU2Slave

        from mftire.fmu.host import make_callbacks

        md = fmpy.read_model_description(str(fmu))
        self._unzip = fmpy.extract(str(fmu))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=self._unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                             instanceName="tyre")  # fmt: skip
        self.messages: list = []  #: (status, category, message) logged by the FMU
        self.fmu.instantiate(callbacks=make_callbacks(self.messages))
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        self._in = [self.vr[k] for k in ("Fz", "Vx", "omega")]
        self._out = [self.vr[k] for k in ("Fx", "Re", "u")]

    def step(self, t: float, h: float, Fz: float, Vx: float, omega: float) -> tuple[float, float, float]:
        self.fmu.setReal(self._in, [Fz, Vx, omega])
        self.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        Fx, Re, u = self.fmu.getReal(self._out)
        return Fx, Re, u

    def close(self) -> None:
        import shutil

        self.fmu.terminate()
        self.fmu.freeInstance()
        shutil.rmtree(self._unzip, ignore_errors=True)


class CosimTyre:
    """The transient FMU in the Open Simulation Platform's co-simulation engine (``libcosimpy``, optional):
    the master sets the inputs with an override manipulator, steps the execution and reads the outputs with
    a last-value observer."""

    def __init__(self, fmu: str | Path, h: float) -> None:
        import fmpy
        from libcosimpy.CosimExecution import CosimExecution
        from libcosimpy.CosimManipulator import CosimManipulator
        from libcosimpy.CosimObserver import CosimObserver
        from libcosimpy.CosimSlave import CosimLocalSlave

        md = fmpy.read_model_description(str(fmu))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.ex = CosimExecution.from_step_size(step_size=int(round(h * 1e9)))  # nanoseconds
        self.slave = CosimLocalSlave(fmu_path=str(fmu), instance_name="tyre")
        self.i = self.ex.add_local_slave(local_slave=self.slave)
        self.man = CosimManipulator.create_override()
        self.obs = CosimObserver.create_last_value()
        self.ex.add_manipulator(manipulator=self.man)
        self.ex.add_observer(observer=self.obs)
        self._in = [self.vr[k] for k in ("Fz", "Vx", "omega")]
        self._out = [self.vr[k] for k in ("Fx", "Re", "u")]

    def step(self, t: float, h: float, Fz: float, Vx: float, omega: float) -> tuple[float, float, float]:
        self.man.slave_real_values(self.i, self._in, [Fz, Vx, omega])
        self.ex.step()
        Fx, Re, u = self.obs.last_real_values(self.i, self._out)
        return Fx, Re, u

    def close(self) -> None:
        self.ex.stop()


def cosim_available() -> bool:
    """Whether ``libcosimpy`` (the Open Simulation Platform's libcosim for Python) is importable."""
    try:
        import libcosimpy.CosimExecution  # noqa: F401
    except (ImportError, OSError):
        return False
    return True


class PythonTyre:
    """:class:`mftire.transient.TransientStepper`: the FMU's Co-Simulation step in Python."""

    def __init__(self, tyre) -> None:
        from mftire.transient import TransientStepper, TransientTyre

        self.s = TransientStepper(TransientTyre(tyre))

    def step(self, t: float, h: float, Fz: float, Vx: float, omega: float) -> tuple[float, float, float]:
        out = self.s.step(h, Fz=Fz, Vx=Vx, omega=omega)
        return out["Fx"], out["Re"], self.s.x[0]

    def close(self) -> None:
        pass


def brake_torque(car: QuarterCar, t: float, T_max: float) -> float:
    """Brake torque capacity [N m]: 0 before t_brake, a linear ramp, then T_max."""
    return T_max * min(max((t - car.t_brake) / car.ramp, 0.0), 1.0) if car.ramp > 0 else T_max * (t >= car.t_brake)


def run(tyre_block, car: QuarterCar, T_max: float, h: float, Re0: float) -> dict[str, np.ndarray]:
    """Fixed-step co-simulation of the quarter car; returns the time series."""
    n = int(round(car.t_end / h))
    theta = math.atan(car.grade)
    Fz = car.m * car.g * math.cos(theta)
    Fslope = car.m * car.g * math.sin(theta)
    V, x = car.V0, 0.0
    omega = car.V0 / Re0
    rec = np.empty((n + 1, 6))
    Fx, u = 0.0, 0.0
    rec[0] = (0.0, x, V, omega, Fx, u)
    for k in range(n):
        t = k * h
        Fx, Re, u = tyre_block.step(t, h, Fz, V, omega)
        # vehicle: explicit step with the tyre force at the end of the tyre's step
        V_new = V + h * (Fx + Fslope) / car.m
        x += h * V_new
        Tb = brake_torque(car, t + h, T_max)
        T_tyre = -Fx * Re  # torque of the road on the wheel
        if omega == 0.0 and abs(T_tyre) <= Tb:
            omega_new = 0.0  # the brake sticks
        else:
            s = math.copysign(1.0, omega) if omega != 0.0 else math.copysign(1.0, T_tyre)
            omega_new = omega + h * (T_tyre - Tb * s) / car.I
            if omega != 0.0 and omega_new * omega < 0.0 and abs(T_tyre) <= Tb:
                omega_new = 0.0  # would reverse within the step: stopped by the brake
        V, omega = V_new, omega_new
        rec[k + 1] = (t + h, x, V, omega, Fx, u)
    return {name: rec[:, i] for i, name in enumerate(("t", "x", "V", "omega", "Fx", "u"))}


def metrics(res: dict[str, np.ndarray], hold: float = 3.0) -> dict[str, float]:
    """Travel after the first standstill and drift over the last ``hold`` seconds [m]."""
    t, x, V = res["t"], res["x"], res["V"]
    stop = int(np.argmax(V <= 0.0)) if np.any(V <= 0.0) else len(t) - 1
    travel = float(np.max(np.abs(x[stop:] - x[stop])))
    last = t >= t[-1] - hold
    drift = float(np.max(x[last]) - np.min(x[last]))
    locked = bool(np.any((res["omega"] == 0.0) & (V > 1.0)))
    return {"t_stop": float(t[stop]), "x_stop": float(x[stop]), "travel": travel, "drift": drift, "locked": locked,
            "Vmax_after": float(np.max(np.abs(V[stop:])))}  # fmt: skip


def export(tir: Path, directory: Path) -> Path:
    from mftire.fmu.export import export_fmu

    return Path(export_fmu(tir, directory / "quarter_car_tyre.fmu", transient=True))


def free_rolling_radius(tyre, Fz: float, V: float) -> float:
    from mftire.transient import TransientTyre

    model = TransientTyre(tyre)
    om = V / tyre["UNLOADED_RADIUS"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(30):
            om = V / float(model.kinematics(Fz=Fz, Vx=V, omega=om).zero["Re"])
    return V / om


def campaign(tir: Path, steps=(1e-3, 10e-3), hold_steps=(1e-3, 2e-3, 5e-3, 10e-3),
             couplings=("fmu", "libcosim", "python"), t_end: float = 10.0,
             workdir: Path | None = None) -> tuple[list[dict], dict]:  # fmt: skip
    """All cases: (rows of the table, time series by case)."""
    from mftire.tyre import load

    tyre = load(tir)
    car = QuarterCar(t_end=t_end)
    Re0 = free_rolling_radius(tyre, car.m * car.g, car.V0)
    rows, series = [], {}
    with tempfile.TemporaryDirectory() as tmp:
        fmu = export(tir, Path(workdir or tmp))
        make = {
            "fmu": lambda h: FMUTyre(fmu),
            "libcosim": lambda h: CosimTyre(fmu, h),
            "python": lambda h: PythonTyre(tyre),
        }
        cases = [("stop", T, h) for T in (3000.0, 1200.0) for h in steps]
        cases += [("slope", 1200.0, h) for h in hold_steps]
        for how in couplings:
            for kind, T, h in cases:
                c = car if kind == "stop" else QuarterCar(V0=0.0, t_brake=0.0, ramp=0.0, grade=0.2, t_end=t_end)
                block = make[how](h)
                try:
                    res = run(block, c, T, h, Re0)
                finally:
                    block.close()
                m = metrics(res)
                rows.append({"case": kind, "coupling": how, "T_brake": T, "h_ms": h * 1e3, **m})
                series[(kind, how, T, h)] = res
    return rows, series


def table(rows: list[dict]) -> str:
    lines = ["| case | tyre | brake [N·m] | step [ms] | wheel locked | travel after stop [mm] | drift, last 3 s [mm] |",
             "|---|---|---|---|---|---|---|"]  # fmt: skip
    for r in rows:
        case = "stop from 30 m/s" if r["case"] == "stop" else "parked, 20 % slope"
        lock = "yes" if r["locked"] else "no"
        lines.append(f"| {case} | {r['coupling']} | {r['T_brake']:.0f} | {r['h_ms']:g} | {lock} | "
                     f"{r['travel'] * 1e3:.2f} | {r['drift'] * 1e3:.2g} |")  # fmt: skip
    return "\n".join(lines)


def plot(series: dict, path: Path) -> None:
    """Position after the stop [mm] and Fx around the stop, both brakes, every step size (FMU through fmpy)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 6.5))
    axs = fig.subplots(2, 2)
    for (kind, how, T, h), res in series.items():
        if kind != "stop" or how != "fmu":
            continue
        m = metrics(res)
        i = 0 if T > 2000 else 1
        sel = (res["t"] >= m["t_stop"] - 0.3) & (res["t"] <= m["t_stop"] + 2.0)
        lab = f"{h * 1e3:g} ms: travel {m['travel'] * 1e3:.1f} mm"
        axs[0, i].plot(res["t"][sel] - m["t_stop"], (res["x"][sel] - m["x_stop"]) * 1e3, label=lab)
        axs[1, i].plot(res["t"][sel] - m["t_stop"], res["Fx"][sel], label=f"{h * 1e3:g} ms")
        axs[0, i].set_title(f"brake ramped to {T:.0f} N·m")
    for ax in axs[0]:
        ax.set_ylabel("x - x(stop) [mm]")
        ax.set_ylim(-40, 30)
        ax.axhline(-25, color="0.6", lw=0.8, ls="--")
        ax.axhline(25, color="0.6", lw=0.8, ls="--")
        ax.legend(loc="lower right")
    for ax in axs[1]:
        ax.set_ylabel("Fx [N]")
        ax.set_xlabel("t - t(stop) [s]")
        ax.legend(loc="lower right")
    fig.suptitle("Quarter car (400 kg, 1.2 kg·m²) from 30 m/s on the transient tyre FMU (fmpy, Co-Simulation)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", type=Path, default=DEFAULT_TIR)
    ap.add_argument("--output", type=Path, default=Path("quarter_car.png"))
    ap.add_argument("--steps", default="1,10", help="communication steps of the stops [ms]")
    a = ap.parse_args(argv)
    steps = tuple(float(s) * 1e-3 for s in a.steps.split(","))
    couplings = ("fmu", "libcosim", "python") if cosim_available() else ("fmu", "python")
    if cosim_available():
        from libcosimpy.CosimLogging import CosimLogLevel, log_output_level

        log_output_level(CosimLogLevel.ERROR)
    rows, series = campaign(a.tir, steps=steps, couplings=couplings)
    print(table(rows))
    plot(series, a.output)
    print(f"wrote {a.output}")
    ok = all(r["travel"] < 0.025 and r["drift"] < 1e-3 for r in rows)
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
