"""``mftire demo`` end to end: wall time, CPU time of this process and of the workers, per step.

Run: ``python benchmarks/bench_demo.py [--quick] [--jobs N] [--serial]``.  Target (issue 15): the
full demo under 60 s wall on 2 cores.  The demo runs as ``mftire demo`` does (all cores by default,
``--jobs``); ``--serial`` also runs it with every step in this process one after the other
(``--jobs 1``) in the same run and prints the ratio.  The results that the demo's tests check
(cause, held-out errors, band coverage, the rig stage) are printed for each run and must agree.

On a shared machine the wall time follows the load (printed before and after each run): read the
CPU times.  ``idle estimate`` is the lower bound of the wall time on an idle machine with the
given cores: the larger of this process's CPU time (the steps that wait for each other) and the
total CPU time spread over the cores.
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import tempfile
import time

from mftire.demo import run_demo
from mftire.parallel import Executor

TARGET_S = 60.0


def _cpu() -> tuple[float, float]:
    s, c = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime, c.ru_utime + c.ru_stime


def _load() -> str:
    return "load average " + ", ".join(f"{x:.2f}" for x in os.getloadavg())


def _run(quick: bool, ex: Executor) -> dict:
    print(f"-- {ex.describe()} ({_load()})", flush=True)
    with tempfile.TemporaryDirectory() as out:
        (s0, c0), t0 = _cpu(), time.perf_counter()
        summary = run_demo(out, quick=quick, progress=True, executor=ex)
        (s1, c1), wall = _cpu(), time.perf_counter() - t0
    cpu_self, cpu_children = s1 - s0, c1 - c0
    cores = 1 if ex.scheduler else ex.workers
    idle = max(cpu_self, (cpu_self + cpu_children) / max(cores, 1))
    print(f"   wall {wall:6.1f} s   CPU {cpu_self + cpu_children:6.1f} s (this process {cpu_self:.1f} s, workers and "
          f"compiler {cpu_children:.1f} s)   idle estimate on {cores} core(s) >= {idle:.1f} s   ({_load()})")
    rig = summary["rig"]
    print(f"   cause {summary['cause']}, held-out Fx {summary['heldout_Fx_rms_pct_before']:.2f} -> "
          f"{summary['heldout_Fx_rms_pct_after']:.2f} % of peak, inside the prediction band "
          f"{summary.get('heldout_inside_prediction_band', float('nan')):.3f}; rig cause {rig['cause']}, Fx "
          f"{rig['heldout_Fx_rms_pct_before']:.2f} -> {rig['heldout_Fx_rms_pct_after']:.2f} %, Fy "
          f"{rig['heldout_Fy_rms_pct_before']:.2f} -> {rig['heldout_Fy_rms_pct_after']:.2f} %", flush=True)
    return {"wall": wall, "cpu": cpu_self + cpu_children, "summary": summary}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the reduced demo (mftire demo --quick, as in CI)")
    ap.add_argument("--jobs", type=int, default=0, help="local processes (default 0: all cores)")
    ap.add_argument("--serial", action="store_true", help="also run with --jobs 1 and print the ratio")
    args = ap.parse_args()
    par = _run(args.quick, Executor(jobs=args.jobs))
    ok = par["wall"] < TARGET_S or args.quick
    if args.serial:
        ser = _run(args.quick, Executor(jobs=1))
        same = ser["summary"] == par["summary"]
        print(f"{Executor(jobs=args.jobs).describe()} vs this process alone: {ser['wall'] / par['wall']:.2f}x wall, "
              f"CPU {par['cpu'] / ser['cpu']:.2f}x; summaries {'equal' if same else 'DIFFERENT'}")
        ok = ok and same
    if not args.quick:
        met = "met" if par["wall"] < TARGET_S else "not met"
        print(f"target < {TARGET_S:.0f} s wall on 2 cores: {met} in this run")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
