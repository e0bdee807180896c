"""FE surrogate: the `mftire fe` command line (sweep, campaign --quick, identify)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from mftire.cli import main
from mftire.fe.slip_sweeps import FREE_ROLLING_COLUMNS, SWEEP_COLUMNS


@pytest.fixture(scope="module")
def quick_campaign(tmp_path_factory):
    out = tmp_path_factory.mktemp("campaign")
    assert main(["fe", "campaign", "--output", str(out), "--quick"]) == 0
    return out


def test_campaign_quick_writes_schema_tables(quick_campaign):
    sweeps = pd.read_csv(quick_campaign / "sweeps.csv")
    free = pd.read_csv(quick_campaign / "free_rolling.csv")
    assert list(sweeps.columns) == SWEEP_COLUMNS + ["kind", "load_fraction"]
    assert list(free.columns) == FREE_ROLLING_COLUMNS
    assert set(sweeps["kind"]) == {"braking", "cornering", "combined"}
    np.testing.assert_allclose(sorted(sweeps["load_fraction"].round(6).unique()), [0.4, 0.8, 1.2])
    assert sweeps[SWEEP_COLUMNS].notna().all().all()
    assert sweeps["kappa"].between(-1, 0).all() and (sweeps["alpha"].abs() <= np.deg2rad(12) + 1e-12).all()
    assert sweeps["P"].nunique() == 3 and sweeps["Vx"].nunique() == 3
    assert (free["re"].between(0.30, 0.32)).all()
    np.testing.assert_allclose(free["omega"] * free["re"], free["Vx"])
    assert not list(quick_campaign.glob(".*tmp"))  # atomic writes leave no temp files


def test_sweep_command(tmp_path, capsys):
    out = tmp_path / "s.csv"
    rc = main(["fe", "sweep", "--kind", "cornering", "--load-fraction", "0.8", "--kmh", "60",
               "--points", "9", "--output", str(out)])
    assert rc == 0
    df = pd.read_csv(out)
    assert list(df.columns) == SWEEP_COLUMNS and len(df) == 9
    np.testing.assert_allclose(np.rad2deg(df["alpha"]), np.linspace(-12, 12, 9))
    assert "wrote 9 rows" in capsys.readouterr().out


def test_user_errors_exit_2(tmp_path, capsys):
    rc = main(["fe", "sweep", "--kind", "braking", "--Fz", "50000", "--Vx", "10", "--output", str(tmp_path / "x.csv")])
    assert rc == 2
    err = capsys.readouterr().err
    assert "exceeds the model's range" in err and err.count("\n") == 1
    bad = tmp_path / "bad.toml"
    bad.write_text("[carcass]\ncpsi = -1\n")
    rc = main(["fe", "sweep", "--tyre", str(bad), "--kind", "braking", "--Fz", "4000", "--Vx", "10",
               "--output", str(tmp_path / "x.csv")])
    assert rc == 2 and "carcass.cpsi" in capsys.readouterr().err
    rc = main(["fe", "identify", str(tmp_path / "missing.csv")])
    assert rc == 2


def test_identify_command(quick_campaign, tmp_path, capsys):
    out = tmp_path / "friction.json"
    rc = main(["fe", "identify", str(quick_campaign / "sweeps.csv"), "--load-fraction", "0.8",
               "--output", str(out)])
    assert rc == 0
    assert "[friction]" not in capsys.readouterr().out  # JSON requested
    d = json.loads(out.read_text())
    fr = d["friction"]
    assert len(fr["mu_m"]) == 2 and len(fr["mu_s"]) == 3 and fr["kappa_max"] == 0.05
    per = pd.DataFrame(d["per_speed"])
    assert len(per) == 3
    assert (per["mu_s"] < fr["mu_lock"]).all() and (per["mu_m"] > fr["mu_lock"]).all()
