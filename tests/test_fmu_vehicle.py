"""The vehicle-dynamics example (validation/vehicle_example.py), shortened: four FMU
instances through fmpy and the Python evaluator give the same trajectory."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
from conftest import needs_c_compiler

ROOT = Path(__file__).resolve().parents[1]




@needs_c_compiler
def test_vehicle_example_short(tmp_path):
    spec = importlib.util.spec_from_file_location("vehicle_example", ROOT / "validation" / "vehicle_example.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules["vehicle_example"] = mod  # dataclasses look their module up
    spec.loader.exec_module(mod)
    png = tmp_path / "vehicle.png"
    res = mod.run(output=png, short=True)
    assert png.stat().st_size > 10_000
    fmu, py = res["fmu"], res["python"]
    assert len(fmu["t"]) == len(py["t"]) == 501
    # braking then a left step steer actually happened, identically in both runs
    assert fmu["vx"][-1] < 25.0 - 2.0
    assert fmu["r"][-1] > 0.05
    for k in ("vx", "vy", "r", "x", "y"):
        np.testing.assert_allclose(fmu[k], py[k], rtol=1e-9, atol=1e-9)
    assert max(res["max_diff"].values()) < 1e-9
