"""Transient tyre speed: one Model Exchange derivative in C, and a 4-tyre vehicle manoeuvre through fmpy.

Run: ``python benchmarks/bench_transient.py [--tir FILE] [--n 200000]``.

1. **ME derivative in C** -- the transient C model with a small harness
   (:func:`mftire.fmu.transient_export.build_probe_library`) loops, inside C, the work of
   one ``fmi2GetDerivatives`` after new inputs: the kinematics (one steady-state
   evaluation for the relaxation lengths and Re) and the state rates.  Target: <= 2 µs.
2. **Vehicle manoeuvre** -- the two-track car of ``validation/vehicle_example.py`` on
   four instances of the transient FMU in Co-Simulation at 1 kHz for 10 s (standstill,
   launch, stop, hold on a 20 % slope).  fmpy loads and instantiates the FMU; each step
   calls ``fmi2SetReal``/``fmi2DoStep``/``fmi2GetReal`` of fmpy's loaded library
   (:class:`mftire.fmu.transient_host.TransientFMUs`, direct ctypes calls, and through
   fmpy's wrapper methods).  Target: >= 100x faster than real time.  The tyre calls
   alone (no vehicle model) are timed too, and the same 4 x 10,000 tyre steps from a C
   host that ``dlopen``s the FMU binary (the FMU's own cost, without the Python/ctypes
   per-call overhead).
"""

from __future__ import annotations

import argparse
import ctypes
import importlib.util
import subprocess
import sys
import tempfile
import time
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


def manoeuvre_seconds(fmu: Path, fast: bool, t_end: float = 10.0) -> tuple[float, float]:
    """(wall seconds of the 10 s manoeuvre, largest |V| over its last second)."""
    from mftire.fmu.transient_host import TransientFMUs

    ve = _vehicle_module()
    sc = ve.StopAndHold(t_end=t_end, tilt=6.5, tilt_time=1.0)
    with TransientFMUs(fmu, ve.WHEELS, outputs=("Fx", "Fy", "Mz", "My", "Re"), fast=fast) as tyres:
        t0 = time.perf_counter()
        res = ve.simulate_stop_and_hold(tyres, sc=sc)
        dt = time.perf_counter() - t0
    last = res["t"] > t_end - 1.0
    return dt, float(abs(res["V"][last]).max())


def tyre_only_seconds(fmu: Path, steps: int = 10_000) -> float:
    from mftire.fmu.transient_host import TransientFMUs

    with TransientFMUs(fmu, outputs=("Fx", "Fy", "Mz", "My", "Re")) as tyres:
        tyres.u[:, 0], tyres.u[:, 1], tyres.u[:, 3] = 4000.0, 10.0, 26.0
        t0 = time.perf_counter()
        for i in range(steps):
            tyres.u[:, 2] = 1e-3 * (i % 7)  # new inputs every step
            tyres.step(i * 1e-3, 1e-3)
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


def c_host_seconds(fmu: Path, tmp: Path, steps: int = 10_000) -> float:
    """Seconds for 4 x ``steps`` Co-Simulation steps (SetReal, DoStep, GetReal) from a C host."""
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
    res = subprocess.run([str(exe), str(so), md.guid, str(steps), *args], capture_output=True, text=True,
                         check=True, env={"PATH": "/usr/bin:/bin"})  # fmt: skip
    return float(res.stdout.split()[0])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", default=str(DEFAULT_TIR))
    ap.add_argument("--n", type=int, default=200_000, help="derivative evaluations timed in C")
    args = ap.parse_args(argv)
    from mftire.fmu.export import export_fmu

    with tempfile.TemporaryDirectory(prefix="mftire-bench-") as tmp:
        tmp = Path(tmp)
        t_der = c_derivative_seconds(args.tir, tmp / "probe", args.n)
        print(f"ME derivative evaluation in C (kinematics + rates): {t_der * 1e6:.3f} µs   (target <= 2 µs)")
        fmu = export_fmu(args.tir, tmp / "tyre_transient.fmu", transient=True)
        t_fast, drift = manoeuvre_seconds(fmu, fast=True)
        t_wrap, _ = manoeuvre_seconds(fmu, fast=False)
        t_tyres = tyre_only_seconds(fmu)
        t_host = c_host_seconds(fmu, tmp)
    print("10 s vehicle manoeuvre at 1 kHz, four transient tyre FMUs (Co-Simulation) through fmpy:")
    print(f"  direct FMI calls on fmpy's library: {t_fast:.3f} s  -> {10.0 / t_fast:6.1f}x real time "
          "(target >= 100x)")  # fmt: skip
    print(f"  fmpy wrapper methods:               {t_wrap:.3f} s  -> {10.0 / t_wrap:6.1f}x real time")
    print(f"  tyre calls only (4 x SetReal/DoStep/GetReal per step, no vehicle): {t_tyres:.3f} s  -> "
          f"{10.0 / t_tyres:6.1f}x real time, {t_tyres / 40_000 * 1e6:.2f} µs per tyre step")  # fmt: skip
    print(f"  the same 4 x 10,000 tyre steps from a C host (dlopen): {t_host:.4f} s  -> {10.0 / t_host:7.1f}x real "
          f"time, {t_host / 40_000 * 1e6:.2f} µs per tyre step (the FMU's own cost)")  # fmt: skip
    print(f"  parked on the 20 % slope: largest speed over the last second {drift * 1e3:.2e} mm/s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
