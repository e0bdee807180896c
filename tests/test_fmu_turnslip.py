"""Turn-slip mode 112 in C and Python: the same numbers on a grid of edge cases.

Zero camber with a tyre whose camber-torque coefficients vanish (MF 5.2 files) makes
the spin-moment ratio of the residual torque infinite; both evaluators take the
documented limit (aligning.py, "MFeval departure") and stay finite.
"""

from __future__ import annotations

import itertools
import warnings

import numpy as np
import pytest
from conftest import REFERENCE_TYRES, needs_c_compiler

from mftire import load
from mftire.fmu.export import export_fmu

pytestmark = needs_c_compiler


@pytest.mark.parametrize("name", ["MF52", "MF61", "MF62"])
def test_mode_112_edge_grid_agrees_and_is_finite(name, tmp_path):
    from mftire.fmu.host import FMUTyre

    tyre = load(REFERENCE_TYRES[name])
    F0 = tyre["FNOMIN"]
    path = export_fmu(tyre, tmp_path / "t.fmu")
    grid = itertools.product([1.0, F0, 2 * F0], [-1.0, 0.0, 0.3], [0.0, 0.2, -0.5], [0.0, 0.1], [0.0, 0.5, -2.0],
                             [1e-9, -0.5, 5.0, -20.0], [0.0, 50.0])  # fmt: skip
    n = 0
    with FMUTyre(str(path), "ME", start_values={"useMode": 112}) as fmu, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for Fz, k, a, g, phit, Vx, om in grid:
            got = fmu.evaluate(Fz, k, a, g, phit, Vx, None, om)
            ref = tyre.evaluate(Fz, k, a, g, phit, Vx, None, None if om == 0 else om, mode=112)
            for ch in ("Fx", "Fy", "Mz", "Mx", "My"):
                r = float(ref[ch])
                assert np.isfinite(r) and np.isfinite(got[ch]), (ch, Fz, k, a, g, phit, Vx, om)
                assert got[ch] == pytest.approx(r, rel=1e-9, abs=1e-9 * F0), (ch, Fz, k, a, g, phit, Vx, om)
            n += 1
    assert n == 3 * 3 * 3 * 2 * 3 * 4 * 2
