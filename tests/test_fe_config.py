"""FE surrogate: tyre file loading and validation (clear errors naming the parameter)."""

from __future__ import annotations

import numpy as np
import pytest

from mftire.errors import MftireInputError
from mftire.fe.config import TyreConfig, check_operating_range, default_tyre_path, load_tyre


def test_default_tyre_file_matches_builtin_defaults():
    tyre = load_tyre("default")
    builtin = TyreConfig()
    for section in ("size", "vertical", "patch", "carcass", "tread", "friction", "rolling_resistance", "grid"):
        assert getattr(tyre, section) == getattr(builtin, section), section
    assert default_tyre_path().name == "default_tyre.toml"
    # 205/55 R16 91: R0 = 8 in + 112.75 mm, LI 91 = 615 kg
    assert tyre.unloaded_radius == pytest.approx(0.31595, abs=1e-5)
    assert tyre.load_index_load == pytest.approx(615 * 9.80665)
    assert tyre.grid.nx >= 40 and tyre.grid.ny >= 15


@pytest.mark.parametrize(
    ("change", "name"),
    [
        ({"tread.kx": -1e7}, "tread.kx"),
        ({"carcass.cy": 0.0}, "carcass.cy"),
        ({"vertical.cz0": -5.0}, "vertical.cz0"),
        ({"friction.mu_m": (0.0, 0.5)}, "friction.mu_m"),
        ({"friction.k": 1.5}, "friction.k"),
        ({"friction.mu_lock": 2.0}, "friction.mu_lock"),
    ],
)
def test_bad_values_name_the_parameter(change, name):
    with pytest.raises(MftireInputError, match=name.replace(".", r"\.")):
        TyreConfig().updated(change)


def test_mu_m_below_mu_s_is_rejected_with_explanation():
    with pytest.raises(MftireInputError, match=r"mu_m.*<.*mu_s"):
        TyreConfig().updated({"friction.mu_s": (0.0, 0.0, 1.2)})


def test_load_beyond_model_range():
    tyre = TyreConfig()
    check_operating_range(tyre, [0.8 * tyre.load_index_load], [16.7], [2.2e5])
    with pytest.raises(MftireInputError, match=r"Fz = .* exceeds the model's range"):
        check_operating_range(tyre, [2.0 * tyre.load_index_load], [16.7], [2.2e5])
    with pytest.raises(MftireInputError, match="Fz must be positive"):
        check_operating_range(tyre, [-1.0], [16.7], [2.2e5])
    with pytest.raises(MftireInputError, match="P must lie"):
        check_operating_range(tyre, [4000.0], [16.7], [0.5e5])


def test_toml_file_roundtrip_and_errors(tmp_path):
    good = tmp_path / "t.toml"
    good.write_text('name = "stiff"\n[tread]\nkx = 1.2e8\n[friction]\nh = 0.4\n')
    tyre = load_tyre(good)
    assert tyre.tread.kx == 1.2e8 and tyre.friction.h == 0.4 and tyre.friction.mu_lock is None
    bad = tmp_path / "bad.toml"
    bad.write_text("[tread]\nkx = -3.0\n")
    with pytest.raises(MftireInputError, match=r"tread\.kx"):
        load_tyre(bad)
    unknown = tmp_path / "unknown.toml"
    unknown.write_text("[tread]\nkz = 3.0\n")
    with pytest.raises(MftireInputError, match=r"tread\.kz"):
        load_tyre(unknown)
    with pytest.raises(MftireInputError, match="not found"):
        load_tyre(tmp_path / "missing.toml")
    broken = tmp_path / "broken.toml"
    broken.write_text("[tread\n")
    with pytest.raises(MftireInputError, match="cannot parse"):
        load_tyre(broken)


def test_h_and_mu_lock_are_alternatives():
    tyre = TyreConfig().updated({"friction.h": 0.3})
    assert tyre.friction.mu_lock is None
    with pytest.raises(MftireInputError, match="exactly one"):
        TyreConfig().updated({"friction.h": 0.3, "friction.mu_lock": 0.7})
    assert np.isfinite(TyreConfig().max_load)
