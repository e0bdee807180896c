"""Tests of the TYDEX (.tdx) reader and writer."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mftire.errors import MftireInputError
from mftire.iotools.tydex import parse_tydex, read_tydex, write_tydex
from mftire.segmentation.grouping import group_sweeps, summarize_sweeps

DATA = Path(__file__).parent / "data" / "tydex"
LATERAL = DATA / "lateral_fz4kN_2p2bar.tdx"
LONGITUDINAL = DATA / "longitudinal_fz6kN_whitespace.tdx"


def _write(tmp_path: Path, text: str, name: str = "t.tdx") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


MINIMAL = """**HEADER
RELEASE   Release of TYDEX-Format                 1.3
**MEASURCHANNELS
SLIPANGL  Slip angle                    {unit:<10}1         0
FYW       Lateral force                 N         1         0
**MEASURDATA
  -4.0   2500.0
   0.0      0.0
   4.0  -2500.0
**END
"""


# ------------------------------------------------------------------------------ reading


def test_fixed_width_sample_units_factor_offset_and_constants():
    df = read_tydex(LATERAL)
    assert len(df) == 13
    np.testing.assert_allclose(df["alpha"], np.deg2rad(np.arange(-12, 13, 2.0)))
    assert df["kappa"].iloc[0] == pytest.approx(0.0012)  # 0.12 %
    assert df["gamma"].tolist() == [0.0] * 13
    assert df["Vx"].iloc[0] == pytest.approx(60 / 3.6)  # km/h
    assert df["Fz"].iloc[0] == pytest.approx(4012.0)  # kN
    assert df["Fy"].iloc[0] == pytest.approx(4188.1)  # stored 418.81 x factor 10
    assert df["Mz"].iloc[0] == pytest.approx(70.29)  # stored 72.79 + offset -2.5
    assert df["Mz"].iloc[6] == pytest.approx(0.0)
    assert df["Fx"].iloc[6] == pytest.approx(-48.0)
    assert df["time"].iloc[-1] == pytest.approx(6.0)
    assert df["meas_no"].tolist() == list(range(1, 14))
    # constants: INFLPRES fills P (bar -> Pa), FZW is shadowed by the channel
    assert df["P"].unique() == pytest.approx([2.2e5])
    assert df["Fz_nominal"].unique().tolist() == [4000.0]
    assert df["NOMWIDTH"].iloc[0] == 205.0 and df["RIMDIAME"].iloc[0] == 16.0
    assert df["TRCKSURF"].iloc[0] == "SAFETYWALK" and df["AMBITEMP"].iloc[0] == 21.5
    assert df["TREADTMP"].iloc[-1] == pytest.approx(35.8)  # unmapped channel kept as is
    assert df["file"].unique().tolist() == [str(LATERAL)]
    units = df.attrs["units_read"]
    assert units["alpha"] == "deg" and units["kappa"] == "%" and units["Vx"] == "km/h"
    assert units["Fz"] == "kN" and units["P"] == "bar" and units["AMBITEMP"] == "deg C"
    assert units["TREADTMP"] == "deg C" and units["meas_no"] == ""
    meta = df.attrs["tydex"][0]
    assert meta["header"]["RELEASE"] == "1.3" and meta["header"]["SUPPLIER"] == "MFTIRE-TEST"
    assert meta["comments"][0].startswith("Pure lateral slip sweep")
    assert meta["warnings"] == []
    # model blocks are ignored
    assert "MODEL" not in df.columns and "FNOMIN" not in df.columns


def test_whitespace_sample_with_tabs_notavail_and_constants():
    df = read_tydex(LONGITUDINAL)
    assert len(df) == 11
    np.testing.assert_allclose(df["kappa"], np.round(np.linspace(-0.2, 0.2, 11), 3))
    assert df["alpha"].tolist() == [0.0] * 11
    assert df["gamma"].unique() == pytest.approx([math.radians(2.0)])
    assert df["P"].unique() == pytest.approx([2.2e5])  # constant in kPa
    assert df["Vx"].unique().tolist() == [16.5]
    assert df["Fx"].iloc[0] == pytest.approx(-6068.14)
    assert df["My"].unique().tolist() == [-18.5]
    assert math.isnan(df["Mz"].iloc[5]) and df["Mz"].iloc[6] == pytest.approx(12.4)
    assert df.attrs["units_read"]["My"] == "N*m"
    assert df.attrs["units_read"]["kappa"] == "-"


def test_many_files_one_table_then_validate_and_group():
    df = read_tydex([LATERAL, LONGITUDINAL], validate=True, source="rig")
    assert len(df) == 24
    assert df["file"].tolist() == [str(LATERAL)] * 13 + [str(LONGITUDINAL)] * 11
    assert (df["source"] == "rig").all()
    assert df.attrs["units_read"]["alpha"] == "deg|rad"
    assert df.attrs["report"]["nan_in_measured"]["Mz"] == 1
    s = summarize_sweeps(group_sweeps(df))
    assert s["kind"].tolist() == ["pure_lateral", "pure_longitudinal"]
    assert s["Fz_set"].tolist() == [4000.0, 6000.0]
    assert s["direction"].tolist() == ["increasing", "increasing"]
    assert s["gamma_set"].tolist() == pytest.approx([0.0, math.radians(2)])


def test_w_axis_name_preferred_and_other_kept(tmp_path):
    text = """**MEASURCHANNELS
SLIPANGL  Slip angle                    rad       1         0
FY        Lateral force other axis      N         1         0
FYW       Lateral force W-axis          kN        1         0
**MEASURDATA
0.1  -100.0  -2.0
**END
"""
    df = read_tydex(_write(tmp_path, text))
    assert df["Fy"].tolist() == [-2000.0]
    assert df["FY"].tolist() == [-100.0]
    assert df.attrs["channel_map"]["Fy"] == "FYW"


def test_three_conversion_numbers_and_glued_numbers(tmp_path):
    text = """**MEASURCHANNELS
SLIPANGL  Slip angle                    deg       0.1       0         0
FZW       Vertical force                N         1         100       -50
**MEASURDATA
 -120.000-4000.000
  120.000 4000.000
**END
"""
    df = read_tydex(_write(tmp_path, text))
    np.testing.assert_allclose(df["alpha"], np.deg2rad([-12.0, 12.0]))
    assert df["Fz"].tolist() == [-3950.0, 4050.0]


def test_constant_fills_load_and_unknown_block_is_ignored(tmp_path):
    text = """**HEADER
RELEASE   Release of TYDEX-Format                 1.3
**CONSTANTS
FZW       Vertical force                kN        5.5
INCLANGL  Inclination angle             deg       -2
**MYBLOCK
anything at all
**MEASURCHANNELS
SLIPANGL  Slip angle                    deg       1         0
FYW       Lateral force                 N         1         0
**MEASURDATA
  -4.0   2500.0
**END
"""
    df = read_tydex(_write(tmp_path, text))
    assert df["Fz"].tolist() == [5500.0]
    assert df["gamma"].tolist() == pytest.approx([math.radians(-2)])
    assert df.attrs["units_read"]["Fz"] == "kN"
    assert any("MYBLOCK" in w for w in df.attrs["tydex"][0]["warnings"])


# ------------------------------------------------------------------------------ errors


def test_wrong_number_of_values_names_file_and_line(tmp_path):
    path = _write(tmp_path, MINIMAL.format(unit="deg").replace("   0.0      0.0", "   0.0      0.0   7.0"))
    with pytest.raises(MftireInputError, match=rf"{path.name}:8: .*3 values, expected 2"):
        read_tydex(path)


def test_unknown_unit_of_known_channel(tmp_path):
    path = _write(tmp_path, MINIMAL.format(unit="grad"))
    with pytest.raises(MftireInputError, match=r":4: .*SLIPANGL.*'grad'"):
        read_tydex(path)


def test_wrong_dimension_unit(tmp_path):
    path = _write(tmp_path, MINIMAL.format(unit="kN"))
    with pytest.raises(MftireInputError, match="SLIPANGL.*not angle"):
        read_tydex(path)


def test_missing_measurdata(tmp_path):
    text = MINIMAL.format(unit="deg").split("**MEASURDATA")[0] + "**END\n"
    with pytest.raises(MftireInputError, match=r"no \*\*MEASURDATA block"):
        read_tydex(_write(tmp_path, text))


def test_missing_measurdata_keyword_with_data_lines(tmp_path):
    text = MINIMAL.format(unit="deg").replace("**MEASURDATA\n", "")
    with pytest.raises(MftireInputError, match=r":6: .*starts with a number"):
        read_tydex(_write(tmp_path, text))


def test_missing_measurchannels(tmp_path):
    with pytest.raises(MftireInputError, match=r"no \*\*MEASURCHANNELS"):
        read_tydex(_write(tmp_path, "**HEADER\nRELEASE x 1.3\n**END\n"))


def test_not_a_tydex_file(tmp_path):
    with pytest.raises(MftireInputError, match=r":1: text before the first \*\* keyword"):
        read_tydex(_write(tmp_path, "Fz,kappa\n1,2\n"))


def test_non_numeric_value(tmp_path):
    path = _write(tmp_path, MINIMAL.format(unit="deg").replace("-2500.0", "  abc  "))
    with pytest.raises(MftireInputError, match=r":9: channel 'FYW' value 'abc' is not a number"):
        read_tydex(path)


def test_duplicate_channel_and_empty_data(tmp_path):
    again = "SLIPANGL  Slip angle again            deg       1         0\n"
    dup = MINIMAL.format(unit="deg").replace("FYW ", again + "FYW ")
    with pytest.raises(MftireInputError, match="'SLIPANGL' listed twice"):
        read_tydex(_write(tmp_path, dup, "dup.tdx"))
    empty = MINIMAL.format(unit="deg").split("**MEASURDATA")[0] + "**MEASURDATA\n**END\n"
    with pytest.raises(MftireInputError, match="no data rows"):
        read_tydex(_write(tmp_path, empty, "empty.tdx"))


def test_missing_unit_for_angle(tmp_path):
    text = MINIMAL.format(unit="deg").replace("SLIPANGL  Slip angle                    deg       1         0",
                                              "SLIPANGL Slip angle 1 0")
    with pytest.raises(MftireInputError, match="no known unit for SLIPANGL.*'angle'"):
        read_tydex(_write(tmp_path, text))


def test_missing_file_is_input_error(tmp_path):
    with pytest.raises(MftireInputError, match="cannot read TYDEX file"):
        read_tydex(tmp_path / "nope.tdx")


def test_parse_tydex_keeps_raw_numbers():
    tf = parse_tydex(LATERAL)
    assert [c.key for c in tf.channels][:3] == ["MEASNUMB", "RUNTIME", "SLIPANGL"]
    fyw = next(c for c in tf.channels if c.key == "FYW")
    assert fyw.unit == "N" and fyw.values == ["10", "0"] and fyw.line == 38
    assert tf.data["FYW"].iloc[0] == pytest.approx(418.81)


# ------------------------------------------------------------------------------ writing


def test_write_read_round_trip_with_units_constants_and_extra(tmp_path):
    df = read_tydex(LATERAL)
    path = tmp_path / "out.tdx"
    units = {"alpha": "deg", "kappa": "%", "Fz": "kN", "Vx": "km/h", "P": "bar", "gamma": "deg"}
    write_tydex(df, path, units=units, columns=["TREADTMP"],
                constants={"NOMWIDTH": (205, "mm", "Nominal width"), "TRCKSURF": "SAFETYWALK"},
                header={"MEASID": "LAT-01"}, comments=["written by the test"])
    back = read_tydex(path)
    for col in ("alpha", "kappa", "gamma", "Vx", "P", "Fz", "Fx", "Fy", "Mz", "time", "meas_no", "TREADTMP"):
        np.testing.assert_allclose(back[col], df[col], rtol=1e-9, atol=1e-12, err_msg=col)
    assert back.attrs["units_read"]["alpha"] == "deg" and back.attrs["units_read"]["P"] == "bar"
    assert back["NOMWIDTH"].iloc[0] == 205.0 and back["TRCKSURF"].iloc[0] == "SAFETYWALK"
    meta = back.attrs["tydex"][0]
    assert meta["header"]["MEASID"] == "LAT-01" and meta["comments"] == ["written by the test"]
    assert [p.name for p in tmp_path.iterdir()] == ["out.tdx"]  # no temporary file left
    text = path.read_text()
    assert "SLIPANGL  Slip angle                    deg       1         0" in text


def test_write_nan_as_notavail_and_bad_key(tmp_path):
    df = pd.DataFrame({"alpha": [0.0, 0.1], "Fy": [np.nan, -500.0], "my long name": [1.0, 2.0]})
    path = tmp_path / "n.tdx"
    write_tydex(df, path)
    assert "NOTAVAIL" in path.read_text()
    back = read_tydex(path)
    assert math.isnan(back["Fy"].iloc[0]) and back["Fy"].iloc[1] == -500.0
    with pytest.raises(MftireInputError, match="cannot be a TYDEX key"):
        write_tydex(df, tmp_path / "bad.tdx", columns=["my long name"])
    assert not (tmp_path / "bad.tdx").exists()


def test_write_keeps_old_file_when_writing_fails(tmp_path, monkeypatch):
    path = tmp_path / "keep.tdx"
    path.write_text("old content")
    df = pd.DataFrame({"alpha": [0.0], "Fy": [1.0]})

    def boom(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", boom)
    with pytest.raises(OSError, match="disk full"):
        write_tydex(df, path)
    assert path.read_text() == "old content"
    assert [p.name for p in tmp_path.iterdir()] == ["keep.tdx"]


_UNIT_CHOICES = {
    "alpha": ["rad", "deg"], "gamma": ["rad", "deg"], "kappa": ["-", "%"], "Vx": ["m/s", "km/h", "mph"],
    "P": ["Pa", "kPa", "bar", "psi"], "Fz": ["N", "kN", "daN"], "Fx": ["N", "kN"], "Fy": ["N", "lbf"],
    "Mz": ["Nm", "kNm", "N*m"], "Mx": ["Nm"], "My": ["Nm"],
}


@settings(max_examples=40, deadline=None)
@given(
    data=st.data(),
    n=st.integers(1, 25),
)
def test_hypothesis_round_trip(tmp_path_factory, data, n):
    cols = data.draw(st.lists(st.sampled_from(sorted(_UNIT_CHOICES)), min_size=1, unique=True))
    finite = st.floats(-1e6, 1e6, allow_nan=False, allow_subnormal=False)
    df = pd.DataFrame({c: data.draw(st.lists(finite, min_size=n, max_size=n)) for c in cols})
    units = {c: data.draw(st.sampled_from(_UNIT_CHOICES[c])) for c in cols}
    path = tmp_path_factory.mktemp("tdx") / "r.tdx"
    write_tydex(df, path, units=units, precision=15)
    back = read_tydex(path)
    for c in cols:
        np.testing.assert_allclose(back[c], df[c], rtol=1e-12, atol=1e-9, err_msg=f"{c} [{units[c]}]")
        assert back.attrs["units_read"][c] == units[c]
