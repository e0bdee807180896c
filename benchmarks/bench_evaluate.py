"""Evaluator throughput: the compiled kernel against the numpy reference and a per-point loop.

Run: ``python benchmarks/bench_evaluate.py [--tir FILE] [--repeat 5]``.  Every figure is
measured in the same run, each the median of ``--repeat`` measurements:

* forces only (``channels=("Fx", "Fy")``) and all 30 channels at 1e5 points, mode 111,
  by the kernel and by the numpy reference (``backend="numpy"``);
* a per-point Python loop calling ``Tyre.evaluate`` one point at a time (the baseline,
  kernel and numpy), whose points/s is the single-call latency inverted;
* the peak memory of one call at 1e6 points (all channels) over the outputs themselves
  (30 x 8 bytes x 1e6), by :mod:`tracemalloc` (numpy reports its allocations to it).

Targets (issue 15): >= 1e7 points/s for the forces and >= 5e6 for all channels at 1e5
points on one core, <= 5 us per single-point call, peak memory <= 1.2x the outputs.
"""

from __future__ import annotations

import argparse
import gc
import statistics
import time
import tracemalloc
import warnings
from pathlib import Path

import numpy as np

import mftire
from mftire.mf import kernel

ROOT = Path(__file__).resolve().parents[1]
FORCES = ("Fx", "Fy")


def _inputs(tyre: mftire.Tyre, n: int, seed: int = 0) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    F0 = tyre["FNOMIN"]
    return dict(
        Fz=rng.uniform(0.3 * F0, 1.5 * F0, n),
        kappa=rng.uniform(-0.5, 0.5, n),
        alpha=rng.uniform(-0.3, 0.3, n),
        gamma=rng.uniform(-0.05, 0.05, n),
        Vx=rng.uniform(5.0, 40.0, n),
    )


def _rate(fn, n_points: int, min_time: float) -> float:
    """Points per second of ``fn`` (one warm-up call, then repeated for ``min_time`` seconds)."""
    fn()
    reps, t0 = 0, time.perf_counter()
    while True:
        fn()
        reps += 1
        dt = time.perf_counter() - t0
        if dt >= min_time:
            return reps * n_points / dt


def _peak(fn) -> int:
    """Peak bytes allocated (tracemalloc) during ``fn()`` above what was allocated before; the
    result is dropped before the measurement ends only after the peak is read."""
    gc.collect()
    tracemalloc.start()
    tracemalloc.reset_peak()
    base = tracemalloc.get_traced_memory()[0]
    out = fn()
    peak = tracemalloc.get_traced_memory()[1] - base
    tracemalloc.stop()
    del out
    return peak


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", default=str(ROOT / "tirfiles" / "mfeval" / "MF61_255-55R20_mfeval4.0.tir"))
    ap.add_argument("--mode", type=int, default=111)
    ap.add_argument("--min-time", type=float, default=0.5, help="seconds per measurement")
    ap.add_argument("--repeat", type=int, default=5, help="measurements per figure (the median is printed)")
    ap.add_argument("--no-memory", action="store_true", help="skip the 1e6-point peak-memory measurement")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    tyre = mftire.load(args.tir)
    if not kernel.available():
        raise SystemExit(f"the compiled kernel is not available: {kernel.status()}")
    mode, t_min = args.mode, args.min_time

    loop_n = 500
    xl = _inputs(tyre, loop_n)
    scalars = [tuple(float(xl[k][i]) for k in ("Fz", "kappa", "alpha", "gamma", "Vx")) for i in range(loop_n)]
    big = _inputs(tyre, 100_000)

    def loop(backend: str):
        def run():
            for Fz, kappa, alpha, gamma, Vx in scalars:
                tyre.evaluate(Fz, kappa, alpha, gamma, Vx=Vx, mode=mode, backend=backend)

        return run

    cases = {
        "loop, kernel": (loop("kernel"), loop_n),
        "loop, numpy": (loop("numpy"), loop_n),
        "forces 1e5, kernel": (lambda: tyre.evaluate(**big, mode=mode, channels=FORCES, backend="kernel"), 100_000),
        "forces 1e5, numpy": (lambda: tyre.evaluate(**big, mode=mode, channels=FORCES, backend="numpy"), 100_000),
        "all 1e5, kernel": (lambda: tyre.evaluate(**big, mode=mode, backend="kernel"), 100_000),
        "all 1e5, numpy": (lambda: tyre.evaluate(**big, mode=mode, backend="numpy"), 100_000),
    }
    runs: dict[str, list[float]] = {k: [] for k in cases}
    ratios: dict[str, list[float]] = {k: [] for k in ("forces", "all", "loop")}
    for _ in range(args.repeat):  # interleaved, so that each ratio is taken within one round
        r = {k: _rate(fn, n, t_min) for k, (fn, n) in cases.items()}
        for k, v in r.items():
            runs[k].append(v)
        ratios["forces"].append(r["forces 1e5, kernel"] / r["forces 1e5, numpy"])
        ratios["all"].append(r["all 1e5, kernel"] / r["all 1e5, numpy"])
        ratios["loop"].append(r["loop, kernel"] / r["loop, numpy"])
    med = {k: statistics.median(v) for k, v in runs.items()}
    base = med["loop, numpy"]

    print(f"tyre {tyre.name} (FITTYP {tyre.fittyp}), mode {mode}; {kernel.status()}")
    print(f"medians of {args.repeat} runs; ratios within each run, then their median")
    print(f"{'case':22s} {'points/s':>11s} {'us/point':>9s} {'x numpy-loop':>13s}")
    for k, v in med.items():
        print(f"{k:22s} {v:11.4g} {1e6 / v:9.3g} {v / base:13.1f}")
    rf, ra, rl = (statistics.median(ratios[k]) for k in ("forces", "all", "loop"))
    print(f"kernel / numpy, same run: forces {rf:.2f}x, all channels {ra:.2f}x, single point {rl:.1f}x")
    print(f"single-point call: kernel {1e6 / med['loop, kernel']:.2f} us, numpy {1e6 / med['loop, numpy']:.1f} us "
          "(target <= 5 us)")  # fmt: skip
    print(f"targets: forces >= 1e7 pts/s: {med['forces 1e5, kernel']:.3g}; all >= 5e6: {med['all 1e5, kernel']:.3g}")

    # where the time of one single-point call goes (medians of --repeat timings of 2000 calls)
    from mftire.mf import solver

    lib = kernel.load()
    packed = kernel._packed(tyre.flat, tyre.extension_set)
    io = kernel._c_double_io(0, 0, mode, 0, kernel._ALL, 4000.0, 0.1, 0.05, 0.0, 0.0, tyre["LONGVL"], tyre["INFLPRES"], 0.0)
    layers = {
        "C only (ctypes call)": lambda: lib.mf_kernel_point(packed[4], packed[5], io),
        "+ kernel.evaluate": lambda: kernel.evaluate(tyre.flat, 4000.0, 0.1, 0.05, 0.0, 0.0, None, None, None, mode,
                                                     tyre.extension_set, None),
        "+ evaluate_arrays": lambda: solver.evaluate_arrays(tyre.flat, 4000.0, 0.1, 0.05, mode=mode,
                                                            extensions=tyre.extension_set),
        "+ Tyre.evaluate": lambda: tyre.evaluate(4000.0, 0.1, 0.05, mode=mode),
    }  # fmt: skip
    print("single-point call, cumulative by layer:")
    for name, fn in layers.items():
        us = statistics.median(1e6 / _rate(fn, 1, t_min / 4) for _ in range(args.repeat))
        print(f"  {name:22s} {us:7.2f} us")

    if not args.no_memory:
        x6 = _inputs(tyre, 1_000_000)
        outputs = 30 * 8 * 1_000_000
        for backend in ("kernel", "numpy"):
            peak = _peak(lambda b=backend: tyre.evaluate(**x6, mode=mode, backend=b))
            print(f"peak memory at 1e6 points, {backend}: {peak / 2**20:.0f} MiB = {peak / outputs:.2f}x the outputs "
                  f"({outputs / 2**20:.0f} MiB; target <= 1.2x)")  # fmt: skip


if __name__ == "__main__":
    main()
