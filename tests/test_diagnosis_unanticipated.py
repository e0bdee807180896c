"""Issue 11: effects nobody anticipated, on the reduced simulated campaigns of
validation/data/unanticipated_reduced/ (made by validation/make_unanticipated_campaigns.py).

For each case with an effect: the right variable ranks first, the right scaling-factor
family is named, and the held-out Fx+Fy RMS (a condition not used in any fit, from
``expected.json``) is cut by at least 60 %.  For each null case: no finding.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from mftire import load
from mftire.diagnosis.diagnose import diagnose
from mftire.diagnosis.effects import FAMILY_TARGETS

DATA = Path(__file__).resolve().parents[1] / "validation" / "data" / "unanticipated_reduced"
CASES = sorted(p.name for p in DATA.iterdir() if (p / "expected.json").exists())
#: Cases whose reduced copy holds too little evidence for the ranking's corrected significance test: the
#: fade with loads in blocks has 300 rows there, and its time, sequence and friction-work candidates explain
#: ~30 % of the residual at an uncorrected p of 0.03-0.1, which the correction over the candidates tested does
#: not pass.  Its full campaign is used (9 s).
FULL = {"fade_blocked_load"}


def _folder(case: str) -> Path:
    return DATA.parent / "unanticipated" / case if case in FULL else DATA / case


def _run(case: str):
    d = _folder(case)
    exp = json.loads((d / "expected.json").read_text())
    h = exp["holdout"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = diagnose(pd.read_csv(d / "sweeps.csv"), load(d / "fitted.tir"), holdout=(h["column"], h["values"]),
                       n_perm=49, progress=False)  # fmt: skip
    return exp, res


def _cut(res) -> float:
    ssb = sum(c.rms_before**2 * c.n for c in res.errors if c.channel in ("Fx", "Fy"))
    ssa = sum(c.rms_after**2 * c.n for c in res.errors if c.channel in ("Fx", "Fy"))
    return 1.0 - float(np.sqrt(ssa / ssb))


@pytest.mark.parametrize("case", CASES)
def test_unanticipated_campaign(case):
    exp, res = _run(case)
    if not exp["effect"]:
        assert not res.significant, res.summary()
        assert res.extended is None
        return
    assert res.significant, res.messages
    assert res.ranking[0].variable == exp["variable"], [r.variable for r in res.ranking[:3]]
    expected = set(exp.get("scaling_factors") or ())
    family = exp.get("family")
    if family in FAMILY_TARGETS:
        expected |= {t for ts in FAMILY_TARGETS[family].values() for t in ts}
    assert set(res.effect.targets) & expected, (res.effect.name, res.effect.targets, expected)
    # a held-out level beyond the range the law was fitted on: in modes 1xx the law is clamped to that range
    # (issue 21, as MF clamps its inputs), so it predicts the edge of the range there, not an extrapolation
    h = exp["holdout"]
    train = pd.read_csv(_folder(case) / "sweeps.csv")
    train = train[~np.isin(train[h["column"]], h["values"])] if h["column"] == exp["variable"] else None
    beyond = train is not None and (min(h["values"]) > train[h["column"]].max()
                                    or max(h["values"]) < train[h["column"]].min())  # fmt: skip
    assert _cut(res) >= (0.5 if beyond else 0.6), [(c.channel, c.rms_pct_before, c.rms_pct_after) for c in res.errors]
    for name in exp.get("confounded_with", ()):  # said, with what the within-block variation supports
        assert any(name in note for note in res.confounding), res.confounding


def test_all_zero_channel_is_not_measured():
    d = DATA / "zero_channel_with_effect"
    df = pd.read_csv(d / "sweeps.csv")
    assert (df["Mx"] == 0).all()
    from mftire.diagnosis.candidates import with_sweeps
    from mftire.diagnosis.diagnose import measured_channels

    chans, out = measured_channels(with_sweeps(df), ("Fx", "Fy", "Mz", "Mx", "My"))
    assert "Mx" not in chans and out["Mx"] == "not measured: all zeros"
    assert {"Fx", "Fy"} <= set(chans)
