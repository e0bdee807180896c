"""Staged Magic Formula fit of a large data set: wall time per stage.

Run: ``python benchmarks/bench_fit.py [--tir FILE] [--seed N] [--repeat N] [--no-baseline]``.
The data are synthetic sweeps of the tyre (5 loads x 3 cambers x 3 pressures x 2 speeds;
pure kappa and alpha sweeps of 61 points, four combined sweeps of 31 points per
condition: 22,140 points) with 1 % Gaussian noise and 1 % gross outliers; the template
is the tyre with every fitted coefficient perturbed by up to +-30 %.  Target (issue 15):
a full staged fit of >= 20,000 points in under 5 s on one core.

The fit runs with exact (algorithmic, reverse-mode) Jacobians, and, as the baseline measured in the
same run, with forward finite differences (``fit_tir(..., jacobian="2-point")``); the
ratio of the medians of ``--repeat`` runs is printed.  Both run with one BLAS thread.  The
CPU time of the process is printed too: on a machine shared with other jobs it stands
for the wall time on one free core.
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np

from mftire.fitting import fit_tir
from mftire.fitting.fit_report import channel_summary, compute_metrics
from mftire.fitting.stages import FITTED_KEYS
from mftire.fitting.synthetic import synthetic_sweeps
from mftire.iotools.tir import read_tir
from mftire.parameters import with_defaults

ROOT = Path(__file__).resolve().parents[1]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", default=str(ROOT / "tests/data/tir/mfeval/MagicFormula61_Paramerters.tir"))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repeat", type=int, default=3, help="runs of each variant (median reported)")
    ap.add_argument("--no-baseline", action="store_true", help="skip the finite-difference baseline")
    args = ap.parse_args()

    true = read_tir(args.tir)
    pt = with_defaults(true)
    F0, Pn, V0 = pt["FNOMIN"], pt["NOMPRES"], pt["LONGVL"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        data = synthetic_sweeps(true, np.array([0.4, 0.7, 1.0, 1.3, 1.6]) * F0, np.radians([-3.0, 0.0, 4.0]),
                                [0.9 * Pn, Pn, 1.15 * Pn], [0.6 * V0, V0], n_kappa=61, n_alpha=61,
                                n_combined=31, noise=0.01, outliers=0.01, seed=args.seed)
    rng = np.random.default_rng(args.seed + 1)
    template = true.copy()
    for key in sorted(FITTED_KEYS):
        if pt.get(key, 0.0):
            template.set(key, float(pt[key] * (1.0 + rng.uniform(-0.3, 0.3))))

    variants = ["exact"] + ([] if args.no_baseline else ["2-point"])
    times: dict[str, list[float]] = {v: [] for v in variants}
    cpu: dict[str, list[float]] = {v: [] for v in variants}
    results = {}
    for _ in range(args.repeat):
        for v in variants:  # interleaved: both see the same machine load
            t0, c0 = time.perf_counter(), time.process_time()
            results[v] = fit_tir(data, template, progress=False, jacobian=v)
            times[v].append(time.perf_counter() - t0)
            cpu[v].append(time.process_time() - c0)
    res = results["exact"]
    total = float(np.median(times["exact"]))

    print(f"mftire staged fit: {len(data)} points, {res.data['sweep_id'].nunique()} sweeps, "
          f"median of {args.repeat} run(s)")
    print(f"{'stage':<28}{'channel':<8}{'points':>8}{'coeffs':>8}{'nfev':>6}{'time [s]':>10}"
          + ("" if args.no_baseline else f"{'nfev FD':>9}{'FD [s]':>8}"))
    base = results.get("2-point")
    for i, s in enumerate(res.stages):
        line = f"{s.number} {s.name:<26}{s.channel:<8}{s.n_points:>8}{len(s.identified):>8}{s.nfev:>6}{s.time:>10.2f}"
        if base is not None:
            b = base.stages[i]
            line += f"{b.nfev:>9}{b.time:>8.2f}"
        print(line)
    cpu_total = float(np.median(cpu["exact"]))
    print(f"{'total (incl. loading, grouping), exact Jacobians':<58}{total:>10.2f}   runs: "
          + ", ".join(f"{t:.2f}" for t in times["exact"]))
    print(f"{'  CPU time of the process (one core when the machine is shared)':<58}{cpu_total:>10.2f}   runs: "
          + ", ".join(f"{t:.2f}" for t in cpu["exact"]))
    if base is not None:
        tb = float(np.median(times["2-point"]))
        print(f"{'total, finite-difference Jacobians (baseline)':<58}{tb:>10.2f}   runs: "
              + ", ".join(f"{t:.2f}" for t in times["2-point"]))
        print(f"{'  CPU time':<58}{float(np.median(cpu['2-point'])):>10.2f}")
        print(f"speed-up of exact over finite-difference Jacobians: {tb / total:.2f}x wall, "
              f"{float(np.median(cpu['2-point'])) / cpu_total:.2f}x CPU")
        worst, key = max((abs(res.flat[k] - base.flat[k]) / max(abs(base.flat[k]), 1e-12), k) for k in res.identified)
        print(f"largest relative difference of a fitted coefficient (exact vs FD): {worst:.2e} ({key})")
    print(f"target < 5 s on one core: wall {'met' if total < 5 else 'NOT met'}, "
          f"CPU time {'met' if cpu_total < 5 else 'NOT met'}")
    summary = channel_summary(compute_metrics(res))
    print("\nworst RMS % of peak (without gross outliers) per channel and sweep family:")
    for _, r in summary.iterrows():
        print(f"  {r['channel']:<3} {r['family']:<18} {r['rms_inliers_pct_max']:.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
