"""The .tir files people actually have (issue 16): tolerant reading and the wild collection.

The collection is every third-party file shipped in ``tests/data/tir`` and
``tests/data/tir_wild`` (sources and licences in their README/NOTICE), plus two
variants built here with the quirks of real files (``KEY =`` with nothing after it,
``MASS = kg``), since the public files that have them could not be shipped under
their licence (see ``tests/data/tir_wild/README.md``).
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import DATA, TIR

from mftire.cli import main
from mftire.errors import MftireTirWarning
from mftire.iotools.evaluator_keys import EVALUATOR_KEYS, evaluator_keys
from mftire.iotools.tir import MalformedLineError, NonNumericValueError, TirError, TirWarning, read_tir
from mftire.mf import usedkeys
from mftire.tyre import Tyre, load

WILD = DATA / "tir_wild"
MF61 = TIR / "MagicFormula61_Parameters.tir"
MF52 = TIR / "MagicFormula52_Parameters.tir"


def _quirky(src: Path, dst: Path, edits: dict[str, str]) -> Path:
    """Copy ``src`` with the value of each key of ``edits`` replaced by the given text.

    The last line of the key is edited (``MASS`` is both a ``[UNITS]`` entry and the tyre mass).
    """
    text = src.read_text(encoding="latin-1")
    for key, value in edits.items():
        m = list(re.finditer(rf"(?m)^({key}\s*=)[^\r\n]*", text))[-1]
        text = text[: m.start()] + m.group(1) + value + text[m.end() :]
    dst.write_text(text, encoding="latin-1")
    return dst


# ------------------------------------------------------------------ tolerant reading
def test_blank_and_non_numeric_values_on_unused_keys_warn_and_are_absent(tmp_path):
    path = _quirky(MF61, tmp_path / "q.tir", {"MASS": " kg", "IXX": " ", "BELT_MASS": "   $ no value", "TYRESIDE": ""})
    with pytest.warns(TirWarning) as caught:
        params = read_tir(path)
    messages = [str(w.message) for w in caught]
    assert len(messages) == 1  # one warning per file, every line named
    (m,) = messages
    assert m.startswith(f"{path}: 4 value(s) treated as absent (") and "the evaluator uses" not in m
    text = path.read_text().splitlines()
    lines = {k: [i for i, t in enumerate(text, 1) if re.match(rf"{k}\s*=", t)][-1]  # the edited (last) line
             for k in ("MASS", "IXX", "BELT_MASS", "TYRESIDE")}
    assert f"line {lines['MASS']}: MASS needs a number: " in m and f"line {lines['IXX']}: IXX has no value" in m
    assert f"line {lines['BELT_MASS']}: BELT_MASS has no value" in m and f"line {lines['TYRESIDE']}: TYRESIDE" in m
    assert "MASS" not in params and "IXX" not in params and "TYRESIDE" not in params
    # the tyre evaluates exactly as the original file
    ref = load(MF61).evaluate(4000.0, np.array([-0.1, 0.0, 0.05]), np.array([0.0, 0.05, -0.02]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TirWarning)
        out = load(path).evaluate(4000.0, np.array([-0.1, 0.0, 0.05]), np.array([0.0, 0.05, -0.02]))
    for k in ref:
        np.testing.assert_array_equal(out[k], ref[k], err_msg=k)


def test_blank_value_on_a_used_key_with_a_default_warns_and_takes_the_default(tmp_path):
    """MF-Tool / MF-Swift exports leave unfitted keys blank (INFLPRES, the ranges, VERTICAL_STIFFNESS):
    the file evaluates, the warning names each line and the default the evaluator takes."""
    path = _quirky(MF61, tmp_path / "blank.tir", {"INFLPRES": " ", "FZMAX": "", "VERTICAL_STIFFNESS": "   $ n/a"})
    with pytest.warns(TirWarning) as caught:
        tyre = Tyre.from_file(path)
    m = " ".join(str(w.message) for w in caught if isinstance(w.message, TirWarning))
    assert "3 value(s) treated as absent (INFLPRES, VERTICAL_STIFFNESS, FZMAX)" in m
    assert ("the evaluator uses the defaults of INFLPRES (NOMPRES), VERTICAL_STIFFNESS (200000 N/m), "
            "FZMAX (10000 N)") in m
    assert tyre.flat["INFLPRES"] == tyre.flat["NOMPRES"] and tyre.flat["FZMAX"] == 10000.0
    out = tyre.evaluate(4000.0, 0.05, 0.02)
    assert np.isfinite([out[k] for k in ("Fx", "Fy", "Mz", "Re", "Rl")]).all()
    with pytest.raises(MalformedLineError, match=r"blank\.tir, line \d+: INFLPRES has no value \(strict reading\)"):
        read_tir(path, strict=True)


@pytest.mark.parametrize(
    ("key", "value", "cls"),
    [("PKY1", " ", MalformedLineError), ("FNOMIN", " kN", NonNumericValueError), ("FNOMIN", "", MalformedLineError),
     ("QDZ1", " $ blank", MalformedLineError), ("LONGVL", " fast", NonNumericValueError),
     ("QSY1", " ", MalformedLineError), ("RBX1", "", MalformedLineError),
     ("PDX1", " 1,2", NonNumericValueError)],
)
def test_blank_or_non_numeric_value_on_a_used_key_is_an_error(tmp_path, key, value, cls):
    path = _quirky(MF61, tmp_path / "bad.tir", {key: value})
    lineno = next(i for i, t in enumerate(path.read_text().splitlines(), 1) if t.startswith(key))
    with pytest.raises(cls) as excinfo:
        read_tir(path)
    err = excinfo.value
    assert err.line == lineno and err.path == str(path)
    assert f"bad.tir, line {lineno}" in str(err) and f"the evaluator uses {key}" in str(err)
    if value == " 1,2":
        assert "decimal comma" in str(err)


def test_strict_makes_warnings_errors(tmp_path):
    path = _quirky(MF61, tmp_path / "q.tir", {"MASS": " kg"})
    with pytest.raises(NonNumericValueError, match=r"q\.tir, line \d+: MASS needs a number \(strict reading\)"):
        read_tir(path, strict=True)
    with pytest.raises(TirError, match="strict"):
        Tyre.from_file(path, strict=True)


def test_cli_strict(tmp_path, capsys):
    path = _quirky(MF61, tmp_path / "q.tir", {"MASS": " kg"})
    assert main(["info", str(path)]) == 0
    cap = capsys.readouterr()
    assert "FITTYP 61" in cap.out
    assert "MASS needs a number" in cap.err  # the reading warning, printed by the CLI as one line
    assert main(["info", "--strict", str(path)]) == 2
    err = capsys.readouterr().err
    assert "q.tir, line" in err and "MASS" in err and len(err.strip().splitlines()) == 1
    csv = tmp_path / "in.csv"
    csv.write_text("Fz,kappa,alpha,gamma\n4000,0,0.05,0\n")
    assert main(["evaluate", "--strict", str(path), "--input", str(csv), "--output", "-"]) == 2


def test_info_reports_pac2002_not_an_invented_fittyp(capsys):
    assert main(["info", str(TIR / "chrono_HMMWV_Pac02Tire.tir")]) == 0
    out = capsys.readouterr().out
    assert "model:           PAC2002" in out and "FITTYP" not in out


def test_evaluator_keys_come_from_the_code():
    keys = evaluator_keys()
    assert {"PKY1", "FNOMIN", "QSX14", "LMUV", "LGAY", "IP_NOM", "Q_RA1"} <= keys
    assert not {"MASS", "IXX", "TYRESIDE", "BELT_MASS", "FREQ_LONG"} & keys


def test_evaluator_keys_data_module_is_current():
    # the reader's table is data (iotools imports nothing above it); it must equal a fresh scan of the
    # evaluator's look-ups, and the generated file must be what the generator writes today
    scanned = usedkeys.scan_evaluator_keys()
    assert EVALUATOR_KEYS == scanned, f"regenerate: python -m mftire.mf.usedkeys ({sorted(EVALUATOR_KEYS ^ scanned)})"
    assert usedkeys.TARGET.read_text(encoding="utf-8") == usedkeys.module_text(scanned)


# ------------------------------------------------------------------ the wild collection
#: MF_05 / MF-Tyre 5.0 files (one Goodyear tyre at 40, 60, 70, 95 psi): evaluated with the PAC2002 equations.
MF05 = {"chrono_335_65R22_5_G275MSA_60psi.tir"} | {f"chrono_feda_335_65R22_5_G275MSA_{p}psi.tir" for p in (40, 70, 95)}
#: Files that evaluate but have no longitudinal characteristic (PCX1 = PDX1 = 0): MFeval's deliberately
#: broken example, which also has VERTICAL_STIFFNESS = 0.  The loader warns about both.
NO_FX = {"mfeval_Model_Unstable.tir"}


def _collection(tmp_path: Path) -> list[Path]:
    shipped = sorted(TIR.rglob("*.tir")) + sorted(WILD.glob("*.tir"))
    quirky = [
        _quirky(MF61, tmp_path / "quirk_MF61_mass_kg_blank.tir", {"MASS": " kg", "IXX": "", "IYY": " $ blank"}),
        _quirky(MF52, tmp_path / "quirk_MF52_blank.tir", {"USER_SUB_ID": " ", "VERTICAL_DAMPING": ""}),
    ]
    return shipped + quirky


def _plausibility(tyre) -> dict[str, float]:
    """Peak friction at nominal load, and the forces at small slip inside the file's own slip ranges
    (an MF_05 file fitted for braking only has KPUMAX = 0: its driving side is not checked)."""
    f = tyre.flat
    Fz = f["FNOMIN"] * f["LFZO"]
    alpha = np.radians(np.linspace(-20.0, 20.0, 81))
    kappa = np.linspace(-0.5, 0.5, 81)
    lat = tyre.evaluate(Fz, 0.0, alpha)
    lon = tyre.evaluate(Fz, kappa, 0.0)
    k = min(0.05, f["KPUMAX"]) if f["KPUMAX"] > 0 else np.nan
    small = tyre.evaluate(Fz, np.array([np.nan_to_num(k), max(-0.05, f["KPUMIN"]), 0.0]),
                          np.array([0.0, 0.0, min(np.radians(3.0), f["ALPMAX"])]))
    finite = all(np.isfinite(out[k]).all() for out in (lat, lon, small) for k in ("Fx", "Fy", "Mz", "Mx", "My"))
    return {
        "finite": float(finite),
        "muy": float(np.abs(lat["Fy"]).max() / Fz),
        "mux": float(np.abs(lon["Fx"]).max() / Fz),
        "Fx_drive": float(small["Fx"][0]) if k == k else np.nan,
        "Fx_brake": float(small["Fx"][1]),
        "Fy": float(small["Fy"][2]),
        "Mz": float(small["Mz"][2]),
        "My": float(small["My"][2]),
    }


def _plausible(tyre, q: dict[str, float]) -> bool:
    """Peak friction at nominal load (road tyres 0.6..1.3, FSAE slicks up to 3) and the ISO-W signs:
    driving/braking force, side force against the slip angle, restoring Mz, rolling resistance My < 0."""
    return (
        0.5 <= q["muy"] <= 3.2
        and 0.5 <= q["mux"] <= 3.2
        and not q["Fx_drive"] <= 0.0  # NaN: the file's KPUMAX <= 0
        and q["Fx_brake"] < 0.0
        and q["Fy"] < 0.0 < q["Mz"]
        and (q["My"] < 0.0 or tyre.flat["QSY1"] == 0.0)
    )


def test_wild_collection_evaluates_with_plausible_signs_and_magnitudes(tmp_path):
    files = _collection(tmp_path)
    no_fx, plausible, formats = set(), set(), set()
    for path in files:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            tyre = load(path)
            q = _plausibility(tyre)
        formats.add(tyre.format)
        if path.name in MF05:
            assert tyre.format == "MF_05" and tyre.fittyp == 5
        # no NaN/inf force or moment from any file, broken ones included
        assert q["finite"] == 1.0, (path.name, q)
        if _plausible(tyre, q):
            plausible.add(path.name)
        elif q["mux"] == 0.0:
            # the loader said why: the file has no longitudinal characteristic
            assert any("Fx is identically zero" in str(w.message) for w in caught), path.name
            no_fx.add(path.name)
        else:
            raise AssertionError(f"implausible: {path.name} {q}")
    assert {"PAC2002", "MF_05", "FITTYP 6", "FITTYP 61", "FITTYP 62"} <= formats
    assert no_fx == NO_FX and MF05 <= plausible
    assert len(files) == 25 and len(plausible) == 24 == len(files) - len(NO_FX)
    print(f"\nwild collection: {len(plausible)} of {len(files)} plausible; "
          f"no longitudinal characteristic: {len(no_fx)}")


def test_zero_vertical_stiffness_and_zero_peak_factors_warn(tmp_path):
    with pytest.warns(MftireTirWarning) as caught:
        tyre = load(WILD / "mfeval_Model_Unstable.tir")
    text = " ".join(str(w.message) for w in caught)
    assert "VERTICAL_STIFFNESS = 0 N/m" in text and "PCX1 = PDX1 = 0: Fx is identically zero" in text
    assert "Fy is identically zero" not in text
    out = tyre.evaluate(5260.0, np.array([-0.1, 0.1]), 0.05)
    np.testing.assert_array_equal(out["Fx"], 0.0)
    assert np.isnan(out["Re"]).all()  # divides by the zero vertical stiffness, as the warning says
    path = _quirky(MF61, tmp_path / "lat0.tir", {"PDY1": " 0"})
    with pytest.warns(MftireTirWarning, match=r"PDY1 = 0: Fy is identically zero \(the file has no lateral"):
        load(path)
