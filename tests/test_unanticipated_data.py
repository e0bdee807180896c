"""The shipped campaigns of validation/data/unanticipated*/ (issue 11): files, schema, truth.

Checks only the data and their generator (validation/make_unanticipated_campaigns.py):
the files exist and read, the columns follow the sweep schema, expected.json agrees with
the table, the generating model reproduces the stored channels to the noise level, and
the sizes fit CI.  What the diagnosis finds on them is tested elsewhere.
"""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from mftire import Tyre, read_tir
from mftire.extensions import BUILTIN_VARIABLES, SECTION

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "validation" / "data"
_spec = importlib.util.spec_from_file_location("make_unanticipated_campaigns",
                                               ROOT / "validation" / "make_unanticipated_campaigns.py")  # fmt: skip
gen = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = gen
_spec.loader.exec_module(gen)

SCHEMA = ["Fz", "kappa", "alpha", "gamma", "Vx", "P", "Fx", "Fy", "Mz", "Mx", "My"]
FOLDERS = {False: DATA / "unanticipated", True: DATA / "unanticipated_reduced"}
EFFECT_CASES = [c for c in gen.CASES if not c.startswith("null")]
#: (case, reduced) of every shipped copy: the FE-made effect cases are shipped at full size only
COPIES = [(c, r) for c in gen.CASES for r in (True, False) if not (r and c in gen.FULL_ONLY)]


def _size(name: str) -> bool:
    """The copy a check reads: the reduced one where it exists."""
    return name not in gen.FULL_ONLY


def _load(name: str, reduced: bool) -> tuple[pd.DataFrame, dict, Path]:
    folder = FOLDERS[reduced] / name
    return pd.read_csv(folder / "sweeps.csv"), json.loads((folder / "expected.json").read_text()), folder


def test_every_case_is_shipped():
    assert len(gen.CASES) >= 8
    for name, reduced in COPIES:
        for f in ("sweeps.csv", "fitted.tir", "expected.json"):
            assert (FOLDERS[reduced] / name / f).is_file(), (reduced, name, f)
    for name in gen.FULL_ONLY:
        assert not (FOLDERS[True] / name).exists()


@pytest.mark.parametrize("name, reduced", COPIES, ids=[f"{c}-{'reduced' if r else 'full'}" for c, r in COPIES])
def test_schema_sizes_and_expected(name, reduced):
    d, exp, folder = _load(name, reduced)
    assert list(d.columns[: len(SCHEMA)]) == SCHEMA
    assert {"time", "run"} <= set(d.columns)
    assert all(pd.api.types.is_numeric_dtype(d[c]) for c in d.columns)
    assert not d.isna().any().any()
    assert len(d) <= (1500 if reduced else 20000)
    assert len(d) == exp["rows"]
    # the programme: time increases, runs are numbered in order, loads tested in blocks of 3-4 levels
    assert np.all(np.diff(d.time) > 0)
    assert np.all(np.diff(d.run) >= 0) and d.run.iloc[0] == 0
    assert d.kappa.min() == pytest.approx(-0.3) and np.degrees(d.alpha).max() == pytest.approx(12.0, abs=1e-3)
    setpoints = np.sort(d.groupby("run").Fz.median().to_numpy())
    assert 3 <= 1 + np.sum(np.diff(setpoints) / setpoints[:-1] > 0.1) <= 4
    assert np.max(np.abs(d.Fz / d.groupby("run").Fz.transform("median") - 1.0)) < 0.045  # +-2 % wander
    # expected.json
    assert exp["effect"] == (exp["variable"] is not None) == bool(exp["scaling_factors"])
    assert exp["effect"] == (name in EFFECT_CASES)
    if exp["effect"]:
        assert exp["variable"] in d.columns or exp["variable"] in BUILTIN_VARIABLES
        assert exp["family"] in ("friction", "stiffness", "shape", "curvature")
        assert exp["truth"]["EXT1_VARIABLE"] == exp["variable"]
        assert exp["truth"]["EXT1_TARGET"].split() == exp["scaling_factors"]
    else:
        assert exp["truth"] is None and exp["family"] is None
    extra = set(d.columns) - set(SCHEMA) - {"time", "run"}
    if name == "null_plain":
        assert not extra
    for ch in exp["not_measured"]:
        assert (d[ch] == 0).all()
    for ch in set(SCHEMA[6:]) - set(exp["not_measured"]):
        assert d[ch].std() > 0
    # the held-out condition: some rows, not all, and exactly the listed runs
    h = exp["holdout"]
    hold = gen.holdout_mask(d, h["column"], h["values"])
    assert 0 < hold.sum() < 0.5 * len(d) and hold.sum() == exp["rows_heldout"]
    assert sorted(d.run[hold].unique()) == exp["holdout_runs"]
    if h["column"] != "run":  # a level of the column, also tested in training rows below and/or above it
        levels = np.unique(d[h["column"]])
        assert len(levels) >= 4 and all(np.isclose(levels, v).any() for v in h["values"])
    # the fit: a plain MF file
    fitted = read_tir(folder / "fitted.tir")
    assert SECTION not in fitted.sections
    assert fitted.fittyp == 61


def _clean_residuals(name: str, reduced: bool, rows: slice | None = None):
    d, exp, folder = _load(name, reduced)
    case = gen.make_case(name, reduced)
    table = d if rows is None else d[d.run.isin(rows)]
    true = gen.truth(case, table)
    return table, true, exp, folder


@pytest.mark.parametrize("name", gen.CASES)
def test_truth_reproduces_the_stored_channels(name):
    """The generating model at the stored inputs gives the stored Fx, Fy to the noise level."""
    case = gen.make_case(name, _size(name))
    # FE cases: two runs (one braking, one cornering) to keep the FE solves short
    runs = [0, 1] if case.model == "fe" else None
    table, true, exp, _ = _clean_residuals(name, _size(name), runs)
    for ch in ("Fx", "Fy"):
        sigma = exp["noise_sigma"][ch]  # the largest sigma of the campaign
        r = (table[ch] - true[ch]).to_numpy()
        assert np.mean(np.abs(r) <= 5 * sigma) >= 0.95, ch
        assert np.median(np.abs(r)) <= sigma, ch
        assert np.max(np.abs(r)) > 0.05 * sigma, ch  # the data carry noise
    if case.model == "fe":
        return
    # 1 % outliers: spikes of 10-30 sigma on Fx, Fy or Mz
    n_spikes = sum(
        int(np.sum(np.abs(table[ch] - true[ch]) > 8.0 * exp["noise_sigma"][ch])) for ch in ("Fx", "Fy", "Mz")
    )
    assert 0.5 * exp["outlier_fraction"] * len(table) <= n_spikes <= 1.5 * exp["outlier_fraction"] * len(table) + 1


@pytest.mark.parametrize("name", gen.CASES)
def test_oracle_cut(name):
    """expected.json's oracle: the held-out Fx+Fy RMS of fitted.tir and of the truth, recomputed."""
    d, exp, folder = _load(name, _size(name))
    case = gen.make_case(name, _size(name))
    h = exp["holdout"]
    held = d[gen.holdout_mask(d, h["column"], h["values"])]
    true = gen.truth(case, held)
    keep = np.all([np.abs(held[ch] - true[ch]) < 8 * exp["noise_sigma"][ch] for ch in ("Fx", "Fy", "Mz")], axis=0)
    held, true = held[keep], true[keep]
    fit = Tyre(read_tir(folder / "fitted.tir")).evaluate(
        held.Fz.to_numpy(), held.kappa.to_numpy(), held.alpha.to_numpy(), held.gamma.to_numpy(), 0.0,
        held.Vx.to_numpy(), held.P.to_numpy())  # fmt: skip
    rms_fit = np.sqrt(np.mean(np.concatenate([held.Fx - fit["Fx"], held.Fy - fit["Fy"]]) ** 2))
    rms_true = np.sqrt(np.mean(np.concatenate([held.Fx - true.Fx, held.Fy - true.Fy]) ** 2))
    oracle = exp["oracle"]
    assert rms_fit == pytest.approx(oracle["holdout_rms_FxFy_fitted"], rel=0.05)
    assert rms_true == pytest.approx(oracle["holdout_rms_FxFy_truth"], rel=0.05)
    if name in EFFECT_CASES:  # the effect is there to find: the truth cuts the held-out error by >= 60 %
        assert 1 - rms_true / rms_fit >= 0.6
    elif case.model == "mf":  # the plain fit is already as good as the truth, up to fitting error
        assert 1 - rms_true / rms_fit < 0.4
    # (null_fe: the MF fit of FE curves keeps its model error; no effect to find all the same)
