"""The command line: evaluate, convert, info, plot, demo, and its input errors."""

from __future__ import annotations

import io

import numpy as np
import pandas as pd
import pytest
from conftest import REFERENCE_TYRES, TIR

from mftire import OUTPUT_NAMES, load
from mftire.cli import main

MF61 = str(REFERENCE_TYRES["MF61"])


def _write(path, text):
    path.write_text(text)
    return str(path)


def test_evaluate_writes_inputs_then_30_outputs(tmp_path):
    src = _write(tmp_path / "in.csv", "Fz,kappa,alpha,gamma,Vx\n4000,-0.1,0.05,0,20\n6000,0,0.1,0.02,30\n")
    dst = tmp_path / "out.csv"
    assert main(["evaluate", MF61, "--input", src, "--output", str(dst)]) == 0
    header = dst.read_text().splitlines()[0].split(",")
    echoed = {"Fz", "kappa", "alpha", "gamma", "Vx"}  # outputs named like an input column get "_model"
    model = [n + "_model" if n in echoed else n for n in OUTPUT_NAMES]
    assert header == ["Fz", "kappa", "alpha", "gamma", "Vx", *model]
    values = np.loadtxt(dst, delimiter=",", skiprows=1)
    ref = load(MF61).evaluate([4000, 6000], [-0.1, 0], [0.05, 0.1], [0, 0.02], Vx=[20, 30])
    for j, name in enumerate(OUTPUT_NAMES):
        np.testing.assert_array_equal(values[:, 5 + j], ref[name], err_msg=name)


def test_evaluate_to_stdout(tmp_path, capsys):
    src = _write(tmp_path / "in.csv", "Fz,kappa,alpha,gamma\n4000,-0.1,0.05,0\n")
    assert main(["evaluate", MF61, "--input", src, "--output", "-", "--mode", "211"]) == 0
    df = pd.read_csv(io.StringIO(capsys.readouterr().out))
    assert len(df) == 1 and df.shape[1] == 34


@pytest.mark.parametrize(
    "content, expected",
    [
        ("Fz,kappa,alpha\n4000,0,0\n", "missing column(s) gamma"),
        ("Fz,kappa,alpha,gamma\n4000,0,0,0\n4000,abc,0,0\n", "column 'kappa', row 2 (line 3): 'abc'"),
        ("Fz,kappa,alpha,gamma\n4000,0,,0\n", "column 'alpha', row 1 (line 2): empty or NaN"),
        ("Fz,kappa,alpha,gamma,Vx\n4000,0,0,0,nan\n", "column 'Vx', row 1"),
    ],
)
def test_evaluate_input_errors_exit_2_with_one_line(tmp_path, capsys, content, expected):
    src = _write(tmp_path / "in.csv", content)
    assert main(["evaluate", MF61, "--input", src, "--output", str(tmp_path / "o.csv")]) == 2
    err = capsys.readouterr().err
    assert expected in err
    assert err.count("\n") == 1
    assert not (tmp_path / "o.csv").exists()


def test_bad_tir_exits_2(tmp_path, capsys):
    bad = _write(tmp_path / "bad.tir", "[MODEL]\nFITTYP = 61\nLONGVL = fast\n")
    src = _write(tmp_path / "in.csv", "Fz,kappa,alpha,gamma\n4000,0,0,0\n")
    assert main(["evaluate", bad, "--input", src, "--output", "-"]) == 2
    err = capsys.readouterr().err
    assert "bad.tir" in err and "3" in err


def test_convert_evaluates_bit_identically(tmp_path):
    for src in [MF61, str(REFERENCE_TYRES["MF62"]), str(TIR / "MagicFormula52_Parameters.tir")]:
        dst = tmp_path / "copy.tir"
        assert main(["convert", src, str(dst), "--force"]) == 0  # replaced on each pass
        a, b = load(src), load(dst)
        rng = np.random.default_rng(1)
        args = (rng.uniform(500, 9000, 300), rng.uniform(-1, 1, 300), rng.uniform(-0.4, 0.4, 300))
        oa, ob = a.evaluate(*args, mode=211), b.evaluate(*args, mode=211)
        for k in OUTPUT_NAMES:
            np.testing.assert_array_equal(oa[k], ob[k], err_msg=k)


def test_info_reports_the_essentials(capsys):
    assert main(["info", MF61]) == 0
    out = capsys.readouterr().out
    assert "FITTYP 61" in out
    assert "FNOMIN = 6752 N" in out
    assert "NOMPRES = 2.6 bar" in out
    assert "[LATERAL_COEFFICIENTS]" in out
    assert "alpha -55.00 .. 55.00 deg" in out


def test_plot_writes_png_and_csv(tmp_path, capsys):
    png, csv = tmp_path / "c.png", tmp_path / "c.csv"
    assert main(["plot", MF61, "--output", str(png), "--csv", str(csv)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    curves = pd.read_csv(csv)
    assert set(curves.curve) == {"pure_long", "pure_lat", "combined"}
    assert set(curves.load_factor) == {0.5, 1.0, 1.5}
