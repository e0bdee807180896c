"""Issue 7: a reduced `mftire demo` (smaller grids) runs the whole loop in CI."""

from __future__ import annotations

import base64
import json
import re

from mftire import load
from mftire.cli import main


def test_reduced_demo_runs_the_whole_loop(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "--output", str(out), "--quick"]) == 0
    printed = capsys.readouterr().out
    assert "[8/8" in printed  # progress shown step by step
    for name in ("fitted.tir", "extended.tir", "tyre.fmu", "report.html", "report.json", "headline.png",
                 "fe_sweeps.csv", "measured_sweeps.csv", "diagnosis/diagnosis.json"):
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
    # every table of the page is in the JSON
    assert {"fit_stages", "diagnosis_ranking", "band_coverage"} <= set(doc["tables"])
    ext = load(out / "extended.tir")
    assert ext.extensions and ext.required_variables == []
