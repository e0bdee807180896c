"""Raw rig import speed: 1 million rows (about 3 h at 100 Hz) of a TTC-style run file.

Run: ``python benchmarks/bench_import.py [--rows N] [--keep FILE]``.  Target (issue 12,
2-core machine): ``mftire import`` of 1 million rows (read, SAE -> ISO, segmentation,
10 points per sweep, CSV written) under 20 s wall time.  Exits non-zero when it is missed.
The CPU time of the import process is printed too: on a machine shared with other
jobs the wall time can be several times the CPU time.

The rows are generated here (not timed): a schedule of 30 s blocks cycling through four
loads, three inclinations, two pressures and two speeds, each block a 2.5 s load ramp, a
2.5 s dwell and 25 s of slip-angle sweeps (+-12 deg, 1 Hz) or braking sweeps; forces from
the Magic Formula (``tirfiles/MF61_255-55R20_mfeval-jl.tir``, Tyre API) in SAE axes,
with sensor noise.  Simulated data.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

import mftire
from mftire.iotools.rig import read_ttc, write_ttc
from mftire.segmentation.rig_segments import import_rig, segment

ROOT = Path(__file__).resolve().parent.parent
TARGET_S = 20.0
FS = 100.0


def make_rows(n: int, seed: int = 0) -> pd.DataFrame:
    """``n`` rows of TTC channels (SI, SAE axes), vectorised."""
    tyre = mftire.load(ROOT / "tirfiles" / "MF61_255-55R20_mfeval-jl.tir")
    rng = np.random.default_rng(seed)
    t = np.arange(n) / FS
    block = (t // 30.0).astype(int)
    tl = t - 30.0 * block
    loads = np.array([0.4, 0.7, 1.0, 1.3]) * tyre["FNOMIN"]
    ias = np.array([0.0, 2.0, 4.0])
    ps = np.array([220.0, 260.0])
    vs = np.array([40.0, 72.0])
    cond = np.arange(block.max() + 2)
    fz_b, ia_b = loads[cond % 4], ias[(cond // 4) % 3]
    p_b, v_b = ps[(cond // 12) % 2], vs[(cond // 24) % 2]
    ramp = np.clip(tl / 2.5, 0.0, 1.0)
    prev = np.maximum(block - 1, 0)

    def level(x):
        return x[prev] + (x[block] - x[prev]) * ramp

    Fz, ia, P, V = level(fz_b), level(ia_b), level(p_b), level(v_b)
    sweeping = tl >= 5.0
    tri = 4.0 * np.abs(((tl - 5.0) + 0.25) % 1.0 - 0.5) - 1.0
    braking = (block % 5) == 4
    sa = np.where(sweeping & ~braking, 12.0 * tri, 0.0)  # deg, SAE
    sr = np.where(sweeping & braking, -0.125 * (1 - np.cos(np.pi * (tl - 5.0))), 0.0)
    out = tyre.evaluate(Fz, sr, -np.radians(sa), np.radians(ia), Vx=V / 3.6, P=P * 1e3)

    def noise(s):
        return s * rng.standard_normal(n)

    raw = pd.DataFrame({
        "ET": t, "V": (V + noise(0.05)) / 3.6, "N": out["omega"] + noise(0.05), "SA": np.radians(sa + noise(0.02)),
        "IA": np.radians(ia + noise(0.02)), "RL": out["Rl"] + noise(2e-4), "RE": out["Re"] + noise(2e-4),
        "P": (P + noise(0.3)) * 1e3, "FX": out["Fx"] + noise(12), "FY": -out["Fy"] + noise(12),
        "FZ": -Fz + noise(15), "MX": out["Mx"] + noise(1), "MZ": -out["Mz"] + noise(1),
        "RST": 30 + noise(0.2), "TSTI": 50 + noise(0.3), "TSTC": 50 + noise(0.3), "TSTO": 50 + noise(0.3),
        "AMBTMP": 25 + noise(0.1), "SR": sr + noise(0.001),
    })  # fmt: skip
    return raw


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=1_000_000)
    ap.add_argument("--keep", help="also keep the generated raw file here")
    args = ap.parse_args()
    t0 = time.perf_counter()
    raw = make_rows(args.rows)
    with tempfile.TemporaryDirectory() as tmp:
        path = args.keep or os.path.join(tmp, "bench_run.dat")
        write_ttc(raw, path, title="SIMULATED benchmark run (mftire benchmarks/bench_import.py)")
        size = os.path.getsize(path) / 1e6
        print(f"generated {args.rows} rows ({args.rows / FS / 3600:.2f} h at {FS:.0f} Hz), {size:.0f} MB "
              f"in {time.perf_counter() - t0:.1f} s (not timed)")
        t1, c1 = time.perf_counter(), time.process_time()
        table, rep = import_rig(path, "ttc", output=os.path.join(tmp, "sweeps.csv"), points_per_sweep=10)
        total, cpu = time.perf_counter() - t1, time.process_time() - c1
        # the parts, for the record
        t2 = time.perf_counter()
        df = read_ttc(path)
        t_read = time.perf_counter() - t2
        t3 = time.perf_counter()
        segment(df, points_per_sweep=10)
        t_seg = time.perf_counter() - t3
    print(f"import of {args.rows} rows: {total:.2f} s wall, {cpu:.2f} s CPU (target < {TARGET_S:.0f} s); "
          f"read {t_read:.2f} s, "
          f"segment + bin {t_seg:.2f} s; {rep.n_sweeps} sweeps, {len(table)} points, "
          f"{sum(s['status'] == 'kept' for s in rep.segments)} segments kept")
    return 0 if total < TARGET_S else 1


if __name__ == "__main__":
    sys.exit(main())
