"""PAC2002 and MF_05 against an independent implementation: Project Chrono's ChPac02Tire.

``tests/data/tir_wild/chrono_pac02_oracle.csv`` holds outputs of Chrono's own steady-state
functions (``ChPac02Tire::CalcFxyMz`` and ``CalcMx``, BSD-3-Clause, commit 07ecad77 of
projectchrono/chrono), built and run once outside this repository on the PAC2002 and MF_05
files of the collection (how: ``tests/data/tir_wild/README.md``, "Independent oracle").  Only the
numbers are shipped.  Two columns per channel:

* ``Fx`` .. ``Mx``: Chrono's code as published.  It adds 0.1 N to the denominators of Bx and By
  and clamps Bx*kappa_x and By*alpha_y to +-(pi/2 - 0.01) (its own regularisations, not
  Pacejka's), so it agrees with the equations to about 1e-5 of Fz at these points;
* ``*_unreg``: the same code with those two regularisations removed: it agrees with mftire
  to the last digits (5e-9 of Fz at most), so every term in between is the same equation.

Chrono takes |muy| (mftire the signed value: the same Fy and Mz, see
``test_pac2002.test_mf05_negative_pdy1_is_the_sign_convention_of_its_exporter``) and
writes (1 + PDY3 gamma^2) where Pacejka 2006 eq 4.E23 has (1 - PDY3 gamma^2): the camber
points are made with PDY3 = 0 on both sides.  Its combined-slip alpha_t,eq takes the sign of
kappa, so the combined points have sgn(kappa) = sgn(alpha).  Points lie inside each file's
ranges (mftire clips there in modes 1xx; Chrono does not).
"""

from __future__ import annotations

import csv
import warnings
from collections import defaultdict

import numpy as np
import pytest
from conftest import DATA, TIR

from mftire.tyre import Tyre, load

ORACLE = DATA / "tir_wild" / "chrono_pac02_oracle.csv"
CHANNELS = {"pure_long": ("Fx",), "pure_lat": ("Fy", "Mz", "Mx"), "camber": ("Fy", "Mz", "Mx"),
            "combined": ("Fx", "Fy", "Mz")}


def _rows() -> dict[tuple[str, str], list[dict]]:
    groups: dict[tuple[str, str], list[dict]] = defaultdict(list)
    with ORACLE.open(newline="") as fh:
        for row in csv.DictReader(fh):
            groups[(row["file"], row["kind"])].append(row)
    return groups


GROUPS = _rows()


def _path(name: str):
    return TIR / name if (TIR / name).exists() else DATA / "tir_wild" / name


@pytest.mark.parametrize(("name", "kind"), sorted(GROUPS))
def test_agrees_with_chrono_chpac02tire(name, kind):
    rows = GROUPS[(name, kind)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tyre = load(_path(name))
        if kind == "camber":  # Chrono's (1 + PDY3 gamma^2): compared with PDY3 = 0 on both sides
            params = tyre.parameters.copy()
            params.set("PDY3", 0.0)
            tyre = Tyre(params)
        x = {k: np.array([float(r[k]) for r in rows]) for k in ("kappa", "alpha", "Fz", "gamma")}
        out = tyre.evaluate(x["Fz"], x["kappa"], x["alpha"], x["gamma"], mode=111 if kind == "combined" else 110)
    R0 = tyre.flat["UNLOADED_RADIUS"]
    for ch in CHANNELS[kind]:
        scale = x["Fz"] * (R0 if ch.startswith("M") else 1.0)
        for suffix, tol in (("_unreg", 1e-7), ("", 1e-4)):
            ref = np.array([float(r[ch + suffix]) for r in rows])
            err = np.max(np.abs(out[ch] - ref) / scale)
            assert err < tol, (name, kind, ch + suffix, err)


def test_the_oracle_covers_pac2002_and_mf05_files():
    formats = defaultdict(set)
    for name, kind in GROUPS:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            formats[load(_path(name)).format].add(kind)
    assert set(formats) == {"PAC2002", "MF_05"}
    assert all(set(CHANNELS) <= kinds for kinds in formats.values())
    assert len(GROUPS) >= 40 and sum(len(v) for v in GROUPS.values()) >= 400
