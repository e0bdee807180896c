"""Tyre FMU speed: C cost per evaluation, and the per-step overhead of fmpy.

Run: ``python benchmarks/bench_fmu.py [--tir FILE ...] [--n 200000] [--repeat R] [--c-only]``.

1. **C cost per evaluation** -- a small C host (compiled here) ``dlopen``s the FMU
   binary and loops ``fmi2SetReal`` (load, slip, slip angle, camber, speed; new
   values every call, so every call re-evaluates) + ``fmi2GetReal`` (all 19 outputs).  Target: <= 1 µs.  The
   same loop through ``ctypes`` is shown for comparison (dominated by ctypes).  ``--repeat R``: the C loop
   R times, the fastest shown (on a shared machine; compare trees back to back).
2. **fmpy overhead per step** -- ``fmpy.simulate_fmu`` over 5,000 communication
   steps (Co-Simulation and Model Exchange), divided by the number of steps.
"""

from __future__ import annotations

import argparse
import ctypes
import os
import subprocess
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_TIRS = [ROOT / "tests" / "data" / "tir" / f"MagicFormula6{v}_Parameters.tir" for v in (1, 2)] + [
    ROOT / "tests" / "data" / "tir" / "MagicFormula52_Parameters.tir"
]

C_BENCH = r"""
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c, fmi2String m, ...)
{ (void)e; (void)n; (void)s; (void)c; (void)m; }

static double now(void) { struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t); return t.tv_sec + 1e-9 * t.tv_nsec; }

int main(int argc, char **argv)
{
    void *lib = dlopen(argv[1], RTLD_NOW);
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    long i, n = atol(argv[3]);
    unsigned first_out = (unsigned)atoi(argv[4]);
    fmi2ValueReference in[5] = {1, 2, 3, 4, 6}, out[19];
    fmi2Real u[5] = {4000.0, 0.0, 0.05, 0.02, 20.0}, y[19], sink = 0.0, t0, t1;
    fmi2Component c;
    fmi2InstantiateTYPE *inst = (fmi2InstantiateTYPE *)dlsym(lib, "fmi2Instantiate");
    fmi2SetRealTYPE *setr = (fmi2SetRealTYPE *)dlsym(lib, "fmi2SetReal");
    fmi2GetRealTYPE *getr = (fmi2GetRealTYPE *)dlsym(lib, "fmi2GetReal");
    fmi2EnterInitializationModeTYPE *en = (fmi2EnterInitializationModeTYPE *)dlsym(lib, "fmi2EnterInitializationMode");
    fmi2ExitInitializationModeTYPE *ex = (fmi2ExitInitializationModeTYPE *)dlsym(lib, "fmi2ExitInitializationMode");
    for (i = 0; i < 19; i++) out[i] = first_out + (unsigned)i;
    c = inst("bench", fmi2ModelExchange, argv[2], "", &cb, fmi2False, fmi2False);
    if (!c || en(c) != fmi2OK || ex(c) != fmi2OK) return 2;
    t0 = now();
    for (i = 0; i < n; i++) {
        u[1] = -0.3 + 0.6 * (double)(i % 1000) / 1000.0;   /* a new slip every call */
        u[2] = 0.1 * (double)(i % 37) / 37.0 - 0.05;
        u[3] = 0.04 * (double)(i % 11) / 11.0 - 0.02;
        u[0] = 2000.0 + 4000.0 * (double)(i % 13) / 13.0;
        setr(c, in, 5, u);
        getr(c, out, 19, y);
        sink += y[0];
    }
    t1 = now();
    printf("%.6e %g\n", (t1 - t0) / (double)n, sink);
    return 0;
}
"""


def _export(tir, tmp: Path) -> tuple[Path, str, dict]:
    from fmpy import extract, read_model_description

    from mftire.fmu.export import export_fmu

    fmu = export_fmu(tir, tmp / (Path(tir).stem + ".fmu"))
    md = read_model_description(str(fmu))
    unzipdir = extract(str(fmu), unzipdir=str(tmp / Path(tir).stem))
    so = Path(unzipdir) / "binaries" / "linux64" / (md.modelExchange.modelIdentifier + ".so")
    vr = {v.name: v.valueReference for v in md.modelVariables}
    return fmu, str(so), {"guid": md.guid, "vr": vr, "unzipdir": unzipdir}


def c_loop(so: str, info: dict, n: int, tmp: Path) -> float:
    """Seconds per evaluation (SetReal + GetReal of all outputs) from a C loop."""
    from mftire.fmu.export import find_compiler

    exe = tmp / "bench_host"
    if not exe.exists():
        (tmp / "bench_host.c").write_text(C_BENCH)
        subprocess.run([*find_compiler(), "-O2", "-std=c99", "-D_POSIX_C_SOURCE=199309L", "-I",
                        os.path.join(info["unzipdir"], "sources"), str(tmp / "bench_host.c"), "-o", str(exe), "-ldl"],
                       check=True)  # fmt: skip
    vr = info["vr"]
    assert [vr[k] for k in ("Fz", "kappa", "alpha", "gamma", "Vx")] == [1, 2, 3, 4, 6]
    res = subprocess.run([str(exe), so, info["guid"], str(n), str(vr["Fx"])], capture_output=True, text=True,
                         check=True, env={"PATH": "/usr/bin:/bin"})  # fmt: skip
    return float(res.stdout.split()[0])


def ctypes_loop(so: str, info: dict, n: int) -> float:
    """Seconds per evaluation from a Python loop calling the binary through ctypes."""
    from mftire.fmu.host import make_callbacks

    lib = ctypes.CDLL(so)
    cb = make_callbacks()
    lib.fmi2Instantiate.restype = ctypes.c_void_p
    c = ctypes.c_void_p(lib.fmi2Instantiate(b"bench", 0, info["guid"].encode(), b"", ctypes.byref(cb), 0, 0))
    lib.fmi2EnterInitializationMode(c)
    lib.fmi2ExitInitializationMode(c)
    vr = info["vr"]
    vin = (ctypes.c_uint * 4)(vr["Fz"], vr["kappa"], vr["alpha"], vr["Vx"])
    vout = (ctypes.c_uint * 19)(*range(vr["Fx"], vr["Fx"] + 19))
    u = (ctypes.c_double * 4)(4000.0, 0.0, 0.05, 20.0)
    y = (ctypes.c_double * 19)()
    set_real, get_real = lib.fmi2SetReal, lib.fmi2GetReal
    t0 = time.perf_counter()
    for i in range(n):
        u[1] = -0.3 + 0.6 * (i % 1000) / 1000.0
        set_real(c, vin, 4, u)
        get_real(c, vout, 19, y)
    dt = (time.perf_counter() - t0) / n
    lib.fmi2FreeInstance(c)
    return dt


def fmpy_per_step(fmu: Path, fmi_type: str, steps: int = 5000) -> float:
    """Seconds per communication step of fmpy.simulate_fmu (no inputs, all outputs recorded)."""
    from fmpy import simulate_fmu

    h = 1e-3
    t0 = time.perf_counter()
    simulate_fmu(str(fmu), fmi_type=fmi_type, stop_time=steps * h, step_size=h, output_interval=h)
    return (time.perf_counter() - t0) / steps


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", nargs="*", default=[str(t) for t in DEFAULT_TIRS])
    ap.add_argument("--n", type=int, default=200_000, help="evaluations in the C loop")
    ap.add_argument("--repeat", type=int, default=1, help="C loops per tyre, the fastest shown (default 1)")
    ap.add_argument("--c-only", action="store_true", help="the C loop only (no ctypes loop, no fmpy)")
    args = ap.parse_args(argv)
    print(f"{'tyre':32s} {'C loop':>12s} {'ctypes loop':>12s} {'fmpy CS/step':>13s} {'fmpy ME/step':>13s}")
    with tempfile.TemporaryDirectory(prefix="mftire-bench-") as tmp:
        tmp = Path(tmp)
        for tir in args.tir:
            fmu, so, info = _export(tir, tmp)
            t_c = min(c_loop(so, info, args.n, tmp) for _ in range(max(1, args.repeat)))
            if args.c_only:
                print(f"{Path(tir).name:32s} {t_c * 1e6:9.3f} µs")
                continue
            t_ct = ctypes_loop(so, info, 20_000)
            t_cs = fmpy_per_step(fmu, "CoSimulation")
            t_me = fmpy_per_step(fmu, "ModelExchange")
            print(f"{Path(tir).name:32s} {t_c * 1e6:9.3f} µs {t_ct * 1e6:9.2f} µs {t_cs * 1e6:10.1f} µs "
                  f"{t_me * 1e6:10.1f} µs")  # fmt: skip
    print("C loop: fmi2SetReal(5 inputs) + fmi2GetReal(19 outputs), a full evaluation each; target <= 1 µs.")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
