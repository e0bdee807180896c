"""Transient tyre speed: one Model Exchange derivative in C, and a 4-tyre vehicle manoeuvre through fmpy.

Run: ``python benchmarks/bench_transient.py [--tir FILE] [--n 200000] [--repeat 5] [--workdir DIR]``.

1. **ME derivative in C** -- the transient C model with a small harness
   (:func:`mftire.fmu.transient_export.build_probe_library`) loops, inside C, the work of
   one ``fmi2GetDerivatives`` after new inputs: the kinematics (one steady-state
   evaluation for the relaxation lengths and Re) and the state rates.  Target: <= 2 µs.
2. **Vehicle manoeuvre** -- the two-track car of ``validation/vehicle_example.py`` on
   four instances of the transient FMU in Co-Simulation at 1 kHz for 10 s (standstill,
   launch, stop, hold on a 20 % slope).  fmpy loads and instantiates the FMU; each step
   calls ``fmi2SetReal``/``fmi2DoStep``/``fmi2GetReal`` of fmpy's loaded library once per
   tyre (:class:`mftire.fmu.transient_host.TransientFMUs`: prebound ctypes calls, or
   fmpy's wrapper methods).  Target: >= 100x faster than real time.  Median (and best) of
   ``--repeat`` runs.
3. **Where a vehicle step goes** (medians of ``--repeat`` runs, 10,000 steps each): the
   vehicle model alone (tyres replaced by a stub returning constants); the 4 x 3 tyre
   calls alone from Python; the same calls with no work in C (``fmi2GetReal`` of no
   variable: the ctypes cost of a call); and the same 4 x 10,000 tyre steps from a C host
   that ``dlopen``s the FMU binary (the FMU's own cost).  With ``--workdir`` the FMU and
   the C host are kept and the host's command line is printed, e.g. for
   ``valgrind --tool=callgrind``.
"""

from __future__ import annotations

import argparse
import ctypes
import importlib.util
import statistics
import subprocess
import sys
import tempfile
import time
from functools import partial
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_TIR = ROOT / "tests" / "data" / "tir" / "MagicFormula61_Parameters.tir"


def c_derivative_seconds(tir, tmp: Path, n: int) -> float:
    from mftire.fmu.transient_export import build_probe_library

    lib = ctypes.CDLL(str(build_probe_library(tir, tmp)))
    lib.mt_probe_bench.restype = ctypes.c_double
    lib.mt_probe_bench.argtypes = [ctypes.c_int, ctypes.POINTER(ctypes.c_double), ctypes.c_long]
    inputs = (ctypes.c_double * 8)(4000.0, 20.0, 0.3, 52.0, 0.01, 2.2e5, 1.0, 0.05)
    lib.mt_probe_bench(111, inputs, max(n // 10, 1))  # warm-up
    return min(lib.mt_probe_bench(111, inputs, n) for _ in range(3))


def _vehicle_module():
    spec = importlib.util.spec_from_file_location("vehicle_example", ROOT / "validation" / "vehicle_example.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules["vehicle_example"] = mod
    spec.loader.exec_module(mod)
    return mod


def _median(fn, repeat: int) -> tuple[float, float]:
    """(median, best) of ``repeat`` calls of ``fn()``, each returning seconds."""
    times = [fn() for _ in range(repeat)]
    return statistics.median(times), min(times)


def manoeuvre_seconds(fmu: Path, fast: bool, t_end: float = 10.0) -> tuple[float, float]:
    """(wall seconds of the 10 s manoeuvre, largest |V| over its last second)."""
    from mftire.fmu.transient_host import TransientFMUs

    ve = _vehicle_module()
    sc = ve.StopAndHold(t_end=t_end, tilt=6.5, tilt_time=1.0)
    with TransientFMUs(fmu, ve.WHEELS, inputs=ve.STOP_INPUTS, outputs=ve.STOP_OUTPUTS, fast=fast) as tyres:
        t0 = time.perf_counter()
        res = ve.simulate_stop_and_hold(tyres, sc=sc)
        dt = time.perf_counter() - t0
    last = res["t"] > t_end - 1.0
    return dt, float(abs(res["V"][last]).max())


def vehicle_only_seconds(t_end: float = 10.0) -> float:
    """The manoeuvre's vehicle model with the tyres replaced by a stub returning constants."""
    ve = _vehicle_module()

    class Stub:
        inputs, outputs, n = ve.STOP_INPUTS, ve.STOP_OUTPUTS, 4
        y = (0.0, 0.0, 0.3) * 4  # Fx, My, Re

        def step_values(self, t, h, values):
            return self.y

    t0 = time.perf_counter()
    ve.simulate_stop_and_hold(Stub(), sc=ve.StopAndHold(t_end=t_end, tilt=6.5, tilt_time=1.0))
    return time.perf_counter() - t0


def _inputs(i: int) -> tuple[float, ...]:
    """Tyre inputs (Fz, Vx, Vy, omega) x 4 of step i, as the C host sets them."""
    return tuple(x for j in range(4) for x in (4000.0 + 10.0 * j, 10.0, 1e-3 * (i % 7), 26.0 + 1e-3 * (i % 5)))


def tyre_only_seconds(fmu: Path, steps: int = 10_000, empty: bool = False) -> float:
    """4 x ``steps`` SetReal/DoStep/GetReal from Python with new inputs every step (``empty``: the
    same number of calls, all ``fmi2GetReal`` of no variable, so that C does no work)."""
    from mftire.fmu.transient_host import TransientFMUs

    with TransientFMUs(fmu, inputs=("Fz", "Vx", "Vy", "omega"), outputs=("Fx", "Fy", "Mz", "My")) as tyres:
        values = [_inputs(i) for i in range(35)]  # the inputs repeat every 35 steps
        # empty: GetReal of no variable, on the same function objects and instances
        calls = [(e, e, e) for e in (partial(g.func, *g.args[:2], ctypes.c_size_t.from_param(0), g.args[3])
                                     for _, _, g in tyres._calls)]  # fmt: skip
        t0 = time.perf_counter()
        if empty:
            for _ in range(steps):
                for a, b, c in calls:
                    a() or b() or c()
        else:
            step = tyres.step_values
            for i in range(steps):
                step(i * 1e-3, 1e-3, values[i % 35])
        return time.perf_counter() - t0


C_HOST = r"""
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c, fmi2String m, ...)
{ (void)e; (void)n; (void)s; (void)c; (void)m; }

static double now(void) { struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t); return t.tv_sec + 1e-9 * t.tv_nsec; }

/* argv: library, GUID, steps, vr Fz Vx Vy omega, vr Fx Fy Mz My */
int main(int argc, char **argv)
{
    void *lib = dlopen(argv[1], RTLD_NOW);
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    long i, n = atol(argv[3]);
    int j;
    fmi2ValueReference in[4], out[4];
    fmi2Real u[4], y[4], sink = 0.0, t0, t1;
    fmi2Component c[4];
    fmi2InstantiateTYPE *inst;
    fmi2SetRealTYPE *setr;
    fmi2GetRealTYPE *getr;
    fmi2DoStepTYPE *step;
    fmi2EnterInitializationModeTYPE *en;
    fmi2ExitInitializationModeTYPE *ex;
    if (argc < 12 || !lib) return 2;
    inst = (fmi2InstantiateTYPE *)dlsym(lib, "fmi2Instantiate");
    setr = (fmi2SetRealTYPE *)dlsym(lib, "fmi2SetReal");
    getr = (fmi2GetRealTYPE *)dlsym(lib, "fmi2GetReal");
    step = (fmi2DoStepTYPE *)dlsym(lib, "fmi2DoStep");
    en = (fmi2EnterInitializationModeTYPE *)dlsym(lib, "fmi2EnterInitializationMode");
    ex = (fmi2ExitInitializationModeTYPE *)dlsym(lib, "fmi2ExitInitializationMode");
    for (j = 0; j < 4; j++) {
        in[j] = (unsigned)atoi(argv[4 + j]);
        out[j] = (unsigned)atoi(argv[8 + j]);
    }
    for (j = 0; j < 4; j++) {
        c[j] = inst("tyre", fmi2CoSimulation, argv[2], "", &cb, fmi2False, fmi2False);
        if (!c[j] || en(c[j]) != fmi2OK || ex(c[j]) != fmi2OK) return 3;
    }
    t0 = now();
    for (i = 0; i < n; i++)
        for (j = 0; j < 4; j++) {
            u[0] = 4000.0 + 10.0 * j; u[1] = 10.0; u[2] = 1e-3 * (double)(i % 7); u[3] = 26.0 + 1e-3 * (double)(i % 5);
            setr(c[j], in, 4, u);
            step(c[j], 1e-3 * (double)i, 1e-3, fmi2True);
            getr(c[j], out, 4, y);
            sink += y[0];
        }
    t1 = now();
    printf("%.6e %g\n", t1 - t0, sink);
    return 0;
}
"""


def c_host_command(fmu: Path, tmp: Path, steps: int = 10_000) -> list[str]:
    """Build the C host; its command line for 4 x ``steps`` Co-Simulation steps (SetReal, DoStep, GetReal)."""
    from fmpy import extract, read_model_description

    from mftire.fmu.export import find_compiler

    md = read_model_description(str(fmu))
    unzipdir = Path(extract(str(fmu), unzipdir=str(tmp / "host_fmu")))
    so = unzipdir / "binaries" / "linux64" / (md.coSimulation.modelIdentifier + ".so")
    exe = tmp / "transient_host"
    (tmp / "transient_host.c").write_text(C_HOST)
    subprocess.run([*find_compiler(), "-O2", "-std=c99", "-D_POSIX_C_SOURCE=199309L", "-I", str(unzipdir / "sources"),
                    str(tmp / "transient_host.c"), "-o", str(exe), "-ldl"], check=True)  # fmt: skip
    vr = {v.name: v.valueReference for v in md.modelVariables}
    args = [str(vr[k]) for k in ("Fz", "Vx", "Vy", "omega", "Fx", "Fy", "Mz", "My")]
    return [str(exe), str(so), md.guid, str(steps), *args]


def c_host_seconds(cmd: list[str]) -> float:
    res = subprocess.run(cmd, capture_output=True, text=True, check=True, env={"PATH": "/usr/bin:/bin"})
    return float(res.stdout.split()[0])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", default=str(DEFAULT_TIR))
    ap.add_argument("--n", type=int, default=200_000, help="derivative evaluations timed in C")
    ap.add_argument("--repeat", type=int, default=5, help="runs of each timing (median and best reported)")
    ap.add_argument("--workdir", help="keep the FMU and the C host here (default: a temporary folder)")
    args = ap.parse_args(argv)
    from mftire.fmu.export import export_fmu

    r = max(args.repeat, 1)
    with tempfile.TemporaryDirectory(prefix="mftire-bench-") as tmp:
        tmp = Path(args.workdir or tmp)
        tmp.mkdir(parents=True, exist_ok=True)
        t_der = c_derivative_seconds(args.tir, tmp / "probe", args.n)
        print(f"ME derivative evaluation in C (kinematics + rates): {t_der * 1e6:.3f} µs   (target <= 2 µs)")
        fmu = export_fmu(args.tir, tmp / "tyre_transient.fmu", transient=True)
        drift = manoeuvre_seconds(fmu, fast=True)[1]
        t_fast = _median(lambda: manoeuvre_seconds(fmu, fast=True)[0], r)
        t_wrap = _median(lambda: manoeuvre_seconds(fmu, fast=False)[0], r)
        t_veh = _median(vehicle_only_seconds, r)
        t_tyres = _median(lambda: tyre_only_seconds(fmu), r)
        t_empty = _median(lambda: tyre_only_seconds(fmu, empty=True), r)
        cmd = c_host_command(fmu, tmp)
        t_host = _median(lambda: c_host_seconds(cmd), r)
    print(f"10 s vehicle manoeuvre at 1 kHz, four transient tyre FMUs (Co-Simulation) through fmpy "
          f"(median / best of {r}):")  # fmt: skip
    print(f"  prebound FMI calls on fmpy's library: {t_fast[0]:.3f} / {t_fast[1]:.3f} s  -> {10.0 / t_fast[0]:5.1f}x"
          f" / {10.0 / t_fast[1]:5.1f}x real time (target >= 100x)")  # fmt: skip
    print(f"  fmpy wrapper methods:                 {t_wrap[0]:.3f} / {t_wrap[1]:.3f} s  -> {10.0 / t_wrap[0]:5.1f}x"
          f" / {10.0 / t_wrap[1]:5.1f}x real time")  # fmt: skip
    print(f"  parked on the 20 % slope: largest speed over the last second {drift * 1e3:.2e} mm/s")
    us = 1e6 / 10_000  # seconds per 10,000 steps -> µs per step
    print("Where a vehicle step goes (medians; µs per step of 4 tyres):")
    print(f"  vehicle model alone (stub tyres):                       {t_veh[0] * us:6.2f}")
    print(f"  tyre calls alone from Python (4 x SetReal/DoStep/GetReal): {t_tyres[0] * us:6.2f}")
    print(f"    of which the 12 ctypes calls with no C work:          {t_empty[0] * us:6.2f}  "
          f"({t_empty[0] * us / 12:.2f} µs per call)")  # fmt: skip
    print(f"  the same tyre steps from a C host (the FMU's own work): {t_host[0] * us:6.2f}  "
          f"({t_host[0] * us / 4:.2f} µs per tyre step; C alone {10.0 / t_host[0]:.0f}x real time)")  # fmt: skip
    floor = t_empty[0] + t_host[0]
    print(f"  fmpy floor (12 calls + the FMU's work, no vehicle):     {floor * us:6.2f}  -> at most "
          f"{10.0 / floor:.0f}x real time through ctypes")  # fmt: skip
    if args.workdir:
        print("C host kept: " + " ".join(cmd))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
