"""Curve comparison: a model against data generated from itself, stiffness, trail, free rolling, CLI."""

from __future__ import annotations

import json
import math
import os
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
    rc = main(["compare", "--tir", str(TIR), "--fe", str(tmp_path / "nofe.csv"), "--conditions", "loads=1",
               "--output", str(tmp_path / "c")])
    assert rc == 2 and "--conditions is for a comparison without data" in capsys.readouterr().err


def test_figures_drawn_on_workers_are_the_serial_ones(tmp_path, self_comparison):
    from mftire.parallel import Executor

    serial = self_comparison.plots(tmp_path / "serial")
    with Executor(jobs=2).session() as ex:
        pooled = self_comparison.plots(tmp_path / "pooled", executor=ex)
    assert [p.replace("pooled", "serial") for p in pooled] == serial
    # one file per family channel, and the summaries (a comparison with data: the stiffness and free rolling too)
    assert [os.path.basename(p) for p in serial] == [
        "braking.png", "cornering.png", "cornering_Mz.png", "cornering_Mx.png", "combined.png", "combined_Fy.png",
        "combined_Mz.png", "combined_alpha.png", "combined_alpha_Fy.png", "combined_alpha_Mz.png", "stiffness.png",
        "trail.png", "free_rolling.png"]  # fmt: skip
    for a, b in zip(serial, pooled, strict=True):  # the same files, byte for byte
        assert open(a, "rb").read() == open(b, "rb").read(), a


# ------------------------------------------------------------------------------------
# figures: every condition, labelled axes, held-out condition marked (issue 26)
# ------------------------------------------------------------------------------------


def _visible_axes(fig):
    return [ax for ax in fig.axes if ax.get_visible()]


@pytest.fixture(scope="module")
def many_conditions():
    """Two loads x three speeds x two pressures: 6 conditions per pure family, 12 per combined family
    (braking, cornering and combined sweeps at α = ±4° of the model itself)."""
    from mftire.compare.conditions import Conditions, design_sweeps
    from mftire.compare.models import evaluate_at

    F0 = with_defaults(read_tir(TIR))["FNOMIN"]
    design = design_sweeps(Conditions((0.6 * F0, 1.2 * F0), (10.0, 20.0, 30.0), (2.0e5, 2.6e5), (0.0,)), n=31)
    df = pd.concat([design, evaluate_at(load(TIR), design, channels=("Fx", "Fy", "Mz", "Mx"))], axis=1)
    df["source"], df["origin"] = "rig", "measured"
    return compare([TIR], df, heldout=("Vx", [20.0]))


def test_family_figures_show_every_condition_with_labels(many_conditions):
    from mftire.compare.data import FAMILY_CHANNELS
    from mftire.compare.plots import _panel_keys, family_figures

    comp = many_conditions
    for family in ("braking", "cornering", "combined"):
        d = comp.data[comp.data["family"] == family]
        pkeys, skey = _panel_keys(family)
        n_cond = len(d.groupby(pkeys))
        assert n_cond == (6 if family in ("braking", "cornering") else 12)
        n_held = len(d[np.isclose(d["Vx_set"], 20.0)].groupby(pkeys))
        figs = family_figures(family, comp.data, comp.grid, comp.grid_predictions, heldout=comp.heldout)
        assert [ch for ch, _ in figs] == list(FAMILY_CHANNELS[family])  # one figure per channel
        for ch, fig in figs:
            axes = _visible_axes(fig)
            assert len(axes) == n_cond  # every condition has its panel, nothing truncated
            titles = [ax.get_title() for ax in axes]
            assert len(set(titles)) == n_cond
            assert sum("HELD OUT" in t for t in titles) == n_held
            for ax in axes:
                assert ax.get_xlabel() in ("κ [-]", "α [deg]")
                assert ax.get_ylabel().startswith(ch) and ax.get_ylabel().endswith("]")
                assert ax.lines  # curves drawn in every panel
            legend = [t.get_text() for t in fig.legends[0].get_texts()]
            for v in d[skey].unique():  # every series (load or held slip) named in the legend
                assert sum(t.startswith(("Fz", "α", "κ")) for t in legend) == d[skey].nunique(), (v, legend)
            assert "held-out condition" in legend and any(t.startswith("MF: ") for t in legend)
            w, h = fig.get_size_inches()
            assert w <= 3.0 * 5 + 4.5  # at most five panels in a row: readable at the report's width


def test_summary_figures_show_every_condition_with_labels(many_conditions):
    from mftire.compare.plots import free_rolling_figure, stiffness_figure, trail_figure

    comp = many_conditions
    speeds = sorted(comp.data["Vx_set"].unique())
    for fig in (stiffness_figure(comp.stiffness, comp.heldout), free_rolling_figure(comp.free_rolling, comp.heldout)):
        axes = _visible_axes(fig)
        assert len(axes) in (2, 4)  # one panel (pair) per pressure
        for ax in axes:
            assert ax.get_xlabel() == "Fz [N]" and ax.get_ylabel().endswith("]")
        legend = [t.get_text() for t in fig.legends[0].get_texts()]
        speed_labels = [t for t in legend if "km/h" in t]
        assert len(speed_labels) == len(speeds)  # one colour per speed, every speed named
        assert sum("(held out)" in t for t in speed_labels) == 1
    fig = trail_figure(comp.trail, comp.grid, comp.grid_predictions, comp.heldout)
    axes = _visible_axes(fig)
    assert len(axes) == 6 and sum("HELD OUT" in ax.get_title() for ax in axes) == 2
    assert all(ax.get_ylabel() == "trail t [m]" and ax.get_xlabel() == "α [deg]" for ax in axes)


# ------------------------------------------------------------------------------------
# compare without data (issue 26)
# ------------------------------------------------------------------------------------


def test_compare_models_without_data():
    from mftire.compare import compare_models
    from mftire.tyre import Tyre

    p = read_tir(TIR)
    p.set("LMUY", 1.1)
    comp = compare_models({"base": TIR, "muy+10%": Tyre(p, name="muy")}, "loads=3000,5000,speeds=40,80")
    t = comp.characteristics
    assert len(t) == 2 * 4 and set(t["Fz"]) == {3000.0, 5000.0}
    assert np.allclose(sorted(set(t["Vx"])), [40 / 3.6, 80 / 3.6])
    base = t[t["model"] == "base"]
    assert (base[[c for c in t.columns if c.startswith("d_")]].abs().to_numpy() < 1e-12).all()
    muy = t[t["model"] == "muy+10%"]
    assert ((muy["d_mu_y_peak_pct"] > 9.0) & (muy["d_mu_y_peak_pct"] < 11.0)).all()  # lateral friction +10 %
    assert (muy["d_Kya_pct"].abs() < 1e-9).all() and (muy["d_Kxk_pct"].abs() < 1e-9).all()
    # the numbers are the model's own at each condition
    tyre = load(TIR)
    r = base.iloc[0]
    out = tyre.evaluate(np.array([r["Fz"]]), 0.0, 0.0, 0.0, Vx=np.array([r["Vx"]]), P=np.array([r["P"]]))
    assert r["Kya"] == pytest.approx(float(out["Kya"][0]), rel=1e-12)
    assert r["Kxk"] == pytest.approx(float(out["Kxk"][0]), rel=1e-12)
    assert 0.8 < r["mu_x_peak"] < 2.0 and 0.005 < r["t0"] < 0.1
    # the figures: model curves over every condition
    from mftire.compare.plots import family_figures

    figs = family_figures("braking", comp.data, comp.grid, comp.grid_predictions)
    assert len(figs) == 1 and len(_visible_axes(figs[0][1])) == 2  # two speeds, one panel each


@pytest.mark.parametrize("spec, message", [
    ("", "empty"), ("loads=", "no value"), ("loads=3000,,4000", "empty value"), ("3000", "before any key"),
    ("lods=3000", "did you mean loads"), ("loads=3kN", "not a number"), ("loads=-100", "out of range"),
    ("speeds=-5", "out of range"), ("pressures=0", "out of range"), ("cambers=30", "out of range"),
    ("loads=1000,loads=2000", "given twice"),
])  # fmt: skip
def test_conditions_syntax_errors(spec, message):
    from mftire.compare.conditions import parse_conditions
    from mftire.errors import MftireInputError

    with pytest.raises(MftireInputError, match=message):
        parse_conditions(spec)


def test_conditions_parse_to_si():
    from mftire.compare.conditions import parse_conditions

    c = parse_conditions("loads=3000, 4500,speeds=36,72,pressures=2.2,cambers=-2,0")
    assert c["loads"] == (3000.0, 4500.0)
    assert c["speeds"] == pytest.approx((10.0, 20.0))
    assert c["pressures"] == pytest.approx((2.2e5,))
    assert c["cambers"] == pytest.approx((math.radians(-2), 0.0))


def test_cli_compare_without_data(tmp_path, capsys):
    out = tmp_path / "nodata"
    assert main(["compare", "--tir", str(TIR), str(TIR), "--conditions", "loads=4000,speeds=60",
                 "--output", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "no data, 1 condition(s)" in printed and "Kxk" in printed
    js = json.loads((out / "compare.json").read_text())
    assert len(js["characteristics"]) == 2
    assert (out / "braking.png").exists() and (out / "cornering_Mz.png").exists()
    assert "Slip stiffness, cornering stiffness, peak µ and trail" in (out / "compare.md").read_text()
    assert main(["compare", "--tir", str(TIR), "--conditions", "speeds=fast", "--output", str(tmp_path / "x")]) == 2
    assert "not a number" in capsys.readouterr().err


def test_cli_prints_a_repeated_warning_once_with_its_count(capsys):
    from mftire.cli import _one_line_warning

    shown = _one_line_warning("mftire diagnose")
    for _ in range(5):
        shown(UserWarning("Ex over limit"), UserWarning, "x.py", 1)
    shown(UserWarning("other"), UserWarning, "x.py", 2)
    shown.repeats()
    err = capsys.readouterr().err.splitlines()
    assert err == ["mftire diagnose: warning: Ex over limit", "mftire diagnose: warning: other",
                   "mftire diagnose: warning (×5 in all): Ex over limit"]
