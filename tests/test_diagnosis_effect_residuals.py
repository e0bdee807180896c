"""Issue 21 (speed of the diagnosis): an effect fit's Jacobian is exact (mftire.diagnosis.effects._EffectResiduals,
algorithmic derivatives through the model pipeline and the law's forms), not finite differences.  Each column must
be the derivative that central differences of the residual function measure, for every kind of law the diagnosis
fits: a factor law, a hinge, an interaction with the load, a table, an offset with its constant, an input law, and
the pressure terms."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from mftire import load
from mftire.diagnosis import effects
from mftire.diagnosis.candidates import with_sweeps

DATA = Path(__file__).resolve().parents[1] / "validation" / "data" / "slip_speed"


@pytest.fixture(scope="module")
def problem():
    tyre = load(DATA / "fitted.tir")
    df = with_sweeps(pd.read_csv(DATA / "sweeps.csv"))
    keep = [sid for _, g in df.groupby("kind") for sid in g["sweep_id"].unique()[::4]]  # every 4th sweep per kind
    df = df[df["sweep_id"].isin(keep)].reset_index(drop=True)
    prob = effects.make_problem(tyre, df, ("Fx", "Fy", "Mz"))
    assert set(effects.covered_channels(prob)) == {"Fx", "Fy", "Mz"}
    return prob


LAWS = [
    (effects.Law("slip_speed_quadratic", ("LMUX", "LMUY"), "quadratic"), "Vs"),
    (effects.Law("stiffness_threshold", ("LKX", "LKY"), "hinge"), "time"),
    (effects.Law("shape_interaction", ("LCY",), "interaction", "dfz"), "time"),
    (effects.Law("trail_levels", ("LTR",), "table"), "load_fraction"),
    (effects.Law("shift_variable", ("FY_OFFSET",), "linear"), "time"),
    (effects.Law("slip_angle_offset", ("ALPHA_OFFSET",), "linear"), "time"),
    (effects.Law("horizontal_shift_variable", ("LHY",), "linear"), "time"),
]


def _fun_and_start(prob, law: effects.Law, variable: str):
    """The residual function of ``law`` (its terms, the main coefficients and the shifts it scales) and a start
    point away from the neutral law (its coefficients 0.3 and the hinge inside the data)."""
    tyre = prob.tyre
    v = None if variable in effects.BUILTIN_VARIABLES else prob.df[variable].to_numpy(float)
    v2 = None
    if law.variable2 == "dfz":
        fz0 = float(tyre["LFZO"]) * float(tyre["FNOMIN"])
        v2 = (prob.df["Fz"].to_numpy(float) - fz0) / fz0
    terms = [effects.law_term(law, variable, v, tyre, 1, v2)]
    if set(law.targets) <= effects.ADDITIVE_TARGETS and law.form != "table":
        terms.append(effects.intercept_term(law, variable, v, 2))
    section = {k: val for t in terms for k, val in t.section().items()}
    variables = ({} if v is None else {variable: v}) | ({} if v2 is None else {"dfz": v2})
    model = effects._model(prob, effects.parse_section(section), variables)
    keys = [k for t in terms for k in t.coefficient_keys]
    refit = [k for ch in prob.channels for k in effects.REFIT_KEYS[ch]]
    refit += [effects.SHIFT_COEFFICIENTS[t] for t in law.targets if t in effects.SHIFT_COEFFICIENTS]
    names = keys + refit
    x0 = np.array([(0.3 if k.endswith(("_C1", "_C2", "_C3")) else 0.1) for k in keys]
                  + [float(tyre[k]) for k in refit])  # fmt: skip
    if law.form == "hinge":
        x0[1] = 0.2  # the threshold inside the data's range of the scaled variable, away from every row

    def q_of(x):
        return {**tyre.flat, **dict(zip(names, x, strict=True))}

    return effects._EffectResiduals(prob, model, q_of, names), x0, names


@pytest.mark.parametrize(("law", "variable"), LAWS, ids=[law.name for law, _ in LAWS])
def test_exact_jacobian_equals_central_differences(problem, law, variable):
    fun, x0, names = _fun_and_start(problem, law, variable)
    jac = fun.jacobian(x0)
    r0 = fun(x0)
    typical = np.linalg.norm(jac) / np.sqrt(len(names))  # a column's size; a nearly idle one is judged against it
    assert jac.shape == (r0.size, len(names))
    for j, key in enumerate(names):
        h = 1e-6 * max(1.0, abs(x0[j]))
        xp, xm = x0.copy(), x0.copy()
        xp[j] += h
        xm[j] -= h
        fd = (fun(xp) - fun(xm)) / (2 * h)
        scale = max(np.linalg.norm(fd), np.linalg.norm(jac[:, j]), 1e-3 * typical)
        assert np.linalg.norm(jac[:, j] - fd) <= 1e-5 * scale, key
        if key.startswith(("EXT1_C1", "EXT2_C1")) or key in ("PDX1", "PDY1"):
            assert np.linalg.norm(fd) > 0, key  # a column that acts: the comparison is not 0 == 0


def test_masked_rows_have_zero_derivative(problem):
    """The rows a channel does not score (the Fx rows of a cornering sweep) have residual 0 and Jacobian rows 0."""
    fun, x0, _ = _fun_and_start(problem, *LAWS[0])
    r, jac = fun(x0), fun.jacobian(x0)
    zero = r == 0.0
    assert zero.any() and (~zero).any()
    assert np.all(jac[zero] == 0.0)


def test_effect_fit_with_the_exact_jacobian_recovers_a_friction_law(problem):
    """Data made by the tyre with a law LMUX·LMUY × (1 + 0.08·z + 0.03·z²) in Vs: the fit finds the coefficients."""
    law = effects.Law("slip_speed_quadratic", ("LMUX", "LMUY"), "quadratic")
    fun, x0, names = _fun_and_start(problem, law, "Vs")
    truth = x0.copy()
    truth[:2] = (0.08, 0.03)
    y = {}
    with np.errstate(all="ignore"):
        out = fun.model.channels(fun.q_of(truth), problem.channels)
    for ch in problem.channels:
        y[ch] = np.real(getattr(out, ch))
    df = problem.df.assign(**y)
    prob = effects.make_problem(problem.tyre, df, ("Fx", "Fy", "Mz"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = effects.fit_effect(prob, law, "Vs", None)
    c = [fit.parameters[k] for k in sorted(fit.parameters)]
    assert c == pytest.approx([0.08, 0.03], abs=2e-3)
    assert fit.ss_after < 1e-6 * fit.ss_before
