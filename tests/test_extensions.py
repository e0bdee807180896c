"""Model extensions as scaling-factor terms: evaluation, forms, .tir round trip, the one
pipeline shared by the evaluator and the fitter, and fitting from an extended template."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from conftest import REFERENCE_TYRES
from hypothesis import given, settings
from hypothesis import strategies as st

from mftire import OUTPUT_NAMES, MftireInputError, Tyre, load, read_tir, write_tir
from mftire.cli import main
from mftire.fitting import fit_tir
from mftire.fitting.model import Inputs, predict
from mftire.mf.extensions import FORMS, SECTION, make_extension, parse_section
from mftire.mf.modes import Mode

MODES = (111, 121, 211, 221, 110, 112, 212, 222)


def _term(n: int, target: str, form: str, variable: str, **numbers) -> dict:
    out = {f"EXT{n}_TARGET": target, f"EXT{n}_FORM": form, f"EXT{n}_VARIABLE": variable}
    out.update({f"EXT{n}_{k.upper()}": v for k, v in numbers.items()})
    return out


def _extended(entries: dict, base: str = "MF61") -> Tyre:
    params = read_tir(REFERENCE_TYRES[base])
    for k, v in entries.items():
        params.set(k, v, section=SECTION)
    return Tyre(params, name="ext.tir")


def _scaled(**factors: float) -> Tyre:
    """The base tyre with the named scaling factors multiplied."""
    flat = dict(load(REFERENCE_TYRES["MF61"]).flat)
    for k, f in factors.items():
        flat[k] *= f
    return Tyre(flat)


def _same(a, b, keys=("Fx", "Fy", "Mz", "Mx", "My", "mux", "muy", "Kxk", "Kya")):
    for k in keys:
        np.testing.assert_allclose(a[k], b[k], rtol=1e-12, atol=1e-9, err_msg=k)


ARGS = ([3000.0, 6000.0, 9000.0], [-0.3, 0.0, 0.1], [0.1, -0.05, 0.0])


@pytest.mark.parametrize("form", list(FORMS))
def test_neutral_terms_change_nothing(form):
    numbers = {"ref": 4000.0} if form == "power" else {}
    if form == "table":
        numbers.update(l1=3000.0, l2=6000.0)
    entries = _term(1, "LMUX LMUY LKX LKY LEX", form, "Fz", **numbers)
    if FORMS[form].two_variables:
        entries["EXT1_VARIABLE2"] = "Vs"
    ext = _extended(entries)
    base = load(REFERENCE_TYRES["MF61"])
    a, b = base.evaluate(*ARGS), ext.evaluate(*ARGS)
    for k in OUTPUT_NAMES:
        np.testing.assert_allclose(a[k], b[k], rtol=1e-14, atol=1e-12, err_msg=k)


def test_slip_speed_decay_is_eq_4E7():
    """decay(Vs) with SCALE = LONGVL on LMUX, LMUY is Pacejka 2012 eq 4.E7 with LMUV = C1."""
    ext = _extended(_term(1, "LMUX LMUY", "decay", "Vs", scale=16.7, c1=0.5))
    for Vx, kappa, alpha in [(30.0, -1.0, 0.0), (10.0, -0.1, 0.05), (20.0, 0.0, 0.2)]:
        Vs = Vx * np.hypot(kappa, np.tan(alpha))
        f = 1.0 / (1.0 + 0.5 * Vs / 16.7)  # eq 4.E7
        _same(ext.evaluate(5000.0, kappa, alpha, Vx=Vx), _scaled(LMUX=f, LMUY=f).evaluate(5000.0, kappa, alpha, Vx=Vx))
    base = load(REFERENCE_TYRES["MF61"])
    r5 = float(ext.evaluate(5000.0, -1.0, 0.0, Vx=5.0)["Fx"] / base.evaluate(5000.0, -1.0, 0.0, Vx=5.0)["Fx"])
    r30 = float(ext.evaluate(5000.0, -1.0, 0.0, Vx=30.0)["Fx"] / base.evaluate(5000.0, -1.0, 0.0, Vx=30.0)["Fx"])
    assert r30 < r5 < 1.0
    assert float(ext.evaluate(5000.0, 0.0, 0.0)["Kxk"]) == float(base.evaluate(5000.0, 0.0, 0.0)["Kxk"])


def test_stiffness_term_moves_stiffness_not_friction():
    ext = _extended(_term(1, "LKX LKY", "linear", "temperature", ref=50.0, scale=25.0, c1=-0.2))
    base = load(REFERENCE_TYRES["MF61"])
    hot = ext.evaluate(5000.0, 0.0, 0.0, temperature=75.0)
    ref = base.evaluate(5000.0, 0.0, 0.0)
    assert float(hot["Kxk"]) == pytest.approx(0.8 * float(ref["Kxk"]), rel=1e-12)
    assert float(hot["Kya"]) == pytest.approx(0.8 * float(ref["Kya"]), rel=1e-12)
    assert float(hot["mux"]) == pytest.approx(float(ref["mux"]), rel=1e-12)


@pytest.mark.parametrize(
    ("form", "numbers", "u", "expected"),
    [
        ("linear", {"ref": 10.0, "scale": 5.0, "c1": 0.1}, 20.0, 1.2),
        ("quadratic", {"ref": 10.0, "scale": 5.0, "c1": 0.1, "c2": -0.05}, 20.0, 1.0),
        ("saturating", {"ref": 0.0, "scale": 100.0, "c1": -0.3, "c2": 2.0}, 50.0, 1 - 0.3 * (1 - np.exp(-1.0))),
        ("saturating", {"ref": 0.0, "scale": 100.0, "c1": -0.3, "c2": 2.0}, -50.0, 1.0),
        ("power", {"ref": 4000.0, "c1": -0.5}, 16000.0, 0.5),
        ("decay", {"scale": 10.0, "c1": 1.0}, 10.0, 0.5),
        # a table is linear between its levels (a temperature between two tested ones), the end value beyond them
        ("table", {"l1": 0.0, "l2": 1.0, "c1": 0.0, "c2": -0.3}, 0.9, 0.73),
        ("table", {"l1": 0.0, "l2": 1.0, "c1": 0.0, "c2": -0.3}, 1.0, 0.7),
        ("table", {"l1": 0.0, "l2": 1.0, "c1": 0.0, "c2": -0.3}, 7.0, 0.7),
        ("table", {"l1": 0.0, "l2": 1.0, "c1": 0.1, "c2": -0.3}, -2.0, 1.1),
        ("table", {"l1": 50.0, "l2": 10.0, "l3": 30.0, "c1": 0.2, "c2": -0.2, "c3": 0.0}, 40.0, 1.1),  # any order
        ("linear", {"ref": 10.0, "scale": 5.0, "min": 0.0, "max": 15.0, "c1": 0.1}, 40.0, 1.1),  # clipped
    ],
)
def test_form_values(form, numbers, u, expected):
    t = make_extension(1, "LMUX", form, "x", **numbers)
    assert float(t.factor(np.array(u), None)) == pytest.approx(expected, rel=1e-12)


def test_interaction_acts_only_where_the_flag_is_set():
    t = make_extension(1, "LMUX LMUY", "interaction", "wet", variable2="Vx", ref2=10.0, scale2=10.0, c1=-0.1,
                       c2=-0.2)  # fmt: skip
    f = t.factor(np.array([0.0, 0.0, 1.0, 1.0]), np.array([10.0, 30.0, 10.0, 30.0]))
    np.testing.assert_allclose(f, [1.0, 1.0, 0.9, 0.5], rtol=1e-12)


@settings(max_examples=40, deadline=None)
@given(c1=st.floats(0.0, 5.0), vs=st.floats(0.0, 60.0))
def test_decay_never_increases_friction(c1, vs):
    t = make_extension(1, "LMUX", "decay", "Vs", scale=16.7, c1=c1)
    f = float(t.factor(np.array(vs), None))
    assert 0.0 < f <= 1.0


def test_external_variable_is_required_and_named():
    tyre = _extended(_term(1, "LMUX LMUY", "saturating", "time", scale=100.0, c1=-0.2, c2=1.0))
    assert tyre.required_variables == ["time"]
    with pytest.raises(MftireInputError, match="'time'"):
        tyre.evaluate(5000.0, -0.2, 0.0)
    out = tyre.evaluate(5000.0, -0.3, 0.05, time=[0.0, 100.0, 1e6])
    for i, t in enumerate([0.0, 100.0, 1e6]):
        f = 1 - 0.2 * (1 - np.exp(-t / 100.0))
        _same({k: out[k][i] for k in out}, _scaled(LMUX=f, LMUY=f).evaluate(5000.0, -0.3, 0.05))


def test_history_quantities_are_not_variables():
    with pytest.raises(MftireInputError, match="measured history"):
        _extended(_term(1, "LMUX", "linear", "energy", c1=0.1))


def test_offsets_add_force_proportional_to_load():
    ext = _extended(_term(1, "FY_OFFSET", "linear", "sign_alpha", c1=0.02))
    base = load(REFERENCE_TYRES["MF61"])
    d = ext.evaluate(5000.0, 0.0, [0.1, -0.1], mode=110)["Fy"] - base.evaluate(5000.0, 0.0, [0.1, -0.1], mode=110)["Fy"]
    np.testing.assert_allclose(d, [100.0, -100.0], rtol=1e-12)


def test_extended_file_round_trips_and_plain_reader_ignores_section(tmp_path):
    tyre = _extended(_term(1, "LMUX LMUY", "quadratic", "temperature", ref=40.0, scale=20.0, c1=-0.05, c2=-0.01))
    path = tmp_path / "ext.tir"
    write_tir(tyre.parameters, path)
    again = tmp_path / "again.tir"
    write_tir(read_tir(path), again)
    assert read_tir(again) == read_tir(path)
    text = path.read_text()
    assert f"[{SECTION}]" in text
    plain = {}
    for line in text.splitlines():
        line = line.split("$")[0].strip()
        if "=" in line and not line.startswith("["):
            k, v = (s.strip() for s in line.split("=", 1))
            plain[k] = v
    base = load(REFERENCE_TYRES["MF61"]).flat
    for k in ("PCX1", "PDY1", "QSX3", "FNOMIN"):
        assert float(plain[k]) == base[k]
    assert parse_section(read_tir(path).sections[SECTION]) == tyre.extension_set


def test_cli_evaluate_passes_extra_columns_and_names_missing_ones(tmp_path, capsys):
    tyre = _extended(_term(1, "LMUX LMUY", "linear", "temperature", ref=40.0, scale=20.0, c1=-0.1))
    path = tmp_path / "ext.tir"
    write_tir(tyre.parameters, path)
    src = tmp_path / "in.csv"
    src.write_text("Fz,kappa,alpha,gamma,temperature\n5000,-0.2,0,0,40\n5000,-0.2,0,0,60\n")
    dst = tmp_path / "out.csv"
    assert main(["evaluate", str(path), "--input", str(src), "--output", str(dst)]) == 0
    out = pd.read_csv(dst)
    fx = out[[c for c in out.columns if c.startswith("Fx")][0]].to_numpy()
    assert fx[0] == pytest.approx(float(_scaled().evaluate(5000.0, -0.2, 0.0)["Fx"]), rel=1e-12)
    assert fx[1] == pytest.approx(float(_scaled(LMUX=0.9, LMUY=0.9).evaluate(5000.0, -0.2, 0.0)["Fx"]), rel=1e-12)
    src.write_text("Fz,kappa,alpha,gamma\n5000,-0.2,0,0\n")
    assert main(["evaluate", str(path), "--input", str(src), "--output", str(dst), "--force"]) == 2
    assert "temperature" in capsys.readouterr().err


def test_bad_extension_values_raise_input_errors():
    flat = dict(load(REFERENCE_TYRES["MF61"]).flat)
    flat[SECTION] = _term(1, "LMUX", "decay", "Vs", c1="fast")
    with pytest.raises(MftireInputError, match="EXT1_C1"):
        Tyre(flat)
    flat[SECTION] = _term(1, "LMUX", "linear", "phit", c1=0.1)
    with pytest.raises(MftireInputError, match="phit"):
        Tyre(flat)
    flat[SECTION] = {"VS_DECAY": 0.3}
    with pytest.raises(MftireInputError, match="VS_DECAY: not an extension key"):
        Tyre(flat)


# --------------------------------------------------------------------------- one pipeline

EXTENDED = {
    **_term(1, "LMUX LMUY", "decay", "Vs", scale=16.7, c1=0.4),
    **_term(2, "LKX LKY LTR", "linear", "temperature", ref=50.0, scale=25.0, c1=-0.1),
    **_term(3, "FX_OFFSET", "linear", "sign_kappa", c1=0.005),
    **_term(4, "P_FACTOR ALPHA_OFFSET", "hinge", "temperature", ref=50.0, scale=25.0, min=0.0, max=90.0, c1=0.02,
            c2=-0.5),
}


@pytest.mark.filterwarnings("ignore::mftire.mf.inputs.MFLimitWarning")  # Ex clipped at the largest slips
@pytest.mark.parametrize("extended", [False, True])
@pytest.mark.parametrize("mode", MODES)
def test_fitter_prediction_equals_evaluate(mode, extended):
    """The fitter's model and Tyre.evaluate are the same pipeline: equal to the last bit."""
    tyre = _extended(EXTENDED if extended else {}, base="MF62" if mode % 2 else "MF61")
    rng = np.random.default_rng(mode)
    n = 200
    x = Inputs(rng.uniform(1000, 9000, n), rng.uniform(-0.5, 0.5, n), rng.uniform(-0.3, 0.3, n),
               rng.uniform(-0.08, 0.08, n), rng.uniform(1, 40, n), rng.uniform(1.8e5, 2.8e5, n),
               {"temperature": rng.uniform(0, 100, n)} if extended else {})  # fmt: skip
    # bit for bit with the numpy reference (the compiled kernel agrees to 1e-12: tests/test_kernel.py)
    ref = tyre.evaluate(x.Fz, x.kappa, x.alpha, x.gamma, 0.0, x.Vx, x.P, mode=mode, backend="numpy", **x.variables)
    for ch in ("Fx", "Fy", "Mz", "Mx", "My"):
        got = predict(tyre.flat, x, ch, Mode.from_code(mode), tyre.extension_set)
        np.testing.assert_array_equal(got, ref[ch], err_msg=f"{ch} mode {mode}")


def _campaign(tyre: Tyre, seed: int = 0) -> pd.DataFrame:
    """Pure braking and cornering sweeps at three loads and three temperatures, 0.5 % noise."""
    rng = np.random.default_rng(seed)
    rows = []
    for Fz in (3000.0, 5000.0, 7000.0):
        for temp in (20.0, 50.0, 80.0):
            k = np.linspace(-0.3, 0.3, 41)
            a = np.radians(np.linspace(-12, 12, 41))
            rows.append(pd.DataFrame(dict(Fz=Fz, kappa=k, alpha=0.0, gamma=0.0, Vx=16.7, P=2.2e5, temperature=temp)))
            rows.append(pd.DataFrame(dict(Fz=Fz, kappa=0.0, alpha=a, gamma=0.0, Vx=16.7, P=2.2e5, temperature=temp)))
    df = pd.concat(rows, ignore_index=True)
    extra = {"temperature": df["temperature"].to_numpy()} if "temperature" in tyre.required_variables else {}
    out = tyre.evaluate(df["Fz"], df["kappa"], df["alpha"], df["gamma"], 0.0, df["Vx"], df["P"], mode=211, **extra)
    for ch in ("Fx", "Fy", "Mz"):
        y = np.asarray(out[ch])
        df[ch] = y + rng.normal(0, 0.005 * np.abs(y).max(), len(y))
    return df


def test_fit_from_extended_template_improves_and_evaluates_to_prediction(tmp_path):
    truth = _extended(_term(1, "LMUX LMUY", "linear", "temperature", ref=50.0, scale=30.0, c1=-0.12))
    data = _campaign(truth)
    start = _extended(_term(1, "LMUX LMUY", "linear", "temperature", ref=50.0, scale=30.0, c1=0.0))
    plain = load(REFERENCE_TYRES["MF61"])
    res = fit_tir(data, start.parameters, stages="1,2,3")
    res_plain = fit_tir(data.drop(columns="temperature"), plain.parameters, stages="1,2,3")
    assert "EXT1_C1" in res.identified
    assert res.flat["EXT1_C1"] == pytest.approx(-0.12, abs=0.01)
    path = tmp_path / "fitted.tir"
    write_tir(res.parameters, path)
    fitted = load(path)
    out = fitted.evaluate(data["Fz"], data["kappa"], data["alpha"], data["gamma"], 0.0, data["Vx"], data["P"],
                          mode=211, temperature=data["temperature"].to_numpy())  # fmt: skip
    for ch in ("Fx", "Fy", "Mz"):
        np.testing.assert_allclose(out[ch], res.data[f"fit_{ch}"], rtol=1e-9, atol=1e-9, err_msg=ch)
        rms = np.sqrt(np.mean((res.data[f"fit_{ch}"] - data[ch]) ** 2))
        rms_plain = np.sqrt(np.mean((res_plain.data[f"fit_{ch}"] - data[ch]) ** 2))
        if ch != "Mz":
            assert rms < 0.5 * rms_plain, (ch, rms, rms_plain)


def test_fit_refuses_template_variable_missing_from_data():
    start = _extended(_term(1, "LMUX LMUY", "linear", "temperature", c1=0.0))
    data = _campaign(load(REFERENCE_TYRES["MF61"]))
    with pytest.raises(MftireInputError, match="temperature"):
        fit_tir(data.drop(columns="temperature"), start.parameters, stages="1")


def test_entry_points_accept_path_parameters_or_tyre(tmp_path):
    from mftire.curves import standard_curves
    from mftire.tyre import as_tyre

    path = REFERENCE_TYRES["MF61"]
    tyre = load(path)
    for obj in (path, str(path), tyre.parameters, tyre):
        assert as_tyre(obj).flat == tyre.flat
        curves = standard_curves(obj, n=5)
        assert np.isfinite(curves["Fx"]).all()
    with pytest.raises(TypeError):
        as_tyre(3.0)


def test_fitting_model_clips_curvature_as_the_fitted_file_evaluates():
    """A fit may reach curvature factors above 1 at some loads (eqs 4.E14, 4.E24); the file it writes is
    evaluated in mode 111, which clips them to 1.  The fitter's model clips them too (without clipping the
    inputs), so its prediction is what the written file gives."""
    import warnings

    from mftire.fitting.model import fitting_mode
    from mftire.mf.inputs import MFLimitWarning

    params = read_tir(REFERENCE_TYRES["MF61"])
    params.set("PEX1", 0.9)
    params.set("PEX2", 0.6)  # Ex > 1 above FNOMIN
    params.set("PEY1", 0.95)
    params.set("PEY2", -0.5)  # Ey > 1 below FNOMIN
    tyre = Tyre(params)
    n = 120
    rng = np.random.default_rng(3)
    x = Inputs(rng.uniform(1500, 8000, n), rng.uniform(-0.3, 0.3, n), rng.uniform(-0.2, 0.2, n), np.zeros(n),
               np.full(n, 16.7), np.full(n, 2.2e5))  # fmt: skip
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        # bit for bit with the numpy reference (the compiled kernel agrees to 1e-12: tests/test_kernel.py)
        ref = tyre.evaluate(x.Fz, x.kappa, x.alpha, x.gamma, 0.0, x.Vx, x.P, mode=111, backend="numpy")
        assert any(issubclass(w.category, MFLimitWarning) for w in seen)  # the clip is active here
        seen.clear()
        unclipped = tyre.evaluate(x.Fz, x.kappa, x.alpha, x.gamma, 0.0, x.Vx, x.P, mode=211)
        for ch in ("Fx", "Fy", "Mz"):
            got = predict(tyre.flat, x, ch, fitting_mode())
            np.testing.assert_array_equal(got, ref[ch], err_msg=ch)
            assert np.max(np.abs(got - unclipped[ch])) > 10.0, ch  # and it matters
        assert not any(issubclass(w.category, MFLimitWarning) for w in seen)  # silent while fitting


# ------------------------------------------------------------ issue 21: identifiers, new forms, input laws


@pytest.mark.parametrize("name", ["run", "sweep_id", "RunNumber", "seg_no", "file3", "row", "test_index", "Sequence"])
def test_identifier_is_refused_as_law_variable_through_the_api(name):
    with pytest.raises(MftireInputError, match="identifier"):
        make_extension(1, "LMUX", "linear", name, c1=0.1)
    with pytest.raises(MftireInputError, match="EXT1_VARIABLE2.*identifier"):
        make_extension(1, "LMUX", "interaction", "wet", variable2=name, c1=0.1)


@pytest.mark.parametrize("name", ["tread_temp", "time", "wet", "sweep_dir", "mileage", "runtime"])
def test_physical_variables_are_not_identifiers(name):
    assert make_extension(1, "LMUX", "linear", name, c1=0.1).variable == name


def test_identifier_is_refused_when_reading_a_tir(tmp_path):
    params = read_tir(REFERENCE_TYRES["MF61"])
    for k, v in _term(1, "LMUX LMUY", "interaction", "wet", c1=-0.1, c2=0.01).items():
        params.set(k, v, section=SECTION)
    params.set("EXT1_VARIABLE2", "run", section=SECTION)
    path = tmp_path / "run_law.tir"
    write_tir(params, path)
    with pytest.raises(MftireInputError, match=r"EXT1_VARIABLE2 = 'run'.*identifier"):
        load(path)


@pytest.mark.parametrize(
    ("form", "numbers", "u", "expected"),
    [
        ("hinge", {"ref": 50.0, "scale": 10.0, "c1": -0.1, "c2": 1.0}, 55.0, 1.0),  # below the threshold
        ("hinge", {"ref": 50.0, "scale": 10.0, "c1": -0.1, "c2": 1.0}, 80.0, 0.8),  # 2 scales above it
        ("direction", {"c1": 0.05}, 1.0, 1.05),
        ("direction", {"c1": 0.05}, -1.0, 0.95),
        ("direction", {"c1": 0.05}, 0.0, 1.0),
    ],
)
def test_hinge_and_direction_form_values(form, numbers, u, expected):
    t = make_extension(1, "LMUY", form, "x", **numbers)
    assert float(t.factor(np.array(u), None)) == pytest.approx(expected, rel=1e-12)


def test_input_laws_equal_the_corrected_inputs():
    """P_FACTOR evaluates the tyre at P·f, ALPHA_OFFSET / GAMMA_OFFSET / KAPPA_OFFSET at alpha / gamma / kappa
    + (f − 1)."""
    base = load(REFERENCE_TYRES["MF61"])
    P0 = base["NOMPRES"]
    ext = _extended({**_term(1, "P_FACTOR", "linear", "tread_temp", ref=20.0, scale=100.0, c1=0.1),
                     **_term(2, "ALPHA_OFFSET", "linear", "tread_temp", ref=20.0, scale=100.0, c1=0.01),
                     **_term(3, "GAMMA_OFFSET", "linear", "tread_temp", ref=20.0, scale=100.0, c1=-0.02),
                     **_term(4, "KAPPA_OFFSET", "linear", "tread_temp", ref=20.0, scale=100.0, c1=0.015)})  # fmt: skip
    T = np.array([20.0, 70.0, 120.0])
    f = 1.0 + (T - 20.0) / 100.0
    got = ext.evaluate(5000.0, -0.05, 0.04, 0.01, P=P0, tread_temp=T, mode=121)
    ref = base.evaluate(5000.0, -0.05 + 0.015 * (f - 1), 0.04 + 0.01 * (f - 1), 0.01 - 0.02 * (f - 1),
                        P=P0 * (1.0 + 0.1 * (f - 1)), mode=121)  # fmt: skip
    for k in ("Fx", "Fy", "Mz", "Mx", "My"):
        np.testing.assert_allclose(got[k], ref[k], rtol=1e-10, atol=1e-9, err_msg=k)
    assert not np.allclose(got["Fy"], base.evaluate(5000.0, -0.05, 0.04, 0.01, P=P0, mode=121)["Fy"])


def test_shift_factor_laws_take_wider_bounds_on_their_size_only():
    """A file's shift is often near zero (PHX1 ~ 1e-3), so a law on LHX/LHY/LVX/LVY may move it by many times:
    its size coefficients take WIDE_TARGETS x the form's bounds, of either sign; a threshold, a rate or another
    target's law keeps the form's bounds."""
    from mftire.mf.extensions import FORMS, WIDE_TARGETS, make_extension

    w = WIDE_TARGETS["LHX"]
    lin = make_extension(1, ("LHX",), "linear", "T", REF=0.0, SCALE=1.0)
    assert lin.bounds("EXT1_C1") == (-2.0 * w, 2.0 * w)
    sat = make_extension(1, ("LVY",), "saturating", "T", REF=0.0, SCALE=1.0)
    assert sat.bounds("EXT1_C1") == (-2.0 * w, 2.0 * w)  # the form's (-0.9, 2) keeps a factor positive
    assert sat.bounds("EXT1_C2") == FORMS["saturating"].bounds[1]  # a rate
    hinge = make_extension(1, ("LVX",), "hinge", "T", REF=0.0, SCALE=1.0)
    assert hinge.bounds("EXT1_C2") == FORMS["hinge"].bounds[1]  # a threshold
    assert make_extension(1, ("LMUX",), "linear", "T", REF=0.0, SCALE=1.0).bounds("EXT1_C1") == (-2.0, 2.0)
    # the residual torque is an additive torque of a few N·m (Dr, eq 4.E47): a hysteresis torque that changes sign
    # between up and down sweeps (LRES x (1 ± 3)) must be inside the bounds, which the form's ±0.5 is not
    hyst = make_extension(1, ("LRES",), "direction", "sweep_dir", REF=0.0, SCALE=1.0)
    assert hyst.bounds("EXT1_C1") == (-0.5 * WIDE_TARGETS["LRES"], 0.5 * WIDE_TARGETS["LRES"])
    assert hyst.bounds("EXT1_C1")[1] >= 3.0 and FORMS["direction"].bounds[0][1] < 1.0
    # a term on a shift and a friction factor together keeps the narrow bounds
    assert make_extension(1, ("LHX", "LMUX"), "linear", "T", REF=0.0, SCALE=1.0).bounds("EXT1_C1") == (-2.0, 2.0)
