"""Issue 7: a reduced `mftire demo` (smaller grids) runs the whole loop in CI."""

from __future__ import annotations

import base64
import json
import re

from mftire import load


def test_reduced_demo_runs_the_whole_loop(quick_demo):
    out, stdout, stderr = quick_demo  # `mftire demo --quick`, run once for the session (tests/conftest.py)
    # progress goes to stderr, and only on a terminal (tests/test_progress.py)
    assert "[9/9" not in stdout + stderr
    # the closing summary on stdout: held-out errors before and after, the cause, the band coverage, the run time
    tail = stdout[stdout.index("done in "):]
    assert "done: local/report.html" in tail
    assert re.search(r"held-out Vx = \d+ km/h", tail) and re.search(r"Fx: \d+\.\d\d % -> \d+\.\d\d %", tail)
    assert "cause: Vs" in tail and "prediction band, held-out points inside: Fx " in tail
    assert "cross-validated over sweeps (measured): Fx " in tail and "rig run: cause TS" in tail
    for name in ("fitted.tir", "extended.tir", "tyre.fmu", "report.html", "report.json", "headline.png",
                 "fe_sweeps.csv", "measured_sweeps.csv", "diagnosis/diagnosis.json", "rig_sweeps.csv",
                 "rig_fitted.tir", "rig_run.png", "rig_diagnosis/diagnosis.json", "rig_diagnosis/extended.tir"):
        assert (out / name).exists(), name
    html = (out / "report.html").read_text()
    images = re.findall(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', html)
    assert len(images) >= 5
    assert base64.b64decode(images[0])[:4] == b"\x89PNG"
    for section in ("Summary", "Fit", "Curve comparison", "Diagnosis", "Uncertainty", "Outputs"):
        assert section in html
    doc = json.loads((out / "report.json").read_text())
    s = doc["numbers"]["summary"]
    assert s["cause"] == "Vs"
    assert s["heldout_Fx_rms_pct_after"] <= 0.5 * s["heldout_Fx_rms_pct_before"]
    assert 0.8 <= s["heldout_inside_prediction_band"] <= 1.0
    for ch in ("Fx", "Fy", "Mz", "Mx", "My"):  # per channel: held-out points and the cross-validated coverage
        assert 0.8 <= s[f"heldout_{ch}_inside_prediction_band"] <= 1.0
        assert 0.8 <= s[f"cv_{ch}_inside_prediction_band"] <= 1.0
    assert "band_cv_coverage" in doc["tables"]
    # the FE source has many sweeps: its cross-validated coverage is near the nominal 95 % on every channel
    # (quick run: 90.7-97.4 %; the full demo's figures are in validation/README.md)
    fe_cv = [r for r in doc["tables"]["band_cv_coverage"] if r["source"] == "fe"]
    assert len(fe_cv) == 5 and all(abs(r["inside_prediction"] - 0.95) <= 0.06 for r in fe_cv), fe_cv
    # every table of the page is in the JSON
    assert {"fit_stages", "diagnosis_ranking", "band_coverage"} <= set(doc["tables"])
    # the third source: the simulated raw rig run, imported, fitted and diagnosed (issue 12)
    assert "Third source: raw rig time series (SIMULATED)" in html
    rig = doc["numbers"]["rig"]
    assert rig["data"].startswith("SIMULATED") and rig["raw_rows"] == 54400 and rig["sweeps_imported"] == 400
    assert rig["cause"] in ("TSTI", "TSTC", "TSTO")  # a tread surface temperature
    assert rig["effect"].startswith("friction_")
    for ch in ("Fx", "Fy"):  # held-out load: at least half the error removed, under 1 % of peak after
        assert rig[f"heldout_{ch}_cut"] >= 0.5, (ch, rig)
        assert rig[f"heldout_{ch}_rms_pct_after"] < 1.0 < rig[f"heldout_{ch}_rms_pct_before"], (ch, rig)
    assert s["rig"]["cause"] == rig["cause"]
    assert {"rig_import_dropped", "rig_fit_stages", "rig_diagnosis_ranking", "rig_heldout"} <= set(doc["tables"])
    # the thermal tyre (issue 22): the rig fit made thermal on the thermal run's first part, its stint replayed
    assert "thermal stint (held out, " in tail
    for name in ("thermal.tir", "thermal_replay.csv", "thermal_stint.png"):
        assert (out / name).exists(), name
    th = doc["numbers"]["thermal"]
    assert th["data"].startswith("SIMULATED") and th["tir"].startswith("rig_fitted.tir")
    assert th["surface_rms_K"] < 3.0 and s["thermal"]["surface_rms_K"] == th["surface_rms_K"]
    for ch in ("Fx", "Fy"):  # the force errors include the rig fit's own: the thermal replay still beats isothermal
        assert th[f"thermal_{ch}_rms_N"] < th[f"isothermal_{ch}_rms_N"], (ch, th)
    assert {"thermal_heldout", "thermal_parameters", "thermal_laws"} <= set(doc["tables"])
    ext = load(out / "extended.tir")
    assert ext.extensions and ext.required_variables == []
