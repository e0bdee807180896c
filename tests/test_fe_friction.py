"""FE surrogate: the van der Steen friction law (eqs 2.46, 5.2, 5.5-5.8, 5.10, 5.12)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mftire.fe.config import FrictionParams
from mftire.fe.friction import (
    friction_coefficient,
    h_from_mu_lock,
    mu_v_of_kappa,
    pressure_factor,
    regularised_shear,
    velocity_factor,
    velocity_law,
)


def test_pressure_factor_limits_and_values():
    # thesis Fig. 2.14 demo values: p0 = 0.5 MPa, k = 0.5, plimit = 0.2 MPa
    assert pressure_factor(0.5e6, 0.5e6, 0.5, 0.2e6) == pytest.approx(1.0)
    assert pressure_factor(1.0e6, 0.5e6, 0.5, 0.2e6) == pytest.approx(0.7071, abs=1e-4)
    assert pressure_factor(0.2e6, 0.5e6, 0.5, 0.2e6) == pytest.approx(1.5811, abs=1e-4)
    assert pressure_factor(0.0, 0.5e6, 0.5, 0.2e6) == pressure_factor(0.2e6, 0.5e6, 0.5, 0.2e6)


def test_velocity_factor_shape():
    mu_s, mu_m, h, vmax = 0.2, 1.1, 0.5, 0.695  # thesis Table 2.2
    assert velocity_factor(vmax, mu_s, mu_m, h, vmax) == pytest.approx(mu_m)
    assert velocity_factor(0.0, mu_s, mu_m, h, vmax) == pytest.approx(mu_s, abs=1e-6)
    assert velocity_factor(1e9, mu_s, mu_m, h, vmax) == pytest.approx(mu_s, abs=1e-3)
    v = np.geomspace(1e-3, 100.0, 200)
    mu = velocity_factor(v, mu_s, mu_m, h, vmax)
    assert np.all((mu >= mu_s) & (mu <= mu_m + 1e-12))


@settings(max_examples=60, deadline=None)
@given(
    mu_s=st.floats(0.05, 0.6),
    gap_lock=st.floats(0.02, 0.3),
    gap_m=st.floats(0.02, 0.5),
    kappa_max=st.floats(0.01, 0.1),
)
def test_h_from_mu_lock_reproduces_mu_lock_at_full_slip(mu_s, gap_lock, gap_m, kappa_max):
    mu_lock = mu_s + gap_lock
    mu_m = mu_lock + gap_m
    h = h_from_mu_lock(mu_s, mu_m, mu_lock, kappa_max)  # eq 5.8
    assert mu_v_of_kappa(1.0, mu_s, mu_m, h, kappa_max) == pytest.approx(mu_lock, rel=1e-9)  # eq 5.7
    assert mu_v_of_kappa(kappa_max, mu_s, mu_m, h, kappa_max) == pytest.approx(mu_m, rel=1e-12)


def test_speed_dependence_and_regularisation():
    f = FrictionParams(mu_m=(-0.002, 1.05), mu_s=(-1e-4, 0.0, 0.62), h=None, mu_lock=0.72)
    law = velocity_law(f, np.array([5.0, 25.0]))
    np.testing.assert_allclose(law.mu_m, [1.04, 1.0])  # eq 5.10
    np.testing.assert_allclose(law.mu_s, [0.6175, 0.5575])  # eq 5.12
    np.testing.assert_allclose(law.v_max, [0.25, 1.25])  # eq 5.13
    np.testing.assert_allclose(law.gamma_crit, [0.05, 0.25])
    # at the locked wheel (v = Vx) every speed gives mu_v = mu_lock (eq 5.7)
    mu_lock_check = velocity_factor(np.array([5.0, 25.0]), law.mu_s, law.mu_m, law.h, law.v_max)
    np.testing.assert_allclose(mu_lock_check, 0.72)
    # regularised shear (eqs 2.47-2.49): linear below gamma_crit, mu p above
    p = 0.4e6
    tau_small = regularised_shear(p, 0.01, 10.0, f)
    mu_small = friction_coefficient(p, 0.01, 10.0, f)
    assert tau_small == pytest.approx(mu_small * p * 0.01 / 0.1)
    assert regularised_shear(p, 2.0, 10.0, f) == pytest.approx(friction_coefficient(p, 2.0, 10.0, f) * p)
