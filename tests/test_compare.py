"""Curve comparison: a model against data generated from itself, stiffness, trail, free rolling, CLI."""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pandas as pd
import pytest
from conftest import REFERENCE_TYRES

from mftire.cli import main
from mftire.compare import compare, curve_grid, linear_stiffness, load_comparison_data, write_comparison
from mftire.fitting.synthetic import synthetic_sweeps
from mftire.iotools.tir import read_tir
from mftire.parameters import with_defaults
from mftire.tyre import load

TIR = REFERENCE_TYRES["MF61"]


def _synthetic(**kw) -> pd.DataFrame:
    tyre = read_tir(TIR)
    F0 = with_defaults(tyre)["FNOMIN"]
    args = dict(n_kappa=61, n_alpha=41, n_combined=11, noise=0.0, seed=1)
    args.update(kw)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        df = synthetic_sweeps(tyre, [0.6 * F0, 1.2 * F0], **args)
    df["source"] = "self"
    return df


@pytest.fixture(scope="module")
def self_comparison():
    return compare([TIR], _synthetic())


def test_model_against_its_own_data_has_zero_error(self_comparison):
    comp = self_comparison
    e = comp.errors
    assert set(e["family"]) == {"braking", "cornering", "combined", "combined_alpha"}
    assert set(e[e["family"] == "cornering"]["channel"]) == {"Fy", "Mz", "Mx"}
    assert len(e[e["family"] == "braking"]) == 2  # one curve per load
    assert e["rms"].max() < 1e-6 and e["max_err"].max() < 1e-6
    assert np.abs(e["peak_err"]).max() < 1e-6
    assert (e["peak_data"] > 0).all()


def test_curve_errors_detect_a_scaled_model(self_comparison, tmp_path):
    # a copy of the model with 10 % more lateral friction: Fy peak error ~ +10 %, Fx unchanged
    p = read_tir(TIR)
    p.set("LMUY", 1.1)
    comp = compare({"true": load(TIR), "muy+10%": type(load(TIR))(p, name="muy")}, self_comparison.data)
    fy = comp.errors[(comp.errors["model"] == "muy+10%") & (comp.errors["family"] == "cornering")
                     & (comp.errors["channel"] == "Fy")]
    assert ((fy["peak_err_pct"] > 7) & (fy["peak_err_pct"] < 11)).all()
    fx = comp.errors[(comp.errors["model"] == "muy+10%") & (comp.errors["family"] == "braking")]
    assert fx["rms"].max() < 1e-6
    true = comp.errors[comp.errors["model"] == "true"]
    assert true["rms"].max() < 1e-6


def test_stiffness_equals_model_slope_and_kya():
    tyre = load(TIR)
    # dense alpha sweep: 0.1 deg steps within +-2 deg
    data = _synthetic(alpha_max=math.radians(2.0), n_alpha=41)
    comp = compare([TIR], data, alpha_window_deg=0.5)
    st = comp.stiffness
    d = st[st["who"] == "data"].set_index("sweep_id")
    m = st[st["who"] != "data"].set_index("sweep_id")
    assert len(d) == 2 and (d["n"] == 11).all()
    # data and model are fitted at the same points: identical slopes
    assert np.allclose(d["C_Fa"], m["C_Fa"], rtol=1e-9) and np.allclose(d["C_Ma"], m["C_Ma"], rtol=1e-9)
    assert np.abs(m["C_Fa_err_pct"]).max() < 1e-6
    # over +-0.5 deg the LSQ slope is the cornering stiffness Kya of the generating model (N/rad -> N/deg)
    assert np.allclose(d["C_Fa"], m["Kya"], rtol=0.01)
    assert np.allclose(d["C_Fa_deg"], m["Kya"] * math.pi / 180, rtol=0.01)
    # the thesis window (2.5 deg) gives a lower slope for this early-saturating tyre
    a = np.radians(np.linspace(-2.5, 2.5, 51))
    out = tyre.evaluate(np.full(a.size, 4000.0), 0.0, a, 0.0)
    c, _, n = linear_stiffness(a, out["Fy"])
    assert n == 51 and abs(c) < abs(out["Kya"][25]) and abs(c / out["Kya"][25] - 1) < 0.2
    # trail at alpha -> 0 from the stiffnesses is the model's t near zero
    t_model = tyre.evaluate(np.array([data["Fz"].min()]), 0.0, np.radians([0.1]), 0.0)["t"][0]
    assert d["t0"].iloc[0] == pytest.approx(float(t_model), rel=0.05)


def test_trail_and_free_rolling(self_comparison):
    comp = self_comparison
    tr = comp.trail
    assert len(tr) > 0 and np.isfinite(tr["t_data"]).all()
    assert np.abs(tr["t_err"]).max() < 1e-9  # model -Mz/Fy equals data -Mz/Fy at the same points
    # t output excludes the residual torque: t_model = t_data - Mzr/Fy, close but not equal
    assert (np.abs(tr["t_model"] - tr["t_data"]) < 0.02).all()
    # only points where |Fy| >= 10 % of the sweep's peak
    assert tr["alpha_deg"].abs().min() > 0.2
    fr = comp.free_rolling
    assert len(fr) == 2
    assert np.abs(fr["err"]).max() < 1e-6  # kappa = 0 is a data point: interpolation is exact


def test_grid_covers_each_curve(self_comparison):
    g = curve_grid(self_comparison.data, n=11)
    assert len(g) == 11 * g["curve_id"].nunique()
    corner = g[g["family"] == "cornering"]
    assert corner["alpha"].min() == pytest.approx(-math.radians(12)) and (corner["kappa"] == 0).all()


def test_write_and_cli(tmp_path, self_comparison):
    paths = write_comparison(self_comparison, tmp_path / "api", plots=False)
    js = json.loads(open(paths["json"]).read())
    assert len(js["curve_errors"]) == len(self_comparison.errors)
    for key in ("summary", "stiffness", "trail_points", "trail_summary", "free_rolling"):
        assert key in js

    # CLI with measured data and FE-surrogate sweeps
    from mftire.fe.config import load_tyre
    from mftire.fe.slip_sweeps import sweep

    fe_tyre = load_tyre(None)
    fe = pd.concat([sweep(fe_tyre, k, [4000.0], [16.7], [fe_tyre.size.nominal_pressure], n_kappa=8, n_alpha=9,
                          combined_alphas_deg=(-4.0, 4.0), progress=False).assign(kind=k)
                    for k in ("braking", "cornering", "combined")], ignore_index=True)
    fe.to_csv(tmp_path / "fe.csv", index=False)
    _synthetic(n_kappa=21, n_alpha=21, noise=0.01).to_csv(tmp_path / "rig.csv", index=False)
    out = tmp_path / "cli"
    rc = main(["compare", "--tir", str(TIR), str(TIR), "--data", str(tmp_path / "rig.csv"), "--fe",
               str(tmp_path / "fe.csv"), "--output", str(out)])
    assert rc == 0
    js = json.loads((out / "compare.json").read_text())
    assert set(js["models"]) == {"MagicFormula61_Paramerters", "MagicFormula61_Paramerters#2"}
    assert {s["source"] for s in js["sources"]} == {"self", "fe"}
    fams = {(r["source"], r["family"]) for r in js["curve_errors"]}
    assert {("fe", "braking"), ("fe", "cornering"), ("fe", "combined"), ("self", "braking")} <= fams
    for png in ("braking", "cornering", "combined", "stiffness", "trail", "free_rolling"):
        assert (out / f"{png}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    md = (out / "compare.md").read_text()
    assert "Cornering and aligning stiffness" in md and "Free-rolling Fx" in md
    data = load_comparison_data([tmp_path / "rig.csv"], [tmp_path / "fe.csv"])
    assert set(data["origin"]) == {"measured", "fe"} and "fe_kind" in data.columns


def test_cli_errors(tmp_path, capsys):
    rc = main(["compare", "--tir", str(TIR), "--data", str(tmp_path / "missing.csv"), "--output", str(tmp_path)])
    assert rc == 2
    assert "missing.csv" in capsys.readouterr().err
    rc = main(["compare", "--tir", str(TIR), "--output", str(tmp_path)])
    assert rc == 2


def test_figures_drawn_on_workers_are_the_serial_ones(tmp_path, self_comparison):
    from mftire.parallel import Executor

    serial = self_comparison.plots(tmp_path / "serial")
    with Executor(jobs=2).session() as ex:
        pooled = self_comparison.plots(tmp_path / "pooled", executor=ex)
    assert [p.replace("pooled", "serial") for p in pooled] == serial and len(serial) >= 4
    for a, b in zip(serial, pooled, strict=True):  # the same files, byte for byte
        assert open(a, "rb").read() == open(b, "rb").read(), a
