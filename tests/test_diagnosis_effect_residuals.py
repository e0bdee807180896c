"""An effect fit's residual function (mftire.diagnosis.effects._EffectResiduals) and its exact Jacobian
(mftire.mf.derivatives through the model and the law's form): the columns of the law's coefficients and of
the main coefficients refitted with it agree with central differences, and the fit with it with the fit by
finite differences."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import least_squares

from mftire import load
from mftire.diagnosis import effects
from mftire.diagnosis.candidates import with_sweeps

DATA = Path(__file__).resolve().parents[1] / "validation" / "data" / "slip_speed"


@pytest.fixture(scope="module")
def problem():
    tyre = load(DATA / "fitted.tir")
    df = with_sweeps(pd.read_csv(DATA / "sweeps.csv"))
    keep = [sid for _, g in df.groupby("kind") for sid in g["sweep_id"].unique()[::3]]  # every 3rd sweep per kind
    df = df[df["sweep_id"].isin(keep)].reset_index(drop=True)
    prob = effects.make_problem(tyre, df, ("Fx", "Fy", "Mz"))
    assert set(effects.covered_channels(prob)) == {"Fx", "Fy", "Mz"}
    return prob


def _residual_function(prob, law, size=0.05):
    term = effects.law_term(law, "Vs", None, prob.tyre, 1)
    model = effects._model(prob, effects.parse_section(term.section()), {})
    names = [*term.coefficient_keys, *(k for ch in ("Fx", "Fy", "Mz") for k in effects.REFIT_KEYS[ch])]
    base_q = {**prob.tyre.flat, **dict.fromkeys(term.coefficient_keys, size)}

    def q_of(x):
        return {**base_q, **dict(zip(names, x, strict=True))}

    return effects._EffectResiduals(prob, model, q_of, names), np.array([base_q[k] for k in names], float), names


@pytest.mark.parametrize("law", [effects.Law("slip_speed_quadratic", ("LMUX", "LMUY"), "quadratic"),
                                 effects.Law("mixed", ("LKX", "FY_OFFSET", "ALPHA_OFFSET", "LTR"), "hinge")],
                         ids=["friction", "stiffness-offset-input-trail"])  # fmt: skip
def test_jacobian_matches_central_differences(problem, law):
    fun, x0, names = _residual_function(problem, law)
    with np.errstate(all="ignore"):
        assert fun(x0).tobytes() == effects._residuals(problem, fun.model, fun.q_of(x0)).tobytes()
    jac = fun.jac(x0)
    assert jac.shape == (len(fun(x0)), len(names))
    moved = 0
    for j, key in enumerate(names):
        h = 1e-6 * max(1.0, abs(x0[j]))
        up, down = x0.copy(), x0.copy()
        up[j] += h
        down[j] -= h
        fd = (fun(up) - fun(down)) / (2 * h)
        if np.linalg.norm(fd) == 0.0:
            assert np.all(jac[:, j] == 0.0), key
            continue
        moved += 1
        assert np.linalg.norm(jac[:, j] - fd) / np.linalg.norm(fd) < 1e-5, key
    assert moved >= len(names) - 2


def test_effect_fit_with_exact_jacobian_matches_the_finite_difference_fit(problem, monkeypatch):
    law = effects.Law("slip_speed_quadratic", ("LMUX", "LMUY"), "quadratic")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exact = effects.fit_effect(problem, law, "Vs", None)
        monkeypatch.setattr(effects, "least_squares", lambda *a, jac, **k: least_squares(*a, **k))  # 2-point
        fd = effects.fit_effect(problem, law, "Vs", None)
    assert exact.ss_after < 0.5 * exact.ss_before
    assert exact.ss_after == pytest.approx(fd.ss_after, rel=1e-3)
    for key, value in fd.parameters.items():  # the same law
        assert exact.parameters[key] == pytest.approx(value, abs=0.01 * max(abs(v) for v in fd.parameters.values()))
