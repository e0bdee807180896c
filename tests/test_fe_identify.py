"""FE surrogate: chapter-5 identification of the velocity part of the friction law."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from mftire.errors import MftireInputError
from mftire.fe.config import load_tyre
from mftire.fe.friction import h_from_mu_lock, mu_m_of_speed, mu_v_of_kappa
from mftire.fe.friction_identify import identify_velocity_law
from mftire.fe.slip_sweeps import KMH, sweep

SPEEDS = np.array([20.0, 40.0, 60.0, 80.0, 100.0]) * KMH


def _synthetic(mu_p=1.3, mu_lock=0.7, kappa_max=0.05):
    """Global braking curves that follow eq 5.5 exactly (mu_m linear, mu_s quadratic in Vx)."""
    rows = []
    k = -np.linspace(0.0, 1.0, 81)
    for v in SPEEDS:
        mu_m, mu_s = 1.05 - 0.002 * v, 0.62 - 1e-4 * v**2
        h = h_from_mu_lock(mu_s, mu_m, mu_lock, kappa_max)
        fx = -4800.0 * mu_p * mu_v_of_kappa(k, mu_s, mu_m, h, kappa_max)
        rows.append(pd.DataFrame({"Fz": 4800.0, "kappa": k, "alpha": 0.0, "Vx": v, "Fx": fx}))
    return pd.concat(rows, ignore_index=True)


def test_recovers_exact_parameters_from_eq_5_5_curves():
    res = identify_velocity_law(_synthetic(), mu_p=1.3)
    assert res.mu_lock == pytest.approx(0.7, abs=1e-6)
    assert res.a1 == pytest.approx(-0.002, abs=2e-5) and res.a2 == pytest.approx(1.05, abs=5e-4)
    assert res.a3 == pytest.approx(-1e-4, abs=3e-6)
    assert res.a5 == pytest.approx(0.62, abs=3e-3)
    np.testing.assert_allclose(res.per_speed["mu_s"], 0.62 - 1e-4 * SPEEDS**2, atol=2e-3)
    assert "[friction]" in res.to_toml() and "mu_lock" in res.to_toml()


def test_identification_on_surrogate_braking_curves():
    tyre = load_tyre("default")
    li = tyre.load_index_load
    data = sweep(tyre, "braking", 0.8 * li, SPEEDS, tyre.size.nominal_pressure, n_kappa=30)
    res = identify_velocity_law(data, tyre)
    assert 1.1 < res.mu_p < 1.5  # global pressure part of the default tyre
    per = res.per_speed
    assert (per["mu_s"] > 0).all() and (per["mu_s"] < res.mu_lock).all() and (per["mu_m"] > res.mu_lock).all()
    # mu_m from global curves lands within 3 % of the local law's mu_m (thesis 5.4)
    truth = mu_m_of_speed(per["Vx"], *tyre.friction.mu_m)
    np.testing.assert_allclose(per["mu_m"], truth, rtol=0.03)
    assert res.a1 < 0  # mu_m falls with speed, as in the tyre
    # re-simulating with the identified law reproduces the curves (peak within 2 %)
    t2 = tyre.updated({"friction.mu_m": (res.a1, res.a2), "friction.mu_s": (res.a3, res.a4, res.a5),
                       "friction.mu_lock": res.mu_lock})
    again = sweep(t2, "braking", 0.8 * li, SPEEDS[[0, 4]], tyre.size.nominal_pressure, n_kappa=30)
    for v in SPEEDS[[0, 4]]:
        a = again[np.isclose(again["Vx"], v)]["Fx"].min()
        b = data[np.isclose(data["Vx"], v)]["Fx"].min()
        assert a == pytest.approx(b, rel=0.02)


def test_identify_input_errors():
    df = _synthetic()
    with pytest.raises(MftireInputError, match=">= 3 speeds"):
        identify_velocity_law(df[df["Vx"] < 12], mu_p=1.3)
    with pytest.raises(MftireInputError, match="lacks column"):
        identify_velocity_law(df.drop(columns="Fx"), mu_p=1.3)
    with pytest.raises(MftireInputError, match="wheel lock"):
        identify_velocity_law(df[df["kappa"] > -0.5], mu_p=1.3)
