"""FE surrogate: property tests (symmetry, monotonicity, sign conventions)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from mftire.fe.config import TyreConfig
from mftire.fe.rolling_contact import solve
from mftire.fe.slip_sweeps import free_rolling

BASE = TyreConfig()
LI = BASE.load_index_load
PN = BASE.size.nominal_pressure
SYMMETRIC = BASE.updated({"patch.groove_centres": (-0.04, 0.0, 0.04), "carcass.plysteer": 0.0})


@settings(max_examples=12, deadline=None)
@given(
    alpha_deg=st.floats(0.5, 12.0),
    kappa=st.floats(-0.6, 0.0),
    load=st.sampled_from([0.4, 0.8, 1.2]),
)
def test_symmetric_tread_gives_mirror_symmetric_forces(alpha_deg, kappa, load):
    fz, v = load * LI, 16.0
    a = np.deg2rad(alpha_deg)
    omega = v / 0.31 * (1.0 + kappa)
    r = solve(SYMMETRIC, fz, v, PN, omega, np.array([a, -a]))
    assert np.isclose(r.Fy[0], -r.Fy[1], rtol=1e-6, atol=1.0)
    assert np.isclose(r.Mz[0], -r.Mz[1], rtol=1e-5, atol=0.05)
    assert np.isclose(r.Fx[0], r.Fx[1], rtol=1e-6, atol=1.0)
    assert r.Fy[0] < 0  # ISO: alpha > 0 gives Fy < 0


@settings(max_examples=8, deadline=None)
@given(load=st.floats(0.4, 1.2), speed=st.floats(6.0, 28.0), dp=st.floats(-0.5e5, 0.5e5))
def test_braking_force_monotone_in_slip_before_peak(load, speed, dp):
    fz, p = load * LI, PN + dp
    omega_free, _ = free_rolling(BASE, fz, speed, p)
    kappa = -np.linspace(0.0, 0.5, 41)
    fx = solve(BASE, fz, speed, p, omega_free[0] * (1.0 + kappa)).Fx
    i_pk = int(np.argmax(-fx))
    assert 0.06 <= -kappa[i_pk] <= 0.22
    assert np.all(np.diff(-fx[: i_pk + 1]) > 0)  # |Fx| grows monotonically up to the peak
    assert fx[0] < 0  # free rolling: rolling resistance, Fx slightly negative
    # driving: kappa > 0 gives Fx > 0
    assert solve(BASE, fz, speed, p, omega_free[0] * 1.05).Fx[0] > 0


def test_camber_thrust_sign_and_spin():
    r = solve(BASE, 0.8 * LI, 16.7, PN, 16.7 / 0.31, 0.0, np.deg2rad([-3.0, 3.0]))
    assert r.Fy[1] < 0 < r.Fy[0]  # ISO: positive camber (top to the right) pushes to -y
