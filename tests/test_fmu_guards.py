"""FMU input guards (issue 14): every output finite for any input, replacements logged.

Fuzz: 10^5 random input vectors through fmpy in Model Exchange and 10^5 in
Co-Simulation (FMI 2.0), spread over three tyres (MF 6.1, MF 6.2, MF 5.2) and all
twelve use modes; 10^4 more through FMI 3.0 and through an FMU with model
extensions (data inputs).  Each component of a vector is NaN, ±Inf, ±0, huge,
tiny, subnormal, a log-uniform magnitude of either sign, or a value in the usual
range.  One instance per FMU, inputs set and outputs read in a loop (CS: one
``doStep`` per vector).
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import REFERENCE_TYRES, needs_c_compiler

from mftire.fmu.export import export_fmu
from mftire.fmu.host import INPUT_NAMES, FMUTyre
from mftire.iotools.tir import read_tir
from mftire.tyre import Tyre

pytestmark = needs_c_compiler

SPECIAL = np.array([np.nan, np.inf, -np.inf, 0.0, -0.0, 1e300, -1e300, 1e-300, -1e-300, 5e-324, 1e308, -1e308])
MODES = [m for m in (111, 112, 110, 121, 122, 120, 211, 212, 210, 221, 222, 220)]
USUAL = {"Fz": (0.0, 12000.0), "kappa": (-1.0, 1.0), "alpha": (-0.5, 0.5), "gamma": (-0.2, 0.2),
         "phit": (-1.0, 1.0), "Vx": (-5.0, 60.0), "P": (1e5, 4e5), "omega": (-50.0, 200.0), "muRoad": (0.2, 1.5)}


def fuzz_vectors(n: int, names, seed: int) -> np.ndarray:
    """``n`` x ``len(names)`` inputs: 25 % special values, 20 % log-uniform magnitudes, 55 % usual range."""
    rng = np.random.default_rng(seed)
    out = np.empty((n, len(names)))
    for j, name in enumerate(names):
        lo, hi = USUAL.get(name, (-100.0, 100.0))
        usual = rng.uniform(lo, hi, n)
        logmag = rng.choice([-1.0, 1.0], n) * 10.0 ** rng.uniform(-12, 12, n)
        special = rng.choice(SPECIAL, n)
        pick = rng.uniform(size=n)
        out[:, j] = np.where(pick < 0.25, special, np.where(pick < 0.45, logmag, usual))
    return out


def _fuzz(fmu, interface: str, n: int, seed: int, names=INPUT_NAMES) -> tuple[int, list]:
    """Drive one instance through ``n`` vectors (modes cycled in blocks); return (count, bad rows)."""
    x = fuzz_vectors(n, names, seed)
    bad = []
    with FMUTyre(fmu, interface) as tyre:
        f = tyre.fmu
        v2 = tyre.fmi_version == 2
        set_real, get_real = (f.setReal, f.getReal) if v2 else (f.setFloat64, f.getFloat64)
        set_int = f.setInteger if v2 else f.setInt32
        in_vrs = [tyre.vr[k] for k in names]
        out_vrs = [tyre.vr[k] for k in tyre.outputs]
        mode_vr = [tyre.vr["useMode"]]
        block = n // len(MODES) + 1
        for i in range(n):
            if i % block == 0:
                set_int(mode_vr, [MODES[i // block]])
            set_real(in_vrs, list(x[i]))
            if interface == "CS":
                f.doStep(currentCommunicationPoint=tyre.time, communicationStepSize=tyre.step)
                tyre.time += tyre.step
            y = np.asarray(get_real(out_vrs))
            if not np.isfinite(y).all():
                bad.append((i, dict(zip(names, x[i], strict=True)), dict(zip(tyre.outputs, y, strict=True))))
        msgs = tyre.messages
    return n, bad, msgs


def extension_entries(variables) -> dict:
    """``[MFTIRE_EXTENSIONS]`` entries of a friction term per external variable, in the
    section format of the installed :mod:`mftire.extensions` (terms ``EXTn_*``, or the
    older keyed extensions ``FADE_*`` / ``FVAR_*``)."""
    from mftire import extensions as ex

    out: dict = {}
    if hasattr(ex, "FORMS"):
        for n, v in enumerate(variables, 1):
            out.update({f"EXT{n}_TARGET": "LMUX LMUY", f"EXT{n}_FORM": "linear", f"EXT{n}_VARIABLE": v,
                        f"EXT{n}_REF": 50.0, f"EXT{n}_SCALE": 25.0, f"EXT{n}_C1": -0.1})
        return out
    keyed = (("FADE_VARIABLE", {"FADE_DEPTH": 0.2, "FADE_SCALE": 40.0}),
             ("FVAR_VARIABLE", {"FVAR_C1": 0.05, "FVAR_C2": 0.01, "FVAR_REF": 25.0, "FVAR_SCALE": 10.0}))
    for v, (key, numbers) in zip(variables, keyed, strict=False):
        out.update(numbers)
        out[key] = v
    return out


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    d = tmp_path_factory.mktemp("guards")
    out = {}
    for label in ("MF61", "JuliaMF62", "MF52"):
        out[(label, 2)] = str(export_fmu(REFERENCE_TYRES[label], d / f"{label}.fmu"))
    out[("JuliaMF62", 3)] = str(export_fmu(REFERENCE_TYRES["JuliaMF62"], d / "JuliaMF62_3.fmu", fmi_version=3))
    params = read_tir(REFERENCE_TYRES["MF61"])
    for k, v in extension_entries(["road_temp", "temperature"]).items():
        params.set(k, v, section="MFTIRE_EXTENSIONS")
    ext = Tyre(params, name="ext")
    assert ext.required_variables == ["road_temp", "temperature"]
    out["ext"] = str(export_fmu(ext, d / "ext.fmu"))
    return out


@pytest.mark.parametrize("interface", ["ME", "CS"])
def test_fuzz_1e5_vectors_give_finite_outputs(fmus, interface):
    total, bad = 0, []
    for (label, version), n, seed in ((("MF61", 2), 50_000, 1), (("JuliaMF62", 2), 30_000, 2),
                                      (("MF52", 2), 20_000, 3)):
        k, b, msgs = _fuzz(fmus[(label, version)], interface, n, seed + (10 if interface == "CS" else 0))
        total += k
        bad += [(label, *row) for row in b]
        assert any("saturated to the bound" in m for _, _, m in msgs)  # the guards log through the FMI logger
        assert all(status in (0, 1) for status, _, _ in msgs)  # warnings, never errors
    assert total == 100_000
    assert bad == [], bad[:3]


@pytest.mark.parametrize("interface", ["ME", "CS"])
def test_fuzz_fmi3_and_extension_inputs(fmus, interface):
    n, bad, _ = _fuzz(fmus[("JuliaMF62", 3)], interface, 5_000, 7)
    assert bad == [], bad[:3]
    n, bad, msgs = _fuzz(fmus["ext"], interface, 5_000, 8, names=(*INPUT_NAMES, "road_temp", "temperature"))
    assert bad == [], bad[:3]
    assert any("input 'temperature'" in m or "input 'road_temp'" in m for _, _, m in msgs)


@pytest.mark.parametrize("interface", ["ME", "CS"])
def test_the_issue_cases(fmus, interface):
    """muRoad NaN, kappa inf, Fz 1e9 and Vx 1e6: finite, sane outputs and one log line each."""
    base = dict(Fz=4000.0, kappa=-0.1, alpha=0.05, Vx=20.0)
    with FMUTyre(fmus[("MF61", 2)], interface) as tyre:
        ref = tyre.evaluate(**base)
        got = tyre.evaluate(**base, muRoad=float("nan"))
        assert got["Fx"] == ref["Fx"] and got["Fy"] == ref["Fy"]  # NaN muRoad: 1, documented
        got = tyre.evaluate(**{**base, "kappa": float("inf")})
        assert np.isfinite(list(got.values())).all() and 0.3 < got["Re"] < 0.45
        got = tyre.evaluate(**{**base, "Fz": 1e9})
        assert 0.2 < got["Re"] < 0.45 and got["Fz_out"] == 3 * 18000.0  # 3 FZMAX
        got = tyre.evaluate(**{**base, "Vx": 1e6})
        assert abs(got["My"]) < 1e4
        text = [m for _, _, m in tyre.messages]
    assert any("input 'muRoad' = nan replaced by 1" in m for m in text)
    assert any("input 'kappa' = inf saturated to the bound 10" in m for m in text)
    assert any("input 'Fz' = 1000000000 saturated to the bound 54000" in m for m in text)
    assert any("input 'Vx' = 1000000 saturated to the bound 200" in m for m in text)


@pytest.mark.filterwarnings("ignore:.*(saturated|Low speed mode)")
def test_inputs_in_range_are_untouched(fmus):
    """The guards do not move a usual operating point: FMU equals Python there."""
    tyre = Tyre(read_tir(REFERENCE_TYRES["MF61"]))
    x = fuzz_vectors(200, INPUT_NAMES, 5)
    rng = np.random.default_rng(0)
    with FMUTyre(fmus[("MF61", 2)], "ME") as fmu:
        for _ in range(200):
            pt = {k: rng.uniform(*USUAL[k]) for k in INPUT_NAMES}
            pt["Fz"] = rng.uniform(500.0, 9000.0)
            pt["muRoad"] = 1.0
            got = fmu.evaluate(**pt)
            ref = tyre.evaluate(pt["Fz"], pt["kappa"], pt["alpha"], pt["gamma"], pt["phit"], pt["Vx"], pt["P"],
                                pt["omega"] if pt["omega"] != 0 else None)
            assert got["Fx"] == pytest.approx(float(ref["Fx"]), rel=1e-9, abs=1e-6)
            assert got["Mz"] == pytest.approx(float(ref["Mz"]), rel=1e-9, abs=1e-6)
    assert x.shape == (200, 9)
