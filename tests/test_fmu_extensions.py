"""FMU export of the model extensions ([MFTIRE_EXTENSIONS], mftire/mf/extensions.py).

One small FMU per case (each form of :data:`mftire.mf.extensions.FORMS` on its own, the
force offsets, several targets, builtin and external variables, and many terms
together), compiled once per module.  The FMU must agree with the Python evaluator
point by point to 1e-9 relative, with the absolute floors of tests/test_fmu_export.py,
in Model Exchange and Co-Simulation, in every mode (turn slip 112 and 222 included),
with random values of the external-variable inputs.
"""

from __future__ import annotations

import os
import re
import subprocess
import warnings

import numpy as np
import pytest
from conftest import REFERENCE_TYRES, needs_c_compiler
from test_fmu_export import CHANNEL, OUTPUTS, _random_points, _rel_errors, _scale

from mftire import read_tir
from mftire.errors import MftireError
from mftire.fmu import variables as vt
from mftire.fmu.export import export_fmu, find_compiler, generate_sources
from mftire.mf.extensions import FORMS, SECTION, TARGETS, parse_section
from mftire.mf.solver import evaluate_arrays
from mftire.tyre import Tyre

pytestmark = needs_c_compiler

BASE_INPUTS = ["Fz", "kappa", "alpha", "gamma", "phit", "Vx", "P", "omega", "muRoad"]
ODD_NAME = "brake temp [°C]"  # not a C identifier: kept as the FMI name, escaped in the C sources


def _term(n: int, target: str, form: str, variable: str, **numbers) -> dict:
    out = {f"EXT{n}_TARGET": target, f"EXT{n}_FORM": form, f"EXT{n}_VARIABLE": variable}
    for k, v in numbers.items():
        out[f"EXT{n}_{k.upper()}"] = v
    return out


#: case -> (base .tir, [MFTIRE_EXTENSIONS] entries)
CASES: dict[str, tuple[str, dict]] = {
    "decay_Vs": ("JuliaMF62", _term(1, "LMUX LMUY", "decay", "Vs", scale=16.7, c1=0.6)),
    "linear_ext": ("JuliaMF61", _term(1, "LKX LKY", "linear", ODD_NAME, ref=60.0, scale=30.0, min=0.0, max=150.0,
                                      c1=-0.1)),
    "quadratic_Vx": ("JuliaMF62", _term(1, "LMUX LMUY LEX", "quadratic", "Vx", ref=16.7, scale=10.0, c1=-0.08,
                                        c2=0.03)),
    "saturating_time": ("JuliaMF62", _term(1, "LMUX LMUY", "saturating", "time", ref=0.0, scale=100.0, c1=-0.25,
                                           c2=0.8)),
    "power_Fz": ("MF52", _term(1, "LMUY", "power", "Fz", ref=4000.0, c1=-0.1)),
    "table_surface": ("JuliaMF61", _term(1, "LMUX LMUY", "table", "surface", l1=0.0, l2=1.0, l3=2.0, c1=0.0,
                                         c2=-0.2, c3=-0.45)),
    "interaction": ("JuliaMF62", {**_term(1, "LMUX LMUY", "interaction", "wet", ref=0.0, scale=1.0, c1=-0.1,
                                         c2=-0.05), "EXT1_VARIABLE2": "Vx", "EXT1_REF2": 16.7, "EXT1_SCALE2": 10.0}),
    "offsets": ("JuliaMF61", {**_term(1, "FX_OFFSET", "linear", "sign_kappa", c1=0.01),
                              **_term(2, "FY_OFFSET", "linear", "dfz", c1=0.02)}),
    "moments": ("JuliaMF62", {**_term(1, "LTR LRES LKZC LS", "linear", "dpi", c1=0.3),
                              **_term(2, "LMX LVMX LMY", "linear", "sign_alpha", c1=0.1),
                              **_term(3, "LCX LCY LHX LHY LVX LVY", "linear", "gamma", scale=0.05, c1=0.2),
                              **_term(4, "LXAL LYKA LVYKA LKYC LEY LFZO", "quadratic", "kappa", c1=0.2, c2=0.3)}),
    "hinge_temperature": ("JuliaMF61", _term(1, "LMUY LKY", "hinge", "temperature", ref=50.0, scale=20.0, min=0.0,
                                             max=120.0, c1=-0.08, c2=0.5)),
    "direction_offset": ("JuliaMF62", {**_term(1, "FY_OFFSET", "direction", "sweep_dir", c1=0.02),
                                       **_term(2, "LMUX", "direction", "sweep_dir", c1=-0.03)}),
    "input_laws": ("JuliaMF61", {**_term(1, "P_FACTOR", "linear", "temperature", ref=20.0, scale=50.0, min=0.0,
                                         max=120.0, c1=0.08),
                                 **_term(2, "ALPHA_OFFSET", "linear", "time", ref=0.0, scale=1000.0, c1=0.01),
                                 **_term(3, "GAMMA_OFFSET", "quadratic", "temperature", ref=20.0, scale=50.0,
                                         c1=0.005, c2=0.002),
                                 **_term(4, "KAPPA_OFFSET", "hinge", "temperature", ref=20.0, scale=50.0,
                                         c1=0.01, c2=0.2)}),
    "all": ("JuliaMF62", {
        **_term(1, "LMUX LMUY", "decay", "Vs", scale=16.7, c1=0.3),
        **_term(2, "LMUX LMUY", "saturating", "time", scale=300.0, c1=-0.15, c2=1.0),
        **_term(3, "LKX LKY", "linear", "temperature", ref=50.0, scale=40.0, min=-10.0, max=120.0, c1=-0.04),
        **_term(4, "LMUY", "linear", "sign_alpha", c1=0.04),
        **_term(5, "FX_OFFSET", "linear", "sign_kappa", c1=0.01),
        **_term(6, "LTR", "quadratic", "temperature", ref=50.0, scale=40.0, c1=0.03, c2=-0.01),
    }),
}  # fmt: skip

#: external variable -> (low, high) of its random values
DATA_RANGES = {"time": (-50.0, 3000.0), "temperature": (-20.0, 140.0), ODD_NAME: (-10.0, 200.0),
               "surface": (-0.5, 2.7), "wet": (0.0, 1.0), "sweep_dir": (-1.0, 1.0)}  # fmt: skip
MODES = (111, 121, 211, 112, 110, 222)
N_POINTS = 300  # per case and interface


def _tyre(case: str) -> Tyre:
    base, entries = CASES[case]
    params = read_tir(REFERENCE_TYRES[base])
    for key, value in entries.items():
        params.set(key, value, section=SECTION)
    return Tyre(params, name=f"{case}.tir")


@pytest.fixture(scope="module")
def build(tmp_path_factory):
    """build(case, version) -> (fmu path, extracted directory), compiled once per module."""
    from fmpy import extract

    d = tmp_path_factory.mktemp("fmu_ext")
    cache: dict = {}

    def get(case: str, version: int = 2):
        if (case, version) not in cache:
            path = export_fmu(_tyre(case), d / f"{case}_fmi{version}.fmu", fmi_version=version)
            cache[case, version] = (path, extract(str(path), unzipdir=str(d / f"{case}_x{version}")))
        return cache[case, version]

    return get


def _python(tyre: Tyre, pt: dict, data: dict, mode: int, flat: dict | None = None, record=None) -> dict:
    """Tyre.evaluate's evaluator (evaluate_arrays with the tyre's extensions) on one point, muRoad folded
    into LMUX/LMUY as the FMU does."""
    q = dict(flat or tyre.flat)
    q["LMUX"] = q["LMUX"] * pt["muRoad"]
    q["LMUY"] = q["LMUY"] * pt["muRoad"]
    omega = None if pt["omega"] == 0 else pt["omega"]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = evaluate_arrays(q, pt["Fz"], pt["kappa"], pt["alpha"], pt["gamma"], pt["phit"], pt["Vx"], pt["P"],
                              omega, mode, tyre.extensions, data or None)  # fmt: skip
    if record is not None:
        record.extend(str(w.message) for w in caught)
    return {k: float(out[CHANNEL.get(k, k)]) for k in OUTPUTS}


def _data_points(rng, names, n) -> list[dict]:
    cols = {v: rng.uniform(*DATA_RANGES[v], n) for v in names}
    return [{v: float(cols[v][i]) for v in names} for i in range(n)]


def _agreement(unzipdir: str, tyre: Tyre, seed: int, n: int) -> dict[str, float]:
    from mftire.fmu.host import FMUTyre

    rng = np.random.default_rng(seed)
    p = tyre.flat
    pts = _random_points(rng, p, n)
    data = _data_points(rng, tyre.required_variables, n)
    modes = [MODES[i % len(MODES)] for i in range(n)]
    refs = [_python(tyre, pt, dv, mode) for pt, dv, mode in zip(pts, data, modes, strict=True)]
    worst = {}
    for iface in ("ME", "CS"):
        worst[iface] = 0.0
        for mode in MODES:
            with FMUTyre(unzipdir, iface, start_values={"useMode": mode}) as fmu:
                for pt, dv, m, ref in zip(pts, data, modes, refs, strict=True):
                    if m != mode:
                        continue
                    got = fmu.evaluate(**pt, **dv)
                    errs = _rel_errors(p, got, ref)
                    assert max(errs.values()) <= 1e-9, (iface, mode, pt, dv, {k: (got[k], ref[k]) for k in errs
                                                                              if errs[k] > 1e-9})  # fmt: skip
                    worst[iface] = max(worst[iface], max(errs.values()))
    return worst


# --------------------------------------------------------------------------- agreement


@pytest.mark.parametrize("case", list(CASES))
def test_extension_fmu_agrees_with_python_me_and_cs(build, case):
    """300 random points per interface (6 modes, random muRoad and data inputs), 1e-9 relative."""
    from fmpy.validation import validate_fmu

    path, unzipdir = build(case)
    assert validate_fmu(str(path)) == []
    tyre = _tyre(case)
    worst = _agreement(unzipdir, tyre, seed=1000 + list(CASES).index(case), n=N_POINTS)
    print(f"{case}: max relative error vs Python over {N_POINTS} points: ME {worst['ME']:.1e}, CS {worst['CS']:.1e}")


def test_every_form_and_target_is_covered():
    sets = [parse_section(entries) for _, entries in CASES.values()]
    assert {t.form.name for e in sets for t in e.terms} == set(FORMS)
    assert {x for e in sets for t in e.terms for x in t.targets} == set(TARGETS)


def test_extension_fmu_fmi3(build):
    from fmpy.validation import validate_fmu

    path, unzipdir = build("all", 3)
    assert validate_fmu(str(path)) == []
    worst = _agreement(unzipdir, _tyre("all"), seed=3, n=120)
    print(f"FMI 3 all extensions: ME {worst['ME']:.1e}, CS {worst['CS']:.1e}")


def test_extensions_change_the_outputs(build):
    """The extended FMU is not the plain tyre (guards against a silently neutral C path)."""
    from mftire.fmu.host import FMUTyre

    _, unzipdir = build("all")
    base = _tyre("all")
    plain = Tyre(read_tir(REFERENCE_TYRES["JuliaMF62"]))
    pt = dict(Fz=5000.0, kappa=-0.15, alpha=0.08, gamma=0.02, phit=0.0, Vx=25.0, P=2.3e5, omega=0.0, muRoad=1.0)
    data = {"time": 2500.0, "temperature": 115.0}
    with FMUTyre(unzipdir, "ME") as fmu:
        got = fmu.evaluate(**pt, **data)
    ref_plain = _python(plain, pt, {}, 111)
    ref = base.evaluate(pt["Fz"], pt["kappa"], pt["alpha"], pt["gamma"], pt["phit"], pt["Vx"], pt["P"], **data)
    for k in ("Fx", "Fy", "Mz", "Mx", "mux", "muy"):  # (My: QSY2 = 0 in this file, Fx does not reach it)
        assert abs(got[k] - ref_plain[k]) > 1e-3 * abs(ref_plain[k]), k
        assert got[k] == pytest.approx(float(ref[k]), rel=1e-12, abs=1e-12), k


# --------------------------------------------------------------------------- variables


@pytest.mark.parametrize("version", [2, 3])
def test_data_variables_are_inputs_and_keys_are_parameters(build, version):
    from fmpy import read_model_description

    path, unzipdir = build("all", version)
    md = read_model_description(str(path))
    by_name = {v.name: v for v in md.modelVariables}
    inputs = [v for v in md.modelVariables if v.causality == "input"]
    # one input per external variable (temperature is read by two terms: one input), builtins are not inputs
    assert [v.name for v in inputs] == [*BASE_INPUTS, "ext_time", "temperature"]  # 'time' is FMI's
    for name in ("ext_time", "temperature"):
        v = by_name[name]
        assert v.variability == "continuous" and float(v.start) == 0.0 and v.unit is None
    for unknowns in (md.outputs, md.initialUnknowns):
        assert {u.variable.name for u in unknowns} == set(OUTPUTS)
        for u in unknowns:
            assert {d.name for d in u.dependencies} == {v.name for v in inputs}
    # every numeric key of a term is a tunable parameter with the file's value
    entries = CASES["all"][1]
    for t in parse_section(entries).terms:
        for key, value in vt.term_fields(t):
            v = by_name[key]
            assert (v.causality, v.variability) == ("parameter", "tunable"), key
            assert float(v.start) == value, key
            assert v.description.startswith(f"[{SECTION}] EXT{t.index}")
            if key in entries:
                assert value == entries[key]
    assert "EXT1_FORM" not in by_name and "EXT1_TARGET" not in by_name  # string keys are compiled in
    gen = open(os.path.join(unzipdir, "sources", "mf_ext_gen.h")).read()
    assert "#define MF_N_TERMS 6" in gen
    for f in FORMS.values():  # every form's C expression comes from mftire.mf.extensions
        assert f.c_expr in gen


def test_odd_data_variable_name_is_kept_for_fmi_and_escaped_for_c(build):
    from fmpy import read_model_description

    path, unzipdir = build("linear_ext")
    md = read_model_description(str(path))
    assert [v.name for v in md.modelVariables if v.causality == "input"] == [*BASE_INPUTS, ODD_NAME]
    gen = open(os.path.join(unzipdir, "sources", "mf_model_gen.h"), encoding="ascii").read()  # pure ASCII
    assert vt.c_string(ODD_NAME) in gen and r"\302\260" in vt.c_string(ODD_NAME)


def test_builtin_variable_is_not_an_input(build):
    from fmpy import read_model_description

    for case in ("decay_Vs", "quadratic_Vx", "offsets", "moments"):
        path, _ = build(case)
        md = read_model_description(str(path))
        assert [v.name for v in md.modelVariables if v.causality == "input"] == BASE_INPUTS, case


def test_guid_covers_the_compiled_choices():
    """Two files that differ only in a string key (compiled in) get different GUIDs."""
    flat = Tyre(read_tir(REFERENCE_TYRES["JuliaMF62"])).flat
    guids = set()
    for target, form, var in (("LMUX", "linear", "Vs"), ("LMUY", "linear", "Vs"), ("LMUY", "quadratic", "Vs"),
                              ("LMUY", "quadratic", "Fz")):  # fmt: skip
        spec = vt.extension_spec(_term(1, target, form, var, c1=0.1))
        guids.add(vt.guid(vt.variable_table(flat, extensions=spec), 2))
    assert len(guids) == 4
    # a plain tyre's table and GUID are unchanged by the extension machinery
    assert vt.variable_table(flat) == vt.variable_table(flat, extensions=None)


# --------------------------------------------------------------------------- parameters


@pytest.mark.parametrize("iface", ["ME", "CS"])
def test_extension_parameter_start_values_change_outputs_as_python(build, iface):
    from mftire.fmu.host import FMUTyre

    _, unzipdir = build("all")
    tyre = _tyre("all")
    changed = {"EXT1_C1": 0.9, "EXT2_C1": -0.3, "EXT3_C1": -0.1, "EXT5_C1": 0.02, "EXT6_C2": -0.05,
               "EXT3_REF": 30.0}  # fmt: skip
    params = read_tir(REFERENCE_TYRES["JuliaMF62"])
    for key, value in {**CASES["all"][1], **changed}.items():
        params.set(key, value, section=SECTION)
    tuned_py = Tyre(params)
    pt = dict(Fz=5000.0, kappa=-0.12, alpha=0.06, gamma=0.02, phit=0.0, Vx=20.0, P=2.3e5, omega=0.0, muRoad=1.0)
    data = {"time": 700.0, "temperature": 85.0}
    args = [pt[k] for k in ("Fz", "kappa", "alpha", "gamma", "phit", "Vx", "P")]
    with FMUTyre(unzipdir, iface) as base, FMUTyre(unzipdir, iface, start_values=changed) as tuned:
        g0, g1 = base.evaluate(**pt, **data), tuned.evaluate(**pt, **data)
    r0 = {k: float(v) for k, v in tyre.evaluate(*args, **data).items()}
    r1 = {k: float(v) for k, v in tuned_py.evaluate(*args, **data).items()}
    p = tyre.flat
    assert abs(g1["Fx"] - g0["Fx"]) > 0.02 * abs(g0["Fx"])  # the change matters
    for k in OUTPUTS:
        c = CHANNEL.get(k, k)
        assert g0[k] == pytest.approx(r0[c], rel=1e-12, abs=1e-12), k
        assert g1[k] == pytest.approx(r1[c], rel=1e-12, abs=1e-12), k
        assert g1[k] - g0[k] == pytest.approx(r1[c] - r0[c], rel=1e-9, abs=1e-9 * _scale(p, k)), k


def test_nan_data_input_is_zeroed_with_a_warning(build):
    from mftire.fmu.host import FMUTyre

    _, unzipdir = build("all")
    tyre = _tyre("all")
    pt = dict(Fz=4000.0, kappa=0.05, alpha=0.03, gamma=0.01, phit=0.0, Vx=15.0, P=2.4e5, omega=0.0, muRoad=1.0)
    data = {"time": float("nan"), "temperature": float("nan")}
    with FMUTyre(unzipdir, "ME") as fmu:
        got = fmu.evaluate(**pt, **data)
        logged = " | ".join(m for s, c, m in fmu.messages if s == 1)
    py_warnings: list[str] = []
    ref = _python(tyre, pt, data, 111, record=py_warnings)
    assert max(_rel_errors(tyre.flat, got, ref).values()) <= 1e-9
    assert ref == _python(tyre, pt, {"time": 0.0, "temperature": 0.0}, 111)
    assert len(py_warnings) == 2
    for w in py_warnings:
        assert w in logged, (w, logged)


@pytest.mark.parametrize("mode", [111, 211])
def test_extension_variable_beyond_its_fitted_range_is_clamped_with_a_warning_in_modes_1xx(build, mode):
    """The "all" case's LKX·LKY term was fitted on temperature -10..120: at 200 the FMU and Python clamp it to
    120 and warn in mode 111; in mode 211 (no limits) both extrapolate, silently.  (Its LTR term has no
    stored range: Mz moves on.)"""
    from mftire.fmu.host import FMUTyre
    from mftire.mf.extensions import EXT_RANGE_WARNING

    _, unzipdir = build("all")
    tyre = _tyre("all")
    pt = dict(Fz=4000.0, kappa=0.05, alpha=0.03, gamma=0.01, phit=0.0, Vx=15.0, P=2.4e5, omega=0.0, muRoad=1.0)
    with FMUTyre(unzipdir, "ME", start_values={"useMode": mode}) as fmu:
        got = fmu.evaluate(**pt, time=100.0, temperature=200.0)
        logged = " | ".join(m for s, c, m in fmu.messages if s == 1)
    py_warnings: list[str] = []
    ref = _python(tyre, pt, {"time": 100.0, "temperature": 200.0}, mode, record=py_warnings)
    edge = _python(tyre, pt, {"time": 100.0, "temperature": 120.0}, mode)
    assert max(_rel_errors(tyre.flat, got, ref).values()) <= 1e-9
    if mode // 100 == 1:
        assert (ref["Fx"], ref["Fy"]) == (edge["Fx"], edge["Fy"])
        assert EXT_RANGE_WARNING in py_warnings and EXT_RANGE_WARNING in logged
    else:
        assert ref["Fx"] != edge["Fx"]
        assert EXT_RANGE_WARNING not in py_warnings and EXT_RANGE_WARNING not in logged
    # Tyre.evaluate (compiled kernel or numpy) says the same
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        tyre.evaluate(4000.0, 0.05, 0.03, 0.01, mode=mode, time=100.0, temperature=[20.0, 200.0])
    assert (EXT_RANGE_WARNING in [str(w.message) for w in caught]) == (mode // 100 == 1)


# --------------------------------------------------------------------------- sources and errors


def test_extended_sources_rebuild_warning_free(build, tmp_path):
    _, unzipdir = build("all")
    src = os.path.join(unzipdir, "sources")
    files = [os.path.join(src, f) for f in sorted(os.listdir(src)) if f.endswith(".c")]
    res = subprocess.run([*find_compiler(), "-shared", "-fPIC", "-std=c99", "-Wall", "-Wextra", "-I", src, *files,
                          "-o", str(tmp_path / "rebuilt.so"), "-lm"], capture_output=True, text=True)  # fmt: skip
    assert res.returncode == 0, res.stderr
    assert res.stderr.strip() == ""


def _with(entries: dict) -> Tyre:
    params = read_tir(REFERENCE_TYRES["JuliaMF62"])
    for key, value in entries.items():
        params.set(key, value, section=SECTION)
    return Tyre(params, name="bad.tir")


@pytest.mark.parametrize(
    ("entries", "match"),
    [
        (_term(1, "LQQ", "linear", "Vs", c1=0.1), "each target must be one of"),
        (_term(1, "LMUX", "linear", "phit", c1=0.1), "'phit': that name is an input of the evaluator"),
        (_term(1, "LMUX", "linear", "energy", c1=0.1), "needs measured history"),
        (_term(1, "LMUX", "linear", "a\tb", c1=0.1), "cannot be an FMI variable name"),
        (_term(1, "LMUX", "linear", "Vs", c1="fast"), "EXT1_C1 = 'fast' must be a number"),
        (_term(1, "LMUX", "wiggle", "Vs", c1=0.1), "EXT1_FORM = 'wiggle': must be one of"),
        (_term(1, "LMUX", "linear", "Vs", c2=0.1), "the linear form has no such coefficient"),
        (_term(1, "LMUX", "power", "Fz", c1=0.1), "EXT1_REF must be > 0"),
    ],
)
def test_export_refuses_extensions_it_cannot_evaluate(tmp_path, entries, match):
    # a bad section is refused when the tyre is built or, at the latest, by the export
    with pytest.raises(MftireError, match=re.escape(match)):
        export_fmu(_with(entries), tmp_path / "bad.fmu")
    assert not list(tmp_path.iterdir())


def test_generate_sources_without_compiler_for_every_case():
    """The generated headers define what the C code reads (checked without compiling)."""
    for case in CASES:
        tyre = _tyre(case)
        spec = vt.extension_spec(tyre.extensions)
        _, files = generate_sources(tyre.flat, "x", 2, 111, spec)
        assert f"#define MF_N_DATA {len(tyre.required_variables)}" in files["mf_params.h"]
        assert f"#define MF_N_TERMS {len(spec.terms)}" in files["mf_ext_gen.h"]
