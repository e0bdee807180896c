"""Bootstrap-over-sweeps bands: resampling, band ordering, coverage of held-out points, CLI."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pandas as pd
import pytest
from conftest import REFERENCE_TYRES
from hypothesis import given, settings
from hypothesis import strategies as st

from mftire.cli import main
from mftire.fitting.bands import band_coverage, bootstrap_bands, coverage_table, resample_sweeps
from mftire.fitting.fitter import fit_tir
from mftire.fitting.synthetic import synthetic_sweeps
from mftire.iotools.tir import read_tir
from mftire.parameters import with_defaults
from mftire.segmentation.grouping import group_sweeps

TIR = REFERENCE_TYRES["MF61"]
NOISE = 0.02  # of each channel's peak


def _data(loads, seed, noise=NOISE):
    tyre = read_tir(TIR)
    F0 = with_defaults(tyre)["FNOMIN"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        df = synthetic_sweeps(tyre, [f * F0 for f in loads], np.radians([0.0, 2.0]), n_kappa=21, n_alpha=21,
                              n_combined=11, noise=noise, seed=seed, channels=("Fx", "Fy"))
    df["source"] = "rig"
    return df


@pytest.fixture(scope="module")
def bands():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bootstrap_bands(_data([0.5, 1.0, 1.5], seed=1), TIR, n=6, stages="1,2", seed=3)


def test_resample_keeps_strata_and_separates_copies():
    table = fit_tir(_data([0.5, 1.0], seed=1), TIR, stages="1", progress=False).data
    sample = resample_sweeps(table, np.random.default_rng(0))
    assert "sweep_id" not in sample.columns and "fit_Fx" not in sample.columns
    regrouped = group_sweeps(sample)
    per_kind = lambda t: t.groupby("kind")["sweep_id"].nunique().to_dict()  # noqa: E731
    assert per_kind(regrouped) == per_kind(table)  # same number of sweeps of every kind
    assert sample["file"].str.contains("/").all()


def test_band_ordering_and_grid(bands):
    assert len(bands.replicates) == 6 and bands.n_failed == 0
    g = bands.grid
    assert {"curve_id", "family", "x", "Fx_lo", "Fx_pred_hi"} <= set(g.columns)
    for ch in ("Fx", "Fy"):
        assert (g[f"{ch}_pred_lo"] <= g[f"{ch}_lo"] + 1e-9).all()
        assert (g[f"{ch}_lo"] <= g[ch] + 1e-9).all() and (g[ch] <= g[f"{ch}_hi"] + 1e-9).all()
        assert (g[f"{ch}_hi"] <= g[f"{ch}_pred_hi"] + 1e-9).all()
    # the replicates differ: the confidence band has width somewhere
    assert (g["Fy_hi"] - g["Fy_lo"]).max() > 0
    coef = bands.coefficient_table()
    assert set(coef["coefficient"]) == set(bands.keys) and (coef["std"] >= 0).all()


def test_heldout_coverage_near_nominal(bands):
    held = _data([0.75, 1.25], seed=11)
    cov = coverage_table(bands, held, channels=("Fx", "Fy"))
    allrow = cov.iloc[-1]
    assert allrow["n"] == 2 * len(held)
    # prediction bands: within +-10 % of the nominal 95 %
    assert 0.85 <= allrow["inside_prediction"] <= 1.0
    # the confidence band of the mean curve alone is far too narrow for noisy points
    assert allrow["inside_confidence"] < allrow["inside_prediction"] - 0.2
    assert band_coverage(bands, held, channels=("Fx", "Fy")) == pytest.approx(allrow["inside_prediction"])
    # sigma estimated from residuals matches the synthetic noise
    peaks = {ch: np.abs(_data([0.5, 1.0, 1.5], seed=1, noise=0.0)[ch]).max() for ch in ("Fx", "Fy")}
    for ch in ("Fx", "Fy"):
        assert bands.sigma[ch]["rig"] == pytest.approx(NOISE * peaks[ch], rel=0.25)


def test_cli_fit_bands(tmp_path, capsys):
    _data([0.5, 1.0, 1.5], seed=2).to_csv(tmp_path / "rig.csv", index=False)
    _data([0.75], seed=12).to_csv(tmp_path / "held.csv", index=False)
    rc = main(["fit", str(tmp_path / "rig.csv"), "--template", str(TIR), "--output", str(tmp_path / "fit.tir"),
               "--stages", "1,2", "--bands", "3", "--heldout", str(tmp_path / "held.csv")])
    assert rc == 0
    out = capsys.readouterr().out
    assert "bands: 3 bootstrap replicates" in out and "held-out coverage" in out
    js = json.loads((tmp_path / "bands.json").read_text())
    assert js["n_replicates"] == 3 and js["coverage"][-1]["channel"] == "all"
    assert len(js["replicates"]) == 3
    csv = pd.read_csv(tmp_path / "bands.csv")
    assert {"Fx_lo", "Fx_hi", "Fy_pred_lo", "Fy_pred_hi"} <= set(csv.columns)
    # the comparison draws the bands from bands.csv
    rc = main(["compare", "--tir", str(tmp_path / "fit.tir"), "--data", str(tmp_path / "rig.csv"), "--bands",
               str(tmp_path / "bands.csv"), "--output", str(tmp_path / "cmp")])
    assert rc == 0 and (tmp_path / "cmp" / "cornering.png").exists()
    assert main(["fit", str(tmp_path / "rig.csv"), "--template", str(TIR), "--output", str(tmp_path / "x.tir"),
                 "--bands", "1"]) == 2


@settings(max_examples=60, deadline=None)
@given(st.integers(2, 15), st.integers(1, 40), st.floats(0.0, 0.5), st.integers(0, 2**31 - 1))
def test_column_quantiles_are_numpys_nanquantile(rows, cols, nan_share, seed):
    from mftire.fitting.bands import _column_quantiles

    rng = np.random.default_rng(seed)
    mat = rng.normal(size=(rows, cols)) * rng.choice([1e-3, 1.0, 1e4], size=cols)
    mat[rng.random(mat.shape) < nan_share] = np.nan
    q = (0.025, 0.975)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns
        expected = np.nanquantile(mat, q, axis=0)
        got = _column_quantiles(mat, q)
    assert got.tobytes() == np.asarray(expected).tobytes()
