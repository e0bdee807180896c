"""Exact Jacobians of the fitting stages (mftire.mf.derivatives) against finite differences,
and the fit with them against the finite-difference fit."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from conftest import REFERENCE_TYRES

from mftire.fitting import fit_tir, fitter
from mftire.fitting.model import Inputs, fitting_mode, predict
from mftire.fitting.stages import FITTED_KEYS, STAGES
from mftire.fitting.synthetic import synthetic_sweeps
from mftire.iotools.tir import read_tir
from mftire.mf.extensions import FORMS, SECTION, ExtensionSet, make_extension
from mftire.parameters import with_defaults
from mftire.segmentation.grouping import group_sweeps


@pytest.fixture(scope="module")
def case():
    true = read_tir(REFERENCE_TYRES["MF61"])
    pt = with_defaults(true)
    F0, Pn = pt["FNOMIN"], pt["NOMPRES"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        data = synthetic_sweeps(true, [0.5 * F0, F0, 1.5 * F0], np.radians([-2.0, 0.0, 4.0]), [Pn, 1.15 * Pn],
                                n_kappa=21, n_alpha=21, n_combined=11, noise=0.01, outliers=0.01, seed=5)
    rng = np.random.default_rng(7)
    template = true.copy()
    for key in sorted(FITTED_KEYS):
        if pt.get(key, 0.0):
            template.set(key, float(pt[key] * (1.0 + rng.uniform(-0.3, 0.3))))
    return data, template


GROUPS = [(s, ch, g) for s in STAGES for ch, g in zip(fitter._stage_channels(s), s.groups, strict=True)]


@pytest.mark.parametrize("stage,channel,coeffs", GROUPS, ids=[f"{s.number}-{ch}" for s, ch, _ in GROUPS])
def test_jacobian_matches_finite_differences(case, stage, channel, coeffs):
    data, template = case
    table = fitter._classify_rows(group_sweeps(data))
    rows = table[table["kind"].isin(stage.kinds)] if stage.kinds else table
    p = with_defaults(template)
    keys = [c.key for c in coeffs]
    ev = fitter._Evaluator(channel, p, Inputs.from_frame(rows), fitting_mode(), ExtensionSet(()), keys)
    value, jac = ev.jacobian(p, keys)
    np.testing.assert_allclose(value, ev(p), rtol=1e-14, atol=1e-9)
    for j, (key, c) in enumerate(zip(keys, coeffs, strict=True)):
        h = 1e-6 * max(abs(p[key]), c.scale)  # central differences: error ~ h^2
        up, down = dict(p), dict(p)
        up[key] += h
        down[key] -= h
        fd = (ev(up) - ev(down)) / (2 * h)
        scale = max(np.linalg.norm(fd), 1e-9 * np.linalg.norm(jac))
        assert np.linalg.norm(jac[:, j] - fd) / scale < 1e-6, key


def test_residual_jacobian_with_free_rolling_penalty(case):
    data, template = case
    table = fitter._classify_rows(group_sweeps(data))
    rows = table[table["kind"].isin(STAGES[0].kinds)]
    p = with_defaults(template)
    keys = [c.key for c in STAGES[0].coefficients]
    mode, ext = fitting_mode(), ExtensionSet(())
    free = fitter._Evaluator("Fx", p, fitter._condition_inputs(fitter._free_rolling_targets(rows), ext), mode, ext,
                             keys)
    fx = free(p)
    margin = -np.median(fx) * np.ones_like(fx)  # about half of the conditions active
    prob = fitter._Problem(fitter._Evaluator("Fx", p, Inputs.from_frame(rows), mode, ext, keys),
                         rows["Fx"].to_numpy(float), np.full(len(rows), 0.01), fitter._Penalty(free, 3.0, margin))
    jac = prob.jacobian(p, keys)
    pen = jac[len(rows):]
    assert 0 < np.count_nonzero(np.any(pen != 0, axis=1)) < len(fx)
    for j, key in enumerate(keys):
        h = 1e-6 * max(abs(p[key]), 1e-2)
        up, down = dict(p), dict(p)
        up[key] += h
        down[key] -= h
        fd = (prob.residuals(up) - prob.residuals(down)) / (2 * h)
        assert np.linalg.norm(jac[:, j] - fd) / max(np.linalg.norm(fd), 1e-12) < 1e-6, key


def test_exact_fit_matches_finite_difference_fit(case):
    data, template = case
    fits = {j: fit_tir(data, template, stages="1,2,3", progress=False, jacobian=j) for j in ("exact", "2-point")}
    x = Inputs.from_frame(data)
    for channel in ("Fx", "Fy", "Mz"):
        y = data[channel].to_numpy(float)
        model = {j: predict(f.flat, x, channel, fitting_mode()) for j, f in fits.items()}
        rms = {j: float(np.sqrt(np.mean((m - y) ** 2))) for j, m in model.items()}
        diff = float(np.sqrt(np.mean((model["exact"] - model["2-point"]) ** 2)))
        print(f"{channel}: rms exact {rms['exact']:.4g}, FD {rms['2-point']:.4g}, curves differ by {diff:.3g}")
        # the same fit: the curves agree far inside the 1 % noise, the error to the data equally good
        assert diff < 0.02 * np.sqrt(np.mean(y**2)) * 0.01
        assert rms["exact"] <= 1.001 * rms["2-point"]
    assert fits["exact"].identified == fits["2-point"].identified
    assert all(s.success for s in fits["exact"].stages)


def test_model_reuses_the_basic_quantities_only_while_their_parameters_hold(case):
    from mftire.fitting.model import CHANNELS, Model

    data, template = case
    p = with_defaults(template)
    x = Inputs.from_frame(group_sweeps(data).iloc[::5])
    model = Model(p, x, fitting_mode(), ExtensionSet(()))
    for q in (p, dict(p, PDX1=1.1 * p["PDX1"], QDZ1=0.9 * p["QDZ1"]), dict(p, LMUX=0.8 * p["LMUX"]),
              dict(p, LFZO=1.2), p):  # coefficients, then the parameters of eqs 4.E1-4.E8, then back
        got = model.channels(q, CHANNELS)
        fresh = Model(p, x, fitting_mode(), ExtensionSet(())).channels(q, CHANNELS)
        for ch in CHANNELS:
            assert np.asarray(getattr(got, ch)).tobytes() == np.asarray(getattr(fresh, ch)).tobytes(), ch
    assert model.channels(dict(p, LFZO=1.2), ("Fx",)).Fx.tobytes() != model.channels(p, ("Fx",)).Fx.tobytes()


#: one target of each kind an extension term acts through: a friction factor, a slip stiffness, a shift
#: factor, the trail, a force offset, and the input laws (an effective pressure, slip-angle and camber offsets)
EXT_TARGETS = ("LMUY", "LKX", "LHY", "LTR", "FY_OFFSET", "P_FACTOR", "ALPHA_OFFSET", "GAMMA_OFFSET")


@pytest.mark.parametrize("form", sorted(FORMS))
def test_jacobian_through_every_extension_form_matches_finite_differences(case, form):
    """The fitter differentiates every extension form exactly (a stage that fits a law's coefficients no
    longer falls back to finite differences): the columns of the law's coefficients, and of a Magic Formula
    coefficient beside them, agree with central differences on every target kind and channel."""
    data, template = case
    rows = fitter._classify_rows(group_sweeps(data)).iloc[::7].copy()
    rng = np.random.default_rng(3)
    rows["temp"] = rng.uniform(20.0, 80.0, len(rows))  # continuous: no point sits on the hinge's kink
    rows["level"] = rng.integers(0, 3, len(rows)).astype(float)
    numbers = {"table": dict(L1=0.0, L2=1.0, L3=2.0), "power": dict(REF=15.0, SCALE=1.0),
               "interaction": dict(REF=20.0, SCALE=20.0, REF2=3000.0, SCALE2=2000.0)}.get(form, dict(REF=20.0,
                                                                                                  SCALE=20.0))
    variable = {"table": "level", "power": "Vx"}.get(form, "temp")
    checked = 0
    for target in EXT_TARGETS:
        term = make_extension(1, target, form, variable, variable2="Fz" if form == "interaction" else None,
                              **numbers)  # fmt: skip
        size = 0.002 if target.endswith("_OFFSET") and target != "FY_OFFSET" else 0.02
        c = {k: size * (i + 1) for i, k in enumerate(term.coefficient_keys)}
        if form == "saturating":
            c[term.key("C2")] = 3.0
        if form == "hinge":
            c[term.key("C2")] = 0.5
        ext = ExtensionSet((term,))
        p = {**with_defaults(template), **c}
        keys = [*term.coefficient_keys, "PDY1", "PKX1"]
        for channel in ("Fx", "Fy", "Mz"):
            ev = fitter._Evaluator(channel, p, fitter._condition_inputs(rows, ext), fitting_mode(), ext, keys)
            value, jac = ev.jacobian(p, keys)
            np.testing.assert_allclose(value, ev(p), rtol=1e-13, atol=1e-9)
            for j, key in enumerate(keys):
                h = (1e-4 if key.startswith("EXT") else 1e-6) * max(abs(p[key]), 1e-2)
                up, down = dict(p), dict(p)
                up[key] += h
                down[key] -= h
                fd = (ev(up) - ev(down)) / (2 * h)
                if max(np.linalg.norm(fd), np.linalg.norm(jac[:, j])) < 1e-6:
                    continue  # the channel does not read this coefficient (Fx and a lateral law)
                checked += 1
                assert np.linalg.norm(jac[:, j] - fd) / np.linalg.norm(fd) < 1e-4, (target, channel, key)
    assert checked >= 3 * len(EXT_TARGETS)


def test_fit_of_a_law_with_exact_derivatives_matches_the_finite_difference_fit(case):
    """A law's coefficient fitted with the exact Jacobian (the default) and with finite differences lands on
    the same value, the generating one: grip falling linearly with a tread temperature that varies from sweep
    to sweep, fitted with the pure-slip stages."""
    data, template = case
    rng = np.random.default_rng(11)
    sweeps = group_sweeps(data)
    temp = rng.uniform(20.0, 80.0, int(sweeps["sweep_id"].max()) + 1)[sweeps["sweep_id"].to_numpy()]
    true = with_defaults(read_tir(REFERENCE_TYRES["MF61"]))
    factor = 1.0 - 0.1 * (temp - 50.0) / 20.0
    x = Inputs.from_frame(sweeps)
    measured = sweeps.drop(columns=["sweep_id"]).assign(temp=temp)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for ch in ("Fx", "Fy"):
            clean = predict({**true, "LMUX": factor, "LMUY": factor}, x, ch, fitting_mode())
            measured[ch] = clean + 0.005 * np.std(clean) * rng.standard_normal(len(clean))
        start = template.copy()
        law = make_extension(1, "LMUX LMUY", "linear", "temp", REF=50.0, SCALE=20.0, MIN=20.0, MAX=80.0)
        for k, v in law.section().items():
            start.set(k, v, section=SECTION)
        fits = {j: fit_tir(measured, start, stages="1,2", progress=False, jacobian=j) for j in ("exact", "2-point")}
    c1 = {j: float(f.parameters[law.key("C1")]) for j, f in fits.items()}
    assert c1["exact"] == pytest.approx(-0.1, abs=0.01), c1  # the generating law
    assert c1["exact"] == pytest.approx(c1["2-point"], abs=2e-3), c1
