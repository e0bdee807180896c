"""Parameter recovery (issue 3, "Done when"): fit noisy synthetic sweeps from a perturbed
template and reproduce the true curves at a held-out load."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from conftest import REFERENCE_TYRES

from mftire.fitting import fit_tir
from mftire.fitting.model import Inputs, fitting_mode, predict
from mftire.fitting.stages import FITTED_KEYS
from mftire.fitting.synthetic import synthetic_sweeps
from mftire.iotools.tir import read_tir
from mftire.parameters import with_defaults

TRUE_TIR = REFERENCE_TYRES["MF61"]
CAMBERS = np.radians([-2.0, 0.0, 4.0])


@pytest.fixture(scope="module")
def recovery():
    true = read_tir(TRUE_TIR)
    pt = with_defaults(true)
    F0, Pn = pt["FNOMIN"], pt["NOMPRES"]
    pressures = [Pn, 1.15 * Pn]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        data = synthetic_sweeps(true, [0.5 * F0, F0, 1.5 * F0], CAMBERS, pressures, n_kappa=35, n_alpha=35,
                                n_combined=17, noise=0.01, outliers=0.01, seed=3)
    # every fitted coefficient perturbed by up to +-30 %
    rng = np.random.default_rng(11)
    template = true.copy()
    for key in sorted(FITTED_KEYS):
        if pt.get(key, 0.0):
            template.set(key, float(pt[key] * (1.0 + rng.uniform(-0.3, 0.3))))
    result = fit_tir(data, template, progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        held = synthetic_sweeps(true, [0.75 * F0, 1.25 * F0], CAMBERS, pressures, n_kappa=61, n_alpha=61,
                                n_combined=31, noise=0.0, outliers=0.0)
    return true, template, data, result, held


def _worst_rms_pct(result, held, channel, rows) -> float:
    """Worst RMS error [% of the true curve's peak] over the held-out sweeps."""
    fitted = predict(result.flat, Inputs.from_frame(held), channel, fitting_mode())
    worst = 0.0
    for _, g in held[rows].groupby("run"):
        idx = g.index.to_numpy()
        y = held[channel].to_numpy()[idx]
        e = np.sqrt(np.mean((fitted[idx] - y) ** 2)) / np.max(np.abs(y)) * 100.0
        worst = max(worst, float(e))
    return worst


def test_recovery_pure_curves_at_held_out_load(recovery):
    _, _, _, result, held = recovery
    pure_long = held["run"] % 6 == 0  # the first sweep of every condition is the kappa sweep
    pure_lat = held["run"] % 6 == 1
    fx = _worst_rms_pct(result, held, "Fx", pure_long)
    fy = _worst_rms_pct(result, held, "Fy", pure_lat)
    mz = _worst_rms_pct(result, held, "Mz", pure_lat)
    print(f"held-out worst RMS % of peak: Fx {fx:.3f}, Fy {fy:.3f}, Mz {mz:.3f}")
    assert fx < 1.0
    assert fy < 1.0
    assert mz < 3.0


def test_recovery_combined_curves_at_held_out_load(recovery):
    _, _, _, result, held = recovery
    combined = held["run"] % 6 >= 2
    fx = _worst_rms_pct(result, held, "Fx", combined)
    fy = _worst_rms_pct(result, held, "Fy", combined)
    mz = _worst_rms_pct(result, held, "Mz", combined)
    print(f"held-out combined worst RMS % of peak: Fx {fx:.3f}, Fy {fy:.3f}, Mz {mz:.3f}")
    assert fx < 1.0
    assert fy < 1.0
    assert mz < 3.0


def test_recovery_bookkeeping(recovery):
    true, template, data, result, _ = recovery
    assert result.success
    assert result.n_dropped_nan == 0
    # two pressures: quadratic pressure terms are not identifiable; one speed: no speed terms
    for key in ("PPX2", "PPX4", "PPY4"):
        assert "pressures" in result.not_identified[key]
    assert "speeds" in result.not_identified["QSY3"]
    for key in ("PPX2", "QSY3"):
        assert result.flat[key] == pytest.approx(with_defaults(template)[key])
    # constants come from the template, untouched
    for key in ("FNOMIN", "NOMPRES", "UNLOADED_RADIUS", "LONGVL", "LFZO", "LMUX"):
        assert result.flat[key] == with_defaults(template)[key]
    # identified core coefficients close to the truth
    pt = with_defaults(true)
    for key in ("PDX1", "PKX1", "PDY1", "PCY1", "QDZ1"):
        assert result.flat[key] == pytest.approx(pt[key], rel=0.03), key
    assert {s.number for s in result.stages if s.status == "fitted"} == set(range(1, 8))


def test_recovery_free_rolling_sign(recovery):
    _, _, _, result, _ = recovery
    fr = result.free_rolling
    assert len(fr) == 18  # 3 loads x 3 cambers x 2 pressures
    neg = fr["measured"] < 0
    assert (fr.loc[neg, "fitted"] <= 0).all()
    assert fr["sign_ok"].all()
