"""Issue 15 (speed only): an effect fit's residual function reuses the channels a main coefficient does
not change (mftire.diagnosis.effects._EffectResiduals); the numbers must be those of a full evaluation,
bit for bit, so that the diagnosis does not change."""

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
    keep = [sid for _, g in df.groupby("kind") for sid in g["sweep_id"].unique()[::3]]  # every 3rd sweep per kind
    df = df[df["sweep_id"].isin(keep)].reset_index(drop=True)
    prob = effects.make_problem(tyre, df, ("Fx", "Fy", "Mz"))
    assert set(effects.covered_channels(prob)) == {"Fx", "Fy", "Mz"}
    return prob


def test_finite_difference_columns_equal_full_evaluations_bit_for_bit(problem):
    prob, tyre = problem, problem.tyre
    law = effects.Law("slip_speed_quadratic", ("LMUX", "LMUY"), "quadratic")
    term = effects.law_term(law, "Vs", None, tyre, 1)
    ext = effects.parse_section(term.section())
    model = effects._model(prob, ext, {})
    keys = list(term.coefficient_keys)
    refit = [k for ch in ("Fx", "Fy", "Mz") for k in effects.REFIT_KEYS[ch]]
    names = keys + refit + list(effects.SHIFT_COEFFICIENTS.values())  # the shifts refitted with a law on their factor
    base_q = {**tyre.flat, **{k: term.start(k) for k in keys}}

    def q_of(x):
        return {**base_q, **dict(zip(names, x, strict=True))}

    fun = effects._EffectResiduals(prob, model, q_of, names)
    x0 = np.array([base_q[k] for k in names], float)
    with np.errstate(all="ignore"):
        full0 = effects._residuals(prob, model, q_of(x0))
    assert fun(x0).tobytes() == full0.tobytes()
    n = len(prob.df)
    for j, key in enumerate(names):  # each column as scipy's 2-point rule makes it (others exactly x0)
        x = x0.copy()
        x[j] += 1.5e-8 * max(1.0, abs(x[j]))
        fast = fun(x)
        with np.errstate(all="ignore"):
            full = effects._residuals(prob, model, q_of(x))
        assert fast.tobytes() == full.tobytes(), key
        moved = {ch for i, ch in enumerate(prob.channels)
                 if np.any(fast[i * n:(i + 1) * n] != full0[i * n:(i + 1) * n])}  # fmt: skip
        group = effects._GROUP_OF.get(key)
        if group is not None:  # the reused channels are the ones the coefficient cannot change
            assert moved <= {group, "Mz"}, (key, moved)
            assert group in moved, (key, moved)  # a real column, not a no-op
    # a new point replaces the base; a column there is again exact
    x1 = x0 * (1.0 + 1e-3)
    assert fun(x1).tobytes() == effects._residuals(prob, model, q_of(x1)).tobytes()
    x2 = x1.copy()
    x2[-1] += 1e-6
    assert fun(x2).tobytes() == effects._residuals(prob, model, q_of(x2)).tobytes()


def test_effect_fit_is_unchanged_by_the_reuse(problem, monkeypatch):
    law = effects.Law("slip_speed_quadratic", ("LMUX", "LMUY"), "quadratic")
    monkeypatch.setattr(effects, "MAX_ITER", 6)  # a few iterations (each with its Jacobian) make the point
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fast = effects.fit_effect(problem, law, "Vs", None)
        monkeypatch.setattr(effects, "_GROUP_OF", {})  # every evaluation in full
        full = effects.fit_effect(problem, law, "Vs", None)
    assert fast.ss_after == full.ss_after and fast.parameters == full.parameters and fast.standard == full.standard
    assert fast.ss_after < fast.ss_before
