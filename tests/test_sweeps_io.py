"""Tests of the sweep table: CSV reading, validation, unit helpers and sweep grouping."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mftire.errors import MftireInputError
from mftire.iotools.sweeps import (
    convert_from_si,
    convert_to_si,
    read_sweep_csv,
    to_schema,
    unit_factor,
    validate_sweeps,
)
from mftire.segmentation.grouping import cluster_1d, group_sweeps, summarize_sweeps, sweep_kind


def _lateral(fz: float, n: int = 25, gamma: float = 0.0, **extra: float) -> pd.DataFrame:
    a = np.deg2rad(np.linspace(-10, 10, n))
    return pd.DataFrame({
        "Fz": fz, "kappa": 0.0, "alpha": a, "gamma": gamma, "Vx": 16.7, "P": 2.2e5,
        "Fy": -fz * np.sin(1.3 * np.arctan(9 * a)), "Mz": -60 * np.sin(2 * np.arctan(7 * a)), **extra,
    })


def _longitudinal(fz: float, n: int = 21, alpha: float = 0.0, gamma: float = 0.0) -> pd.DataFrame:
    k = np.linspace(-0.25, 0.25, n)
    return pd.DataFrame({
        "Fz": fz, "kappa": k, "alpha": alpha, "gamma": gamma, "Vx": 16.7, "P": 2.2e5,
        "Fx": fz * np.sin(1.6 * np.arctan(12 * k)),
    })


# ------------------------------------------------------------------------------ CSV


def test_read_sweep_csv_keeps_extra_columns_and_adds_source(tmp_path):
    df = _lateral(4000.0, n=5)
    df["run"] = ["r1"] * 5
    df["T_tread"] = [30.0, 31.0, 32.0, 33.0, 34.0]
    path = tmp_path / "lat.csv"
    path.write_text("# measured on rig 2\n" + df.to_csv(index=False))
    out = read_sweep_csv(path, source="rig")
    assert list(out["run"]) == ["r1"] * 5
    assert out["T_tread"].tolist() == [30.0, 31.0, 32.0, 33.0, 34.0]
    assert (out["source"] == "rig").all()
    assert out["alpha"].iloc[0] == pytest.approx(math.radians(-10))
    assert out.attrs["report"]["n_rows_out"] == 5
    assert out.attrs["report"]["measured_channels"] == ["Fy", "Mz"]


def test_read_sweep_csv_missing_file_is_input_error(tmp_path):
    with pytest.raises(MftireInputError, match="cannot read sweep CSV"):
        read_sweep_csv(tmp_path / "nope.csv")


@settings(max_examples=30, deadline=None)
@given(
    st.lists(
        st.tuples(
            st.floats(500, 9000), st.floats(-0.5, 0.5), st.floats(-0.3, 0.3), st.floats(-0.1, 0.1),
            st.floats(1, 60), st.floats(1.2e5, 4e5), st.floats(-9000, 9000),
        ),
        min_size=1, max_size=30,
    )
)
def test_csv_round_trip(tmp_path_factory, rows):
    df = pd.DataFrame(rows, columns=["Fz", "kappa", "alpha", "gamma", "Vx", "P", "Fx"])
    path = tmp_path_factory.mktemp("csv") / "d.csv"
    df.to_csv(path, index=False, float_format="%.17g")
    out = read_sweep_csv(path, check_units=False)
    np.testing.assert_allclose(out[df.columns].to_numpy(), df.to_numpy(), rtol=1e-15)


# ------------------------------------------------------------------------------ validation


def test_missing_required_column_named_with_alias_hint():
    df = _lateral(4000.0).drop(columns=["alpha"])
    df["SA"] = np.linspace(-10, 10, len(df))
    with pytest.raises(MftireInputError) as err:
        validate_sweeps(df, "rig.csv")
    msg = str(err.value)
    assert "rig.csv" in msg and "alpha" in msg and "'SA'" in msg and "deg" in msg and "to_schema" in msg


def test_missing_required_column_without_alias_suggests_defaults():
    df = _lateral(4000.0).drop(columns=["P"])
    with pytest.raises(MftireInputError, match=r"missing required column\(s\) P .*defaults"):
        validate_sweeps(df)


def test_measured_channel_in_other_case_is_reported():
    df = _lateral(4000.0).rename(columns={"Fy": "FY"})
    with pytest.raises(MftireInputError, match="'FY' looks like Fy"):
        validate_sweeps(df)


def test_non_numeric_column_named():
    df = _lateral(4000.0, n=4)
    df["Fz"] = df["Fz"].astype(object)
    df.loc[2, "Fz"] = "4,0 kN"
    with pytest.raises(MftireInputError, match=r"column 'Fz' is not numeric \(row 2 holds '4,0 kN'\)"):
        validate_sweeps(df)


@pytest.mark.parametrize(
    "column, scale, pattern",
    [
        ("alpha", 180 / math.pi, "'alpha'.*degrees"),
        ("gamma", 180 / math.pi, "'gamma'.*degrees"),
        ("kappa", 100.0, "'kappa'.*percent"),
        ("P", 1e-5, "'P'.*bar"),
        ("P", 1e-3, "'P'.*kPa"),
        ("Fz", 1e-3, "'Fz'.*kN"),
        ("Fz", -1.0, "'Fz'.*negative"),
        ("Vx", 3.6 * 3, "'Vx'.*km/h"),
        ("Fy", 1e-3, "'Fy'.*kN"),
    ],
)
def test_non_si_columns_are_detected(column, scale, pattern):
    df = pd.concat([_lateral(4000.0, gamma=0.05), _longitudinal(4000.0)], ignore_index=True)
    df["Fx"] = df["Fx"].fillna(-40.0)
    df[column] = df[column] * scale
    with pytest.raises(MftireInputError, match=pattern):
        validate_sweeps(df, "x")


def test_nan_rows_dropped_and_counted():
    df = _lateral(4000.0, n=10)
    df.loc[1, "alpha"] = np.nan
    df.loc[2, "Fz"] = np.inf
    df.loc[3, ["Fy", "Mz"]] = np.nan  # every measured channel missing: dropped
    df.loc[4, "Mz"] = np.nan  # one channel missing: kept, counted
    df.loc[5, "Fz"] = -20.0  # lift-off
    clean, rep = validate_sweeps(df, "x")
    assert len(clean) == 6
    assert list(clean.index) == [0, 4, 6, 7, 8, 9]
    assert rep.n_rows_in == 10 and rep.n_rows_out == 6
    assert rep.n_dropped_nan == 3
    assert rep.nan_by_column["alpha"] == 1 and rep.nan_by_column["Fz"] == 1
    assert rep.n_dropped_all_measured_nan == 1
    assert rep.nan_in_measured == {"Fy": 0, "Mz": 1}
    assert rep.n_dropped_nonpositive_fz == 1
    assert "3 rows dropped for NaN" in str(rep)


def test_all_rows_nan_is_an_error():
    df = _lateral(4000.0, n=3)
    df["kappa"] = np.nan
    with pytest.raises(MftireInputError, match="no valid rows"):
        validate_sweeps(df)


def test_defaults_fill_missing_inputs_and_phit_nan_set_to_zero():
    df = _lateral(4000.0, n=3).drop(columns=["kappa", "P"])
    df["phit"] = [0.0, np.nan, 0.01]
    clean, rep = validate_sweeps(df, defaults={"kappa": 0.0, "P": 2.5e5})
    assert clean["P"].tolist() == [2.5e5] * 3
    assert clean["phit"].tolist() == [0.0, 0.0, 0.01]
    assert rep.filled_defaults == {"kappa": 0.0, "P": 2.5e5}
    assert rep.n_phit_filled == 1


def test_validate_does_not_modify_input():
    df = _lateral(4000.0, n=4)
    df.loc[0, "alpha"] = np.nan
    before = df.copy()
    validate_sweeps(df, source="fe")
    pd.testing.assert_frame_equal(df, before)


# ------------------------------------------------------------------------------ units


@pytest.mark.parametrize(
    "value, unit, column, expected",
    [
        (180.0, "deg", "alpha", math.pi),
        (100.0, "%", "kappa", 1.0),
        (0.25, "-", "kappa", 0.25),
        (36.0, "km/h", "Vx", 10.0),
        (2.2, "bar", "P", 2.2e5),
        (220.0, "kPa", "P", 2.2e5),
        (30.0, "psi", "P", 206842.71879504),
        (4.5, "kN", "Fz", 4500.0),
        (45.0, "daN", "Fy", 450.0),
        (0.12, "kNm", "Mz", 120.0),
        (12.0, "N*m", "Mx", 12.0),
        (12.0, "N.m", "My", 12.0),
        (25.0, "mm", "deflection", 0.025),
        (60.0, "rpm", "omega", 2 * math.pi),
        (5.0, "1/km", "phit", 0.005),
        (250.0, "ms", "time", 0.25),
    ],
)
def test_unit_conversions(value, unit, column, expected):
    assert convert_to_si(value, unit, column) == pytest.approx(expected, rel=1e-12)
    assert convert_from_si(expected, unit, column) == pytest.approx(value, rel=1e-12)


def test_unknown_or_wrong_dimension_unit():
    with pytest.raises(MftireInputError, match="unknown unit 'grad'"):
        unit_factor("grad", "angle")
    with pytest.raises(MftireInputError, match="not angle"):
        unit_factor("kN", "angle")


@settings(max_examples=60, deadline=None)
@given(
    st.floats(-1e4, 1e4, allow_nan=False),
    st.sampled_from([("alpha", "deg"), ("kappa", "%"), ("Vx", "km/h"), ("P", "bar"), ("P", "psi"),
                     ("Fz", "kN"), ("Mz", "kNm"), ("Fy", "lbf"), ("Re", "mm"), ("omega", "rpm")]),
)
def test_unit_round_trip(value, column_unit):
    column, unit = column_unit
    si = convert_to_si(value, unit, column)
    assert convert_from_si(si, unit, column) == pytest.approx(value, rel=1e-12, abs=1e-12)


def test_to_schema_converts_and_renames():
    df = pd.DataFrame({"SA": [-6.0, 0.0, 6.0], "P_kPa": [220.0] * 3, "other": [1, 2, 3]})
    out = to_schema(df, {"SA": ("alpha", "deg"), "P_kPa": ("P", "kPa")})
    np.testing.assert_allclose(out["alpha"], np.deg2rad([-6.0, 0.0, 6.0]))
    assert out["P"].tolist() == [2.2e5] * 3
    assert "SA" not in out and out["other"].tolist() == [1, 2, 3]


# ------------------------------------------------------------------------------ grouping


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(0.0, 0.05), st.integers(5, 60))
def test_cluster_noisy_loads(seed, noise, n):
    rng = np.random.default_rng(seed)
    setpoints = np.repeat([2000.0, 4000.0, 6000.0], n)
    fz = setpoints * (1 + rng.uniform(-noise, noise, setpoints.size))
    perm = rng.permutation(fz.size)
    labels = cluster_1d(fz[perm], rel_tol=0.1)
    assert set(labels) == {0, 1, 2}
    np.testing.assert_array_equal(labels, (setpoints[perm] / 2000 - 1).astype(int))


def test_cluster_1d_nan_and_absolute_tolerance():
    labels = cluster_1d([0.0, 0.001, np.nan, 0.035, 0.0351], abs_tol=math.radians(0.5))
    assert labels.tolist() == [0, 0, -1, 1, 1]


@pytest.mark.parametrize(
    "kappa, alpha, kind",
    [
        (np.linspace(-0.2, 0.2, 9), np.zeros(9), "pure_longitudinal"),
        (np.zeros(9), np.linspace(-0.2, 0.2, 9), "pure_lateral"),
        (np.linspace(-0.2, 0.2, 9), np.full(9, 0.07), "combined"),
        (np.full(9, 0.05), np.linspace(-0.2, 0.2, 9), "combined"),
        (np.linspace(-0.2, 0.2, 9), np.linspace(-0.1, 0.1, 9), "combined"),
        (np.full(9, 0.001), np.full(9, 0.001), "free_rolling"),
    ],
)
def test_sweep_kind(kappa, alpha, kind):
    assert sweep_kind(kappa, alpha) == kind


def _test_programme(seed: int = 3) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    parts = []
    for fz in (2000.0, 4000.0, 6000.0):
        for gamma in (0.0, math.radians(3)):
            parts.append(_lateral(fz, n=41, gamma=gamma))
            parts.append(_longitudinal(fz, gamma=gamma))
            for a in (2.0, 4.0):
                parts.append(_longitudinal(fz, alpha=math.radians(a), gamma=gamma).iloc[::-1])
    df = pd.concat(parts, ignore_index=True)
    df["Fz"] = df["Fz"] * (1 + rng.uniform(-0.05, 0.05, len(df)))
    df["gamma"] = df["gamma"] + rng.normal(0, math.radians(0.05), len(df))
    return df


def test_group_sweeps_finds_conditions_kinds_and_directions():
    clean, _ = validate_sweeps(_test_programme())
    g = group_sweeps(clean, fz_tol=0.1)
    assert g.index.equals(clean.index)
    assert sorted(g["Fz_set"].unique()) == [2000.0, 4000.0, 6000.0]
    assert sorted(np.round(np.rad2deg(g["gamma_set"].unique()), 6)) == [0.0, 3.0]
    assert g["P_set"].unique().tolist() == [2.2e5] and g["Vx_set"].unique().tolist() == [16.7]
    s = summarize_sweeps(g)
    assert len(s) == 3 * 2 * 4
    assert s["kind"].value_counts().to_dict() == {"combined": 12, "pure_lateral": 6, "pure_longitudinal": 6}
    assert (s["n"] == np.tile([41, 21, 21, 21], 6)).all()
    lat = s[s["kind"] == "pure_lateral"]
    assert (lat["sweep_var"] == "alpha").all() and (lat["direction"] == "increasing").all()
    assert (lat["kappa_set"] == 0.0).all() and lat["alpha_set"].isna().all()
    comb = s[s["kind"] == "combined"]
    assert (comb["sweep_var"] == "kappa").all() and (comb["direction"] == "decreasing").all()
    np.testing.assert_allclose(np.rad2deg(comb["alpha_set"]), np.tile([2.0, 4.0], 6))
    first = g[g["sweep_id"] == 0]
    assert (first["sweep_dir"] == 1).all()


def test_group_sweeps_up_down_sweep_and_by_column():
    up = _lateral(3000.0, n=21)
    sweep = pd.concat([up, up.iloc[::-1]], ignore_index=True)  # -10 -> 10 -> -10 deg
    sweep["file"] = "a.tdx"
    other = _lateral(3000.0, n=21)
    other["file"] = "b.tdx"
    g = group_sweeps(pd.concat([sweep, other], ignore_index=True))
    s = summarize_sweeps(g)
    assert s["file"].tolist() == ["a.tdx", "b.tdx"]
    assert s["direction"].tolist() == ["increasing-decreasing", "increasing"]
    assert s["n"].tolist() == [42, 21]


def test_group_sweeps_split_false_and_missing_column():
    df = pd.concat([_lateral(4000.0), _longitudinal(4000.0)], ignore_index=True)
    assert group_sweeps(df, split=False)["sweep_id"].nunique() == 1
    assert group_sweeps(df)["sweep_id"].nunique() == 2
    with pytest.raises(MftireInputError, match="missing column"):
        group_sweeps(df.drop(columns=["Vx"]))
    with pytest.raises(MftireInputError, match="'by' column 'run'"):
        group_sweeps(df, by=["run"])


def test_noisy_held_slip_does_not_split_sweeps():
    rng = np.random.default_rng(7)
    parts = []
    for _ in range(5):
        for fz in (2000.0, 4000.0, 6000.0):
            d = _lateral(fz, n=300)
            d["kappa"] = rng.normal(0.0, 0.003, len(d))
            d["alpha"] = d["alpha"] + rng.normal(0.0, 0.001, len(d))
            d["Fz"] = d["Fz"] * (1 + rng.uniform(-0.05, 0.05, len(d)))
            parts.append(d)
    g = group_sweeps(pd.concat(parts, ignore_index=True))
    s = summarize_sweeps(g)
    assert len(s) == 15
    assert (s["n"] == 300).all() and (s["kind"] == "pure_lateral").all()
    assert s["Fz_set"].tolist() == [2000.0, 4000.0, 6000.0] * 5


def test_fit_rows_keeps_the_rows_a_fit_uses():
    from mftire.iotools.sweeps import fit_rows

    df = _lateral(4000.0, n=6)
    assert fit_rows(df) is df  # no fit_row column: every row
    flagged = df.assign(fit_row=[True, False, True, True, False, True])
    assert list(fit_rows(flagged).index) == [0, 2, 3, 5]
    as_text = df.assign(fit_row=["True", "False", "true", "1", "0", "False"])  # a column read back as text
    assert list(fit_rows(as_text).index) == [0, 2, 3]
