"""Transient tyre speed: one Model Exchange derivative in C, and a 4-tyre vehicle manoeuvre through fmpy.

Run: ``python benchmarks/bench_transient.py [--tir FILE] [--n 200000] [--repeat 5] [--workdir DIR] [--callgrind]
[--thermal]``.

``--thermal``: the same with the thermal block (issue 22): the shipped thermal ``.tir``
(``validation/data/thermal/thermal_tyre.tir``: a grip law on the surface node, a stiffness law on the bulk node,
``[MFTIRE_THERMAL]``), or ``--tir`` with a
``[MFTIRE_THERMAL]`` section; five states; the ME derivative in C then also evaluates the forces at the
transient slips for the heat and the node rates.

1. **ME derivative in C** -- the transient C model with a small harness
   (:func:`mftire.fmu.transient_export.build_probe_library`) loops, inside C, the work of
   one ``fmi2GetDerivatives`` after new inputs: the kinematics (one steady-state
   evaluation of the slip stiffnesses for the relaxation lengths, and Re) and the state
   rates.  Target: <= 2 µs.
2. **Vehicle manoeuvre** -- the two-track car of ``validation/vehicle_example.py`` on
   four instances of the transient FMU in Co-Simulation at 1 kHz for 10 s (standstill,
   launch, stop, hold on a 20 % slope), driven through fmpy
   (:class:`mftire.fmu.transient_host.TransientFMUs`) in its three modes: inside fmpy's
   container FMU (3 FMI calls per step), prebound calls of each instance (12 calls per
   step), fmpy's wrapper methods.  Target: >= 100x faster than real time.  Median (and
   best) of ``--repeat`` runs; the modes alternate, so that each sees the same machine.
3. **Where a vehicle step goes** (medians of ``--repeat`` runs, 10,000 steps each): the
   vehicle model alone (tyres replaced by a stub returning constants); the tyre calls
   alone from Python, with the manoeuvre's own tyre inputs (container and direct); the 12
   direct calls with no work in C (``fmi2GetReal`` of no variable: the ctypes cost of a
   call); and the same tyre steps from a C host that ``dlopen``s the FMU binary and
   replays the manoeuvre's tyre inputs (the FMU's own cost).
4. ``--callgrind``: the same parts counted in instructions per vehicle step with
   ``valgrind --tool=callgrind`` (the difference between a 10,000-step and a 1-step run,
   over 10,000), which does not depend on the machine's load.

With ``--workdir`` the FMU, the recorded tyre inputs and the C host are kept and the host's
command line is printed.
"""

from __future__ import annotations

import argparse
import ctypes
import importlib.util
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from functools import partial
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_TIR = ROOT / "tests" / "data" / "tir" / "MagicFormula61_Parameters.tir"
T_END = 10.0  #: the manoeuvre's length [s] (10,000 steps of 1 ms)


def c_derivative_seconds(tir, tmp: Path, n: int, thermal: bool = False) -> float:
    from mftire.fmu.transient_export import build_probe_library

    lib = ctypes.CDLL(str(build_probe_library(tir, tmp)))
    fn = lib.mt_probe_bench_thermal if thermal else lib.mt_probe_bench
    fn.restype = ctypes.c_double
    fn.argtypes = [ctypes.c_int, ctypes.POINTER(ctypes.c_double), ctypes.c_long]
    inputs = (ctypes.c_double * 8)(4000.0, 20.0, 0.3, 52.0, 0.01, 2.2e5, 1.0, 0.05)
    fn(111, inputs, max(n // 10, 1))  # warm-up
    return min(fn(111, inputs, n) for _ in range(3))


def _vehicle_module():
    spec = importlib.util.spec_from_file_location("vehicle_example", ROOT / "validation" / "vehicle_example.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules["vehicle_example"] = mod
    spec.loader.exec_module(mod)
    return mod


def _scenario(ve, t_end: float = T_END):
    return ve.StopAndHold(t_end=t_end, tilt=6.5, tilt_time=1.0)


def _median(fn, repeat: int) -> tuple[float, float]:
    """(median, best) of ``repeat`` calls of ``fn()``, each returning seconds."""
    times = [fn() for _ in range(repeat)]
    return statistics.median(times), min(times)


def manoeuvre(fmu: Path, mode: str, t_end: float = T_END) -> tuple[float, dict]:
    """(wall seconds of the manoeuvre's simulation loop, its result) with the tyres in ``mode``."""
    from mftire.fmu.transient_host import TransientFMUs

    ve = _vehicle_module()
    with TransientFMUs(fmu, ve.WHEELS, inputs=ve.STOP_INPUTS, outputs=ve.STOP_OUTPUTS, mode=mode) as tyres:
        t0 = time.perf_counter()
        res = ve.simulate_stop_and_hold(tyres, sc=_scenario(ve, t_end))
        return time.perf_counter() - t0, res


def vehicle_only_seconds(t_end: float = T_END) -> float:
    """The manoeuvre's vehicle model with the tyres replaced by a stub returning constants."""
    ve = _vehicle_module()

    class Stub:
        inputs, outputs, n = ve.STOP_INPUTS, ve.STOP_OUTPUTS, 4
        y = (0.0, 0.0, 0.3) * 4  # Fx, My, Re

        def step_values(self, t, h, values):
            return self.y

    t0 = time.perf_counter()
    ve.simulate_stop_and_hold(Stub(), sc=_scenario(ve, t_end))
    return time.perf_counter() - t0


def tyre_inputs(res: dict) -> list[tuple[float, ...]]:
    """The manoeuvre's tyre inputs (Fz, Vx, omega) x 4 of every step, from its result."""
    Fz, V, om = res["Fz"], res["V"], res["omega"]
    return [tuple(x for j in range(4) for x in (Fz[i, j], V[i], om[i, j])) for i in range(len(V))]


def tyre_only_seconds(fmu: Path, inputs: list, mode: str = "direct", empty: bool = False) -> float:
    """The tyre calls of the manoeuvre from Python, replaying its tyre inputs ``inputs`` (``empty``: the 12
    direct calls, all ``fmi2GetReal`` of no variable, so that C does no work)."""
    from mftire.fmu.transient_host import TransientFMUs

    ve = _vehicle_module()
    with TransientFMUs(fmu, ve.WHEELS, inputs=ve.STOP_INPUTS, outputs=ve.STOP_OUTPUTS, mode=mode) as tyres:
        if empty:  # GetReal of no variable, on the same function objects and instances
            calls = [(e, e, e) for e in (partial(g.func, *g.args[:2], ctypes.c_size_t.from_param(0), g.args[3])
                                         for _, _, g in tyres._calls)]  # fmt: skip
            t0 = time.perf_counter()
            for _ in inputs:
                for a, b, c in calls:
                    a() or b() or c()
            return time.perf_counter() - t0
        step, dt = tyres.step_values, 1e-3
        t0 = time.perf_counter()
        for i, u in enumerate(inputs):
            step(i * dt, dt, u)
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

/* argv: library, GUID, inputs file (steps x 4 x 3 doubles), steps, vr Fz Vx omega, vr Fx My Re */
int main(int argc, char **argv)
{
    void *lib;
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    long i, n;
    int j;
    fmi2ValueReference in[3], out[3];
    fmi2Real *u, y[3], sink = 0.0, t0, t1;
    fmi2Component c[4];
    fmi2InstantiateTYPE *inst;
    fmi2SetRealTYPE *setr;
    fmi2GetRealTYPE *getr;
    fmi2DoStepTYPE *step;
    fmi2EnterInitializationModeTYPE *en;
    fmi2ExitInitializationModeTYPE *ex;
    FILE *f;
    if (argc < 11) return 2;
    lib = dlopen(argv[1], RTLD_NOW);
    f = fopen(argv[3], "rb");
    n = atol(argv[4]);
    if (!lib || !f) return 2;
    u = (fmi2Real *)malloc(sizeof(fmi2Real) * 12 * (size_t)n);
    if (!u || fread(u, sizeof(fmi2Real) * 12, (size_t)n, f) != (size_t)n) return 2;
    fclose(f);
    inst = (fmi2InstantiateTYPE *)dlsym(lib, "fmi2Instantiate");
    setr = (fmi2SetRealTYPE *)dlsym(lib, "fmi2SetReal");
    getr = (fmi2GetRealTYPE *)dlsym(lib, "fmi2GetReal");
    step = (fmi2DoStepTYPE *)dlsym(lib, "fmi2DoStep");
    en = (fmi2EnterInitializationModeTYPE *)dlsym(lib, "fmi2EnterInitializationMode");
    ex = (fmi2ExitInitializationModeTYPE *)dlsym(lib, "fmi2ExitInitializationMode");
    for (j = 0; j < 3; j++) {
        in[j] = (unsigned)atoi(argv[5 + j]);
        out[j] = (unsigned)atoi(argv[8 + j]);
    }
    for (j = 0; j < 4; j++) {
        c[j] = inst("tyre", fmi2CoSimulation, argv[2], "", &cb, fmi2False, fmi2False);
        if (!c[j] || en(c[j]) != fmi2OK || ex(c[j]) != fmi2OK) return 3;
    }
    t0 = now();
    for (i = 0; i < n; i++)
        for (j = 0; j < 4; j++) {
            setr(c[j], in, 3, u + 12 * i + 3 * j);
            step(c[j], 1e-3 * (double)i, 1e-3, fmi2True);
            getr(c[j], out, 3, y);
            sink += y[0];
        }
    t1 = now();
    printf("%.6e %g\n", t1 - t0, sink);
    return 0;
}
"""


def c_host_command(fmu: Path, tmp: Path, inputs: list, steps: int | None = None) -> list[str]:
    """Build the C host and write the tyre inputs; its command line for ``steps`` (default all) steps of
    the four tyres (SetReal, DoStep, GetReal), replaying the manoeuvre's tyre inputs."""
    import struct

    from fmpy import extract, read_model_description

    from mftire.fmu.export import find_compiler

    md = read_model_description(str(fmu))
    unzipdir = Path(extract(str(fmu), unzipdir=str(tmp / "host_fmu")))
    so = unzipdir / "binaries" / "linux64" / (md.coSimulation.modelIdentifier + ".so")
    exe = tmp / "transient_host"
    (tmp / "transient_host.c").write_text(C_HOST)
    subprocess.run([*find_compiler(), "-O2", "-std=c99", "-D_POSIX_C_SOURCE=199309L", "-I", str(unzipdir / "sources"),
                    str(tmp / "transient_host.c"), "-o", str(exe), "-ldl"], check=True)  # fmt: skip
    data = tmp / "tyre_inputs.bin"
    data.write_bytes(b"".join(struct.pack("=12d", *u) for u in inputs))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    args = [str(vr[k]) for k in ("Fz", "Vx", "omega", "Fx", "My", "Re")]
    return [str(exe), str(so), md.guid, str(data), str(steps or len(inputs)), *args]


def c_host_seconds(cmd: list[str]) -> float:
    res = subprocess.run(cmd, capture_output=True, text=True, check=True, env={"PATH": "/usr/bin:/bin"})
    return float(res.stdout.split()[0])


# ------------------------------------------------------------------ instruction counts (callgrind)


def _callgrind_total(cmd: list[str], tmp: Path) -> int:
    out = tmp / "callgrind.out"
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}  # no BLAS thread spinning in the count
    subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", *cmd], check=True,
                   capture_output=True, env=env)  # fmt: skip
    m = re.search(r"^(?:summary|totals): (\d+)", out.read_text(), re.M)
    out.unlink()
    return int(m.group(1))


def instructions_per_step(cmd_for, tmp: Path, steps: int = 10_000) -> float:
    """Instructions per step of ``cmd_for(n)`` (a command running n steps): (I(steps) - I(1)) / (steps - 1)."""
    return (_callgrind_total(cmd_for(steps), tmp) - _callgrind_total(cmd_for(1), tmp)) / (steps - 1)


def _self_cmd(what: str, fmu: Path, inputs_file: Path):
    """This script running one part for n steps (``--part``), for callgrind."""
    return lambda n: [sys.executable, str(Path(__file__).resolve()), "--part", what, str(fmu), str(inputs_file), str(n)]


def run_part(what: str, fmu: Path, inputs_file: Path, n: int) -> None:
    """One part for n steps (n = 1 .. 10,000): the manoeuvre (``container``, ``direct``), the vehicle alone
    (``vehicle``), the tyre calls alone (``tyres-container``, ``tyres-direct``), the empty calls (``empty``)."""
    import struct

    t_end = n * 1e-3 - 1e-3  # the manoeuvre makes t_end / dt + 1 steps
    if what in ("container", "direct"):
        manoeuvre(fmu, what, t_end)
    elif what == "vehicle":
        vehicle_only_seconds(t_end)
    else:
        raw = inputs_file.read_bytes()
        inputs = [struct.unpack_from("=12d", raw, 96 * i) for i in range(n)]
        if what == "empty":
            tyre_only_seconds(fmu, inputs, "direct", empty=True)
        else:
            tyre_only_seconds(fmu, inputs, what.split("-")[1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", default=str(DEFAULT_TIR))
    ap.add_argument("--n", type=int, default=200_000, help="derivative evaluations timed in C")
    ap.add_argument("--repeat", type=int, default=5, help="runs of each timing (median and best reported)")
    ap.add_argument("--workdir", help="keep the FMU, the tyre inputs and the C host here (default: a temporary folder)")
    ap.add_argument("--callgrind", action="store_true", help="also count instructions per step with valgrind")
    ap.add_argument("--thermal", action="store_true", help="the transient FMU with its thermal block (issue 22)")
    ap.add_argument("--part", nargs=4, help=argparse.SUPPRESS)  # internal: one part under callgrind
    args = ap.parse_args(argv)
    tir = args.tir
    if args.thermal and args.tir == str(DEFAULT_TIR):
        spec = importlib.util.spec_from_file_location("thermal_block", ROOT / "validation" / "thermal_block.py")
        tb = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(tb)
        tir = tb.shipped_tir()
    if args.part:
        run_part(args.part[0], Path(args.part[1]), Path(args.part[2]), int(args.part[3]))
        return 0
    from mftire.fmu.export import export_fmu
    from mftire.fmu.transient_host import container_available

    r = max(args.repeat, 1)
    modes = ("container", "direct", "fmpy") if container_available() else ("direct", "fmpy")
    print(f"load average before: {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} {os.getloadavg()[2]:.2f}")
    with tempfile.TemporaryDirectory(prefix="mftire-bench-") as tmp:
        tmp = Path(args.workdir or tmp)
        tmp.mkdir(parents=True, exist_ok=True)
        t_der = c_derivative_seconds(tir, tmp / "probe", args.n, args.thermal)
        what = "kinematics + rates" + (" + forces, heat, node rates (thermal block)" if args.thermal else "")
        print(f"ME derivative evaluation in C ({what}): {t_der * 1e6:.3f} µs   (target <= 2 µs)")
        fmu = export_fmu(tir, tmp / "tyre_transient.fmu", transient=True, thermal=True if args.thermal else None)
        _, res = manoeuvre(fmu, modes[0])
        last = res["t"] > T_END - 1.0
        drift = float(abs(res["V"][last]).max())
        inputs = tyre_inputs(res)
        times = {m: [] for m in modes}
        for _ in range(r):  # alternate the modes: each sees the same machine state
            for m in modes:
                times[m].append(manoeuvre(fmu, m)[0])
        med = {m: (statistics.median(v), min(v)) for m, v in times.items()}
        t_veh = _median(vehicle_only_seconds, r)
        t_tyres = {m: _median(lambda m=m: tyre_only_seconds(fmu, inputs, m), r) for m in modes if m != "fmpy"}
        t_empty = _median(lambda: tyre_only_seconds(fmu, inputs, "direct", empty=True), r)
        cmd = c_host_command(fmu, tmp, inputs)
        t_host = _median(lambda: c_host_seconds(cmd), r)
        steps = len(inputs)
        print(f"{T_END:g} s vehicle manoeuvre at 1 kHz ({steps} steps), four transient tyre FMUs (Co-Simulation) "
              f"through fmpy (median / best of {r}):")  # fmt: skip
        label = {"container": "fmpy's container FMU, 3 calls/step", "direct": "prebound calls, 12 calls/step",
                 "fmpy": "fmpy's wrapper methods"}  # fmt: skip
        for m in modes:
            a, b = med[m]
            print(f"  {label[m]:37s} {a:.3f} / {b:.3f} s  -> {T_END / a:6.1f}x / {T_END / b:6.1f}x real time"
                  + ("   (target >= 100x)" if m == modes[0] else ""))  # fmt: skip
        print(f"  parked on the 20 % slope: largest speed over the last second {drift * 1e3:.2e} mm/s")
        us = 1e6 / steps  # seconds per run -> µs per step
        print("Where a vehicle step goes (medians; µs per step of 4 tyres):")
        rows = [("vehicle model alone (stub tyres)", t_veh[0])]
        rows += [(f"tyre calls alone from Python ({label[m]})", t[0]) for m, t in t_tyres.items()]
        rows += [("the 12 direct ctypes calls with no C work", t_empty[0])]
        rows += [("the tyre steps from a C host (the FMU's own work)", t_host[0])]
        for text, t in rows:
            print(f"  {text:60s} {t * us:6.2f}")
        print(f"  ({t_empty[0] * us / 12:.2f} µs per empty call; {t_host[0] * us / 4:.2f} µs per tyre step in C, "
              f"C alone {T_END / t_host[0]:.0f}x real time)")  # fmt: skip
        if args.callgrind:
            if not shutil.which("valgrind"):
                print("--callgrind: valgrind not found")
            else:
                print("Instructions per vehicle step (callgrind, (10,000 steps - 1 step) / 9,999):")
                inputs_file = Path(cmd[3])
                parts = [(m, f"manoeuvre, {label[m]}") for m in modes if m != "fmpy"]
                parts += [("vehicle", "vehicle model alone (stub tyres)")]
                parts += [(f"tyres-{m}", f"tyre calls alone, {label[m]}") for m in modes if m != "fmpy"]
                parts += [("empty", "the 12 direct ctypes calls with no C work")]
                for what, text in parts:
                    ins = instructions_per_step(_self_cmd(what, fmu, inputs_file), tmp)
                    print(f"  {text:60s} {ins / 1e3:6.1f} k")
                host = instructions_per_step(lambda n: [*cmd[:4], str(n), *cmd[5:]], tmp)
                text = "the tyre steps from a C host (the FMU's own work)"
                print(f"  {text:60s} {host / 1e3:6.1f} k")
        if args.workdir:
            print("C host kept: " + " ".join(cmd))
    print(f"load average after: {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} {os.getloadavg()[2]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
