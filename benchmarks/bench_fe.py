"""FE-surrogate speed: one 50-point braking sweep and the full thesis campaign.

Run: ``python benchmarks/bench_fe.py``.  Targets (issue 4, 2-core machine): the braking
sweep (free-rolling search included) under 2 s, the full campaign (0.4/0.8/1.2 LI; braking
at 20..100 km/h; cornering and combined at 60 km/h; nominal pressure and +-0.5 bar) under
2 minutes.  Exits non-zero when a target is missed.
"""

from __future__ import annotations

import argparse
import sys
import time

from mftire.fe.config import load_tyre
from mftire.fe.sweeps import KMH, campaign, sweep

TARGET_SWEEP_S = 2.0
TARGET_CAMPAIGN_S = 120.0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tyre", default="default")
    ap.add_argument("--repeat", type=int, default=3, help="repetitions of the braking sweep (best is reported)")
    args = ap.parse_args()
    tyre = load_tyre(args.tyre)
    li = tyre.load_index_load
    best = float("inf")
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        df = sweep(tyre, "braking", 0.8 * li, 60 * KMH, tyre.size.nominal_pressure, n_kappa=50, progress=False)
        best = min(best, time.perf_counter() - t0)
    assert len(df) == 50
    print(f"braking sweep, 50 points:  {best:7.3f} s   (target < {TARGET_SWEEP_S:.0f} s)")
    t0 = time.perf_counter()
    table, free = campaign(tyre, quick=False, progress=False)
    dt = time.perf_counter() - t0
    print(f"full campaign, {len(table)} points, {len(free)} free-rolling conditions: {dt:7.1f} s   "
          f"(target < {TARGET_CAMPAIGN_S:.0f} s)")
    return 0 if (best < TARGET_SWEEP_S and dt < TARGET_CAMPAIGN_S) else 1


if __name__ == "__main__":
    sys.exit(main())
