"""Simulation study: do the prediction bands of :func:`mftire.fitting.bands.bootstrap_bands` hold their level?

Each repeat simulates a measurement campaign of a known MF 6.1 tyre (the repository's reference
``.tir``): pure braking, pure cornering and combined sweeps at several loads and two cambers, with

* white noise of ``noise`` × the channel's peak on every point, and
* a per-sweep grip scatter: each sweep's forces and moments scaled by ``1 + g``, ``g ~ N(0, grip)``
  (the noise is correlated within a sweep and grows with the force: heteroscedastic),

fits MF 6.1 to it, builds the bands (bootstrap over sweeps, conformal calibration on out-of-fold
sweeps), then measures the campaign *again* with new noise and new grip scatter and counts the
new points inside the prediction band, per channel.

    python validation/band_coverage.py [--repeats 20] [--replicates 6] [--level 0.95]

prints one line per repeat and the mean coverage per channel with its standard error across
repeats (the numbers of validation/README.md).  ``tests/test_bands.py`` runs a reduced study.
"""

from __future__ import annotations

import argparse
import time
import warnings
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from mftire.fitting.bands import bootstrap_bands, coverage_table
from mftire.fitting.fitter import fit_tir
from mftire.fitting.synthetic import synthetic_sweeps
from mftire.iotools.tir import read_tir
from mftire.parameters import with_defaults
from mftire.segmentation.grouping import group_sweeps

TIR = Path(__file__).resolve().parents[1] / "tests" / "data" / "tir" / "mfeval" / "MagicFormula61_Paramerters.tir"
CHANNELS = ("Fx", "Fy")


def campaign(seed: int, loads: Sequence[float] = (0.5, 1.0, 1.5), noise: float = 0.015, grip: float = 0.02,
             n: int = 21) -> pd.DataFrame:
    """One simulated campaign (SI sweep table, source ``rig``): see the module docstring."""
    tyre = read_tir(TIR)
    f0 = with_defaults(tyre)["FNOMIN"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        df = synthetic_sweeps(tyre, [f * f0 for f in loads], np.radians([0.0, 2.0]), n_kappa=n, n_alpha=n,
                              n_combined=max(n // 2, 5), noise=noise, seed=seed, channels=CHANNELS)
    g = group_sweeps(df)
    rng = np.random.default_rng(10_000 + seed)
    gain = 1.0 + grip * rng.standard_normal(int(g["sweep_id"].max()) + 1)
    for ch in CHANNELS:
        df[ch] = df[ch].to_numpy(float) * gain[g["sweep_id"].to_numpy()]
    df["source"] = "rig"
    return df


def study(repeats: int, replicates: int = 6, level: float = 0.95, seed: int = 0, stages: str = "1,2",
          **campaign_kw) -> pd.DataFrame:
    """Coverage of the prediction band on a repeated campaign, one row per repeat and channel."""
    rows = []
    for i in range(repeats):
        s = seed + 2 * i
        train, new = campaign(s, **campaign_kw), campaign(s + 1, **campaign_kw)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit = fit_tir(train, TIR, stages=stages, progress=False)
            bands = bootstrap_bands(None, TIR, n=replicates, fit=fit, level=level, seed=s, grid=train.iloc[:0])
        cov = coverage_table(bands, new, channels=CHANNELS)
        for r in cov.itertuples(index=False):
            rows.append({"repeat": i, "channel": r.channel, "n": r.n, "inside": r.inside_prediction,
                         "cv_coverage": bands.calibration.cv_coverage.get(r.channel, {}).get("rig", np.nan)
                         if bands.calibration is not None else np.nan, "nominal": level})
    return pd.DataFrame(rows)


def summary(table: pd.DataFrame) -> pd.DataFrame:
    """Mean coverage per channel and its standard error across repeats."""
    g = table.groupby("channel", sort=False)["inside"]
    return pd.DataFrame({"mean": g.mean(), "se": g.std(ddof=1) / np.sqrt(g.count()), "min": g.min(),
                         "max": g.max(), "repeats": g.count()}).reset_index()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=20)
    ap.add_argument("--replicates", type=int, default=6)
    ap.add_argument("--level", type=float, default=0.95)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    t0 = time.perf_counter()
    table = study(args.repeats, args.replicates, args.level, args.seed)
    for i, g in table.groupby("repeat"):
        print(f"repeat {i}: " + ", ".join(f"{r.channel} {100 * r.inside:.1f} %" for r in g.itertuples()))
    s = summary(table)
    print(f"\nnominal {100 * args.level:g} %, {args.repeats} repeats, {time.perf_counter() - t0:.0f} s")
    for r in s.itertuples(index=False):
        print(f"  {r.channel:>3}: mean {100 * r.mean:.1f} % (s.e. {100 * r.se:.1f}, range {100 * r.min:.1f}-"
              f"{100 * r.max:.1f})")


if __name__ == "__main__":
    main()
