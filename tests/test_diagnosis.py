"""Diagnosis on campaigns generated from a known MF tyre with one injected effect.

The "fitted" model is the true tyre refitted (friction, curvature and stiffness
coefficients) to data that contain the effect, as a real fit would absorb part of
it.  Each scenario checks that the right cause is named first and that the held-out
error falls; the null scenario checks that nothing is reported.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from conftest import REFERENCE_TYRES
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import least_squares

from mftire import Tyre, load, read_tir
from mftire.cli import main
from mftire.diagnosis.candidates import candidates, derived_candidates, with_sweeps
from mftire.diagnosis.diagnose import diagnose
from mftire.diagnosis.holdout import default_holdout, parse_holdout
from mftire.diagnosis.report import write_report
from mftire.errors import MftireInputError
from mftire.mf.extensions import SECTION

# the campaigns reach beyond the .tir's ranges (pressure below PRESMIN, Ex clipped at the largest slips):
# the evaluator's limit warnings are expected here
pytestmark = pytest.mark.filterwarnings("ignore::mftire.mf.inputs.MFLimitWarning")
TYRE = load(REFERENCE_TYRES["MF61"])


def _term(target: str, form: str, variable: str, **numbers) -> dict:
    out = {"EXT1_TARGET": target, "EXT1_FORM": form, "EXT1_VARIABLE": variable}
    out.update({f"EXT1_{k.upper()}": v for k, v in numbers.items()})
    return out


VS_DECAY = _term("LMUX LMUY", "decay", "Vs", scale=TYRE["LONGVL"], c1=0.3)  # Pacejka 2012 eq 4.E7, LMUV = 0.3


def _campaign(seed: int = 0) -> pd.DataFrame:
    """Braking at three speeds and cornering, at three loads, with a temperature log."""
    rng = np.random.default_rng(seed)
    F0 = TYRE["FNOMIN"]
    rows = []
    for lf in (0.5, 1.0, 1.5):
        for V in (20 / 3.6, 60 / 3.6, 100 / 3.6):
            k = np.linspace(0, -1, 41)
            rows.append(pd.DataFrame(dict(Fz=lf * F0 * (1 + 0.02 * rng.standard_normal(41)), kappa=k, alpha=0.0,
                                          gamma=0.0, Vx=V, P=TYRE["NOMPRES"])))  # fmt: skip
        a = np.radians(np.linspace(-12, 12, 49))
        rows.append(pd.DataFrame(dict(Fz=lf * F0 * (1 + 0.02 * rng.standard_normal(49)), kappa=0.0, alpha=a,
                                      gamma=0.0, Vx=60 / 3.6, P=TYRE["NOMPRES"])))  # fmt: skip
    df = pd.concat(rows, ignore_index=True)
    df["time"] = np.arange(len(df)) * 0.5
    # several warm-up/cool-down cycles over the campaign, so temperature is not a proxy for the load blocks
    df["tread_temp"] = 30 + 20 * np.sin(np.arange(len(df)) / 40.0) + rng.standard_normal(len(df))
    return df


def _measure(df: pd.DataFrame, section: dict | None, variables: dict | None = None, seed: int = 1) -> pd.DataFrame:
    tyre = TYRE
    if section:
        flat = dict(TYRE.flat)
        flat[SECTION] = section
        tyre = Tyre(flat)
    out = tyre.evaluate(df.Fz.values, df.kappa.values, df.alpha.values, df.gamma.values, Vx=df.Vx.values,
                        P=df.P.values, **(variables or {}))  # fmt: skip
    rng = np.random.default_rng(seed)
    d = df.copy()
    for ch in ("Fx", "Fy", "Mz"):
        d[ch] = out[ch] + 0.01 * np.max(np.abs(out[ch])) * rng.standard_normal(len(d))
    return d


def _refit(d: pd.DataFrame, keys: tuple[str, ...] = ("PDX1", "PDX2", "PDY1", "PDY2", "PKX1", "PKY1", "QDZ1", "PEX1",
                                                       "PEY1")) -> Tyre:
    keys = list(keys)

    def tyre_of(x):
        flat = dict(TYRE.flat)
        flat.update(dict(zip(keys, x, strict=True)))
        return Tyre(flat)

    def fun(x):
        o = tyre_of(x).evaluate(d.Fz.values, d.kappa.values, d.alpha.values, d.gamma.values, Vx=d.Vx.values,
                                P=d.P.values)  # fmt: skip
        return np.concatenate([(d[c].values - o[c]) / np.abs(d[c]).max() for c in ("Fx", "Fy", "Mz")])

    return tyre_of(least_squares(fun, [TYRE[k] for k in keys], x_scale="jac").x)


@pytest.fixture(scope="module")
def base_df():
    return _campaign()


@pytest.fixture(scope="module")
def vs_case(base_df):
    """The slip-speed campaign, its refitted tyre and its diagnosis, made once for the tests that read them."""
    d = _measure(base_df, VS_DECAY)
    fitted = _refit(d)
    return d, fitted, diagnose(d, fitted, progress=False)


def test_derived_candidates_have_fixed_names(base_df):
    d = with_sweeps(_measure(base_df, None))
    names = [c.name for c in candidates(d)]
    for name in ("Vs", "Vx", "Fz_dev", "sign_alpha", "sequence", "energy", "time", "tread_temp"):
        assert name in names
    assert "sign_kappa" not in names  # braking only: no driving data, no drive/brake asymmetry to test
    vs = derived_candidates(d)["Vs"]
    np.testing.assert_allclose(vs, d.Vx.values * np.sqrt(d.kappa.values**2 + np.tan(d.alpha.values) ** 2))


def test_null_campaign_reports_nothing(base_df):
    d = _measure(base_df, None)
    res = diagnose(d, _refit(d), progress=False)
    assert not res.significant
    assert res.effect is None and res.extended is None


def test_slip_speed_effect_is_named_and_removed(vs_case):
    _, _, res = vs_case
    assert res.significant
    assert res.ranking[0].variable == "Vs"
    assert res.effect.name == "slip_speed_friction"
    assert res.effect.parameters["EXT1_C1"] == pytest.approx(0.3, rel=0.25)
    fx = next(e for e in res.errors if e.channel == "Fx")
    assert fx.rms_after <= 0.5 * fx.rms_before


def test_data_column_effect_with_any_name(base_df):
    sec = _term("LMUX LMUY", "linear", "tread_temp", ref=30.0, scale=20.0, c1=-0.12)
    d = _measure(base_df, sec, {"tread_temp": base_df.tread_temp.values})
    res = diagnose(d, _refit(d), progress=False)
    assert res.significant
    assert res.ranking[0].variable == "tread_temp"
    assert res.effect.name in ("friction_variable", "friction_variable_quadratic") and res.effect.physical
    assert res.extended.required_variables == ["tread_temp"]
    fx = next(e for e in res.errors if e.channel == "Fx")
    assert fx.rms_after < fx.rms_before


def test_left_right_asymmetry(base_df):
    d = _measure(base_df, _term("LMUY", "linear", "sign_alpha", c1=0.05))
    res = diagnose(d, _refit(d), progress=False)
    assert res.ranking[0].variable == "sign_alpha"
    assert res.effect.name == "asymmetry"
    assert res.effect.parameters["EXT1_C1"] == pytest.approx(0.05, rel=0.3)
    fy = next(e for e in res.errors if e.channel == "Fy")
    assert fy.rms_after <= 0.7 * fy.rms_before


def test_report_files_and_round_trip(vs_case, tmp_path):
    _, _, res = vs_case
    doc = write_report(res, tmp_path)
    on_disk = json.loads((tmp_path / "diagnosis.json").read_text())
    assert on_disk == json.loads(json.dumps(doc, default=float))
    for key in ("significant", "ranking", "effect", "holdout", "extended_tir"):
        assert key in on_disk
    assert on_disk["effect"]["name"] == "slip_speed_friction"
    assert set(on_disk["ranking"][0]) >= {"variable", "score", "p_value", "significant"}
    assert (tmp_path / "diagnosis.md").read_text().startswith("# Diagnosis")
    for png in ("ranking.png", "curves_before_after.png", "residual_vs_Vs.png"):
        assert (tmp_path / png).read_bytes()[:4] == b"\x89PNG"
    ext = read_tir(tmp_path / on_disk["extended_tir"])
    assert ext.section(SECTION)["EXT1_C1"] == pytest.approx(on_disk["effect"]["parameters"]["EXT1_C1"])
    assert ext.section(SECTION)["EXT1_VARIABLE"] == "Vs"


def test_holdout_rules(base_df):
    d = with_sweeps(_measure(base_df, None))
    column, values = default_holdout(d, ["Vx"])
    # holding out 60 km/h would remove every cornering sweep: a load is held out instead
    assert column == "Fz"
    assert parse_holdout("Vx=16.67,27.78") == ("Vx", [16.67, 27.78])
    with pytest.raises(MftireInputError):
        parse_holdout("Vx")


def test_cli_diagnose(vs_case, tmp_path, capsys, monkeypatch):
    # the command's own work: read the data and the .tir, parse --holdout and --permutations, hand them to the
    # diagnosis, write the report and print its summary.  The diagnosis itself is the slip-speed case's, already
    # computed (vs_case; the command on a real campaign end to end: tests/test_diagnosis_campaigns.py)
    import mftire.diagnosis.diagnose as diagnose_module

    d, tyre, res = vs_case
    data = tmp_path / "data.csv"
    d.to_csv(data, index=False)
    from mftire import write_tir

    tir = tmp_path / "fitted.tir"
    params = read_tir(REFERENCE_TYRES["MF61"])
    for k in ("PDX1", "PDX2", "PDY1", "PDY2", "PKX1", "PKY1", "QDZ1", "PEX1", "PEY1"):
        params.set(k, tyre[k])
    write_tir(params, tir)
    seen = {}

    def fake(data, tyre, holdout=None, **kw):
        seen.update(rows=len(data), pdx1=tyre["PDX1"], holdout=holdout, **kw)
        return res

    monkeypatch.setattr(diagnose_module, "diagnose", fake)
    out = tmp_path / "diag"
    assert main(["diagnose", str(data), "--tir", str(tir), "--output", str(out), "--holdout", "Fz=3376",
                 "--permutations", "19", "--seed", "3"]) == 0  # fmt: skip
    assert seen["holdout"] == ("Fz", [3376.0]) and seen["n_perm"] == 19 and seen["seed"] == 3
    assert seen["rows"] == len(d) and seen["pdx1"] == pytest.approx(tyre["PDX1"])
    doc = json.loads((out / "diagnosis.json").read_text())
    assert doc["ranking"][0]["variable"] == res.ranking[0].variable == "Vs"
    assert doc["effect"]["name"] == res.effect.name
    printed = capsys.readouterr().out
    assert "Vs" in printed and "held out Fx: RMS" in printed and str(out / "diagnosis.md") in printed


@settings(max_examples=60, deadline=None)
@given(n=st.integers(4, 25), categorical=st.booleans(), seed=st.integers(0, 10_000), lone=st.booleans())
def test_profile_cv_score_is_the_leave_one_sweep_out_refit(n, categorical, seed, lone):
    # the closed form (deleted residuals; level means without the sweep) against refitting without each sweep
    from mftire.diagnosis.profile import _cv_scores

    rng = np.random.default_rng(seed)
    v = rng.integers(0, 3, n).astype(float) if categorical else rng.normal(size=n)
    if lone and not categorical:  # every other sweep at one value: no line without the odd one
        v[:] = 1.0
        v[rng.integers(n)] = 2.0
    lam = rng.normal(size=n) + (0.5 * v if seed % 2 else 0.0)

    def refit(v: np.ndarray) -> float:
        if np.std(v) == 0:
            return 0.0
        pred = np.empty(n)
        for i in range(n):
            m = np.arange(n) != i
            if categorical:
                same = m & (v == v[i])
                pred[i] = lam[same].mean() if same.any() else lam[m].mean()
            elif np.std(v[m]) > 0:
                a, b = np.polyfit(v[m], lam[m], 1)
                pred[i] = a * v[i] + b
            else:
                pred[i] = lam[m].mean()
        return 1.0 - float(np.mean((lam - pred) ** 2)) / float(np.var(lam))

    perms = np.array([v, *(rng.permutation(v) for _ in range(4))])
    got = _cv_scores(perms, lam, categorical)
    assert got == pytest.approx([refit(p) for p in perms], rel=1e-9, abs=1e-9)
