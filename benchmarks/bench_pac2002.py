"""PAC2002 evaluation speed against MF 6.1 and MF 5.2, measured in the same run.

Run: ``python benchmarks/bench_pac2002.py``.  Each tyre is evaluated on the same
random operating points (loads relative to its own FNOMIN), one point per call
and in batches of 1e3 and 1e5 points, combined slip, mode 111.  The ratio column is
PAC2002 throughput over MF 6.1 throughput (>= 1 means PAC2002 is at least as
fast).  Each figure is the best of 5 repeats, and the tyres are measured
interleaved over several rounds, against the noise of a shared machine.
"""

from __future__ import annotations

import argparse
import sys
import time
import timeit
import warnings
from pathlib import Path

import mftire

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_evaluate import _inputs  # noqa: E402  (the same random operating points)

ROOT = Path(__file__).resolve().parents[1]
TYRES = {
    "MF 6.1": ROOT / "tests" / "data" / "tir" / "MagicFormula61_Parameters.tir",
    "MF 5.2": ROOT / "tests" / "data" / "tir" / "MagicFormula52_Parameters.tir",
    "PAC2002": ROOT / "tests" / "data" / "tir" / "chrono_HMMWV_Pac02Tire.tir",
}


def _rate(fn, n_points: int, min_time: float) -> float:
    """Points per second from the fastest of 5 repeats (the machine is shared: the minimum is
    the least disturbed measurement)."""
    fn()  # warm up
    t0 = time.perf_counter()
    fn()
    number = max(1, int(min_time / 5 / max(time.perf_counter() - t0, 1e-9)))
    best = min(timeit.repeat(fn, number=number, repeat=5)) / number
    return n_points / best


def _rates(tyre: mftire.Tyre, min_time: float) -> dict[str, float]:
    out = {}
    x = _inputs(tyre, 200)

    def loop():
        for i in range(200):
            tyre.evaluate(x["Fz"][i], x["kappa"][i], x["alpha"][i], x["gamma"][i], Vx=x["Vx"][i])

    out["1 point/call"] = _rate(loop, 200, min_time)
    for n in (1_000, 100_000):
        xb = _inputs(tyre, n)
        out[f"batch {n:g}"] = _rate(
            lambda xb=xb: tyre.evaluate(xb["Fz"], xb["kappa"], xb["alpha"], xb["gamma"], Vx=xb["Vx"]), n, min_time
        )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--min-time", type=float, default=1.0, help="seconds per measurement")
    ap.add_argument("--rounds", type=int, default=5, help="interleaved rounds; the best of each is kept")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    tyres = {k: mftire.load(p) for k, p in TYRES.items()}
    best: dict[str, dict[str, float]] = {k: {} for k in tyres}
    for _ in range(args.rounds):  # interleaved, so machine load affects all tyres alike
        for name, tyre in tyres.items():
            for case, r in _rates(tyre, args.min_time).items():
                best[name][case] = max(best[name].get(case, 0.0), r)
    cases = list(best["MF 6.1"])
    print(f"{'case':<16}" + "".join(f"{k + ' [pt/s]':>18}" for k in tyres) + f"{'PAC2002/MF 6.1':>16}")
    for case in cases:
        row = "".join(f"{best[k][case]:>18.4g}" for k in tyres)
        print(f"{case:<16}{row}{best['PAC2002'][case] / best['MF 6.1'][case]:>16.2f}")


if __name__ == "__main__":
    main()
