"""Model extensions: evaluation, .tir round trip, plain-reader compatibility, CLI."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import REFERENCE_TYRES

from mftire import OUTPUT_NAMES, MftireInputError, Tyre, load, read_tir, write_tir
from mftire.cli import main
from mftire.extensions import LIBRARY, NEUTRAL, SECTION, active_extensions


def _extended(tmp_path, values: dict) -> str:
    params = read_tir(REFERENCE_TYRES["MF61"])
    for k, v in values.items():
        params.set(k, v, section=SECTION)
    path = tmp_path / "ext.tir"
    write_tir(params, path)
    return str(path)


def test_every_numeric_key_has_a_neutral_value():
    for ext in LIBRARY.values():
        for key in ext.keys:
            assert key in NEUTRAL, key


@pytest.mark.parametrize("name", [n for n, e in LIBRARY.items() if e.variable_key is None])
def test_neutral_extensions_change_nothing(tmp_path, name):
    keys = {k: NEUTRAL[k] for k in LIBRARY[name].keys}
    ext = load(_extended(tmp_path, keys))
    assert active_extensions(ext.extensions) == [name]
    base = load(REFERENCE_TYRES["MF61"])
    args = ([3000.0, 6000.0, 9000.0], [-0.3, 0.0, 0.1], [0.1, -0.05, 0.0])
    a, b = base.evaluate(*args), ext.evaluate(*args)
    for k in OUTPUT_NAMES:
        np.testing.assert_allclose(a[k], b[k], rtol=1e-14, atol=1e-12, err_msg=k)


def _scaled(factor: float) -> Tyre:
    """The base tyre with LMUX and LMUY multiplied by ``factor``."""
    flat = dict(load(REFERENCE_TYRES["MF61"]).flat)
    flat["LMUX"] *= factor
    flat["LMUY"] *= factor
    return Tyre(flat)


def _same(a, b, keys=("Fx", "Fy", "Mz", "Mx", "My", "mux", "muy")):
    for k in keys:
        np.testing.assert_allclose(a[k], b[k], rtol=1e-12, atol=1e-9, err_msg=k)


def test_slip_speed_friction_equals_scaling_lambda_mu(tmp_path):
    ext = load(_extended(tmp_path, {"VS_DECAY": 0.5}))
    V0 = ext["LONGVL"]
    for Vx, kappa, alpha in [(30.0, -1.0, 0.0), (10.0, -0.1, 0.05), (20.0, 0.0, 0.2)]:
        Vs = Vx * np.hypot(kappa, np.tan(alpha))
        factor = 1.0 / (1.0 + 0.5 * Vs / V0)  # Pacejka 2012 eq 4.E7
        _same(ext.evaluate(5000.0, kappa, alpha, Vx=Vx), _scaled(factor).evaluate(5000.0, kappa, alpha, Vx=Vx))
    # more slip speed, less friction: the locked wheel at 30 m/s has lost more than at 5 m/s
    base = load(REFERENCE_TYRES["MF61"])
    r5 = float(ext.evaluate(5000.0, -1.0, 0.0, Vx=5.0)["Fx"] / base.evaluate(5000.0, -1.0, 0.0, Vx=5.0)["Fx"])
    r30 = float(ext.evaluate(5000.0, -1.0, 0.0, Vx=30.0)["Fx"] / base.evaluate(5000.0, -1.0, 0.0, Vx=30.0)["Fx"])
    assert r30 < r5 < 1.0
    # slip stiffness is untouched
    assert float(ext.evaluate(5000.0, 0.0, 0.0)["Kxk"]) == float(base.evaluate(5000.0, 0.0, 0.0)["Kxk"])


def test_fade_needs_its_variable_and_names_it(tmp_path):
    path = _extended(tmp_path, {"FADE_VARIABLE": "energy", "FADE_DEPTH": 0.2, "FADE_SCALE": 1e6})
    tyre = load(path)
    assert tyre.required_variables == ["energy"]
    with pytest.raises(MftireInputError, match="'energy'"):
        tyre.evaluate(5000.0, -0.2, 0.0)
    energies = [0.0, 1e6, 1e9]
    out = tyre.evaluate(5000.0, -0.3, 0.05, energy=energies)
    for i, e in enumerate(energies):
        factor = 1 - 0.2 * (1 - np.exp(-e / 1e6))
        ref = _scaled(factor).evaluate(5000.0, -0.3, 0.05)
        _same({k: out[k][i] for k in out}, ref)


def test_extended_file_round_trips_and_plain_reader_ignores_section(tmp_path):
    path = _extended(tmp_path, {"FVAR_VARIABLE": "temperature", "FVAR_REF": 40.0, "FVAR_SCALE": 20.0,
                                "FVAR_C1": -0.05, "FVAR_C2": -0.01, "RR_FX": 0.012})  # fmt: skip
    again = tmp_path / "again.tir"
    write_tir(read_tir(path), again)
    assert read_tir(again) == read_tir(path)
    text = open(path).read()
    assert f"[{SECTION}]" in text
    # a plain MF 6.1 reader (key = value, '$' comments) gets the same MF parameters
    plain = {}
    for line in text.splitlines():
        line = line.split("$")[0].strip()
        if "=" in line and not line.startswith("["):
            k, v = (s.strip() for s in line.split("=", 1))
            plain[k] = v
    base = load(REFERENCE_TYRES["MF61"]).flat
    for k in ("PCX1", "PDY1", "QSX3", "FNOMIN"):
        assert float(plain[k]) == base[k]
    tyre = load(path)
    out = tyre.evaluate(5000.0, -0.1, 0.05, temperature=60.0)
    assert np.isfinite(out["Fx"])


def test_cli_evaluate_passes_extra_columns_and_names_missing_ones(tmp_path, capsys):
    path = _extended(tmp_path, {"FVAR_VARIABLE": "temperature", "FVAR_REF": 40.0, "FVAR_SCALE": 20.0,
                                "FVAR_C1": -0.1})  # fmt: skip
    src = tmp_path / "in.csv"
    src.write_text("Fz,kappa,alpha,gamma,temperature\n5000,-0.2,0,0,40\n5000,-0.2,0,0,60\n")
    dst = tmp_path / "out.csv"
    assert main(["evaluate", path, "--input", str(src), "--output", str(dst)]) == 0
    fx = np.loadtxt(dst, delimiter=",", skiprows=1)[:, 5]
    assert fx[0] == pytest.approx(float(_scaled(1.0).evaluate(5000.0, -0.2, 0.0)["Fx"]), rel=1e-12)
    assert fx[1] == pytest.approx(float(_scaled(0.9).evaluate(5000.0, -0.2, 0.0)["Fx"]), rel=1e-12)
    src.write_text("Fz,kappa,alpha,gamma\n5000,-0.2,0,0\n")
    assert main(["evaluate", path, "--input", str(src), "--output", str(dst), "--force"]) == 2
    assert "temperature" in capsys.readouterr().err


def test_generic_correction_is_labelled_not_physics():
    assert LIBRARY["generic"].physical is False
    assert all(e.physical for n, e in LIBRARY.items() if n != "generic")


def test_mapping_input_with_extension_section():
    flat = dict(load(REFERENCE_TYRES["MF61"]).flat)
    flat[SECTION] = {"ASYM_MUY": 0.05}
    tyre = Tyre(flat)
    out = tyre.evaluate(5000.0, 0.0, [0.2, -0.2])
    sym = Tyre({k: v for k, v in flat.items() if k != SECTION}).evaluate(5000.0, 0.0, [0.2, -0.2])
    assert abs(out["Fy"][0]) > abs(sym["Fy"][0])
    assert abs(out["Fy"][1]) < abs(sym["Fy"][1])


def test_bad_extension_values_raise_input_errors():
    flat = dict(load(REFERENCE_TYRES["MF61"]).flat)
    flat[SECTION] = {"VS_DECAY": "fast"}
    with pytest.raises(MftireInputError, match="VS_DECAY"):
        Tyre(flat).evaluate(5000.0, -0.1, 0.0)
    flat[SECTION] = {"FVAR_VARIABLE": "phit", "FVAR_C1": 0.1}
    with pytest.raises(MftireInputError, match="phit"):
        Tyre(flat)
