"""Vehicle-dynamics example: a two-track car on four tyre FMUs.

A planar two-track vehicle model (longitudinal, lateral and yaw motion) with
quasi-static longitudinal and lateral load transfer runs a manoeuvre of
straight-line braking at controlled slip, followed by a step steer.  The tyres
are evaluated twice:

1. through the exported FMU -- four instances (FL, FR, RL, RR) of one FMI 2.0
   Model Exchange FMU, driven through fmpy;
2. with mftire's Python evaluator directly.

Both trajectories are plotted to a PNG and the script asserts that they agree.

Second part (:func:`run_transient`): the same car on four instances of the
*transient* tyre FMU (``mftire export-fmu --transient``: wheel kinematics in,
relaxation-length slip states, low-speed model), in Co-Simulation at 1 kHz through
fmpy (by default inside fmpy's container FMU): standing still, launching, braking to a
stop, then held by the brakes while the road tilts to a 20 % slope.  Tyre forces and
vehicle speed through the stop and the hold are plotted to ``<output stem>_transient.png``.

Run::

    python validation/vehicle_example.py [--tir FILE] [--output vehicle_example.png] [--short]

The tyre is the MF 6.2 test tyre shipped in ``tests/data/tir`` unless ``--tir`` is given.
"""

from __future__ import annotations

import argparse
import tempfile
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_TIR = ROOT / "tests" / "data" / "tir" / "MagicFormula62_Parameters.tir"
WHEELS = ("FL", "FR", "RL", "RR")


@dataclass(frozen=True)
class Vehicle:
    """A mid-size car (SI units)."""

    m: float = 1700.0  #: mass [kg]
    Iz: float = 2900.0  #: yaw inertia [kg m^2]
    a: float = 1.25  #: CoG to front axle [m]
    b: float = 1.45  #: CoG to rear axle [m]
    tw: float = 1.6  #: track width [m]
    h: float = 0.55  #: CoG height [m]
    roll_front: float = 0.55  #: front share of the lateral load transfer [-]
    g: float = 9.81


@dataclass(frozen=True)
class Manoeuvre:
    """Braking at controlled slip, release, then a step steer."""

    v0: float = 25.0  #: initial speed [m/s]
    brake_on: float = 0.3  #: [s]
    brake_off: float = 1.6  #: [s]
    kappa_brake: float = -0.08  #: slip ratio while braking (ABS-like slip control) [-]
    steer_at: float = 2.0  #: [s]
    steer: float = np.radians(2.5)  #: road-wheel steer angle of the step [rad]
    ramp: float = 0.1  #: ramp time of each step [s]
    t_end: float = 3.5  #: [s]
    dt: float = 1e-3  #: integration step [s]


SHORT = Manoeuvre(brake_on=0.1, brake_off=0.5, steer_at=0.6, ramp=0.05, t_end=1.0, dt=2e-3)


def _ramp(t: float, t0: float, width: float) -> float:
    return float(np.clip((t - t0) / width, 0.0, 1.0))


def controls(t: float, mv: Manoeuvre) -> tuple[float, float]:
    """(slip ratio of every wheel, front steer angle) at time t."""
    k = mv.kappa_brake * (_ramp(t, mv.brake_on, mv.ramp) - _ramp(t, mv.brake_off, mv.ramp))
    return k, mv.steer * _ramp(t, mv.steer_at, mv.ramp)


def wheel_kinematics(state, delta: float, veh: Vehicle):
    """Wheel-frame longitudinal speed and slip angle of the four wheels (ISO-W: Vsy = tan(alpha)·|Vx|)."""
    vx, vy, r = state[0], state[1], state[2]
    xs = np.array([veh.a, veh.a, -veh.b, -veh.b])
    ys = np.array([veh.tw / 2, -veh.tw / 2, veh.tw / 2, -veh.tw / 2])
    steer = np.array([delta, delta, 0.0, 0.0])
    vxw = vx - r * ys
    vyw = vy + r * xs
    c, s = np.cos(steer), np.sin(steer)
    vx_t = vxw * c + vyw * s
    vy_t = -vxw * s + vyw * c
    return vx_t, np.arctan2(vy_t, np.abs(vx_t)), steer, xs, ys


def wheel_loads(ax: float, ay: float, veh: Vehicle) -> np.ndarray:
    """Quasi-static loads with longitudinal and lateral load transfer [N]."""
    L = veh.a + veh.b
    mg = veh.m * veh.g
    front = mg * veh.b / L / 2 - veh.m * ax * veh.h / L / 2
    rear = mg * veh.a / L / 2 + veh.m * ax * veh.h / L / 2
    dfy = veh.m * ay * veh.h / veh.tw  # total lateral transfer; y left: ay > 0 loads the right wheels
    return np.array([
        front - veh.roll_front * dfy, front + veh.roll_front * dfy,
        rear - (1 - veh.roll_front) * dfy, rear + (1 - veh.roll_front) * dfy,
    ])  # fmt: skip


def simulate(tyre_forces, veh: Vehicle = Vehicle(), mv: Manoeuvre = Manoeuvre()) -> dict[str, np.ndarray]:
    """Integrate the vehicle with ``tyre_forces(Fz, kappa, alpha, Vx) -> (Fx, Fy, Mz)`` (arrays of 4).

    Semi-implicit Euler at ``mv.dt``; the load transfer uses the accelerations of
    the previous step.  Returns the time histories.
    """
    n = int(round(mv.t_end / mv.dt)) + 1
    t = np.arange(n) * mv.dt
    X = np.zeros((n, 6))  # vx, vy, r, x, y, psi
    X[0, 0] = mv.v0
    acc = np.zeros((n, 2))
    Fz_hist = np.zeros((n, 4))
    Fy_hist = np.zeros((n, 4))
    ax = ay = 0.0
    for i in range(n - 1):
        kappa, delta = controls(t[i], mv)
        vx_t, alpha, steer, xs, ys = wheel_kinematics(X[i], delta, veh)
        Fz = wheel_loads(ax, ay, veh)
        Fx, Fy, Mz = tyre_forces(Fz, np.full(4, kappa), alpha, vx_t)
        c, s = np.cos(steer), np.sin(steer)
        Fxb = Fx * c - Fy * s
        Fyb = Fx * s + Fy * c
        vx, vy, r = X[i, :3]
        ax = Fxb.sum() / veh.m
        ay = Fyb.sum() / veh.m
        rdot = (np.sum(xs * Fyb - ys * Fxb) + Mz.sum()) / veh.Iz
        X[i + 1, 0] = vx + (ax + vy * r) * mv.dt
        X[i + 1, 1] = vy + (ay - vx * r) * mv.dt
        X[i + 1, 2] = r + rdot * mv.dt
        psi = X[i, 5]
        X[i + 1, 3] = X[i, 3] + (X[i + 1, 0] * np.cos(psi) - X[i + 1, 1] * np.sin(psi)) * mv.dt
        X[i + 1, 4] = X[i, 4] + (X[i + 1, 0] * np.sin(psi) + X[i + 1, 1] * np.cos(psi)) * mv.dt
        X[i + 1, 5] = psi + X[i + 1, 2] * mv.dt
        acc[i + 1] = (ax, ay)
        Fz_hist[i], Fy_hist[i] = Fz, Fy
    return {"t": t, "vx": X[:, 0], "vy": X[:, 1], "r": X[:, 2], "x": X[:, 3], "y": X[:, 4], "psi": X[:, 5],
            "ax": acc[:, 0], "ay": acc[:, 1], "Fz": Fz_hist, "Fy": Fy_hist}  # fmt: skip


def python_tyres(tir):
    """Tyre forces from mftire's Python evaluator (all four wheels in one call)."""
    from mftire.tyre import load

    tyre = load(tir)

    def forces(Fz, kappa, alpha, Vx):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out = tyre.evaluate(Fz, kappa, alpha, 0.0, 0.0, Vx, mode=111)
        return out["Fx"], out["Fy"], out["Mz"]

    return forces


class FMUTyres:
    """Four instances of one tyre FMU (FMI 2.0 Model Exchange) driven through fmpy."""

    def __init__(self, fmu_path) -> None:
        from fmpy import extract

        from mftire.fmu.host import FMUTyre

        self.unzipdir = extract(str(fmu_path))
        self.wheels = [FMUTyre(self.unzipdir, "ME", instance_name=w) for w in WHEELS]
        self.out_vr = [self.wheels[0].vr[k] for k in ("Fx", "Fy", "Mz")]
        self.in_vr = [self.wheels[0].vr[k] for k in ("Fz", "kappa", "alpha", "Vx")]
        self.time = 0.0

    def __call__(self, Fz, kappa, alpha, Vx):
        res = np.empty((3, 4))
        for j, w in enumerate(self.wheels):
            w.fmu.setReal(self.in_vr, [Fz[j], kappa[j], alpha[j], Vx[j]])
            res[:, j] = w.fmu.getReal(self.out_vr)
        return res[0], res[1], res[2]

    def close(self) -> None:
        import shutil

        for w in self.wheels:
            w.close()
        shutil.rmtree(self.unzipdir, ignore_errors=True)


def run(tir=DEFAULT_TIR, output: str | Path | None = "vehicle_example.png", short: bool = False,
        fmu_path: str | Path | None = None) -> dict:  # fmt: skip
    """Run the manoeuvre through the FMU and through Python; plot; assert agreement.

    Returns the two trajectories and the largest differences.
    """
    from mftire.fmu.export import export_fmu

    mv = SHORT if short else Manoeuvre()
    with tempfile.TemporaryDirectory(prefix="mftire-vehicle-") as tmp:
        if fmu_path is None:
            fmu_path = export_fmu(tir, Path(tmp) / "tyre.fmu")
        t0 = time.perf_counter()
        fmu = FMUTyres(fmu_path)
        try:
            via_fmu = simulate(fmu, mv=mv)
        finally:
            fmu.close()
        t_fmu = time.perf_counter() - t0
        t0 = time.perf_counter()
        via_py = simulate(python_tyres(tir), mv=mv)
        t_py = time.perf_counter() - t0

    diffs = {k: float(np.max(np.abs(via_fmu[k] - via_py[k]))) for k in ("vx", "vy", "r", "x", "y", "ax", "ay")}
    scale = {"vx": mv.v0, "vy": 1.0, "r": 1.0, "x": mv.v0 * mv.t_end, "y": 1.0, "ax": 10.0, "ay": 10.0}
    for k, d in diffs.items():
        assert d <= 1e-9 * scale[k], f"FMU and Python trajectories differ in {k}: {d:.3e}"
    # the manoeuvre did what it should
    brake = (via_py["t"] > mv.brake_on + mv.ramp) & (via_py["t"] < mv.brake_off)
    assert via_py["ax"][brake].min() < -5.0, "braking should decelerate the car"
    assert via_py["r"][-1] > 0.05, "a left step steer should give a positive yaw rate"
    if output:
        _plot(via_fmu, via_py, mv, output)
    return {"fmu": via_fmu, "python": via_py, "max_diff": diffs, "seconds_fmu": t_fmu, "seconds_python": t_py}


def _plot(a: dict, b: dict, mv: Manoeuvre, output) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 3, figsize=(13, 7))
    panels = [
        ("vx", "speed vx [m/s]"), ("ax", "long. acceleration [m/s²]"), ("ay", "lat. acceleration [m/s²]"),
        ("r", "yaw rate [rad/s]"), ("vy", "lateral velocity vy [m/s]"),
    ]  # fmt: skip
    for axis, (k, label) in zip(ax.flat, panels, strict=False):
        axis.plot(a["t"], a[k], lw=2.5, label="FMU (4 instances, fmpy)")
        axis.plot(b["t"], b[k], "--", lw=1.2, color="k", label="Python evaluator")
        axis.set_xlabel("t [s]")
        axis.set_ylabel(label)
        axis.grid(alpha=0.3)
    ax[0, 0].legend()
    ax[1, 2].plot(a["x"], a["y"], lw=2.5, label="FMU")
    ax[1, 2].plot(b["x"], b["y"], "--", lw=1.2, color="k", label="Python")
    ax[1, 2].set_xlabel("X [m]")
    ax[1, 2].set_ylabel("Y [m]")
    ax[1, 2].set_title("path")
    ax[1, 2].grid(alpha=0.3)
    fig.suptitle(f"Two-track car: braking at kappa = {mv.kappa_brake}, then a {np.degrees(mv.steer):.1f}° step steer")
    fig.tight_layout()
    fig.savefig(output, dpi=110)
    plt.close(fig)


@dataclass(frozen=True)
class StopAndHold:
    """Standing still, launching, braking to a stop, then parked while the road tilts to a slope."""

    launch: float = 1.0  #: drive torque on [s]
    drive_torque: float = 700.0  #: per rear wheel [N m]
    brake: float = 4.0  #: drive off, brakes on [s]
    brake_front: float = 1100.0  #: brake torque per front wheel [N m]
    brake_rear: float = 500.0  #: per rear wheel [N m]
    tilt: float = 7.0  #: the road starts tilting [s]
    tilt_time: float = 1.0  #: to the final grade in [s]
    grade: float = 0.20  #: final slope (rise over run) [-]
    t_end: float = 11.0  #: [s]
    ramp: float = 0.2  #: torque ramps [s]
    wheel_inertia: float = 1.2  #: [kg m^2]
    dt: float = 1e-3  #: communication step [s]


#: Tyre variables of the stop-and-hold manoeuvre (Vy stays at its default 0 in straight-line motion;
#: Fy and Mz are not needed).
STOP_INPUTS = ("Fz", "Vx", "omega")
STOP_OUTPUTS = ("Fx", "My", "Re")


def _ramp01(s: np.ndarray) -> np.ndarray:
    """0 below 0, s between 0 and 1, 1 above (the torque and grade ramps)."""
    return np.where(s <= 0.0, 0.0, np.where(s >= 1.0, 1.0, s))


def simulate_stop_and_hold(tyres, veh: Vehicle = Vehicle(), sc: StopAndHold = StopAndHold()) -> dict:
    """Straight-line two-track car on the transient tyres ``tyres`` (a :class:`TransientFMUs` with
    the variables :data:`STOP_INPUTS` and :data:`STOP_OUTPUTS`).

    Explicit co-simulation at ``sc.dt``: the tyres see the wheel kinematics at the start
    of a step and return their forces at its end; the car (speed along the road, four
    wheel spins) advances with semi-implicit Euler.  The brakes are Coulomb friction
    with stiction: a wheel whose free motion the brake torque can stop is held at zero spin.

    The controls (grade, brake, drive torque) depend on time only and are computed for all
    steps before the loop; the step is scalar Python (no numpy inside the loop): one
    :meth:`TransientFMUs.step_values` call per step carries the 4 x 3 inputs in and the 4 x 3
    outputs out, and 16 values per step are recorded as packed doubles.
    """
    import math
    import struct

    if tuple(tyres.inputs) != STOP_INPUTS or tuple(tyres.outputs) != STOP_OUTPUTS or tyres.n != 4:
        raise ValueError(f"simulate_stop_and_hold needs 4 tyres with inputs {STOP_INPUTS} and outputs {STOP_OUTPUTS}")
    n = int(round(sc.t_end / sc.dt))
    L = veh.a + veh.b
    J, dt, m, g, h_cg, b = sc.wheel_inertia, sc.dt, veh.m, veh.g, veh.h, veh.b
    # controls of every step (functions of time only)
    t = np.arange(n + 1) * dt
    grade = sc.grade * _ramp01((t - sc.tilt) / sc.tilt_time)
    bk = _ramp01((t - sc.brake) / sc.ramp)  # brakes ramp on as the drive ramps off
    Td = sc.drive_torque * _ramp01((t - sc.launch) / sc.ramp) * (1.0 - bk)  # rear wheels
    lim_f, lim_r = dt * bk * sc.brake_front / J, dt * bk * sc.brake_rear / J  # brake spin change per step
    controls = zip(t.tolist(), grade.tolist(), Td.tolist(), lim_f.tolist(), lim_r.tolist(), strict=True)
    atan, cos, sin, copysign = math.atan, math.cos, math.sin, math.copysign
    V, X = 0.0, 0.0
    om0 = om1 = om2 = om3 = 0.0
    Fx_sum = 0.0
    grade_last, mg_cos_b, mg_cos_2, g_sin = 0.0, m * g * 1.0 * b, m * g * 1.0 / 2.0, g * 0.0
    step = tyres.step_values
    rec = bytearray()  # V, X, Fz_f, Fz_r, omega x 4, Fx x 4, Re x 4 of every step: 16 doubles
    keep, pack = rec.extend, struct.Struct("=16d").pack
    for ti, gr, Td_r, lf, lr in controls:
        if gr != grade_last:
            th = atan(gr)
            cos_t, sin_t, grade_last = cos(th), sin(th), gr
            mg_cos_b, mg_cos_2, g_sin = m * g * cos_t * b, m * g * cos_t / 2.0, g * sin_t
        # quasi-static pitch load transfer from the previous step's total tyre force
        Fz_f = (mg_cos_b - h_cg * Fx_sum) / L / 2.0
        Fz_r = mg_cos_2 - Fz_f
        Fx0, My0, Re0, Fx1, My1, Re1, Fx2, My2, Re2, Fx3, My3, Re3 = step(
            ti, dt, (Fz_f, V, om0, Fz_f, V, om1, Fz_r, V, om2, Fz_r, V, om3)
        )  # STOP_OUTPUTS per tyre
        keep(pack(V, X, Fz_f, Fz_r, om0, om1, om2, om3, Fx0, Fx1, Fx2, Fx3, Re0, Re1, Re2, Re3))
        Fx_sum = Fx0 + Fx1 + Fx2 + Fx3
        # wheel spin without the brake, then the brake with stiction (held at 0 if it can stop the wheel)
        free = om0 + dt * (My0 - Re0 * Fx0) / J
        om0 = 0.0 if abs(free) <= lf else free - copysign(lf, free)
        free = om1 + dt * (My1 - Re1 * Fx1) / J
        om1 = 0.0 if abs(free) <= lf else free - copysign(lf, free)
        free = om2 + dt * (Td_r - Re2 * Fx2 + My2) / J
        om2 = 0.0 if abs(free) <= lr else free - copysign(lr, free)
        free = om3 + dt * (Td_r - Re3 * Fx3 + My3) / J
        om3 = 0.0 if abs(free) <= lr else free - copysign(lr, free)
        V += dt * (Fx_sum / m - g_sin)
        X += dt * V
    R = np.frombuffer(rec, float).reshape(n + 1, 16)
    return {"t": t, "V": R[:, 0], "X": R[:, 1], "grade": grade, "Fx": R[:, 8:12], "Fz": R[:, [2, 2, 3, 3]],
            "omega": R[:, 4:8], "Re": R[:, 12:16]}  # fmt: skip


def run_transient(tir=DEFAULT_TIR, output: str | Path | None = "vehicle_example_transient.png",
                  sc: StopAndHold = StopAndHold(), fmu_path: str | Path | None = None,
                  mode: str | None = None) -> dict:  # fmt: skip
    """Standstill, launch, stop and hold on a 20 % slope with the transient tyre FMU; plot.

    ``mode``: how fmpy drives the four instances (:class:`mftire.fmu.transient_host.TransientFMUs`);
    default fmpy's container FMU where fmpy has one, else direct calls.  Returns the trajectory and a
    few figures (``drift``: the largest speed over the last second, ``seconds``: run time of the
    simulation loop, ``mode``).
    """
    from mftire.fmu.export import export_fmu
    from mftire.fmu.transient_host import TransientFMUs, container_available

    mode = mode or ("container" if container_available() else "direct")
    with tempfile.TemporaryDirectory(prefix="mftire-vehicle-") as tmp:
        if fmu_path is None:
            fmu_path = export_fmu(tir, Path(tmp) / "tyre_transient.fmu", transient=True)
        with TransientFMUs(fmu_path, WHEELS, inputs=STOP_INPUTS, outputs=STOP_OUTPUTS, mode=mode,
                           step_size=sc.dt) as tyres:  # fmt: skip
            t0 = time.perf_counter()
            res = simulate_stop_and_hold(tyres, sc=sc)
            res["seconds"] = time.perf_counter() - t0
        res["mode"] = mode
    last = res["t"] > sc.t_end - 1.0
    res["drift"] = float(np.max(np.abs(res["V"][last])))
    assert np.all(np.isfinite(res["Fx"])), "tyre forces must stay finite"
    assert res["V"].max() > 3.0, "the car should have launched"
    if output:
        _plot_transient(res, sc, output)
    return res


def _plot_transient(res: dict, sc: StopAndHold, output) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = res["t"]
    fig, ax = plt.subplots(2, 2, figsize=(13, 7))
    ax[0, 0].plot(t, res["V"], lw=2)
    ax[0, 0].set_ylabel("vehicle speed [m/s]")
    tw = ax[0, 0].twinx()
    tw.plot(t, 100 * res["grade"], color="0.6", ls=":")
    tw.set_ylabel("road grade [%] (dotted)")
    for j, w in enumerate(WHEELS):
        ax[0, 1].plot(t, res["Fx"][:, j], label=w)
    ax[0, 1].set_ylabel("tyre Fx [N]")
    ax[0, 1].legend()
    t_stop = float(t[np.argmax((t > sc.brake) & (res["V"] < 0.5))])
    stop = t > t_stop - 0.2
    ax[1, 0].plot(t[stop], 1000 * res["V"][stop], lw=2)
    ax[1, 0].set_ylim(-250.0, 550.0)
    ax[1, 0].set_ylabel("speed through the stop and the hold [mm/s]")
    for j, w in enumerate(WHEELS):
        ax[1, 1].plot(t[stop], res["Fx"][stop, j], label=w)
    ax[1, 1].set_ylabel("tyre Fx through the stop and the hold [N]")
    for a in ax.flat:
        a.set_xlabel("t [s]")
        a.grid(alpha=0.3)
    fig.suptitle(
        "Transient tyre FMU (4 instances, Co-Simulation 1 kHz): standstill, launch, braking to a stop, "
        f"held on a {100 * sc.grade:.0f} % slope (drift {1000 * res['drift']:.3f} mm/s)"
    )
    fig.tight_layout()
    fig.savefig(output, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", default=str(DEFAULT_TIR))
    ap.add_argument("--output", default="vehicle_example.png", help="PNG to write")
    ap.add_argument("--short", action="store_true", help="a 1 s version of the manoeuvre")
    args = ap.parse_args(argv)
    res = run(args.tir, args.output, short=args.short)
    print(f"wrote {args.output}")
    print(f"run time: FMU {res['seconds_fmu']:.2f} s, Python {res['seconds_python']:.2f} s")
    print("largest FMU - Python difference: " + ", ".join(f"{k} {v:.1e}" for k, v in res["max_diff"].items()))
    if not args.short:
        out = Path(args.output)
        out_t = out.with_name(out.stem + "_transient.png")
        tr = run_transient(args.tir, out_t)
        print(f"wrote {out_t}: transient tyre FMU, stop and hold on a 20 % slope, drift {1000 * tr['drift']:.4f} mm/s "
              f"(simulation loop {tr['seconds']:.2f} s for {StopAndHold().t_end:g} s, {tr['mode']} mode)")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
