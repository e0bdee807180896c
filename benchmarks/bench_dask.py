"""Dask overhead against a local run, the worker allocator fix, and the per-task costs of docs/scale.md.

Run: ``python benchmarks/bench_dask.py [--quick]``.  A LocalCluster of 2 worker processes (1 thread each,
started by Dask's nanny, so with its ``MALLOC_TRIM_THRESHOLD_=65536``) on 127.0.0.1.  Prints:

1. the FE thesis campaign (default tyre) in this process, on 2 local processes (``--jobs 2``), and on the
   2 Dask workers: first with a plain Dask client (the nanny's allocator setting as it is), then through
   :class:`mftire.parallel.Executor` (which registers :class:`mftire.parallel.MallocTuning`); the ratio
   Dask / local processes is the overhead (target <= 1.2x, issue 27); the tables agree bit for bit;
2. the per-task costs used in docs/scale.md: one FE point, one fit of a tyre file (stages 1-3, ~1,900
   points), one chunk of ``evaluate`` (kernel, CSV formatting, bytes written per point), the scheduler's cost
   per (empty) task, and the bytes a task result carries.

Exit code 1 when the overhead misses the target.  Wall and CPU seconds: on a shared machine CPU is steadier.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
import warnings

import numpy as np

TARGET_OVERHEAD = 1.2


def _timed(fn):
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - t0, time.process_time() - c0


def _noop(x):
    return x


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the reduced FE programme (a smoke run)")
    args = ap.parse_args()
    import distributed

    from mftire.fe.config import load_tyre
    from mftire.fe.slip_sweeps import campaign
    from mftire.parallel import Executor

    tyre = load_tyre(None)
    print(f"load average before: {os.getloadavg()[0]:.2f}; {os.cpu_count()} CPUs")
    (t_serial, f_serial), w_serial, c_serial = _timed(lambda: campaign(tyre, quick=args.quick, progress=False))
    n_points = len(t_serial)
    print(f"FE campaign in this process: {w_serial:.2f} s wall, {c_serial:.2f} s CPU, {n_points} rows")
    with Executor(jobs=2).session() as ex:
        (t_pool, _), w_pool, _ = _timed(lambda: campaign(tyre, quick=args.quick, progress=False, executor=ex))
    print(f"FE campaign on 2 local processes: {w_pool:.2f} s")

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                           dashboard_address=None, silence_logs=50)
    with cluster:
        addr = cluster.scheduler_address
        env = cluster.scheduler_info["workers"]
        print(f"LocalCluster {addr}: {len(env)} workers (nanny: MALLOC_TRIM_THRESHOLD_ set in their environment)")
        # first without the allocator fix (it stays in a worker once set), then through Executor as mftire runs
        plain = Executor(scheduler=addr, tune_workers=False)
        with plain.session() as ex:  # one client for the campaign's batches, as mftire fe campaign
            (t_plain, _), w_plain, _ = _timed(lambda: campaign(tyre, quick=args.quick, progress=False, executor=ex))
        print(f"FE campaign on 2 Dask workers, nanny's allocator setting: {w_plain:.2f} s "
              f"= {w_plain / w_pool:.2f}x the local processes")
        tuned = Executor(scheduler=addr)
        with tuned.session() as ex:
            (t_dask, _), w_dask, _ = _timed(lambda: campaign(tyre, quick=args.quick, progress=False, executor=ex))
        ratio = w_dask / w_pool
        print(f"FE campaign on 2 Dask workers, MallocTuning (mftire's default): {w_dask:.2f} s "
              f"= {ratio:.2f}x the local processes (target <= {TARGET_OVERHEAD}x)")
        same = all(t.equals(t_serial) for t in (t_pool, t_plain, t_dask))
        print(f"tables bit for bit equal to the serial one: {same}")

        # scheduler cost per task (empty tasks, results in order)
        n = 2000
        with tuned.session() as ex:
            ex.map(_noop, range(10))
            _, w_noop, c_noop = _timed(lambda: ex.map(_noop, range(n)))
        print(f"scheduler round trip per empty task: {1e3 * w_noop / n:.2f} ms wall, {1e3 * c_noop / n:.2f} ms CPU "
              f"of this process (client and LocalCluster scheduler) ({n} tasks, 2 workers)")

    # per-task costs for docs/scale.md, in this process
    print("\nper-task costs (this process, one core):")
    print(f"  FE programme: {c_serial / n_points * 1e3:.2f} ms CPU per point of the programme "
          f"({n_points} points, {c_serial:.1f} s CPU{'; quick grid' if args.quick else ''})")
    import pandas as pd

    from mftire.fitting.fitter import fit_tir
    from mftire.fitting.synthetic import synthetic_sweeps
    from mftire.iotools.tir import read_tir, write_tir
    from mftire.parameters import with_defaults
    from mftire.tyre import Tyre

    tir = os.path.join(os.path.dirname(__file__), "..", "tests", "data", "tir", "mfeval",
                       "MagicFormula61_Paramerters.tir")
    params = read_tir(tir)
    f0 = with_defaults(params)["FNOMIN"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        data = synthetic_sweeps(params, [0.5 * f0, f0, 1.5 * f0], np.radians([0.0, 3.0]), noise=0.01, seed=1,
                                channels=("Fx", "Fy", "Mz"))
        with tempfile.TemporaryDirectory() as d:
            csv = os.path.join(d, "tyre.csv")
            data.to_csv(csv, index=False)
            in_bytes = os.path.getsize(csv)
            res, w_fit, c_fit = _timed(lambda: fit_tir([csv], tir, stages="1,2,3", progress=False))
            out = os.path.join(d, "fitted.tir")
            write_tir(res.parameters, out)
            tir_bytes = os.path.getsize(out)
    print(f"  fit of one tyre file (stages 1-3, {len(data)} points): {w_fit:.2f} s wall, {c_fit:.2f} s CPU; "
          f"input {in_bytes / 1e3:.0f} kB, fitted .tir {tir_bytes / 1e3:.1f} kB")

    from mftire.cli import evaluate_columns
    from mftire.streaming import EvaluateChunk

    rng = np.random.default_rng(0)
    m = 100_000
    frame = pd.DataFrame({"Fz": rng.uniform(2000, 6000, m), "kappa": rng.uniform(-0.2, 0.2, m),
                          "alpha": rng.uniform(-0.2, 0.2, m), "gamma": 0.0})
    tyre_mf = Tyre(params)
    _, _, c_kernel = _timed(lambda: tyre_mf.evaluate_frame(frame))
    (text, _), _, c_chunk = _timed(lambda: EvaluateChunk(params, 111, "bench", evaluate_columns)((frame, 0, m, True)))
    csv_in = frame.to_csv(index=False)
    _, _, c_parse = _timed(lambda: pd.read_csv(__import__("io").StringIO(csv_in)))
    with tempfile.TemporaryDirectory() as d:
        _, w_write, _ = _timed(lambda: open(os.path.join(d, "o.csv"), "wb").write(text))
    print(f"  evaluate (CPU): kernel (30 channels, a table) {m / c_kernel:.3g} points/s; a chunk with its CSV text "
          f"{m / c_chunk:.3g} points/s; {len(text) / m:.0f} bytes of output per point; reading the 4-column input "
          f"({len(csv_in) / m:.0f} bytes per row) {m / c_parse:.3g} rows/s; "
          f"writing {len(text) / w_write / 1e6:.0f} MB/s")
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    return 0 if ratio <= TARGET_OVERHEAD else 1


if __name__ == "__main__":
    sys.exit(main())
