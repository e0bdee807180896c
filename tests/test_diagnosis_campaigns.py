"""Issue 6 'done when': the shipped simulated campaigns (validation/data/).

For each campaign with an effect, ``mftire diagnose`` must name the right cause first
and the added effect must cut the held-out RMS error of the channel the effect
dominates (Fx in these campaigns) by at least 50 %; the null campaign must produce no
finding.  The extended model must round-trip through .tir and a plain MF reader must
still read it.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import needs_c_compiler

from mftire import load, read_tir
from mftire.cli import main
from mftire.mf.extensions import SECTION

# the campaigns reach beyond the .tir's ranges (pressure below PRESMIN, Ex clipped at the largest slips):
# the evaluator's limit warnings are expected here
pytestmark = pytest.mark.filterwarnings("ignore::mftire.mf.inputs.MFLimitWarning")
DATA = Path(__file__).resolve().parents[1] / "validation" / "data"
CASES = {
    # (causes accepted first, laws accepted): slip-speed friction in FE data shows as friction against the
    # sliding speed Vs or, sweep by sweep, against the forward speed Vx of each braking sweep
    "slip_speed": ({"Vs", "Vx"}, {"slip_speed_friction", "slip_speed_quadratic", "speed_friction"}),
    "fade": ({"energy", "time", "sequence", "run"}, {"friction_fade", "friction_variable",
                                                     "friction_variable_quadratic"}),
    "pressure": ({"P"}, {"pressure"}),
}


def _diagnose(name: str, out: Path) -> dict:
    folder = DATA / name
    assert main(["diagnose", str(folder / "sweeps.csv"), "--tir", str(folder / "fitted.tir"),
                 "--output", str(out)]) == 0  # fmt: skip
    return json.loads((out / "diagnosis.json").read_text())


@pytest.fixture(scope="module")
def diagnosed(tmp_path_factory):
    """``mftire diagnose`` of each shipped campaign, run once for the module: name -> (its output folder,
    its diagnosis.json).  The tests read the folder and write only into their own tmp_path."""
    done: dict[str, tuple[Path, dict]] = {}

    def get(name: str) -> tuple[Path, dict]:
        if name not in done:
            out = tmp_path_factory.mktemp(f"diagnose_{name}")
            done[name] = (out, _diagnose(name, out))
        return done[name]

    return get


@pytest.mark.parametrize("name", sorted(CASES))
def test_campaign_cause_and_heldout_improvement(name, diagnosed):
    causes, effects = CASES[name]
    _, doc = diagnosed(name)
    assert doc["significant"] is True
    assert doc["ranking"][0]["variable"] in causes, doc["ranking"][:3]
    assert doc["effect"]["name"] in effects
    assert doc["effect"]["physical"] is True
    fx = doc["holdout"]["channels"]["Fx"]
    assert fx["rms_after"] <= 0.5 * fx["rms_before"], fx
    # no force channel gets materially worse on the held-out condition
    for ch in ("Fx", "Fy"):
        if ch in doc["holdout"]["channels"]:
            c = doc["holdout"]["channels"][ch]
            assert c["rms_after"] <= 1.05 * c["rms_before"], (ch, c)
    assert doc["holdout"]["n_rows"] > 0


def test_null_campaign_has_no_finding(tmp_path):
    doc = _diagnose("null", tmp_path)
    assert doc["significant"] is False
    assert doc["effect"] is None and doc["extended_tir"] is None
    assert not (tmp_path / "extended.tir").exists()


def test_extended_model_round_trips_and_reads_plainly(diagnosed, tmp_path):
    folder, doc = diagnosed("fade")
    path = folder / doc["extended_tir"]
    params = read_tir(path)
    again = tmp_path / "again.tir"
    from mftire import write_tir

    write_tir(params, again)
    assert read_tir(again) == params
    assert SECTION in params.sections
    # a plain reader: key = value lines, '$' comments; every MF key of the fitted file is there unchanged
    plain = {}
    for line in path.read_text().splitlines():
        line = line.split("$")[0].strip()
        if "=" in line and not line.startswith("["):
            k, v = (s.strip() for s in line.split("=", 1))
            plain[k] = v
    fitted = load(DATA / "fade" / "fitted.tir")
    for k in ("PCX1", "PKY1", "QSX3", "FNOMIN", "UNLOADED_RADIUS"):
        assert float(plain[k]) == pytest.approx(fitted[k], rel=0, abs=0) or k in doc["effect"]["refitted_coefficients"]
    tyre = load(path)
    variable = doc["effect"]["variable"]
    out = tyre.evaluate(4000.0, -0.2, 0.0, **({variable: 1e5} if variable in tyre.required_variables else {}))
    assert np.isfinite(out["Fx"])


@needs_c_compiler
@pytest.mark.parametrize("name", sorted(CASES))
def test_diagnosed_tir_evaluates_everywhere_on_the_data_columns(name, diagnosed, tmp_path):
    """Every .tir diagnose writes evaluates with `mftire evaluate`, `mftire compare` and the FMU on
    the columns of the data it was diagnosed on (closed variables), and the FMU agrees with Python."""
    import pandas as pd

    folder, doc = diagnosed(name)
    ext_path = folder / doc["extended_tir"]
    sweeps = DATA / name / "sweeps.csv"
    assert main(["evaluate", str(ext_path), "--input", str(sweeps), "--output", str(tmp_path / "ev.csv")]) == 0
    assert main(["compare", "--tir", str(ext_path), "--data", str(sweeps), "--output", str(tmp_path / "cmp"),
                 "--no-plots"]) == 0  # fmt: skip
    tyre = load(ext_path)
    data = pd.read_csv(sweeps)
    assert set(tyre.required_variables) <= set(data.columns)
    from mftire.fmu.export import export_fmu
    from mftire.fmu.host import FMUTyre

    rows = data.iloc[:: max(1, len(data) // 40)]
    fmu = export_fmu(tyre, tmp_path / "ext.fmu")
    with FMUTyre(str(fmu), "ME") as f:
        for _, r in rows.iterrows():
            extra = {v: float(r[v]) for v in tyre.required_variables}
            got = f.evaluate(r["Fz"], r["kappa"], r["alpha"], r["gamma"], 0.0, r["Vx"], r["P"], **extra)
            ref = tyre.evaluate(r["Fz"], r["kappa"], r["alpha"], r["gamma"], 0.0, r["Vx"], r["P"], **extra)
            for ch in ("Fx", "Fy", "Mz", "Mx", "My"):
                assert got[ch] == pytest.approx(float(ref[ch]), rel=1e-9, abs=1e-9 * tyre["FNOMIN"]), ch
