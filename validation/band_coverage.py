"""Simulation study: do the prediction bands of :func:`mftire.fitting.bands.bootstrap_bands` hold their level?

Two campaign designs, each repeated with new noise; per repeat the campaign is fitted, the bands built
(bootstrap over sweeps, conformal calibration on out-of-fold sweeps), then the campaign is measured
*again* (new noise, new sweep offsets) and the new points inside the 95 % prediction band are counted,
per channel:

``synthetic``
    a campaign of a known MF 6.1 tyre (the repository's reference ``.tir``): pure braking, pure
    cornering and combined sweeps at three loads and two cambers, with white noise of ``noise`` × the
    channel's peak on every point and a per-sweep grip scatter (each sweep's forces and moments scaled
    by ``1 + g``, ``g ~ N(0, grip)``: noise correlated within a sweep and growing with the force).
    MF 6.1 (stages 1, 2, 3, 6, 7: Fx, Fy, Mz, Mx, My) is fitted; the new points are counted on a new
    campaign at the loads between the fitted ones (``new loads``: a sweep the fit did not see, what the
    calibration on out-of-fold sweeps is made for) and on the same campaign re-measured (``same
    conditions``, where the band is a little wide: the fit has seen those conditions).
``slip_speed``
    the demo's measured-like campaign (:func:`mftire.fe.programmes.programme` ``"slip_speed"`` at half
    the slip density): the FE-surrogate tyre with a friction law depending on the sliding speed, which
    MF 6.1 lacks, braking at 20–100 km/h and cornering at 60 km/h at three loads, with rig artefacts
    (per-run zero offsets, drift over the campaign, load wander, 0.5 % noise).  One speed (80 km/h, as in
    the demo) is held out of the fit and of the bands; the new campaign's points are counted at the
    held-out speed (``heldout``) and at the fitted speeds (``fitted``).
``slip_speed_sweeps``
    the same campaign with 3 sweeps drawn at random (any speed, load and kind) held out of the fit and of
    the bands, counted (``random heldout sweeps``: what the band claims, a new sweep of the same campaign),
    and a new campaign (``new campaign``: new offsets and a new drift, beyond the claim).

    python validation/band_coverage.py [--design synthetic|slip_speed|slip_speed_sweeps] [--repeats 20]
        [--replicates 6] [--folds 5] [--conditions] [--csv FILE]
    python validation/band_coverage.py --offsets [--repeats 12]

(``--offsets``: RMS of the per-sweep mean residual on the fitted sweeps, the campaign's own held-out sweeps
and a new campaign.)  Each repeat counts 3 held-out sweeps (slip_speed designs), so the standard error across
repeats is the sweep-cluster standard error of the pooled count.

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
CHANNELS = ("Fx", "Fy", "Mz", "Mx", "My")
DESIGNS = ("synthetic", "slip_speed", "slip_speed_sweeps")
#: Sweeps of the campaign held out at random per repeat in the ``slip_speed_sweeps`` design.
HELDOUT_SWEEPS = 3
#: The held-out speed of the ``slip_speed`` design [km/h] (the demo's).
HELDOUT_KMH = 80.0


def campaign(seed: int, loads: Sequence[float] = (0.5, 1.0, 1.5), noise: float = 0.015, grip: float = 0.02,
             n: int = 21, channels: Sequence[str] = CHANNELS) -> pd.DataFrame:
    """One simulated campaign of the ``synthetic`` design (SI sweep table, source ``rig``)."""
    tyre = read_tir(TIR)
    f0 = with_defaults(tyre)["FNOMIN"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        df = synthetic_sweeps(tyre, [f * f0 for f in loads], np.radians([0.0, 2.0]), n_kappa=n, n_alpha=n,
                              n_combined=max(n // 2, 5), noise=noise, seed=seed, channels=channels)
    g = group_sweeps(df)
    rng = np.random.default_rng(10_000 + seed)
    gain = 1.0 + grip * rng.standard_normal(int(g["sweep_id"].max()) + 1)
    for ch in channels:
        df[ch] = df[ch].to_numpy(float) * gain[g["sweep_id"].to_numpy()]
    df["source"] = "rig"
    return df


def slip_speed_campaign(seed: int, scale: float = 0.5):
    """One campaign of the ``slip_speed`` design: (sweep table with source ``measured``, MF template)."""
    from mftire.fe.programmes import programme

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p = programme("slip_speed", seed=seed, scale=scale)
    return p.data.assign(source="measured"), p.template


def _rows(i: int, what: str, cov: pd.DataFrame, bands, level: float, source: str) -> list[dict]:
    cv = bands.calibration.cv_coverage if bands.calibration is not None else {}
    return [{"repeat": i, "design": what, "channel": r.channel, "n": r.n, "sweeps": r.sweeps,
             "inside": r.inside_prediction, "cv_coverage": cv.get(r.channel, {}).get(source, np.nan),
             "nominal": level} for r in cov.itertuples(index=False)]


def study(repeats: int, replicates: int = 6, level: float = 0.95, seed: int = 0, design: str = "synthetic",
          channels: Sequence[str] = CHANNELS, calibrate: int = 5, conditions: bool = False,
          **campaign_kw) -> pd.DataFrame:
    """Coverage of the prediction band on a repeated campaign, one row per repeat, counted set and channel
    (``conditions``: with the condition folds, ``bootstrap_bands(calibrate_conditions=True)``)."""
    if design not in DESIGNS:
        raise ValueError(f"design must be one of {DESIGNS}")
    rows = []
    for i in range(repeats):
        s = seed + 2 * i
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if design == "synthetic":
                train, new = campaign(s, channels=channels, **campaign_kw), campaign(s + 1, channels=channels,
                                                                                     **campaign_kw)
                stages = ",".join(str(k) for k, ch in ((1, "Fx"), (2, "Fy"), (3, "Mz"), (6, "Mx"), (7, "My"))
                                  if ch in channels)
                fit = fit_tir(train, TIR, stages=stages, progress=False)
                bands = bootstrap_bands(None, TIR, n=replicates, fit=fit, level=level, seed=s, grid=train.iloc[:0],
                                        calibrate=calibrate, calibrate_conditions=conditions)
                # a new campaign at loads between the fitted ones (the conditions a band is calibrated for: a
                # sweep the fit did not see), and the same campaign re-measured
                loads = campaign_kw.get("loads", (0.5, 1.0, 1.5))
                between = tuple((x + y) / 2 for x, y in zip(loads, loads[1:], strict=False))
                other = {k: v for k, v in campaign_kw.items() if k != "loads"}
                # (with the heaviest fitted load in the campaign too: the noise is a share of the campaign's peak)
                new_l = campaign(s + 1, loads=(*between, max(loads)), channels=channels, **other)
                f0 = with_defaults(read_tir(TIR))["FNOMIN"]
                sets = {"new loads": new_l[~np.isclose(new_l["Fz"].to_numpy(float), max(loads) * f0)],
                        "same conditions": new}
                source = "rig"
            elif design == "slip_speed_sweeps":
                train, template = slip_speed_campaign(s, **campaign_kw)
                new, _ = slip_speed_campaign(s + 1, **campaign_kw)
                # sweeps drawn at random from the campaign (any speed, load, kind): what the band claims to cover
                sid = group_sweeps(train)["sweep_id"].to_numpy()
                pick = np.random.default_rng(20_000 + s).choice(np.unique(sid), HELDOUT_SWEEPS, replace=False)
                held = np.isin(sid, pick)
                fit = fit_tir(train[~held], template, progress=False)
                bands = bootstrap_bands(None, template, n=replicates, fit=fit, level=level, seed=s,
                                        grid=train.iloc[:0], calibrate=calibrate,
                                        calibrate_conditions=conditions)
                sets = {"random heldout sweeps": train[held], "new campaign": new}
                source = "measured"
            else:
                train, template = slip_speed_campaign(s, **campaign_kw)
                new, _ = slip_speed_campaign(s + 1, **campaign_kw)
                held = np.isclose(train["Vx"].to_numpy(float) * 3.6, HELDOUT_KMH)
                fit = fit_tir(train[~held], template, progress=False)
                bands = bootstrap_bands(None, template, n=replicates, fit=fit, level=level, seed=s,
                                        grid=train.iloc[:0], calibrate=calibrate,
                                        calibrate_conditions=conditions)
                at_held = np.isclose(new["Vx"].to_numpy(float) * 3.6, HELDOUT_KMH)
                # the held-out sweeps of this campaign (as in the demo: sweeps of the campaign the fit and the
                # calibration did not see), and a new campaign (new offsets and a new drift: beyond the claim)
                sets = {"heldout": train[held], "new campaign heldout": new[at_held],
                        "new campaign fitted": new[~at_held]}
                source = "measured"
        for what, df in sets.items():
            rows += _rows(i, what, coverage_table(bands, df, channels=channels), bands, level, source)
    return pd.DataFrame(rows)


def sweep_offsets(repeats: int, seed: int = 0, channels: Sequence[str] = CHANNELS) -> pd.DataFrame:
    """RMS over sweeps of each sweep's mean residual (its offset against the fit) in the ``slip_speed`` design:
    the fitted sweeps, the campaign's own held-out 80 km/h sweeps and a new campaign (new run offsets and a new
    drift), pooled over ``repeats`` campaigns.  A band calibrated within one campaign holds the first two; the
    new campaign's larger offsets are a campaign-level draw that one campaign does not show."""
    from mftire.tyre import Tyre

    acc: dict[tuple[str, str], list[np.ndarray]] = {}
    for i in range(repeats):
        s = seed + 2 * i
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            train, template = slip_speed_campaign(s)
            new, _ = slip_speed_campaign(s + 1)
            held = np.isclose(train["Vx"].to_numpy(float) * 3.6, HELDOUT_KMH)
            tyre = Tyre(fit_tir(train[~held], template, progress=False).parameters)
            for what, df in (("fitted sweeps", train[~held]), ("held-out sweeps", train[held]),
                             ("new campaign", new)):
                df = df.reset_index(drop=True)
                sid = group_sweeps(df)["sweep_id"].to_numpy()
                ev = tyre.evaluate_frame(df.drop(columns=["phit", "omega"], errors="ignore"), mode=211)
                for ch in channels:
                    r = df[ch].to_numpy(float) - ev[ch].to_numpy(float)
                    acc.setdefault((what, ch), []).append(np.bincount(sid, weights=r) / np.bincount(sid))
    return pd.DataFrame([{"set": w, "channel": ch, "sweeps": sum(v.size for v in m),
                          "rms_sweep_offset": float(np.sqrt(np.mean(np.concatenate(m) ** 2)))}
                         for (w, ch), m in acc.items()])


def summary(table: pd.DataFrame) -> pd.DataFrame:
    """Mean coverage per counted set and channel and its standard error across repeats."""
    g = table.groupby(["design", "channel"], sort=False)["inside"]
    cv = table.groupby(["design", "channel"], sort=False)["cv_coverage"].mean()
    return pd.DataFrame({"mean": g.mean(), "se": g.std(ddof=1) / np.sqrt(g.count()), "min": g.min(),
                         "max": g.max(), "repeats": g.count(), "cv": cv}).reset_index()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--design", choices=DESIGNS, default="synthetic")
    ap.add_argument("--repeats", type=int, default=20)
    ap.add_argument("--replicates", type=int, default=6)
    ap.add_argument("--level", type=float, default=0.95)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--folds", type=int, default=5, help="calibration folds (bootstrap_bands' calibrate)")
    ap.add_argument("--conditions", action="store_true",
                    help="also calibrate on condition folds (leave one speed/load/pressure/camber level out)")
    ap.add_argument("--csv", help="also write the per-repeat table to this CSV file")
    ap.add_argument("--offsets", action="store_true",
                    help="instead: RMS of the per-sweep mean residual, fitted / held-out / new campaign (slip_speed)")
    args = ap.parse_args()
    t0 = time.perf_counter()
    if args.offsets:
        off = sweep_offsets(args.repeats, args.seed).pivot(index="channel", columns="set", values="rms_sweep_offset")
        print(f"RMS of the per-sweep mean residual [N, N m], slip_speed design, {args.repeats} campaigns, "
              f"{time.perf_counter() - t0:.0f} s")
        print(off.to_string(float_format=lambda v: f"{v:.2f}"))
        return
    table = study(args.repeats, args.replicates, args.level, args.seed, args.design, calibrate=args.folds,
                  conditions=args.conditions)
    if args.csv:
        table.to_csv(args.csv, index=False)
    for (i, what), g in table.groupby(["repeat", "design"], sort=False):
        print(f"repeat {i} {what}: " + ", ".join(f"{r.channel} {100 * r.inside:.1f} %" for r in g.itertuples()),
              flush=True)
    s = summary(table)
    extra = " and condition folds" if args.conditions else ""
    print(f"\n{args.design} design, {args.folds} calibration folds{extra}, nominal {100 * args.level:g} %, "
          f"{args.repeats} repeats, {time.perf_counter() - t0:.0f} s")
    for r in s.itertuples(index=False):
        print(f"  {r.design:>15} {r.channel:>3}: mean {100 * r.mean:.1f} % (s.e. {100 * r.se:.1f}, range "
              f"{100 * r.min:.1f}-{100 * r.max:.1f}; cross-validated {100 * r.cv:.1f} %)")


if __name__ == "__main__":
    main()
