"""Thermal vehicle example (issue 22): a constant-radius cornering stint on the thermal tyre.

A car goes round a circle of radius ``Stint.radius`` for ``Stint.corner_s`` seconds, driven at the limit: at
every instant at the speed whose lateral acceleration is ``Stint.driver_share`` of what its four tyres can give
at their present temperatures.  Then it runs ``Stint.straight_s`` seconds on a straight, free rolling at
``Stint.straight_speed``.  120 s in all (90 s cornering, 30 s straight), time step ``Stint.dt``.

**Tyres.**  Forces from mftire's evaluator (:meth:`mftire.tyre.Tyre.evaluate`) of a thermal ``.tir``; the
temperature laws read the node temperatures (:func:`mftire.thermal.simulation.node_tyre`), and the hot
pressure of the gas node (:func:`mftire.thermal.heat.hot_pressure`) is the MF's pressure input.  Each of the
four tyres carries its own three nodes (tread surface, bulk, inflation gas), advanced by the package's node
equations (:func:`mftire.thermal.simulation.simulate_nodes`: one backward-Euler step of
:mod:`mftire.thermal.heat`) with the heat of its operating point: sliding friction power
(:func:`mftire.thermal.heat.friction_power`) into the surface, rolling and hysteresis loss
(:func:`mftire.thermal.simulation.bulk_power`) into the bulk.  The thermal equations are the package's; this
file only drives them.  The default tyre, ``validation/data/thermal/thermal_tyre.tir``, is
``mftire fit-thermal`` of the shipped SIMULATED thermal rig run (``--refit`` redoes it, see :data:`FIT_COMMAND`).

**Range.**  The tyre's laws are fitted where the rig run went: tread surface up to 111 °C, carcass and gas up
to 77 °C.  At the limit for 90 s the front outer tyre's surface stays inside (109 °C), but its bulk and gas nodes
pass it (116 and 92 °C): there the stiffness law (bulk node) is extrapolated; it moves the steer angle more than
the capability, which follows the grip law of the surface node.

**Isothermal reference.**  The same car, driver and ``.tir`` with the node temperatures frozen at their start
values (so the hot pressure too): what a steady-state MF at the start temperature predicts.

**Vehicle** (quasi-static: the thermal time constants, seconds to minutes, are far longer than the vehicle's
own, tenths of a second, so each step is a steady turn).  A two-track car without longitudinal load transfer
(constant speed in each step), tyre aligning moments and drive force neglected, zero camber, both wheels of an
axle at the axle's slip angle:

* axle lateral forces of a steady turn, from the force and yaw-moment balance about the centre of gravity:
  ``Fy_front = m·ay·b/L``, ``Fy_rear = m·ay·a/L`` (Gillespie, *Fundamentals of Vehicle Dynamics*, 1992, ch. 6,
  the steady-state cornering of the bicycle model);
* lateral load transfer ``ΔFz = m·ay·h/t`` shared between the axles by the roll-stiffness share ``q``
  (Gillespie 1992, ch. 8, the lateral load transfer with roll: the front carries ``q·ΔFz``);
* side slip and steer angle of the steady turn: ``β = b/R − α_rear`` and ``δ = L/R + α_front − α_rear``
  (Gillespie 1992, ch. 6: the Ackermann angle ``L/R`` plus the slip-angle difference; Pacejka 2012, §1.3,
  the single-track model in a steady turn);
* capability: the largest ``ay`` both axles can give at their loads (each axle's peak over its slip angle,
  load transfer at that ``ay``, iterated).

Run::

    python validation/thermal_vehicle.py [--tir FILE] [--output validation/figures/thermal_vehicle.png]
                                         [--refit] [--short]

It writes the figure and, next to it, ``thermal_vehicle.csv`` (the headline numbers, thermal and isothermal)
and prints them as a table.  ``--short``: a 20 s corner and an 8 s straight (the tests' reduced case).

**Later: the co-simulation block.**  :func:`advance_tyres` is the one function that steps the tyres' thermal
states.  Once ``mftire.transient.simulate(..., thermal=True)`` is on main, it can replace the body of
:func:`advance_tyres` (one step of the block per wheel, from the wheel's state), with the rest of the file as
it is.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run from a source checkout

from mftire.thermal.heat import friction_power, hot_pressure  # noqa: E402
from mftire.thermal.simulation import bulk_power, node_tyre, simulate_nodes, thermal_of  # noqa: E402

DEFAULT_TIR = ROOT / "validation" / "data" / "thermal" / "thermal_tyre.tir"
DEFAULT_OUTPUT = ROOT / "validation" / "figures" / "thermal_vehicle.png"
#: The command that made DEFAULT_TIR (``--refit`` runs it).
FIT_COMMAND = ["fit-thermal", str(ROOT / "mftire" / "data" / "simulated_thermal_run.dat.gz"), "--tir",
               str(ROOT / "tirfiles" / "MF61_255-55R20_mfeval-jl.tir"), "--output", str(DEFAULT_TIR), "--plot",
               str(DEFAULT_OUTPUT.parent / "thermal_tyre_fit.png"), "--force"]
#: The wheels, turning left (positive ay, ISO): the right wheels are the outer ones.
WHEELS = ("FL", "FR", "RL", "RR")
NODES = ("surface", "bulk", "gas")


@dataclass(frozen=True)
class Car:
    """A large sports SUV on 255/55 R20 tyres (SI units)."""

    m: float = 2200.0  #: mass [kg]
    a: float = 1.40  #: centre of gravity to the front axle [m]
    b: float = 1.50  #: centre of gravity to the rear axle [m]
    track: float = 1.65  #: track width [m]
    h: float = 0.60  #: centre-of-gravity height [m]
    q_front: float = 0.55  #: front share of the lateral load transfer (roll-stiffness share) [-]
    g: float = 9.81  #: [m/s²]

    @property
    def L(self) -> float:
        return self.a + self.b


@dataclass(frozen=True)
class Stint:
    """The manoeuvre and the conditions."""

    radius: float = 80.0  #: circle radius [m]
    corner_s: float = 90.0  #: cornering time [s]
    straight_s: float = 30.0  #: straight after it [s]
    straight_speed: float = 30.0  #: free-rolling speed on the straight [m/s]
    driver_share: float = 0.95  #: share of the present capability the driver uses [-]
    T_start: float = 60.0  #: every node at the start: tyre blankets [°C]
    T_ambient: float = 22.0  #: [°C]
    T_road: float = 30.0  #: [°C]
    dt: float = 0.1  #: time step [s]
    alpha_max_deg: float = 15.0  #: slip-angle grid of the axle curves [deg] ...
    alpha_step_deg: float = 0.1  #: ... and its step [deg]


SHORT = Stint(corner_s=20.0, straight_s=8.0, dt=0.2)


class ThermalCar:
    """The car on one thermal ``.tir``: wheel loads, axle curves, capability, operating point, tyre heat."""

    def __init__(self, tyre, car: Car, stint: Stint):
        self.tyre, self.car, self.stint = tyre, car, stint
        self.params = thermal_of(tyre)
        if self.params is None:
            from mftire.errors import MftireInputError

            raise MftireInputError(f"{tyre.name}: no [MFTIRE_THERMAL] section; the example needs a thermal .tir "
                                   "(mftire fit-thermal writes one)")  # fmt: skip
        self.model = node_tyre(tyre, self.params)
        self.fnomin = float(tyre["FNOMIN"])
        p = self.params
        self.p_cold = p.cold_pressure if p.cold_pressure is not None else float(tyre["INFLPRES"])
        self.alpha = np.radians(np.arange(0.0, stint.alpha_max_deg + 1e-9, stint.alpha_step_deg))

    def pressure(self, T: np.ndarray) -> np.ndarray:
        """Inflation pressure of each wheel [Pa]: the gas law of its gas node (TH_PRESSURE 0: the cold one)."""
        p = self.params
        if not p.pressure:
            return np.full(T.shape[0], self.p_cold)
        return hot_pressure(T[:, 2], self.p_cold, p.cold_temperature, p.atmosphere)

    def loads(self, ay: float) -> np.ndarray:
        """Wheel loads [N] (FL, FR, RL, RR) in a steady left turn at ``ay`` [m/s²] (module docstring)."""
        c = self.car
        front, rear = c.m * c.g * c.b / c.L / 2.0, c.m * c.g * c.a / c.L / 2.0  # static axle loads, per wheel
        d = c.m * ay * c.h / c.track  # lateral load transfer m·ay·h/t, q_front of it in front (Gillespie 1992, ch. 8)
        return np.array([front - c.q_front * d, front + c.q_front * d, rear - (1 - c.q_front) * d,
                         rear + (1 - c.q_front) * d])  # fmt: skip

    def evaluate(self, Fz, alpha, V: float, T: np.ndarray, channels=("Fx", "Fy")):
        """MF forces of the wheels at node temperatures ``T`` (wheel rows; inputs broadcast per wheel)."""
        n = np.asarray(alpha).shape[-1] if np.ndim(alpha) == 2 else 1
        nodes = {f"T_{k}": np.repeat(T[:, i], n) for i, k in enumerate(NODES)}
        var = {k: v for k, v in nodes.items() if k in self.model.required_variables}
        Fz = np.repeat(np.asarray(Fz, float), n)
        P = np.repeat(self.pressure(T), n)
        out = self.model.evaluate(Fz, 0.0, np.ravel(alpha), 0.0, Vx=V, P=P, channels=channels, **var)
        return {k: np.asarray(out[k]).reshape(-1, n) for k in channels}

    def axle_curves(self, ay: float, V: float, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Front and rear axle lateral force [N] over the slip-angle grid ``|α|`` (the wheels at ``-|α|``,
        so that a left turn's forces are positive in ISO axes)."""
        a = np.tile(-self.alpha, (4, 1))
        Fy = self.evaluate(self.loads(ay), a, V, T, channels=("Fy",))["Fy"]
        return Fy[0] + Fy[1], Fy[2] + Fy[3]

    def capability(self, V: float, T: np.ndarray, iterations: int = 6) -> float:
        """The largest steady lateral acceleration [m/s²] (module docstring)."""
        c = self.car
        ay = 0.9 * c.g
        for _ in range(iterations):
            f, r = self.axle_curves(ay, V, T)
            # the axle forces of a steady turn, m·ay·b/L and m·ay·a/L (Gillespie 1992, ch. 6), at their peaks
            ay = min(f.max() / (c.m * c.b / c.L), r.max() / (c.m * c.a / c.L))
        return float(ay)

    def operating_point(self, ay: float, V: float, T: np.ndarray) -> tuple[float, float]:
        """Front and rear slip angles ``|α|`` [rad] that give the axle forces of a steady turn at ``ay``,
        on the rising side of each axle curve (the peak when ``ay`` asks for more)."""
        c = self.car
        out = []
        for curve, need in zip(self.axle_curves(ay, V, T), (c.m * ay * c.b / c.L, c.m * ay * c.a / c.L),
                                strict=True):  # fmt: skip
            k = int(np.argmax(curve))
            rising = np.maximum.accumulate(curve[: k + 1])
            out.append(float(np.interp(need, rising, self.alpha[: k + 1])))
        return out[0], out[1]

    def advance_tyres(self, T: np.ndarray, dt: float, Fz, alpha, V: float) -> tuple[np.ndarray, dict]:
        """One step of every wheel's thermal states (node temperatures ``T`` [°C], wheel rows) at the operating
        point (loads ``Fz`` [N], slip angles ``alpha`` [rad], speed ``V`` [m/s], free rolling κ = 0).

        Returns the new temperatures and the wheels' forces and heat.  THE function to swap for
        ``mftire.transient.simulate(..., thermal=True)`` (one block step per wheel) once it is on main.
        """
        s = self.stint
        f = self.evaluate(Fz, np.asarray(alpha, float)[:, None], V, T)
        Fx, Fy = f["Fx"][:, 0], f["Fy"][:, 0]
        q_s = friction_power(Fx, Fy, 0.0, alpha, V)  # sliding power into the surface [W]
        q_b = bulk_power(self.params, Fz, V, Fx, Fy, self.fnomin)  # rolling and hysteresis loss [W]
        new = np.empty_like(T)
        for w in range(T.shape[0]):  # the package's node equations, one implicit step
            new[w] = simulate_nodes(self.params, [0.0, dt], q_s[w], q_b[w], V, s.T_ambient, s.T_road,
                                    tuple(T[w]))[-1]  # fmt: skip
        return new, {"Fy": Fy, "q_s": q_s, "q_b": q_b}


def run(tyre, car: Car = Car(), stint: Stint = Stint(), thermal: bool = True) -> pd.DataFrame:
    """The stint (module docstring); ``thermal`` False: the node temperatures stay at ``stint.T_start``.

    Returns one row per step: ``t`` [s], ``phase`` (corner/straight), ``V`` [m/s], ``ay`` and the capability
    ``ay_max`` [m/s²] (on the straight: at the last cornering speed), the slip angles ``alpha_front``,
    ``alpha_rear``, the side slip ``beta`` and steer angle ``delta`` [deg], and per wheel ``Fz_W``, ``Fy_W``
    [N], ``q_s_W`` [W], ``P_W`` [Pa], ``T_surface_W``, ``T_bulk_W``, ``T_gas_W`` [°C].
    """
    from mftire.tyre import as_tyre

    m = ThermalCar(as_tyre(tyre), car, stint)
    n = int(round((stint.corner_s + stint.straight_s) / stint.dt))
    T = np.full((4, 3), float(stint.T_start))
    rows = []
    V_corner = np.sqrt(stint.driver_share * 0.9 * car.g * stint.radius)
    for i in range(n + 1):
        t = i * stint.dt
        cornering = t < stint.corner_s - 1e-9
        cap = m.capability(V_corner, T)
        if cornering:  # at the limit: the speed of driver_share of the present capability on the circle
            ay = stint.driver_share * cap
            V = V_corner = float(np.sqrt(ay * stint.radius))
            af, ar = m.operating_point(ay, V, T)
            # steady-turn side slip and steer angle (Gillespie 1992, ch. 6; Pacejka 2012, §1.3)
            beta, delta = car.b / stint.radius - ar, car.L / stint.radius + af - ar
        else:  # the straight: free rolling
            ay, V, af, ar, beta, delta = 0.0, stint.straight_speed, 0.0, 0.0, 0.0, 0.0
        Fz = m.loads(ay)
        alpha = -np.array([af, af, ar, ar])
        new, f = m.advance_tyres(T, stint.dt, Fz, alpha, V)
        row = {"t": t, "phase": "corner" if cornering else "straight", "V": V, "ay": ay, "ay_max": cap,
               "alpha_front": np.degrees(af), "alpha_rear": np.degrees(ar), "beta": np.degrees(beta),
               "delta": np.degrees(delta)}  # fmt: skip
        P = m.pressure(T)
        for w, name in enumerate(WHEELS):
            row.update({f"Fz_{name}": Fz[w], f"Fy_{name}": f["Fy"][w], f"q_s_{name}": f["q_s"][w],
                        f"P_{name}": P[w], **{f"T_{k}_{name}": T[w, j] for j, k in enumerate(NODES)}})
        rows.append(row)
        if thermal:
            T = new
    return pd.DataFrame(rows)


def headline(th: pd.DataFrame, iso: pd.DataFrame, stint: Stint) -> dict[str, float]:
    """The numbers of the figure: capability at the start, its peak, at the end of the corner and after the
    straight; how much of the fade the straight gives back; distance covered in the corner; temperatures and
    pressure of the front outer tyre (FR)."""
    c = th[th["phase"] == "corner"]
    s = th[th["phase"] == "straight"]
    ci = iso[iso["phase"] == "corner"]
    start, peak, end = float(c["ay_max"].iloc[0]), float(c["ay_max"].max()), float(c["ay_max"].iloc[-1])
    after = float(s["ay_max"].iloc[-1]) if len(s) else float("nan")
    return {
        "ay_max_start_mps2": start, "ay_max_peak_mps2": peak, "ay_max_end_corner_mps2": end,
        "ay_max_after_straight_mps2": after, "ay_max_isothermal_mps2": float(ci["ay_max"].iloc[-1]),
        "fade_from_peak_pct": 100.0 * (1.0 - end / peak),
        "fade_vs_isothermal_pct": 100.0 * (1.0 - end / float(ci["ay_max"].iloc[-1])),
        "recovered_on_straight_pct": 100.0 * (after - end) / (peak - end) if peak > end else float("nan"),
        "distance_corner_m": float(c["V"].sum() * stint.dt), "distance_corner_isothermal_m": float(ci["V"].sum()
                                                                                                  * stint.dt),
        "T_surface_FR_max_C": float(th["T_surface_FR"].max()), "T_surface_FR_end_corner_C":
            float(c["T_surface_FR"].iloc[-1]), "T_surface_FR_end_C": float(th["T_surface_FR"].iloc[-1]),
        "T_bulk_FR_max_C": float(th["T_bulk_FR"].max()), "T_bulk_FR_end_C": float(th["T_bulk_FR"].iloc[-1]),
        "T_gas_FR_end_C": float(th["T_gas_FR"].iloc[-1]),
        "P_FR_start_kPa": float(th["P_FR"].iloc[0]) / 1e3, "P_FR_max_kPa": float(th["P_FR"].max()) / 1e3,
        "delta_end_corner_deg": float(c["delta"].iloc[-1]), "delta_isothermal_deg": float(ci["delta"].iloc[-1]),
    }  # fmt: skip


def plot(th: pd.DataFrame, iso: pd.DataFrame, numbers: dict, stint: Stint, path) -> None:
    """One figure: node temperatures, lateral acceleration and capability, steer and side slip, pressure."""
    from mftire.plotting import subplots

    fig, axs = subplots(4, 1, figsize=(9.0, 10.5), sharex=True, constrained_layout=True)
    t = th["t"]
    ax = axs[0]
    for w, col in zip(WHEELS, ("C0", "C1", "C2", "C3"), strict=True):
        ax.plot(t, th[f"T_surface_{w}"], color=col, lw=1.3, label=f"surface {w}")
    ax.plot(t, th["T_bulk_FR"], color="C1", ls="--", lw=1.2, label="bulk FR")
    ax.plot(t, th["T_gas_FR"], color="C1", ls=":", lw=1.2, label="gas FR")
    ax.axhline(stint.T_start, color="0.4", ls="-.", lw=1.0, label="isothermal (all nodes)")
    ax.set_ylabel("node temperature [°C]")
    ax.set_ylim(None, max(th[[f"T_{k}_{w}" for k in NODES for w in WHEELS]].max()) + 22.0)  # room for the legend
    ax.legend(fontsize=7, ncol=4, loc="upper left")
    ax = axs[1]
    ax.plot(t, th["ay_max"], color="C3", lw=1.6, label="capability, thermal")
    ax.plot(iso["t"], iso["ay_max"], color="0.3", lw=1.2, ls="--", label="capability, isothermal")
    ax.plot(t[th["phase"] == "corner"], th["ay"][th["phase"] == "corner"], color="C3", lw=1.0, ls=":",
            label=f"driven ({stint.driver_share:.0%} of it), thermal")
    ax.plot(iso["t"][iso["phase"] == "corner"], iso["ay"][iso["phase"] == "corner"], color="0.3", lw=1.0, ls=":",
            label="driven, isothermal")
    ax.set_ylabel("lateral acceleration [m/s²]")
    ax.set_title(f"capability {numbers['ay_max_peak_mps2']:.2f} → {numbers['ay_max_end_corner_mps2']:.2f} m/s² "
                 f"(−{numbers['fade_from_peak_pct']:.1f} %) over the corner; "
                 f"{numbers['recovered_on_straight_pct']:.0f} % of it back after the straight", fontsize=9)
    ax.legend(fontsize=7, ncol=2, loc="lower left")
    ax = axs[2]
    c, ci = th["phase"] == "corner", iso["phase"] == "corner"
    ax.plot(t[c], th["delta"][c], color="C3", lw=1.4, label="steer angle δ, thermal")
    ax.plot(iso["t"][ci], iso["delta"][ci], color="0.3", lw=1.2, ls="--", label="steer angle δ, isothermal")
    ax.plot(t[c], th["beta"][c], color="C4", lw=1.4, label="side slip β, thermal")
    ax.plot(iso["t"][ci], iso["beta"][ci], color="C4", lw=1.0, ls="--", label="side slip β, isothermal")
    ax.set_ylabel("angle [deg]")
    ax.legend(fontsize=7, ncol=2, loc="center left")
    ax = axs[3]
    for w, col in zip(WHEELS, ("C0", "C1", "C2", "C3"), strict=True):
        ax.plot(t, th[f"P_{w}"] / 1e3, color=col, lw=1.2, label=w)
    ax.axhline(iso["P_FR"].iloc[0] / 1e3, color="0.4", ls="-.", lw=1.0, label="isothermal")
    ax.set_ylabel("hot pressure [kPa]")
    ax.set_xlabel("time [s]")
    ax.legend(fontsize=7, ncol=5, loc="upper left")
    for a in axs:
        a.axvspan(stint.corner_s, stint.corner_s + stint.straight_s, color="0.92", lw=0)
        a.grid(alpha=0.3)
    axs[0].set_title(f"constant radius {stint.radius:g} m at the limit, then a straight at "
                     f"{stint.straight_speed * 3.6:.0f} km/h (shaded); thermal tyre vs isothermal", fontsize=10)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)


def main(argv=None) -> int:
    import warnings

    import mftire
    from mftire.mf.inputs import MFLimitWarning

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tir", default=str(DEFAULT_TIR), help="thermal .tir (default: %(default)s)")
    ap.add_argument("--output", default=str(DEFAULT_OUTPUT), help="figure (default: %(default)s)")
    ap.add_argument("--refit", action="store_true", help="first redo the default .tir with mftire fit-thermal")
    ap.add_argument("--short", action="store_true", help="a 20 s corner and an 8 s straight")
    args = ap.parse_args(argv)
    if args.refit:
        from mftire.cli import main as cli

        if cli(FIT_COMMAND) != 0:
            return 1
    stint = SHORT if args.short else Stint()
    tyre = mftire.load(args.tir)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("error", MFLimitWarning)  # an input outside the file's ranges stops the run
        th = run(tyre, stint=stint, thermal=True)
        iso = run(tyre, stint=stint, thermal=False)
    numbers = headline(th, iso, stint)
    plot(th, iso, numbers, stint, args.output)
    csv = Path(args.output).with_suffix(".csv")
    pd.Series(numbers, name="value").rename_axis("quantity").to_csv(csv, float_format="%.4g")
    print(f"{args.tir}: {time.perf_counter() - t0:.1f} s")
    for k, v in numbers.items():
        print(f"  {k:34s} {v:10.3f}")
    print(f"wrote {args.output} and {csv}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
