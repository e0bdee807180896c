"""A second FMU importer (issue 23): the Open Simulation Platform's libcosim (``libcosimpy``).

When ``libcosimpy`` is installed (a test extra on Linux x86_64, Python >= 3.11), the steady-state FMU in
libcosim gives ``Tyre.evaluate``'s numbers, and the quarter-car stop with the wheel locked at 10 ms steps
through libcosim equals the one through fmpy (to rounding: libcosim's steps are integer nanoseconds).
Skipped where libcosimpy does not install (fmpy is the importer of every other test).
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import REFERENCE_TYRES, needs_c_compiler

pytestmark = [needs_c_compiler, pytest.mark.filterwarnings("ignore")]
cosim = pytest.importorskip("libcosimpy.CosimExecution", reason="libcosimpy not installed")

ROOT = Path(__file__).resolve().parents[1]
TIR = REFERENCE_TYRES["JuliaMF61"]


@pytest.fixture(scope="module", autouse=True)
def quiet():
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level

    log_output_level(CosimLogLevel.ERROR)


def _quarter_car():
    spec = importlib.util.spec_from_file_location("quarter_car", ROOT / "validation" / "quarter_car.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules["quarter_car"] = mod
    spec.loader.exec_module(mod)
    return mod


def test_steady_fmu_in_libcosim_equals_the_evaluator(tmp_path):
    import fmpy
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    from mftire.fmu.export import export_fmu
    from mftire.tyre import load

    fmu = str(export_fmu(TIR, tmp_path / "steady.fmu"))
    vr = {v.name: v.valueReference for v in fmpy.read_model_description(fmu).modelVariables}
    ex = CosimExecution.from_step_size(step_size=int(1e6))
    i = ex.add_local_slave(local_slave=CosimLocalSlave(fmu_path=fmu, instance_name="tyre"))
    man, obs = CosimManipulator.create_override(), CosimObserver.create_last_value()
    ex.add_manipulator(manipulator=man)
    ex.add_observer(observer=obs)
    tyre = load(TIR)
    rng = np.random.default_rng(4)
    names = ("Fz", "kappa", "alpha", "gamma", "Vx")
    for _ in range(20):
        x = (rng.uniform(1000, 8000), rng.uniform(-0.3, 0.3), rng.uniform(-0.2, 0.2), rng.uniform(-0.05, 0.05),
             rng.uniform(5, 40))  # fmt: skip
        man.slave_real_values(i, [vr[k] for k in names], list(x))
        ex.step()
        got = obs.last_real_values(i, [vr[k] for k in ("Fx", "Fy", "Mz")])
        ref = tyre.evaluate(x[0], x[1], x[2], x[3], Vx=x[4])
        np.testing.assert_allclose(got, [float(ref[k]) for k in ("Fx", "Fy", "Mz")], rtol=1e-9, atol=1e-9)
    ex.stop()


def test_quarter_car_in_libcosim_equals_fmpy(tmp_path):
    from mftire.tyre import load

    qc = _quarter_car()
    tyre = load(TIR)
    fmu = qc.export(TIR, tmp_path)
    car = qc.QuarterCar(t_end=8.0)
    Re0 = qc.free_rolling_radius(tyre, car.m * car.g, car.V0)
    runs = []
    for block in (qc.CosimTyre(fmu, 0.01), qc.FMUTyre(fmu)):
        try:
            runs.append(qc.run(block, car, 3000.0, 0.01, Re0))
        finally:
            block.close()
    # libcosim passes the step as integer nanoseconds: H differs from fmpy's by an ulp
    before = runs[1]["V"] > 3.0
    np.testing.assert_allclose(runs[0]["x"][before], runs[1]["x"][before], rtol=1e-12, atol=1e-9)
    for r in runs:
        m = qc.metrics(r)
        assert m["locked"] and m["travel"] < 0.025 and m["drift"] < 1e-3
