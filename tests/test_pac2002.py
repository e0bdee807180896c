"""PAC2002 evaluation (issue 16).

Verification, since no reference outputs ship with the format:

* where PAC2002 and MF 5.2 (FITTYP 6) coincide, a PAC2002 file and its transcription
  to an MF 5.2 parameter set give identical results (all 30 channels);
* an independent scalar transcription of the published PAC2002 equations (Pacejka
  2006, §4.3.2, as in the Adams PAC2002 documentation), written here from the
  equations with gamma_x/y/z = gamma*LGAX/Y/Z and LMUV taken literally, checks the
  folding and the PAC2002-only branches (LMUV, pure-slip Mz, combined Mz);
* property tests (hypothesis): symmetry of a symmetric tyre, ISO signs at small slip.

No open PAC2002 implementation could be run as an oracle here: the open ones found
(Project Chrono's ChPac02Tire in C++, OpenTire's PAC2002 in Python 2, several MATLAB
scripts) are not installable from PyPI/Debian and none ships reference outputs; they
were read for facts only (equation forms, which terms PAC2002 has).
"""

from __future__ import annotations

import math
import re
import warnings

import numpy as np
import pytest
from conftest import TIR, needs_c_compiler
from hypothesis import given, settings
from hypothesis import strategies as st

from mftire.iotools.tir import read_tir
from mftire.mf.family import PAC2002_CODE
from mftire.mf.pac2002 import PAC2002Warning
from mftire.mf.solver import OUTPUT_NAMES, evaluate_arrays
from mftire.tyre import Tyre, load

HMMWV = TIR / "chrono_HMMWV_Pac02Tire.tir"
WILD = TIR.parent / "tir_wild"


def _flat(path=HMMWV, **changes) -> dict[str, float]:
    """Flat PAC2002 parameters (model code set as Tyre does) with ``changes``."""
    flat = dict(load(path).flat)
    flat.update(changes)
    return flat


# ------------------------------------------------------------------ format / reading
def test_format_is_reported_as_the_file_says():
    pac = load(HMMWV)
    assert (pac.fittyp, pac.format) == (None, "PAC2002")
    assert pac.flat["FITTYP"] == PAC2002_CODE  # internal model code only
    assert "PAC2002" in repr(pac) and "FITTYP" not in repr(pac)
    mf05 = load(TIR / "chrono_335_65R22_5_G275MSA_60psi.tir")
    assert (mf05.fittyp, mf05.format) == (5, "MF_05")
    mf61 = load(TIR / "MagicFormula61_Parameters.tir")
    assert (mf61.fittyp, mf61.format) == (61, "FITTYP 61")


def test_mf05_evaluates_with_the_pac2002_equations(tmp_path):
    """MF_05 (FITTYP 5) runs the PAC2002 path (docs/pac2002.md, "MF_05"): the same file marked PAC2002
    instead gives the same numbers, bit for bit, and the format is reported as the file says."""
    src = WILD / "chrono_feda_335_65R22_5_G275MSA_40psi.tir"
    mf05 = load(src)
    assert (mf05.fittyp, mf05.format) == (5, "MF_05") and mf05.flat["FITTYP"] == PAC2002_CODE
    text = src.read_bytes().decode("latin-1")
    as_pac = tmp_path / "as_pac2002.tir"
    as_pac.write_text(re.sub(r"(?m)^FITTYP\s*=.*$", "", text).replace("'MF_05'", "'PAC2002'"), encoding="latin-1")
    no_fittyp = tmp_path / "mf05_no_fittyp.tir"
    no_fittyp.write_text(re.sub(r"(?m)^FITTYP\s*=.*$", "", text), encoding="latin-1")
    pac, bare = load(as_pac), load(no_fittyp)
    assert (pac.fittyp, pac.format) == (None, "PAC2002")
    assert (bare.fittyp, bare.format) == (None, "MF_05")  # no FITTYP invented
    kappa, alpha = np.meshgrid(np.linspace(-0.3, 0.0, 7), np.radians(np.linspace(-10, 10, 9)))
    ref = mf05.evaluate(16929.0, kappa, alpha, 0.02)
    for other in (pac, bare):
        out = other.evaluate(16929.0, kappa, alpha, 0.02)
        for k in ref:
            np.testing.assert_array_equal(out[k], ref[k], err_msg=k)


def test_mf05_negative_pdy1_is_the_sign_convention_of_its_exporter():
    """MF_05 files of the Goodyear exporter have PDY1 < 0 with PKY1 < 0 (Chrono's ChPac02Tire takes |muy|).
    Fy0 = Dy sin(Cy atan(By a - ...)) with By = Kya/(Cy Dy) is odd in (Dy, By) jointly, so the literal
    equations give the same Fy and Mz as |PDY1|, |PDY2| when the kappa-induced side force is zero (RVY = 0)."""
    tyre = load(WILD / "chrono_feda_335_65R22_5_G275MSA_70psi.tir")
    flipped = tyre.parameters.copy()
    for key in ("PDY1", "PDY2"):
        flipped.set(key, -flipped[key])
    assert tyre.flat["PDY1"] < 0 < flipped["PDY1"]
    other = Tyre(flipped)
    kappa, alpha = np.meshgrid(np.linspace(-0.3, 0.0, 7), np.radians(np.linspace(-10, 10, 9)))
    a, b = tyre.evaluate(19000.0, kappa, alpha, 0.03), other.evaluate(19000.0, kappa, alpha, 0.03)
    for k in ("Fx", "Fy", "Mz", "Mx", "My"):
        np.testing.assert_allclose(a[k], b[k], rtol=1e-12, atol=1e-9 * 19000.0, err_msg=k)
    np.testing.assert_allclose(a["muy"], b["muy"], rtol=1e-12)  # the muy output is |muy| (as MFeval)


# ------------------------------------------------------------------ equivalence with MF 5.2
def _transcribe_to_mf52(flat: dict) -> dict:
    """The same tyre as an MF 5.2 (FITTYP 6) parameter set: same keys, FITTYP 6."""
    q = dict(flat)
    q["FITTYP"] = 6.0
    q["NOMPRES"] = q["INFLPRES"] = flat["IP_NOM"]
    return q


def _grid():
    Fz = np.array([8000.0, 20000.0, 35000.0, 50000.0])[:, None, None]
    kappa = np.array([-0.4, -0.05, 0.0, 0.03, 0.2])[None, :, None]
    alpha = np.radians([-12.0, -3.0, 0.0, 1.0, 6.0])[None, None, :]
    return np.broadcast_arrays(Fz, kappa, alpha)


@pytest.mark.parametrize("mode", [111, 211, 121, 112])
def test_pac2002_equals_its_mf52_transcription_where_they_coincide(mode):
    """Camber scaling 1, LMUV 0, LFZO 1 and QSY5-8 zero: PAC2002 and MF 5.2 coincide (to rounding)."""
    pac = _flat(LFZO=1.0)
    mf52 = _transcribe_to_mf52(pac)
    Fz, kappa, alpha = _grid()
    for gamma in (0.0, 0.05):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            a = evaluate_arrays(pac, Fz, kappa, alpha, gamma, 0.1 if mode == 112 else 0.0, 15.0, mode=mode)
            b = evaluate_arrays(mf52, Fz, kappa, alpha, gamma, 0.1 if mode == 112 else 0.0, 15.0, mode=mode)
        for k in OUTPUT_NAMES:
            if k == "Mz" and (gamma != 0.0 or mode == 112):
                # documented difference: MFeval's MF 5.2 recomputes the SVyk of F'y at zero
                # camber and without turn slip; PAC2002 takes the SVyk of Fy (eq 4.E74)
                continue
            np.testing.assert_allclose(a[k], b[k], rtol=1e-13, atol=1e-9, err_msg=f"{k} mode {mode} gamma {gamma}")


def test_documented_differences_from_mf52_show():
    """LFZO on the trail, LMUV, camber scaling and the pure-slip Mz0 differ as documented."""
    Fz, kappa, alpha = 30000.0, 0.05, math.radians(4.0)
    base = _flat()  # LFZO = 0.58 in this file
    mf52 = _transcribe_to_mf52(base)
    a = evaluate_arrays(base, Fz, kappa, alpha, 0.0)
    b = evaluate_arrays(mf52, Fz, kappa, alpha, 0.0)
    assert a["Fx"] == b["Fx"] and a["Fy"] == b["Fy"]
    # MF 5.2 (as MFeval) multiplies the combined-slip trail by LFZO, PAC2002 does not
    assert float(a["t"]) == pytest.approx(float(b["t"]) / base["LFZO"], rel=1e-12)
    # pure slip with camber: PAC2002 uses Fy0 at the actual camber in Mz0
    p = evaluate_arrays(_flat(LFZO=1.0), Fz, 0.0, alpha, 0.05, mode=110)
    q = evaluate_arrays(_transcribe_to_mf52(_flat(LFZO=1.0)), Fz, 0.0, alpha, 0.05, mode=110)
    assert p["Fy"] == q["Fy"] and abs(float(p["Mz"] - q["Mz"])) > 1.0


def test_lmuv_decays_friction_with_slip_speed():
    """eq 4.E7: lambda_mu* = lambda_mu / (1 + LMUV*Vs/V0), Vs the slip speed."""
    Fz, alpha, Vx = 30000.0, math.radians(8.0), 20.0
    slow = evaluate_arrays(_flat(LMUV=0.0), Fz, 0.0, alpha, 0.0, 0.0, Vx, mode=211)
    fast = evaluate_arrays(_flat(LMUV=0.4), Fz, 0.0, alpha, 0.0, 0.0, Vx, mode=211)
    Vs = math.tan(alpha) * Vx
    expected = 1.0 / (1.0 + 0.4 * Vs / 16.7)
    assert float(fast["muy"] / slow["muy"]) == pytest.approx(expected, rel=1e-12)
    assert abs(float(fast["Fy"])) < abs(float(slow["Fy"]))
    # MF 6.1 files ignore LMUV (as MFeval): no change
    mf61 = dict(load(TIR / "MagicFormula61_Parameters.tir").flat)
    r0 = evaluate_arrays(mf61, 4000.0, -0.2, alpha, 0.0)
    r1 = evaluate_arrays({**mf61, "LMUV": 0.4}, 4000.0, -0.2, alpha, 0.0)
    assert r0["Fx"] == r1["Fx"]


def test_rolling_terms_outside_pac2002_are_ignored_with_a_warning():
    params = read_tir(HMMWV)
    params.set("QSY7", 0.85)
    with pytest.warns(PAC2002Warning, match="QSY7"):
        tyre = Tyre(params)
    ref = load(HMMWV).evaluate(20000.0, 0.1, 0.02)
    with warnings.catch_warnings():
        warnings.simplefilter("error", PAC2002Warning)
        assert tyre.evaluate(20000.0, 0.1, 0.02)["My"] == ref["My"]
        # the MF 6.1 defaults of QSY7/QSY8 filled in for a file without them are not the file's
        Tyre(read_tir(WILD / "chrono_Sedan_Pac02Tire.tir"))


# ------------------------------------------------------------------ independent transcription
def _reference(p: dict, Fz: float, kappa: float, alpha: float, gamma: float, Vx: float, combined: bool):
    """Scalar PAC2002 (Pacejka 2006 §4.3.2 / Adams PAC2002 help), no limits, forward driving.

    Written from the equations, independently of mftire.mf: gamma_x = gamma*LGAX etc. and
    LMUV are used as published.  Pressure terms are zero in the tyres used here.  The
    combined-slip alpha_eq uses the arctan/tan form (A54/A55), as mftire documents.
    """
    R0, Fz0 = p["UNLOADED_RADIUS"], p["FNOMIN"]
    Fz0p = Fz0 * p["LFZO"]
    dfz = (Fz - Fz0p) / Fz0p
    gx, gy, gz = gamma * p["LGAX"], gamma * p["LGAY"], gamma * p["LGAZ"]
    Vs = math.hypot(kappa * Vx, math.tan(alpha) * Vx)
    lmux = p["LMUX"] / (1.0 + p["LMUV"] * Vs / p["LONGVL"])
    lmuy = p["LMUY"] / (1.0 + p["LMUV"] * Vs / p["LONGVL"])

    def mf(B, C, D, E, x):
        return D * math.sin(C * math.atan(B * x - E * (B * x - math.atan(B * x))))

    # pure Fx
    SHx = (p["PHX1"] + p["PHX2"] * dfz) * p["LHX"]
    kx = kappa + SHx
    Cx = p["PCX1"] * p["LCX"]
    mux = (p["PDX1"] + p["PDX2"] * dfz) * (1 - p["PDX3"] * gx**2) * lmux
    Dx = mux * Fz
    Ex = (p["PEX1"] + p["PEX2"] * dfz + p["PEX3"] * dfz**2) * (1 - p["PEX4"] * math.copysign(1.0, kx)) * p["LEX"]
    Kx = Fz * (p["PKX1"] + p["PKX2"] * dfz) * math.exp(p["PKX3"] * dfz) * p["LKX"]
    SVx = Fz * (p["PVX1"] + p["PVX2"] * dfz) * p["LVX"] * lmux
    Fx0 = mf(Kx / (Cx * Dx), Cx, Dx, Ex, kx) + SVx
    # pure Fy
    SHy = (p["PHY1"] + p["PHY2"] * dfz) * p["LHY"] + p["PHY3"] * gy
    ay = alpha + SHy
    Cy = p["PCY1"] * p["LCY"]
    muy = (p["PDY1"] + p["PDY2"] * dfz) * (1 - p["PDY3"] * gy**2) * lmuy
    Dy = muy * Fz
    Ey = (p["PEY1"] + p["PEY2"] * dfz) * (1 - (p["PEY3"] + p["PEY4"] * gy) * math.copysign(1.0, ay)) * p["LEY"]
    Ky = p["PKY1"] * Fz0p * math.sin(2 * math.atan(Fz / (p["PKY2"] * Fz0p))) * (1 - p["PKY3"] * abs(gy)) * p["LKY"]
    By = Ky / (Cy * Dy)
    SVy = Fz * ((p["PVY1"] + p["PVY2"] * dfz) * p["LVY"] + (p["PVY3"] + p["PVY4"] * dfz) * gy) * lmuy
    Fy0 = mf(By, Cy, Dy, Ey, ay) + SVy
    # aligning terms
    SHt = p["QHZ1"] + p["QHZ2"] * dfz + (p["QHZ3"] + p["QHZ4"] * dfz) * gz
    at = alpha + SHt
    ar = alpha + SHy + SVy / Ky
    Bt = (
        (p["QBZ1"] + p["QBZ2"] * dfz + p["QBZ3"] * dfz**2)
        * (1 + p["QBZ4"] * gz + p["QBZ5"] * abs(gz))
        * p["LKY"]
        / lmuy
    )
    Ct = p["QCZ1"]
    Dt = Fz * (p["QDZ1"] + p["QDZ2"] * dfz) * (1 + p["QDZ3"] * gz + p["QDZ4"] * gz**2) * (R0 / Fz0p) * p["LTR"]
    Et = (p["QEZ1"] + p["QEZ2"] * dfz + p["QEZ3"] * dfz**2) * (
        1 + (p["QEZ4"] + p["QEZ5"] * gz) * (2 / math.pi) * math.atan(Bt * Ct * at)
    )
    Br = p["QBZ9"] * p["LKY"] / lmuy + p["QBZ10"] * By * Cy
    Dr = Fz * ((p["QDZ6"] + p["QDZ7"] * dfz) * p["LRES"] + (p["QDZ8"] + p["QDZ9"] * dfz) * gz) * R0 * lmuy

    def trail(a):
        return Dt * math.cos(Ct * math.atan(Bt * a - Et * (Bt * a - math.atan(Bt * a)))) * math.cos(alpha)

    if not combined:
        Mz = -trail(at) * Fy0 + Dr * math.cos(math.atan(Br * ar)) * math.cos(alpha)
        Fx, Fy = Fx0, Fy0
    else:
        SHxa = p["RHX1"]
        Bxa = p["RBX1"] * math.cos(math.atan(p["RBX2"] * kappa)) * p["LXAL"]
        Cxa, Exa = p["RCX1"], p["REX1"] + p["REX2"] * dfz

        def weight(B, C, E, x):
            return math.cos(C * math.atan(B * x - E * (B * x - math.atan(B * x))))

        Gxa = weight(Bxa, Cxa, Exa, alpha + SHxa) / weight(Bxa, Cxa, Exa, SHxa)
        Fx = Gxa * Fx0
        SHyk = p["RHY1"] + p["RHY2"] * dfz
        Byk = p["RBY1"] * math.cos(math.atan(p["RBY2"] * (alpha - p["RBY3"]))) * p["LYKA"]
        Cyk, Eyk = p["RCY1"], p["REY1"] + p["REY2"] * dfz
        ks = kappa + SHyk
        Gyk = weight(Byk, Cyk, Eyk, ks) / weight(Byk, Cyk, Eyk, SHyk)
        DVyk = muy * Fz * (p["RVY1"] + p["RVY2"] * dfz + p["RVY3"] * gamma) * math.cos(math.atan(p["RVY4"] * alpha))
        SVyk = DVyk * math.sin(p["RVY5"] * math.atan(p["RVY6"] * kappa)) * p["LVYKA"]
        Fy = Gyk * Fy0 + SVyk
        r2 = (Kx / Ky) ** 2 * kappa**2
        at_eq = math.atan(math.sqrt(math.tan(at) ** 2 + r2)) * math.copysign(1.0, at)
        ar_eq = math.atan(math.sqrt(math.tan(ar) ** 2 + r2)) * math.copysign(1.0, ar)
        s = R0 * (p["SSZ1"] + p["SSZ2"] * Fy / Fz0p + (p["SSZ3"] + p["SSZ4"] * dfz) * gamma) * p["LS"]
        Mzr = Dr * math.cos(math.atan(Br * ar_eq)) * math.cos(alpha)
        Mz = -trail(at_eq) * (Fy - SVyk) + Mzr + s * Fx
    Mx = R0 * Fz * p["LMX"] * (p["QSX1"] * p["LVMX"] - p["QSX2"] * gamma + p["QSX3"] * Fy / Fz0)
    vr = Vx / p["LONGVL"]
    My = -R0 * Fz * p["LMY"] * (p["QSY1"] + p["QSY2"] * Fx / Fz0 + p["QSY3"] * abs(vr) + p["QSY4"] * vr**4)
    return {"Fx": Fx, "Fy": Fy, "Mz": Mz, "Mx": Mx, "My": My}


@pytest.mark.parametrize("combined", [False, True])
def test_agrees_with_an_independent_transcription_of_the_equations(combined):
    p = _flat(LGAX=0.8, LGAY=1.3, LGAZ=0.7, LMUV=0.3, QSX1=0.01, QSX2=0.4, QSX3=0.05, QSY3=0.002, QSY4=0.001)
    rng = np.random.default_rng(16)
    worst = 0.0
    for _ in range(300):
        Fz = rng.uniform(0.3, 1.6) * 20000.0
        kappa = rng.uniform(-0.3, 0.3)
        alpha = rng.uniform(-0.25, 0.25)
        gamma = rng.uniform(-0.1, 0.1)
        Vx = rng.uniform(5.0, 30.0)
        ref = _reference(p, Fz, kappa, alpha, gamma, Vx, combined)
        out = evaluate_arrays(p, Fz, kappa, alpha, gamma, 0.0, Vx, mode=211 if combined else 210)
        for k, v in ref.items():
            scale = Fz * (p["UNLOADED_RADIUS"] if k in ("Mz", "Mx", "My") else 1.0)
            err = abs(float(out[k]) - v) / (abs(v) + 1e-3 * scale)
            worst = max(worst, err)
            assert err < 1e-6, (k, combined, Fz, kappa, alpha, gamma, Vx, float(out[k]), v)
    assert worst < 1e-6


# ------------------------------------------------------------------ properties
def _symmetric() -> dict:
    """The HMMWV PAC2002 tyre with every asymmetric term set to zero."""
    zero = ("PHX1 PHX2 PVX1 PVX2 PEX4 PHY1 PHY2 PVY1 PVY2 PEY3 RHX1 RHY1 RHY2 RVY1 RVY2 RVY3 RBY3 "
            "QHZ1 QHZ2 QDZ6 QDZ7 QDZ3 QBZ4 QEZ4 SSZ1 QSX1").split()  # fmt: skip
    return _flat(**{k: 0.0 for k in zero}, QSX2=0.3, QSX3=0.05)


SYM = _symmetric()


@pytest.mark.filterwarnings("ignore::mftire.mf.inputs.MFLimitWarning")  # inputs beyond the limits on purpose
@settings(max_examples=60, deadline=None)
@given(
    Fz=st.floats(4000.0, 60000.0),
    kappa=st.floats(-0.5, 0.5),
    alpha=st.floats(-0.5, 0.5),
    gamma=st.floats(-0.2, 0.2),
)
def test_symmetric_tyre_is_mirror_symmetric(Fz, kappa, alpha, gamma):
    a = evaluate_arrays(SYM, Fz, kappa, alpha, gamma)
    b = evaluate_arrays(SYM, Fz, kappa, -alpha, -gamma)
    tol = 1e-9 * Fz
    assert float(b["Fx"]) == pytest.approx(float(a["Fx"]), abs=tol)
    assert float(b["Fy"]) == pytest.approx(-float(a["Fy"]), abs=tol)
    assert float(b["Mz"]) == pytest.approx(-float(a["Mz"]), abs=tol)
    assert float(b["Mx"]) == pytest.approx(-float(a["Mx"]), abs=tol)
    assert float(b["My"]) == pytest.approx(float(a["My"]), abs=tol)
    # pure longitudinal slip is odd in kappa when alpha = gamma = 0
    c = evaluate_arrays(SYM, Fz, kappa, 0.0, 0.0)
    d = evaluate_arrays(SYM, Fz, -kappa, 0.0, 0.0)
    assert float(d["Fx"]) == pytest.approx(-float(c["Fx"]), abs=tol)


PAC2002_FILES = [HMMWV, *sorted(p for p in WILD.glob("*.tir") if read_tir(p).format == "PAC2002")]


@pytest.mark.filterwarnings("ignore::mftire.mf.inputs.MFLimitWarning")  # inputs beyond the limits on purpose
@pytest.mark.filterwarnings("ignore::mftire.errors.MftireTirWarning")  # wild files: sections missing on purpose
@settings(max_examples=40, deadline=None)
@given(
    which=st.integers(0, len(PAC2002_FILES) - 1),
    load_factor=st.floats(0.3, 1.5),
    slip=st.floats(0.002, 0.02),
)
def test_iso_signs_at_small_slip(which, load_factor, slip):
    """ISO-W: Fx rises with kappa, Fy falls and Mz rises with alpha at small slip.

    The slopes are taken across zero (the offsets of real tyres, e.g. ply-steer, move
    the zero crossings slightly); at 3 deg and kappa = 0.05 the signs themselves hold.
    """
    tyre = load(PAC2002_FILES[which])
    Fz = load_factor * tyre.flat["FNOMIN"] * tyre.flat["LFZO"]
    out = tyre.evaluate(Fz, np.array([slip, -slip, 0.0, 0.0]), np.array([0.0, 0.0, slip, -slip]))
    assert out["Fx"][0] > out["Fx"][1]
    assert out["Fy"][2] < out["Fy"][3] and out["Mz"][2] > out["Mz"][3]
    firm = tyre.evaluate(Fz, np.array([0.05, -0.05, 0.0]), np.array([0.0, 0.0, math.radians(3.0)]))
    assert firm["Fx"][0] > 0.0 > firm["Fx"][1]
    assert firm["Fy"][2] < 0.0 < firm["Mz"][2]


# ------------------------------------------------------------------ FMU
@needs_c_compiler
def test_fmu_exports_a_pac2002_file_and_agrees_with_python(tmp_path):
    from fmpy import extract

    from mftire.fmu.export import export_fmu
    from mftire.fmu.host import FMUTyre

    params = read_tir(HMMWV)
    for key, value in (("LGAY", 1.2), ("LGAZ", 0.8), ("LGAX", 0.9), ("LMUV", 0.3)):
        params.set(key, value, section="SCALING_COEFFICIENTS")
    tyre = Tyre(params, name="hmmwv_pac")
    path = export_fmu(tyre, tmp_path / "pac.fmu", fmi_version=2)
    unzipdir = extract(str(path), unzipdir=str(tmp_path / "x"))
    assert "PAC2002" in (tmp_path / "x" / "modelDescription.xml").read_text()
    rng = np.random.default_rng(2002)
    n = 0
    for mode in (111, 110, 211, 121):
        with FMUTyre(unzipdir, "CS", start_values={"useMode": mode}) as fmu:
            for _ in range(60):
                pt = {
                    "Fz": rng.uniform(0.2, 1.6) * 20000.0,
                    "kappa": rng.uniform(-0.5, 0.5),
                    "alpha": rng.uniform(-0.3, 0.3),
                    "gamma": rng.uniform(-0.1, 0.1),
                    "phit": 0.0,
                    "Vx": rng.uniform(0.5, 30.0),
                    "P": 800000.0,
                    "omega": 0.0,
                    "muRoad": 1.0,
                }
                got = fmu.evaluate(**pt)
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    ref = tyre.evaluate(pt["Fz"], pt["kappa"], pt["alpha"], pt["gamma"], 0.0, pt["Vx"], mode=mode)
                for k in ("Fx", "Fy", "Mx", "My", "Mz", "t", "Mzr", "mux", "muy", "Kya"):
                    scale = 20000.0 * (0.5 if k in ("Mx", "My", "Mz", "Mzr") else 1.0)
                    if k in ("t", "mux", "muy"):
                        scale = 1.0
                    assert abs(got[k] - float(ref[k])) <= 1e-9 * (abs(float(ref[k])) + scale), (k, mode, pt)
                n += 1
    assert n == 240


@needs_c_compiler
def test_fmu_exports_an_mf05_file_and_agrees_with_python(tmp_path):
    from fmpy import extract

    from mftire.fmu.export import export_fmu
    from mftire.fmu.host import FMUTyre

    tyre = load(WILD / "chrono_feda_335_65R22_5_G275MSA_70psi.tir")
    path = export_fmu(tyre, tmp_path / "mf05.fmu", fmi_version=2)
    unzipdir = extract(str(path), unzipdir=str(tmp_path / "x"))
    rng = np.random.default_rng(5)
    with FMUTyre(unzipdir, "CS", start_values={"useMode": 111}) as fmu:
        for _ in range(40):
            pt = {"Fz": rng.uniform(0.5, 1.3) * 19000.0, "kappa": rng.uniform(-0.5, 0.0),
                  "alpha": rng.uniform(-0.2, 0.2), "gamma": rng.uniform(-0.1, 0.1), "phit": 0.0,
                  "Vx": rng.uniform(2.0, 30.0), "P": 220000.0,
                  "omega": 0.0, "muRoad": 1.0}
            got = fmu.evaluate(**pt)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                ref = tyre.evaluate(pt["Fz"], pt["kappa"], pt["alpha"], pt["gamma"], 0.0, pt["Vx"])
            for k in ("Fx", "Fy", "Mx", "My", "Mz"):
                assert abs(got[k] - float(ref[k])) <= 1e-9 * (abs(float(ref[k])) + 19000.0), (k, pt)
