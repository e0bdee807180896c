"""The data layer lives in iotools, once: unit table, column aliases, table loaders, resources.

Static checks read the package source with :mod:`ast`; behaviour checks use small
loaders.  What "once" means here:

* unit names with SI factors are defined only in :mod:`mftire.iotools.units`; the
  ``.tir`` reader, the sweep conversions, TYDEX and the column checks use that table;
* the column aliases (other names of schema columns) are defined only in
  :mod:`mftire.iotools.sweeps`; the fitter's column check derives from them, and the
  TYDEX channel keys are among them;
* the shared loaders are in :mod:`mftire.iotools.loaders`; ``cli.py`` defines no reader
  and holds no resource path (the default ``.tir`` is :func:`mftire.data.default_tir`);
* the columns that are never model variables are one set for comparison and diagnosis.
"""

from __future__ import annotations

import ast
import math
import re
from fractions import Fraction
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mftire.errors import MftireInputError
from mftire.iotools import columns, loaders, sweeps, tir, tydex, units

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "mftire"


def _sources() -> dict[str, ast.Module]:
    return {str(p.relative_to(ROOT)): ast.parse(p.read_text(encoding="utf-8")) for p in PACKAGE.rglob("*.py")}


def _string_keys(node: ast.AST) -> list[str]:
    """String constants used as names in a dict literal, a ``dict.fromkeys`` tuple or a name tuple."""
    if isinstance(node, ast.Dict):
        out = []
        for k in node.keys:
            if isinstance(k, ast.Constant) and isinstance(k.value, str):
                out.append(k.value)
            elif isinstance(k, ast.Tuple):
                out += [e.value for e in k.elts if isinstance(e, ast.Constant) and isinstance(e.value, str)]
        return out
    if isinstance(node, ast.Tuple):
        return [e.value for e in node.elts if isinstance(e, ast.Constant) and isinstance(e.value, str)]
    return []


def test_unit_names_are_defined_in_one_module():
    # a literal that lists three or more unit names of one dimension is a unit table
    probes = {"psi", "kpa", "bar", "km/h", "kmh", "mph", "lbf", "kn", "dan", "deg", "degree", "rad", "inch",
              "mm", "rpm", "millimeter", "kgf"}
    where = set()
    for path, tree in _sources().items():
        for node in ast.walk(tree):
            names = {units.normalise_unit(s) for s in _string_keys(node)}
            if len(names & probes) >= 3:
                where.add(path)
    assert where == {"mftire/iotools/units.py"}


def test_readers_take_their_units_from_iotools_units():
    for module in (tir, sweeps, tydex, loaders):
        tree = ast.parse(Path(module.__file__).read_text(encoding="utf-8"))
        froms = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
        assert "mftire.iotools.units" in froms, module.__name__
    # the .tir reader's quantities are the very dictionaries of the shared table
    for quantity in ("LENGTH", "FORCE", "ANGLE", "MASS", "TIME", "PRESSURE"):
        assert tir._UNIT_FACTORS[quantity] is units.UNITS[quantity.lower()]
    assert sweeps.SI_UNITS is units.SI_UNITS and sweeps.unit_factor is units.unit_factor


def test_unit_table_values():
    assert units.UNITS["pressure"]["psi"] == Fraction("4.4482216152605") / Fraction("0.0254") ** 2
    assert units.unit_factor("km/h", "speed") == pytest.approx(1 / 3.6, rel=1e-15)
    assert units.unit_factor("[deg]", "angle") == math.pi / 180
    assert units.unit_factor("N*m", "moment") == units.unit_factor("N.m", "moment") == 1.0
    assert units.unit_factor("lb", "force") == pytest.approx(4.4482216152605)
    assert float(units.exact_factor("lb", "mass")) == 0.45359237
    assert units.exact_factor("Newton", "force") == 1 and units.exact_factor("newton", "mass") is None
    assert units.is_known_unit("deg C") and not units.is_known_unit("furlong")
    with pytest.raises(MftireInputError, match="unit of force, not speed"):
        units.unit_factor("kN", "speed")


@settings(max_examples=80, deadline=None)
@given(st.sampled_from([(d, n) for d, table in units.UNITS.items() for n in table if d != "temperature"]),
       st.floats(-1e6, 1e6, allow_nan=False))
def test_every_unit_converts_exactly_once_rounded(dim_name, value):
    dim, name = dim_name
    factor = units.UNITS[dim][name]
    assert factor > 0
    assert units.unit_factor(name, dim) == float(factor)
    si = value * units.unit_factor(name, dim)
    assert si / units.unit_factor(name, dim) == pytest.approx(value, rel=1e-14, abs=1e-300)


def test_tir_reader_accepts_the_shared_names(tmp_path):
    # 'daN' and 'kp' came to the .tir reader with the shared table: 10 N and 9.80665 N
    text = (Path(__file__).parent / "data" / "tir" / "mfeval" / "MagicFormula61_Paramerters.tir").read_text()
    base = tir.read_tir(Path(__file__).parent / "data" / "tir" / "mfeval" / "MagicFormula61_Paramerters.tir")
    for unit, factor in (("daN", 10.0), ("kp", 9.80665)):
        p = tmp_path / f"{unit}.tir"
        p.write_text(re.sub(r"(?m)^FORCE\s*=\s*'newton'", f"FORCE = '{unit}'", text))
        assert f"FORCE = '{unit}'" in p.read_text()
        assert tir.read_tir(p)["FNOMIN"] == pytest.approx(base["FNOMIN"] * factor, rel=1e-15)


def test_column_aliases_are_defined_once():
    # dict literals keyed by several alias spellings of schema columns exist only in sweeps.py
    probes = {"slipangl", "slip_angle", "sa", "camber", "inclangl", "fzw", "runspeed", "inflpres", "longslip"}
    where = set()
    for path, tree in _sources().items():
        for node in ast.walk(tree):
            if len({s.lower() for s in _string_keys(node) if isinstance(node, ast.Dict)} & probes) >= 2:
                where.add(path)
    assert where == {"mftire/iotools/sweeps.py"}
    # the fitter's column check is derived from them, and every TYDEX key of a schema column is an alias
    assert {a for a, _ in loaders._OTHER_NAMES.items()} == {a for al in sweeps.COLUMN_ALIASES.values() for a in al}
    for col, keys in tydex.TYDEX_CHANNELS.items():
        if col in sweeps.COLUMN_ALIASES:
            assert all(k.lower() in sweeps.COLUMN_ALIASES[col] or k.lower() == col.lower() for k in keys), col


def test_check_columns_names_aliases_and_unit_suffixes():
    ok = pd.DataFrame(columns=["Fz", "Fz_set", "Fx_1", "residual_Fx", "tread_temp", "time"])
    loaders.check_columns(ok)  # labels and numbered copies are not mistaken for schema columns
    for col, text in (("alfa", "looks like alpha"), ("SA", "looks like alpha in 'deg'"),
                      ("Vx_kmh", "looks like Vx in 'km/h'"), ("Vx_mph", "looks like Vx in 'mph'"),
                      ("Fz [kN]", "looks like Fz in 'kN'"),
                      ("P_psi", "looks like P in 'psi'"), ("Mz_Nm", "looks like Mz in 'Nm'")):
        with pytest.raises(MftireInputError, match=text):
            loaders.check_columns(pd.DataFrame(columns=["Fz", col]))


def test_cli_holds_no_reader_and_no_resource_path():
    tree = ast.parse((PACKAGE / "cli.py").read_text(encoding="utf-8"))
    defined = {n.name for n in ast.walk(tree) if isinstance(n, ast.FunctionDef)}
    assert not {d for d in defined if d.startswith("read") or d == "default_tir"}
    names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)} | {
        n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)}
    assert not names & {"__file__", "read_csv", "resources"}
    strings = {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, str)}
    assert not any(s.startswith("default") or s in ("data", "mftire.data") for s in strings)


def test_default_tir_is_the_shipped_file():
    from mftire.data import default_tir

    p = tir.read_tir(default_tir())
    assert p.fittyp == 61 and p["FNOMIN"] > 0
    assert Path(default_tir()).parent == PACKAGE / "data"


def test_read_numeric_csv_names_file_column_and_row(tmp_path):
    f = tmp_path / "in.csv"
    f.write_text("Fz,kappa,alpha,gamma\n4000,0,0,0\n4000,abc,0,0\n")
    with pytest.raises(MftireInputError, match=r"in.csv: column 'kappa', row 2 \(line 3\): 'abc'"):
        loaders.read_numeric_csv(str(f), ("Fz", "kappa", "alpha", "gamma"))
    f.write_text("Fz,kappa\n4000,0.1\n")
    with pytest.raises(MftireInputError, match="missing column.*alpha"):
        loaders.read_numeric_csv(str(f), ("Fz", "kappa", "alpha"))
    df = loaders.read_numeric_csv(str(f), ("Fz", "kappa"))
    assert df["kappa"].dtype == np.float64 and df["Fz"].iloc[0] == 4000.0


def test_non_variable_columns_are_one_set():
    from mftire.compare import data as compare_data
    from mftire.diagnosis import candidates

    assert candidates.EXCLUDED is columns.NOT_VARIABLES
    g = pd.DataFrame({"Fz": [1.0], "Fz_set": [1.0], "curve_id": [0], "omega": [3.0], "tread_temp": [40.0],
                      "meas_no": [1], "source": ["a"]})
    assert compare_data._extra_variables(g) == ["tread_temp"]
    from mftire.segmentation.grouping import group_sweeps

    assert set(group_sweeps(pd.DataFrame(
        {"Fz": [4e3] * 5, "kappa": np.linspace(0, 0.1, 5), "alpha": 0.0, "gamma": 0.0, "Vx": 10.0, "P": 2e5}
    )).columns) - {"Fz", "kappa", "alpha", "gamma", "Vx", "P"} == set(columns.GROUPING_COLUMNS)
