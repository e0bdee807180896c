"""What real `.tir` files do, one quirk at a time (issue 16): each is read as a tyre engineer expects
(evaluated, a warning, or an error naming file, line and key), and none changes the numbers.

The reference is MFeval's MF 6.1 example (``MagicFormula61_Parameters.tir``, BSD-3/MIT, see
``tests/data/tir/NOTICE.md``) and Project Chrono's PAC2002 HMMWV tyre; each test writes a variant.
"""

from __future__ import annotations

import re
import warnings
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from conftest import TIR
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mftire.iotools.tir import (
    FittypError,
    MissingFittypError,
    NonNumericValueError,
    TirWarning,
    UnknownFittypError,
    UnsupportedFormatError,
    format_tir,
    parse_tir,
    read_tir,
)
from mftire.iotools.units import UNITS
from mftire.parameters import BY_KEY, UNIT_DIMENSIONS
from mftire.tyre import load

MF61 = TIR / "MagicFormula61_Parameters.tir"
HMMWV = TIR / "chrono_HMMWV_Pac02Tire.tir"
KAPPA = np.array([-0.2, -0.05, 0.0, 0.03, 0.1, 0.0, 0.02])
ALPHA = np.array([0.0, 0.02, -0.08, 0.0, 0.05, 0.15, -0.03])
GAMMA = np.array([0.0, 0.02, -0.03, 0.0, 0.01, 0.0, 0.05])


def _text(path: Path = MF61) -> str:
    return path.read_bytes().decode("latin-1").replace("\r\n", "\n")


def _outputs(tyre) -> dict:
    Fz = tyre.flat["FNOMIN"] * np.array([0.6, 1.0, 1.2, 0.8, 1.0, 0.9, 1.1])
    return tyre.evaluate(Fz, KAPPA, ALPHA, GAMMA)


def _same(a, b, rtol=0.0):
    for k in ("Fx", "Fy", "Mz", "Mx", "My", "Re", "Rl", "2a", "sigmax", "sigmay"):
        np.testing.assert_allclose(a[k], b[k], rtol=rtol, atol=0.0, err_msg=k)


def _load_text(tmp_path: Path, text: str, name: str = "t.tir", newline: str = "\n"):
    path = tmp_path / name
    path.write_bytes(text.replace("\r\n", "\n").replace("\n", newline).encode("utf-8"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load(path)


REFERENCE = None


def _reference():
    global REFERENCE
    if REFERENCE is None:
        REFERENCE = _outputs(load(MF61))
    return REFERENCE


# ------------------------------------------------------------------ layout quirks: same numbers
@pytest.mark.parametrize("newline", ["\r\n", "\r", "\n"])
def test_line_endings(tmp_path, newline):
    _same(_outputs(_load_text(tmp_path, _text(), newline=newline)), _reference())


def test_tabs_lower_case_bom_d_exponents_quoted_numbers_and_odd_section_order(tmp_path):
    text = _text()
    text = re.sub(r"(?m)^([A-Z][A-Z0-9_]*)\s*=\s*", lambda m: f"{m.group(1).lower()}\t=\t", text)  # tabs, lower case
    text = re.sub(r"(?m)^\[([A-Z_]+)\]", lambda m: f"[{m.group(1).lower()}]", text)
    text = re.sub(r"(?m)^(pky1\t=\t)(\S+)", lambda m: f"{m.group(1)}{float(m.group(2)) * 10:.17g}D-1", text)
    text = re.sub(r"(?m)^(fnomin\t=\t)(\S+)", r"\1'\2'", text)  # a quoted number
    # the longitudinal section moved to the end of the file
    blocks = re.split(r"(?m)^(?=\$-+|\[)", text)
    lon = [b for b in blocks if b.startswith("[longitudinal_coefficients]")]
    text = "".join(b for b in blocks if b not in lon) + "\n" + "".join(lon)
    tyre = _load_text(tmp_path, "\ufeff" + text)
    _same(_outputs(tyre), _reference(), rtol=1e-13)  # PKY1 written as 10*PKY1 D-1: one rounding


def test_comment_blocks_of_adams_files_are_kept(tmp_path):
    """Adams files may carry ``(COMMENTS)`` / ``{comment_string}`` / quoted lines inside a section."""
    text = _text().replace("[MDI_HEADER]\n", "[MDI_HEADER]\n(COMMENTS)\n{comment_string}\n'Tire - 205/60 R15'\n"
                           "'Pressure - 2.2 bar'\n", 1)
    params = parse_tir(text)
    assert params.blocks["MDI_HEADER"] == ["(COMMENTS)", "{comment_string}", "'Tire - 205/60 R15'",
                                           "'Pressure - 2.2 bar'"]
    again = parse_tir(format_tir(params))
    assert again == params and again.blocks == params.blocks
    _same(_outputs(_load_text(tmp_path, text)), _reference())


def test_tyreside_is_not_used(tmp_path):
    """The file is evaluated as the tyre it describes (mirroring is a mounting operation), as MFeval."""
    text = re.sub(r"(?m)^TYRESIDE\s*=.*$", "TYRESIDE = 'RIGHT'", _text())
    _same(_outputs(_load_text(tmp_path, text)), _reference())


# ------------------------------------------------------------------ units: same numbers in any unit system
_UNIT_CHOICES = {
    "LENGTH": ["mm", "cm", "inch", "ft", "meter"],
    "FORCE": ["kN", "lbf", "daN", "newton"],
    "ANGLE": ["deg", "radian"],
    "MASS": ["gram", "lbm", "tonne", "kg"],
    "TIME": ["millisecond", "minute", "second"],
    "PRESSURE": ["kPa", "bar", "psi", "pascal", None],
}


def _in_units(text: str, units: dict[str, str | None]) -> str:
    """``text`` (SI) rewritten in ``units``: every dimensional value of a standard key divided by its factor."""
    factors = {q: (UNITS[q.lower()][re.sub(r"\W", "", u.lower())] if u else None) for q, u in units.items()}
    if factors["PRESSURE"] is None:  # absent PRESSURE: FORCE/LENGTH^2
        factors["PRESSURE"] = factors["FORCE"] / factors["LENGTH"] ** 2

    def convert(m: re.Match) -> str:
        key, value = m.group(1), m.group(2)
        p = BY_KEY.get(key)
        if p is None:
            return m.group(0)
        f = Fraction(1)
        for q, power in UNIT_DIMENSIONS.get(p.unit, {}).items():
            f *= factors[q] ** power
        return m.group(0) if f == 1 else f"{key} = {float(Fraction(float(value)) / f)!r}"

    out, section = [], None
    for line in text.splitlines():
        s = line.strip()
        if s.startswith("["):
            section = s
        if section == "[UNITS]" and "=" in s:
            q = s.split("=")[0].strip()
            if q in units:
                if units[q] is None:
                    continue
                line = f"{q} = '{units[q]}'"
        elif section != "[UNITS]":
            line = re.sub(r"^\s*([A-Z][A-Z0-9_]*)\s*=\s*([-+0-9.eE]+)(?=\s|$)", convert, line)
        out.append(line)
    if units.get("PRESSURE") and not re.search(r"(?m)^\s*PRESSURE\s*=", text):
        out = [ln if ln.strip() != "[UNITS]" else f"[UNITS]\nPRESSURE = '{units['PRESSURE']}'" for ln in out]
    return "\n".join(out) + "\n"


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(units=st.fixed_dictionaries({q: st.sampled_from(v) for q, v in _UNIT_CHOICES.items()}))
def test_non_si_units_give_the_same_tyre(tmp_path, units):
    text = _in_units(_text(), units)
    tyre = _load_text(tmp_path, text)
    ref = load(MF61)
    for key in ("UNLOADED_RADIUS", "FNOMIN", "VERTICAL_STIFFNESS", "NOMPRES", "LONGVL", "ALPMAX", "IXX", "MASS"):
        assert tyre.flat[key] == pytest.approx(ref.flat[key], rel=1e-14), key
    _same(_outputs(tyre), _reference(), rtol=1e-9)


# ------------------------------------------------------------------ formats and FITTYP: no version invented
def _without_fittyp(text: str, fmt: str | None) -> str:
    text = re.sub(r"(?m)^\s*FITTYP\s*=.*$", "", text)
    text = re.sub(r"(?m)^\s*PROPERTY_FILE_FORMAT\s*=.*$", "", text)
    if fmt is not None:
        text = text.replace("[MODEL]", f"[MODEL]\nPROPERTY_FILE_FORMAT = {fmt}", 1)
    return text


@pytest.mark.parametrize(("fmt", "reported", "model"), [
    ("'MF_61'", "MF_61", "MF 6.1"), ("'mf6.1'", "MF6.1", "MF 6.1"), ("'MF61'", "MF61", "MF 6.1"),
    ("'MF-Tyre 6.1'", "MF-TYRE 6.1", "MF 6.1"), ("'MF_62'", "MF_62", "MF 6.2"),
])
def test_a_format_naming_the_version_needs_no_fittyp(tmp_path, fmt, reported, model):
    tyre = _load_text(tmp_path, _without_fittyp(_text(), fmt))
    assert (tyre.fittyp, tyre.format, tyre.parameters.model) == (None, reported, model)
    ref = load(MF61) if model == "MF 6.1" else load(TIR / "MagicFormula62_Parameters.tir")
    if model == "MF 6.1":
        _same(_outputs(tyre), _reference())
    else:
        assert tyre.flat["FITTYP"] == 62.0 and ref.fittyp == 62


@pytest.mark.parametrize(("fmt", "cls", "match"), [
    ("'USER'", MissingFittypError, r"no FITTYP in \[MODEL\] and PROPERTY_FILE_FORMAT = 'USER' does not name"),
    ("'MF-TYRE'", MissingFittypError, "does not name the version"),
    (None, MissingFittypError, "no FITTYP in .MODEL. and no PROPERTY_FILE_FORMAT"),
    ("'PAC89'", UnsupportedFormatError, "Pacejka '89 tyre model, not a Magic Formula file"),
    ("'PAC-TIME'", UnsupportedFormatError, "PAC-TIME"),
    ("'BANANA'", MissingFittypError, "not a format mftire knows"),
])
def test_a_file_that_does_not_say_its_version_is_refused_by_name(tmp_path, fmt, cls, match):
    path = tmp_path / "nover.tir"
    path.write_text(_without_fittyp(_text(), fmt))
    with pytest.raises(cls, match=match) as excinfo:
        read_tir(path)
    assert str(path) in str(excinfo.value) and "line" in str(excinfo.value)


@pytest.mark.parametrize(("value", "fittyp", "fmt"), [
    ("61", 61, "FITTYP 61"), ("61.0", 61, "FITTYP 61"), ("'61'", 61, "FITTYP 61"), ("6", 6, "FITTYP 6"),
    ("21", 21, "FITTYP 21"), ("5", 5, "MF_05"), ("62", 62, "FITTYP 62"),
])
def test_fittyp_spellings(tmp_path, value, fittyp, fmt):
    text = re.sub(r"(?m)^(\s*FITTYP\s*=\s*)\S+", rf"\g<1>{value}", _text())
    tyre = _load_text(tmp_path, text)
    assert (tyre.fittyp, tyre.format) == (fittyp, fmt)
    out = tyre.evaluate(4000.0, 0.05, 0.03)
    assert np.isfinite([out["Fx"], out["Fy"], out["Mz"]]).all()
    if fittyp == 61:
        _same(_outputs(tyre), _reference())


def test_fittyp_21_is_evaluated_as_mf52(tmp_path):
    mf52 = TIR / "MagicFormula52_Parameters.tir"
    text = re.sub(r"(?m)^(\s*FITTYP\s*=\s*)\S+", r"\g<1>21", _text(mf52))
    a, b = _load_text(tmp_path, text), load(mf52)
    assert (a.fittyp, b.fittyp) == (21, 6)
    _same(_outputs(a), _outputs(b))


@pytest.mark.parametrize(("value", "hint"), [("52", "an MF 5.2 file has FITTYP = 6"), ("6.1", "did you mean 61"),
                                              ("512", "FITTYP = 6"), ("7", ""), ("'MF61'", "FITTYP needs a number")])
def test_unsupported_fittyp_is_an_error_with_a_hint(tmp_path, value, hint):
    path = tmp_path / "f.tir"
    path.write_text(re.sub(r"(?m)^(\s*FITTYP\s*=\s*)\S+", rf"\g<1>{value}", _text()))
    cls = NonNumericValueError if value.startswith("'") else UnknownFittypError
    with pytest.raises(cls, match=r"FITTYP") as excinfo:
        read_tir(path)
    lineno = next(i for i, t in enumerate(path.read_text().splitlines(), 1) if t.strip().startswith("FITTYP"))
    assert excinfo.value.line == lineno and hint in str(excinfo.value)


@pytest.mark.filterwarnings("ignore:.*PROPERTY_FILE_FORMAT_X")  # the unknown-key hint for the decoy key
def test_fittyp_decides_over_a_contradicting_format(tmp_path):
    text = _text().replace("[MODEL]", "[MODEL]\nPROPERTY_FILE_FORMAT_X = 1", 1)
    text = re.sub(r"(?m)^\s*PROPERTY_FILE_FORMAT\s*=.*$", "PROPERTY_FILE_FORMAT = 'PAC2002'", text)
    path = tmp_path / "c.tir"
    path.write_text(text)
    with pytest.warns(TirWarning, match=r"PROPERTY_FILE_FORMAT = 'PAC2002' names PAC2002, but FITTYP = 61 \(MF 6\.1\) "
                      "decides"):
        params = read_tir(path)
    assert params.model == "MF 6.1"
    with pytest.raises(FittypError, match="strict"):
        read_tir(path, strict=True)
    # PAC2002 with FITTYP 5 (Chrono's FEDA 60 psi file): one equation set, no warning
    with warnings.catch_warnings():
        warnings.simplefilter("error", TirWarning)
        assert read_tir(TIR / "chrono_335_65R22_5_G275MSA_60psi.tir").model == "MF-Tyre 5.0"


# ------------------------------------------------------------------ missing things
def test_missing_unloaded_radius_warns_and_forces_do_not_depend_on_it(tmp_path):
    text = re.sub(r"(?m)^\s*UNLOADED_RADIUS\s*=.*$", "", _text())
    path = tmp_path / "nor0.tir"
    path.write_text(text)
    with pytest.warns(Warning, match=r"UNLOADED_RADIUS missing: MFeval's default 0\.3135 m is used"):
        tyre = load(path)
    a, b = _outputs(tyre), _reference()
    for k in ("Fx", "Fy"):
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)
    assert not np.allclose(a["Mz"], b["Mz"])  # Mz scales with R0, as the warning says


def test_missing_fnomin_is_an_error(tmp_path):
    path = tmp_path / "nofz.tir"
    path.write_text(re.sub(r"(?m)^\s*FNOMIN\s*=.*$", "", _text()))
    with pytest.raises(Exception, match="required key FNOMIN missing"):
        load(path)


def test_pac2002_file_missing_optional_sections_evaluates(tmp_path):
    text = _text(HMMWV)
    for sec in ("OVERTURNING_COEFFICIENTS", "ROLLING_COEFFICIENTS", "TIRE_CONDITIONS", "INCLINATION_ANGLE_RANGE"):
        text = re.sub(rf"(?s)\[{sec}\].*?(?=\n\$|\n\[)", "", text)
    path = tmp_path / "pac_min.tir"
    path.write_text(text)
    with pytest.warns(Warning, match="optional section"):
        tyre = load(path)
    assert tyre.format == "PAC2002"
    out = tyre.evaluate(35000.0, np.array([0.05, 0.0]), np.array([0.0, 0.05]))
    assert out["Fx"][0] > 0 > out["Fy"][1] and out["Mz"][1] > 0


# ------------------------------------------------------------------ PAC2002 spellings
def test_pac2002_tire_conditions_in_kpa_are_converted(tmp_path):
    """IP / IP_NOM of [TIRE_CONDITIONS] are pressures: a file in kPa is the same tyre as one in Pa."""
    text = _text(HMMWV)
    assert re.search(r"(?m)^IP\s*=\s*800000", text)
    kpa = re.sub(r"(?m)^(IP(?:_NOM)?\s*=\s*)800000", r"\g<1>800", text)
    kpa = re.sub(r"(?m)^PRESSURE\s*=.*$", "PRESSURE = 'kPa'", kpa)
    kpa = kpa.replace("[TIRE_CONDITIONS]", "[TYRE_CONDITIONS]")  # the British spelling of Stackpole's files
    a, b = _load_text(tmp_path, kpa), load(HMMWV)
    assert a.flat["INFLPRES"] == b.flat["INFLPRES"] == 800000.0
    _same(_outputs(a), _outputs(b))


def test_pac2002_lkyg_is_the_camber_stiffness_factor_lkyc(tmp_path):
    text = _text(HMMWV)
    with_lkyg = text.replace("[SCALING_COEFFICIENTS]", "[SCALING_COEFFICIENTS]\nLKYG = 0.6", 1)
    with_lkyc = text.replace("[SCALING_COEFFICIENTS]", "[SCALING_COEFFICIENTS]\nLKYC = 0.6", 1)
    a, b, ref = _load_text(tmp_path, with_lkyg, "g.tir"), _load_text(tmp_path, with_lkyc, "c.tir"), load(HMMWV)
    _same(_outputs(a), _outputs(b))
    Fz = 35000.0
    fa, fr = a.evaluate(Fz, 0.0, 0.02, np.array([0.0, 0.05])), ref.evaluate(Fz, 0.0, 0.02, np.array([0.0, 0.05]))
    assert fa["Fy"][0] == fr["Fy"][0] and fa["Fy"][1] != fr["Fy"][1]  # only the camber terms change


def test_ranges_in_one_nonstandard_section_are_used_without_a_missing_section_warning(tmp_path):
    """An FSAE team file keeps KPUMIN .. FZMAX in one [RANGE] section: the values are used, nothing is missing."""
    text = _text()
    moved = []
    for sec in ("LONG_SLIP_RANGE", "SLIP_ANGLE_RANGE", "INCLINATION_ANGLE_RANGE", "VERTICAL_FORCE_RANGE"):
        m = re.search(rf"(?s)\[{sec}\]\n(.*?)(?=\n\$|\n\[)", text)
        moved.append(m.group(1))
        text = text.replace(m.group(0), "")
    text = text.replace("[SCALING_COEFFICIENTS]", "[RANGE]\n" + "\n".join(moved) + "\n[SCALING_COEFFICIENTS]", 1)
    path = tmp_path / "range.tir"
    path.write_text(text)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        tyre = load(path)
    assert not [w for w in caught if "missing" in str(w.message)], [str(w.message) for w in caught]
    ref = load(MF61)
    for k in ("KPUMIN", "KPUMAX", "ALPMIN", "ALPMAX", "CAMMIN", "CAMMAX", "FZMIN", "FZMAX"):
        assert tyre.flat[k] == ref.flat[k], k
    _same(_outputs(tyre), _reference())
