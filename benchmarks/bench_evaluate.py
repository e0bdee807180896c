"""Evaluator throughput: the compiled kernel against the numpy reference and a per-point loop.

Run: ``python benchmarks/bench_evaluate.py [--tir FILE] [--repeat 5]``.  Every figure is
measured in the same run, each the median of ``--repeat`` measurements:

* forces only (``channels=("Fx", "Fy")``) and all 30 channels at 1e5 points, mode 111,
  by the kernel and by the numpy reference (``backend="numpy"``);
* a per-point Python loop calling ``Tyre.evaluate`` one point at a time (the baseline,
  kernel and numpy), whose points/s is the single-call latency inverted;
* the single-point call of issue 15 (``tyre.evaluate(Fz=4000.0, kappa=-0.1, alpha=0.05,
  gamma=0.0, Vx=20.0)``, all 30 channels) by the latency path of scalar calls, by the general
  path (the same call with ``channels=OUTPUT_NAMES``) and by the numpy reference, each the
  fastest batch of calls, and the latency path split into the C call, the point function and
  ``Tyre.evaluate``'s checks; ``--callgrind N`` makes only N such calls, for instruction counts
  with ``valgrind --tool=callgrind`` (the difference of two runs over the difference of N);
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


def _latency(fn, min_time: float, batch: int = 200) -> float:
    """Microseconds per call of ``fn``: the fastest of batches of ``batch`` calls made for
    ``min_time`` seconds (timeit's convention: the minimum is the cost, the rest is the other
    processes of a shared machine)."""
    fn()
    best, t_end = float("inf"), time.perf_counter() + min_time
    while True:
        t0 = time.perf_counter()
        for _ in range(batch):
            fn()
        t1 = time.perf_counter()
        best = min(best, (t1 - t0) / batch)
        if t1 >= t_end:
            return best * 1e6


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


#: The single-point call of issue 15: one operating point as Python floats, all 30 channels.
POINT = dict(Fz=4000.0, kappa=-0.1, alpha=0.05, gamma=0.0, Vx=20.0)


def _single_point(tyre: mftire.Tyre, mode: int, t_min: float, repeat: int, loop_kernel: float, loop_numpy: float):
    """The single-point call by the latency path, by the general path and by the numpy reference
    (interleaved: each ratio within one round; each time the fastest batch, :func:`_latency`),
    and where the latency path's time goes."""
    from mftire.mf.solver import OUTPUT_NAMES

    calls = {  # the call as a user writes it (keywords), and with the same keywords otherwise
        "kernel, latency path": lambda: tyre.evaluate(Fz=4000.0, kappa=-0.1, alpha=0.05, gamma=0.0, Vx=20.0, mode=mode),
        # all channels named: the same outputs through evaluate_arrays and kernel.evaluate
        "kernel, general path": lambda: tyre.evaluate(Fz=4000.0, kappa=-0.1, alpha=0.05, gamma=0.0, Vx=20.0,
                                                      mode=mode, channels=OUTPUT_NAMES),
        "numpy reference": lambda: tyre.evaluate(Fz=4000.0, kappa=-0.1, alpha=0.05, gamma=0.0, Vx=20.0, mode=mode,
                                                 backend="numpy"),
    }  # fmt: skip
    times: dict[str, list[float]] = {k: [] for k in calls}
    for _ in range(repeat):
        for k, fn in calls.items():
            times[k].append(_latency(fn, t_min / 2, batch=2 if k == "numpy reference" else 200))
    us = {k: statistics.median(v) for k, v in times.items()}
    faster = {k: statistics.median(a / b for a, b in zip(v, times["kernel, latency path"], strict=True))
              for k, v in times.items()}  # fmt: skip
    args = ", ".join(f"{k}={v}" for k, v in POINT.items())
    print(f"single-point call tyre.evaluate({args}), mode {mode}, all 30 channels (medians of {repeat}):")
    print(f"  kernel, latency path    {us['kernel, latency path']:8.2f} us   (target <= 5 us)")
    print(f"  kernel, general path    {us['kernel, general path']:8.2f} us   "
          f"{faster['kernel, general path']:.2f}x the latency path's time (channels=OUTPUT_NAMES)")  # fmt: skip
    print(f"  numpy reference         {us['numpy reference']:8.1f} us   "
          f"{faster['numpy reference']:.0f}x the latency path's time")  # fmt: skip
    print(f"  per-point loop (500 different points): kernel {1e6 / loop_kernel:.2f} us/point, "
          f"numpy {1e6 / loop_numpy:.1f} us/point")  # fmt: skip

    # where the latency path's time goes: the C call alone, then the point function (buffer,
    # numpy scalars, MFResult), then Tyre.evaluate (input checks, unit warnings, the state check)
    tyre.evaluate(**POINT, mode=mode)
    point = tyre._point.evaluate
    f, (n_terms, c_params, c_terms) = kernel.load().mf_kernel_point, point.packed[3:6]
    io = kernel._c_double_io(n_terms, 0, mode, 0, kernel._ALL, 4000.0, -0.1, 0.05, 0.0, 0.0, 20.0, tyre["INFLPRES"])
    layers = {
        "C only (mf_kernel_point)": lambda: f(c_params, c_terms, io),
        "+ point function": lambda: point(4000.0, -0.1, 0.05, 0.0, 0.0, 20.0, None, None, mode),
        "+ Tyre.evaluate": calls["kernel, latency path"],
    }
    print("  where the latency path's time goes, cumulative:")
    for name, fn in layers.items():
        t = statistics.median(_latency(fn, t_min / 4) for _ in range(repeat))
        print(f"    {name:26s} {t:7.2f} us")


def _callgrind(tyre: mftire.Tyre, mode: int, n: int) -> None:
    """Only ``n`` single-point calls (after two warm-up calls): run twice under
    ``valgrind --tool=callgrind`` with different ``n``; the difference of the instruction counts
    over the difference of ``n`` is the machine-independent cost of one call."""
    for _ in range(n + 2):
        tyre.evaluate(Fz=4000.0, kappa=-0.1, alpha=0.05, gamma=0.0, Vx=20.0, mode=mode)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", default=str(ROOT / "tirfiles" / "mfeval" / "MF61_255-55R20_mfeval4.0.tir"))
    ap.add_argument("--mode", type=int, default=111)
    ap.add_argument("--min-time", type=float, default=0.5, help="seconds per measurement")
    ap.add_argument("--repeat", type=int, default=5, help="measurements per figure (the median is printed)")
    ap.add_argument("--no-memory", action="store_true", help="skip the 1e6-point peak-memory measurement")
    ap.add_argument("--callgrind", type=int, metavar="N", help="only N single-point calls (see _callgrind)")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    tyre = mftire.load(args.tir)
    if not kernel.available():
        raise SystemExit(f"the compiled kernel is not available: {kernel.status()}")
    mode, t_min = args.mode, args.min_time
    if args.callgrind is not None:
        return _callgrind(tyre, mode, args.callgrind)

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
    print(f"kernel / numpy, same run: forces {rf:.2f}x, all channels {ra:.2f}x, per-point loop {rl:.1f}x")
    print(f"targets: forces >= 1e7 pts/s: {med['forces 1e5, kernel']:.3g}; all >= 5e6: {med['all 1e5, kernel']:.3g}")
    _single_point(tyre, mode, t_min, args.repeat, med["loop, kernel"], med["loop, numpy"])

    if not args.no_memory:
        x6 = _inputs(tyre, 1_000_000)
        outputs = 30 * 8 * 1_000_000
        for backend in ("kernel", "numpy"):
            peak = _peak(lambda b=backend: tyre.evaluate(**x6, mode=mode, backend=b))
            print(f"peak memory at 1e6 points, {backend}: {peak / 2**20:.0f} MiB = {peak / outputs:.2f}x the outputs "
                  f"({outputs / 2**20:.0f} MiB; target <= 1.2x)")  # fmt: skip


if __name__ == "__main__":
    main()
