"""``mftire diagnose`` on a 20,000-point campaign: wall time, against a plain staged fit in the same run.

Run: ``python benchmarks/bench_diagnose.py [--case NAME] [--repeat N]``.

The campaign is a case of ``validation/make_unanticipated_campaigns.py`` (default
``temperature_friction``: friction falling with a tread temperature of a thermal model, four
loads in blocks, three speeds) sampled densely, so that the same programme holds about 20,000
points, with its noise, load wander and 1 % outliers.  The plain MF 6.1 fit of the training rows
(:func:`mftire.fitting.fit_tir`, the diagnosis's starting point) is timed once as the baseline;
then the diagnosis, with the case's held-out condition, ``--repeat`` times (median printed).
Target (issue 11): under 60 s on 2 cores.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default="temperature_friction")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--points", type=int, default=20_000, help="target number of points")
    args = ap.parse_args()

    sys.path.insert(0, str(ROOT / "validation"))
    import make_unanticipated_campaigns as gen

    from mftire import Tyre
    from mftire.diagnosis.diagnose import diagnose
    from mftire.fitting import fit_tir

    case = gen.make_case(args.case, False)
    nk, na = gen.POINTS[False]
    runs = {r.kind for r in case.runs}
    per_run = {"braking": nk, "cornering": 2 * na - 1}
    n0 = sum(per_run[r.kind] for r in case.runs)
    factor = max(1.0, args.points / n0)
    gen.POINTS[False] = (int(round(nk * factor)), int(round(na * factor)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        data, _, _ = gen.simulate(case, False)
        gen._finish_holdout(case, data)
        hold = gen.holdout_mask(data, case.holdout_column, case.holdout_values)
        train = data[~hold].drop(columns=list(case.zero_channels))
        t0 = time.perf_counter()
        fit = fit_tir(train, gen.start_file(case, 7), progress=False)
        t_fit = time.perf_counter() - t0
        fitted = Tyre(fit.parameters)
        times, res = [], None
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            res = diagnose(data, fitted, holdout=(case.holdout_column, case.holdout_values), progress=False)
            times.append(time.perf_counter() - t0)
    med = statistics.median(times)
    print(f"campaign {args.case}: {len(data)} points ({len(train)} training), sweeps of {sorted(runs)}")
    print(f"plain staged fit (baseline): {t_fit:.1f} s")
    print(f"diagnose: median {med:.1f} s over {len(times)} runs (min {min(times):.1f}, max {max(times):.1f}); "
          f"ratio to the plain fit {med / t_fit:.2f}; target < 60 s")
    print(f"result: {res.summary()}")
    if res.significant:
        fx = [c for c in res.errors if c.channel in ("Fx", "Fy")]
        ssb = sum(c.rms_before**2 * c.n for c in fx)
        ssa = sum(c.rms_after**2 * c.n for c in fx)
        print(f"held-out Fx+Fy RMS cut {100 * (1 - np.sqrt(ssa / ssb)):.0f} %")
    return 0


if __name__ == "__main__":
    sys.exit(main())
