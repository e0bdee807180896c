"""Evaluator API, modes, input policy and physical properties."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from conftest import REFERENCE_TYRES, TIR
from hypothesis import given, settings
from hypothesis import strategies as st

from mftire import OUTPUT_NAMES, MftireInputError, Tyre, load, read_tir
from mftire.mf.inputs import MFLimitWarning
from mftire.mf.solver import UnsupportedModelError


@pytest.fixture(scope="module")
def mf61() -> Tyre:
    return load(REFERENCE_TYRES["MF61"])


def test_scalar_inputs_give_all_30_channels(mf61):
    out = mf61.evaluate(4000.0, -0.1, 0.05)
    assert list(out) == list(OUTPUT_NAMES)
    assert len(OUTPUT_NAMES) == 30
    assert np.shape(out["Fx"]) == ()
    # braking gives Fx < 0, positive slip angle gives Fy < 0 (ISO-W)
    assert float(out["Fx"]) < -3000.0
    assert float(out["Fy"]) < -1000.0
    assert float(out["Vx"]) == mf61["LONGVL"]
    assert float(out["P"]) == mf61["INFLPRES"]
    frame = out.to_frame()
    assert frame.shape == (1, 30)
    assert list(frame.columns) == list(OUTPUT_NAMES)


def test_broadcasting_matches_flat_evaluation(mf61):
    Fz = np.array([[2000.0], [5000.0], [8000.0]])
    kappa = np.linspace(-0.3, 0.3, 7)
    out = mf61.evaluate(Fz, kappa, 0.02, gamma=0.01)
    assert out["Fx"].shape == (3, 7)
    flat = mf61.evaluate(np.repeat(Fz.ravel(), 7), np.tile(kappa, 3), 0.02, gamma=0.01)
    for k in ("Fx", "Fy", "Mz", "Mx", "My", "mux", "muy", "Kxk", "Kya", "2a", "2b"):
        np.testing.assert_array_equal(out[k].ravel(), flat[k], err_msg=k)


def test_mode_validation(mf61):
    for bad in (311, 131, 113, 11, 1111, 111.5, "abc"):
        with pytest.raises(MftireInputError):
            mf61.evaluate(4000.0, 0.0, 0.0, mode=bad)


def test_unsupported_fittyp_says_so():
    # (a file with an unsupported FITTYP is refused when read: tests/test_tir_quirks.py)
    flat = dict(load(TIR / "MagicFormula61_Parameters.tir").flat, FITTYP=7)
    with pytest.raises(UnsupportedModelError, match="FITTYP 7 is not evaluated"):
        Tyre(flat).evaluate(4000.0, 0.0, 0.0)


def test_a_file_name_given_to_tyre_points_to_load():
    path = REFERENCE_TYRES["MF61"]
    for name in (str(path), path):
        with pytest.raises(TypeError, match=r"not a file name.*mftire\.load\(path\)"):
            Tyre(name)


def test_pac2002_file_evaluates_without_an_invented_fittyp():
    params = read_tir(TIR / "chrono_HMMWV_Pac02Tire.tir")
    tyre = Tyre(params)
    assert tyre.fittyp is None and tyre.format == "PAC2002"
    out = tyre.evaluate(20000.0, 0.0, np.radians(4.0))
    assert out["Fy"] < 0.0 and out["Mz"] > 0.0  # ISO-W: positive slip angle, negative side force


def test_nan_inputs_are_zeroed_with_a_warning(mf61):
    with pytest.warns(MFLimitWarning, match="NaN value"):
        out = mf61.evaluate([4000.0, 4000.0], [np.nan, 0.0], [0.0, 0.0])
    assert out["Fx"][0] == out["Fx"][1]


def test_negative_load_means_lift_off(mf61):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MFLimitWarning)
        out = mf61.evaluate(-500.0, -0.2, 0.1)
    assert float(out["Fz"]) == 0.0
    assert float(out["Fx"]) == 0.0
    assert float(out["Fy"]) == 0.0


def test_out_of_range_slip_is_clipped_with_warning(mf61):
    with pytest.warns(MFLimitWarning, match="Slip ratio below"):
        a = mf61.evaluate(4000.0, -3.0, 0.0)
    b = mf61.evaluate(4000.0, mf61["KPUMIN"], 0.0)
    assert float(a["Fx"]) == float(b["Fx"])
    # mode 2xx: no limit checks, no clipping
    c = mf61.evaluate(4000.0, -3.0, 0.0, mode=211)
    assert float(c["Fx"]) != float(a["Fx"])


def test_pressure_default_and_explicit(mf61):
    base = mf61.evaluate(4000.0, -0.1, 0.0)
    same = mf61.evaluate(4000.0, -0.1, 0.0, P=mf61["INFLPRES"])
    assert float(base["Fx"]) == float(same["Fx"])
    low = mf61.evaluate(4000.0, -0.1, 0.0, P=0.8 * mf61["NOMPRES"])
    assert float(low["Fx"]) != float(base["Fx"])


def test_uncombined_mode_gives_pure_slip_forces(mf61):
    pure = mf61.evaluate(4000.0, -0.1, 0.1, mode=110)
    fx_alone = mf61.evaluate(4000.0, -0.1, 0.0, mode=111)
    fy_alone = mf61.evaluate(4000.0, 0.0, 0.1, mode=111)
    assert float(pure["Fx"]) == pytest.approx(float(fx_alone["Fx"]), rel=1e-12)
    assert float(pure["Fy"]) == pytest.approx(float(fy_alone["Fy"]), rel=1e-12)
    combined = mf61.evaluate(4000.0, -0.1, 0.1, mode=111)
    assert abs(float(combined["Fx"])) < abs(float(pure["Fx"]))


def test_given_omega_is_used(mf61):
    Vx = 20.0
    out = mf61.evaluate(4000.0, 0.0, 0.0, Vx=Vx, omega=Vx / 0.3)
    assert float(out["omega"]) == pytest.approx(Vx / 0.3, rel=1e-15)
    est = mf61.evaluate(4000.0, 0.0, 0.0, Vx=Vx)
    assert float(est["omega"]) == pytest.approx(Vx / float(est["Re"]), rel=1e-6)


def _symmetric(tyre: Tyre) -> Tyre:
    """The same tyre with every left/right asymmetry coefficient set to zero."""
    flat = dict(tyre.flat)
    asymmetric = "PHY1 PHY2 PVY1 PVY2 PEY3 QHZ1 QHZ2 QDZ6 QDZ7 QEZ4 QEZ5 PHX1 PHX2 PVX1 PVX2 QSX1 RHY1 RHY2 RVY1 RVY2"
    for k in (asymmetric + " RVY3 RHX1 RBY3 SSZ1").split():
        flat[k] = 0.0
    return Tyre(flat)


SYM = _symmetric(load(REFERENCE_TYRES["MF61"]))


@settings(max_examples=60, deadline=None)
@given(
    fz=st.floats(0.3, 2.0),
    alpha=st.floats(1e-4, 0.3),
    kappa=st.floats(-0.5, 0.5),
    vx=st.floats(5.0, 40.0),
)
def test_lateral_symmetry_of_a_symmetric_tyre(fz, alpha, kappa, vx):
    Fz = fz * SYM["FNOMIN"]
    a = SYM.evaluate([Fz, Fz], kappa, [alpha, -alpha], Vx=vx)
    assert a["Fy"][0] == pytest.approx(-a["Fy"][1], rel=1e-9, abs=1e-9)
    assert a["Mz"][0] == pytest.approx(-a["Mz"][1], rel=1e-9, abs=1e-9)
    assert a["Fx"][0] == pytest.approx(a["Fx"][1], rel=1e-9, abs=1e-9)
    assert a["Mx"][0] == pytest.approx(-a["Mx"][1], rel=1e-9, abs=1e-9)


@settings(max_examples=40, deadline=None)
@given(fz=st.floats(0.3, 2.0), gamma=st.floats(-0.05, 0.05))
def test_longitudinal_force_rises_with_slip_in_the_linear_range(fz, gamma):
    tyre = load(REFERENCE_TYRES["MF61"])
    kappa = np.linspace(-0.02, 0.02, 41)
    Fx = tyre.evaluate(fz * tyre["FNOMIN"], kappa, 0.0, gamma=gamma)["Fx"]
    assert np.all(np.diff(Fx) > 0.0)
    # slip stiffness output equals the numerical slope at zero slip within 2 %
    Kxk = tyre.evaluate(fz * tyre["FNOMIN"], 0.0, 0.0, gamma=gamma)["Kxk"]
    slope = np.gradient(Fx, kappa)[20]
    assert slope == pytest.approx(float(Kxk), rel=0.02)


@settings(max_examples=40, deadline=None)
@given(fz=st.floats(0.2, 2.0), kappa=st.floats(-1.0, 1.0), alpha=st.floats(-0.4, 0.4))
def test_combined_slip_never_exceeds_pure_slip(fz, kappa, alpha):
    # holds when the combined-slip weighting has no shift (RHX1 = 0); with a shift
    # Gxa may exceed one near alpha = -RHX1, as the Magic Formula allows
    tyre = SYM
    Fz = fz * tyre["FNOMIN"]
    comb = tyre.evaluate(Fz, kappa, alpha)
    pure = tyre.evaluate(Fz, kappa, alpha, mode=110)
    assert abs(float(comb["Fx"])) <= abs(float(pure["Fx"])) * (1 + 1e-12) + 1e-9
