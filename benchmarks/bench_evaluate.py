"""Evaluator throughput: points per second for batches of 1, 1e3 and 1e5 points.

Run: ``python benchmarks/bench_evaluate.py``.  The baseline, measured in the same
run, is a plain Python loop calling the evaluator one point at a time; the ratio
column is batch throughput over that baseline.  Combined slip, mode 111.
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np

import mftire

ROOT = Path(__file__).resolve().parents[1]


def _inputs(tyre: mftire.Tyre, n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    F0 = tyre["FNOMIN"]
    return dict(
        Fz=rng.uniform(0.3 * F0, 1.5 * F0, n),
        kappa=rng.uniform(-0.5, 0.5, n),
        alpha=rng.uniform(-0.3, 0.3, n),
        gamma=rng.uniform(-0.05, 0.05, n),
        Vx=rng.uniform(5.0, 40.0, n),
    )


def _rate(fn, n_points: int, min_time: float = 1.0) -> float:
    fn()  # warm up
    reps, t0 = 0, time.perf_counter()
    while True:
        fn()
        reps += 1
        dt = time.perf_counter() - t0
        if dt >= min_time:
            return reps * n_points / dt


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", default=str(ROOT / "tirfiles" / "mfeval" / "MF61_255-55R20_mfeval4.0.tir"))
    ap.add_argument("--mode", type=int, default=111)
    ap.add_argument("--min-time", type=float, default=1.0, help="seconds per measurement")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    tyre = mftire.load(args.tir)

    loop_n = 200
    x = _inputs(tyre, loop_n)

    def loop():
        for i in range(loop_n):
            tyre.evaluate(x["Fz"][i], x["kappa"][i], x["alpha"][i], x["gamma"][i], Vx=x["Vx"][i], mode=args.mode)

    base = _rate(loop, loop_n, args.min_time)
    print(f"tyre {tyre.name} (FITTYP {tyre.fittyp}), mode {args.mode}")
    print(f"{'batch':>8} {'points/s':>12} {'ratio vs per-point loop':>24}")
    print(f"{'loop':>8} {base:12.4g} {1.0:24.1f}")
    for n in (1, 1_000, 100_000):
        x = _inputs(tyre, n)
        rate = _rate(lambda x=x: tyre.evaluate(**x, mode=args.mode), n, args.min_time)
        print(f"{n:8d} {rate:12.4g} {rate / base:24.1f}")


if __name__ == "__main__":
    main()
