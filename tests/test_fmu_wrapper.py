"""The FMI wrappers (mftire/fmu/c): prefixes for static linking, call states, refused parameters, the
archive's documentation, the model identifier and the one mode variable (issues 23 and 26)."""

from __future__ import annotations

import math
import shutil
import subprocess
import zipfile
from pathlib import Path

import pytest
from conftest import REFERENCE_TYRES, needs_c_compiler

from mftire.fmu.build import find_compiler
from mftire.fmu.export import export_fmu
from mftire.tyre import load

TYRES = ("MF61", "MF52")


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    d = tmp_path_factory.mktemp("wrapper")
    return {(name, v): export_fmu(REFERENCE_TYRES[name], d / f"{name}_{v}.fmu", v) for name in TYRES for v in (2, 3)}


_MAIN = r"""
#include <stdio.h>
#include <stdlib.h>
#include "fmi2FunctionTypes.h"

/* the two tyres' functions, by their prefixes */
#define DECLARE(P) \
    extern fmi2InstantiateTYPE P##fmi2Instantiate; \
    extern fmi2EnterInitializationModeTYPE P##fmi2EnterInitializationMode; \
    extern fmi2ExitInitializationModeTYPE P##fmi2ExitInitializationMode; extern fmi2SetRealTYPE P##fmi2SetReal; \
    extern fmi2GetRealTYPE P##fmi2GetReal; extern fmi2FreeInstanceTYPE P##fmi2FreeInstance;
DECLARE(tyreA_)
DECLARE(tyreB_)

static void logger(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c, fmi2String m, ...)
{
    (void)e, (void)n, (void)s, (void)c, (void)m;
}

#define RUN(P, GUID, OUT)                                                                                        \
    do {                                                                                                         \
        fmi2ValueReference in[3] = {VR_FZ, VR_KAPPA, VR_ALPHA}, out[1] = {OUT};                                  \
        fmi2Real u[3] = {4000.0, 0.05, 0.03}, y[1];                                                              \
        fmi2Component c = P##fmi2Instantiate("x", fmi2ModelExchange, GUID, "", &cb, fmi2False, fmi2False);       \
        if (!c || P##fmi2EnterInitializationMode(c) || P##fmi2ExitInitializationMode(c)) return 1;              \
        if (P##fmi2SetReal(c, in, 3, u) || P##fmi2GetReal(c, out, 1, y)) return 2;                               \
        printf("%.17g\n", y[0]);                                                                                 \
        P##fmi2FreeInstance(c);                                                                                  \
    } while (0)

int main(void)
{
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    RUN(tyreA_, GUID_A, VR_FX_A);
    RUN(tyreB_, GUID_B, VR_FX_B);
    return 0;
}
"""


@needs_c_compiler
def test_two_tyres_link_statically_into_one_executable_with_prefixes(fmus, tmp_path):
    """FMI2_FUNCTION_PREFIX: each FMU's fmu.c compiled with its own prefix, both objects linked into one program
    (no duplicate symbol: the model is static, only the prefixed FMI functions are external)."""
    from fmpy import read_model_description

    cc = find_compiler()
    objects, defs = [], []
    for tag, name in zip("AB", TYRES, strict=True):
        path = fmus[(name, 2)]
        src = tmp_path / f"src{tag}"
        with zipfile.ZipFile(path) as z:
            for f in z.namelist():
                if f.startswith("sources/"):
                    (src / Path(f).name).parent.mkdir(parents=True, exist_ok=True)
                    (src / Path(f).name).write_bytes(z.read(f))
        obj = tmp_path / f"tyre{tag}.o"
        res = subprocess.run([*cc, "-c", "-std=c99", "-O1", "-Wall", "-Wextra", f"-DFMI2_FUNCTION_PREFIX=tyre{tag}_",
                              "-I", str(src), str(src / "fmu.c"), "-o", str(obj)], capture_output=True, text=True)
        assert res.returncode == 0 and res.stderr.strip() == "", res.stderr[-2000:]
        objects.append(obj)
        md = read_model_description(str(path))
        vr = {v.name: v.valueReference for v in md.modelVariables}
        defs += [f"-DGUID_{tag}=\"{md.guid}\"", f"-DVR_FX_{tag}={vr['Fx']}"]
        defs += [f"-DVR_FZ={vr['Fz']}", f"-DVR_KAPPA={vr['kappa']}", f"-DVR_ALPHA={vr['alpha']}"] if tag == "A" else []
        if shutil.which("nm"):
            symbols = subprocess.run(["nm", "-g", "--defined-only", str(obj)], capture_output=True, text=True).stdout
            external = [line.split()[-1] for line in symbols.splitlines() if line.strip()]
            assert external and all(s.startswith(f"tyre{tag}_fmi2") for s in external), external[:10]
    main = tmp_path / "main.c"
    main.write_text(_MAIN, encoding="utf-8")
    exe = tmp_path / "two_tyres"
    res = subprocess.run([*cc, "-std=c99", *defs, "-I", str(tmp_path / "srcA"), str(main), *map(str, objects), "-o",
                          str(exe), "-lm"], capture_output=True, text=True)  # fmt: skip
    assert res.returncode == 0, res.stderr[-3000:]
    run = subprocess.run([str(exe)], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stdout + run.stderr
    got = [float(x) for x in run.stdout.split()]
    for name, fx in zip(TYRES, got, strict=True):
        ref = float(load(REFERENCE_TYRES[name]).evaluate(4000.0, 0.05, 0.03)["Fx"])
        assert abs(fx - ref) <= 1e-9 * abs(ref), (name, fx, ref)
    assert got[0] != got[1]


def _cs_slave(path: Path, version: int, messages: list):
    """An instantiated Co-Simulation slave of the FMU at ``path`` (FMI ``version``; FMI 2: experiment set up at
    t = 0), its log appended to ``messages`` as (status, category, message)."""
    import fmpy
    from fmpy.fmi2 import FMU2Slave
    from fmpy.fmi3 import FMU3Slave

    from mftire.fmu.host import make_callbacks

    md = fmpy.read_model_description(str(path))
    slave = FMU2Slave if version == 2 else FMU3Slave
    s = slave(guid=md.guid, unzipDirectory=fmpy.extract(str(path)), modelIdentifier=md.coSimulation.modelIdentifier,
              instanceName="s")  # fmt: skip
    if version == 2:
        s.instantiate(callbacks=make_callbacks(messages))
        s.setupExperiment(startTime=0.0)
    else:
        s.instantiate(logMessage=lambda env, status, category, message: messages.append(
            (int(status), category.decode(), message.decode())))  # fmt: skip
    return s


@needs_c_compiler
@pytest.mark.parametrize("version", [2, 3])
def test_do_step_outside_the_running_state_is_an_error(fmus, version):
    import fmpy


    messages: list = []
    s = _cs_slave(fmus[("MF61", version)], version, messages)
    with pytest.raises(fmpy.fmi1.FMICallException):  # before initialisation
        s.doStep(0.0, 1e-3)
    if version == 2:
        s.enterInitializationMode()
    else:
        s.enterInitializationMode(startTime=0.0)
    with pytest.raises(fmpy.fmi1.FMICallException):  # in initialisation mode
        s.doStep(0.0, 1e-3)
    s.exitInitializationMode()
    s.doStep(0.0, 1e-3)  # the right state
    s.terminate()
    with pytest.raises(fmpy.fmi1.FMICallException):  # after terminate
        s.doStep(1e-3, 1e-3)
    s.freeInstance()
    assert sum("DoStep is not allowed in state" in m for _, _, m in messages) == 3, messages


@needs_c_compiler
@pytest.mark.parametrize("version", [2, 3])
def test_functions_the_fmu_does_not_implement_are_refused_by_name(fmus, version):
    """The standard's functions the FMU does not implement (FMU states, clocks, configuration mode, types
    without variables) return an error naming them; FMI 2's status queries answer the last successful time and
    'not terminated' and discard the other kinds; an empty access of a type without variables is fine."""
    import ctypes

    messages: list = []
    s = _cs_slave(fmus[("MF61", version)], version, messages)
    ok, discard, error = 0, 2, 3
    if version == 2:
        s.enterInitializationMode()
        s.exitInitializationMode()
        s.doStep(0.0, 0.25)
        c, dll = ctypes.c_void_p(s.component), ctypes.CDLL(s.dll._name)  # no argument types: the pointer as such
        real, boolean, state = ctypes.c_double(-1.0), ctypes.c_int(7), ctypes.c_void_p()
        assert dll.fmi2GetRealStatus(c, 2, ctypes.byref(real)) == ok and real.value == 0.25  # last successful time
        assert dll.fmi2GetRealStatus(c, 0, ctypes.byref(real)) == discard
        assert dll.fmi2GetBooleanStatus(c, 3, ctypes.byref(boolean)) == ok and boolean.value == 0  # not terminated
        assert dll.fmi2GetBooleanStatus(c, 2, ctypes.byref(boolean)) == discard
        assert dll.fmi2GetIntegerStatus(c, 2, ctypes.byref(boolean)) == discard
        assert dll.fmi2GetRealStatus(None, 2, ctypes.byref(real)) == error
        assert dll.fmi2GetBoolean(c, None, ctypes.c_size_t(0), None) == ok
        vr, value = (ctypes.c_uint * 1)(0), (ctypes.c_int * 1)()
        refused = {"fmi2GetBoolean": dll.fmi2GetBoolean(c, vr, ctypes.c_size_t(1), value),
                   "fmi2GetFMUstate": dll.fmi2GetFMUstate(c, ctypes.byref(state)),
                   "fmi2CancelStep": dll.fmi2CancelStep(c)}  # fmt: skip
        texts = {"fmi2GetBoolean": "no Boolean variables", "fmi2GetFMUstate": "fmi2GetFMUstate is not supported",
                 "fmi2CancelStep": "fmi2CancelStep is not supported"}  # fmt: skip
    else:
        c, dll = ctypes.c_void_p(s.component), ctypes.CDLL(s.dll._name)  # no argument types: the pointer as such
        state, vr = ctypes.c_void_p(), (ctypes.c_uint * 1)(0)
        values, q = (ctypes.c_double * 1)(), (ctypes.c_int * 1)()
        assert dll.fmi3GetClock(c, None, ctypes.c_size_t(0), None) == ok
        refused = {"fmi3GetFMUState": dll.fmi3GetFMUState(c, ctypes.byref(state)),
                   "fmi3GetFloat32": dll.fmi3GetFloat32(c, vr, ctypes.c_size_t(1), values, ctypes.c_size_t(1)),
                   "fmi3GetClock": dll.fmi3GetClock(c, vr, ctypes.c_size_t(1), values),
                   "fmi3GetIntervalDecimal": dll.fmi3GetIntervalDecimal(c, vr, ctypes.c_size_t(1), values, q),
                   "fmi3EnterConfigurationMode": dll.fmi3EnterConfigurationMode(c)}  # fmt: skip
        texts = {"fmi3GetFMUState": "fmi3GetFMUState is not supported",
                 "fmi3GetFloat32": "fmi3GetFloat32: the model has no variables of this type",
                 "fmi3GetClock": "the model has no clocks", "fmi3GetIntervalDecimal": "the model has no clocks",
                 "fmi3EnterConfigurationMode": "the model has no structural parameters"}  # fmt: skip
    assert refused == dict.fromkeys(refused, error)
    errors = [m for st, _, m in messages if st == error]
    assert len(errors) == len(refused) and all(any(t in m for m in errors) for t in texts.values()), errors
    s.freeInstance()


@needs_c_compiler
@pytest.mark.parametrize("version", [2, 3])
def test_non_physical_parameters_are_refused(fmus, version):
    from fmpy.fmi1 import FMICallException

    from mftire.fmu.host import FMUTyre

    with FMUTyre(fmus[("MF61", version)], "CS") as fmu:
        before = fmu.evaluate(4000.0, 0.05, 0.03)
        for key, value in (("FNOMIN", 0.0), ("FNOMIN", -1.0), ("FNOMIN", math.nan), ("UNLOADED_RADIUS", 0.0),
                           ("PCX1", math.inf), ("WIDTH", -0.1)):  # fmt: skip
            with pytest.raises(FMICallException):
                fmu.set({key: value})
            assert any(s == 3 and key in m for s, _, m in fmu.messages), (key, fmu.messages[-3:])
        assert fmu.get(["FNOMIN"])[0] == load(REFERENCE_TYRES["MF61"])["FNOMIN"]  # kept its value
        assert fmu.evaluate(4000.0, 0.05, 0.03) == before  # still usable, unchanged
    # a non-physical start value fails the initialisation
    with pytest.raises(FMICallException):
        FMUTyre(fmus[("MF61", version)], "ME", start_values={"RIM_RADIUS": -1.0})


@needs_c_compiler
def test_archive_documentation_and_licence(fmus):
    from fmpy.validation import validate_fmu

    path = fmus[("MF61", 3)]
    assert validate_fmu(str(path)) == []
    with zipfile.ZipFile(path) as z:
        page = z.read("documentation/index.html").decode()
        licence = z.read("documentation/licenses/license.txt").decode()
    for text in ("Inputs", "Outputs", "Axes", "ISO-W", "Modes", "useMode", "Validity", "Licence", "kappa",
                 "Fz_out", "Mzr", "muRoad", "Vertical load Fz", "license.txt"):
        assert text in page, text
    tyre = load(REFERENCE_TYRES["MF61"])
    assert f"{tyre['FZMAX']:g}" in page
    assert "BSD 3-Clause" in licence and "Modelica" in licence


@needs_c_compiler
def test_one_mode_variable_and_identifiers_that_never_collide(fmus, tmp_path):
    import fmpy

    md = fmpy.read_model_description(str(fmus[("MF61", 2)]))
    names = {v.name for v in md.modelVariables}
    assert "useMode" in names and "USE_MODE" not in names  # issue 26.9: one mode name
    mode = next(v for v in md.modelVariables if v.name == "useMode")
    assert "one mode switch" in mode.description
    # two tyres from files of the same name: different identifiers (a short hash of the parameters)
    tyre = load(REFERENCE_TYRES["MF61"])
    (tmp_path / "a").mkdir()
    shutil.copy(REFERENCE_TYRES["MF61"], tmp_path / "a" / "tyre.tir")
    flat_b = dict(tyre.flat, PCX1=tyre["PCX1"] * 1.01)  # another tyre, also named "tyre"
    ids = []
    for src in (tmp_path / "a" / "tyre.tir", flat_b):
        out = export_fmu(src, tmp_path / f"{len(ids)}.fmu")
        ids.append(fmpy.read_model_description(str(out)).coSimulation.modelIdentifier)
    assert ids[0] != ids[1] and ids[0].startswith("tyre_")
    # the user's name is kept
    out = export_fmu(tyre, tmp_path / "named.fmu", model_identifier="front_left")
    assert fmpy.read_model_description(str(out)).coSimulation.modelIdentifier == "front_left"


@needs_c_compiler
@pytest.mark.parametrize("version", [2, 3])
def test_mode_and_fittyp_are_checked_when_set_in_initialisation_mode(fmus, version):
    """An output's evaluation does not check useMode and FITTYP (mf_evaluate_unchecked): the FMU refuses a bad
    value when it is set, also in initialisation mode, and keeps the last good one, so a read before
    ExitInitializationMode evaluates the valid model."""
    import fmpy

    md = fmpy.read_model_description(str(fmus[("MF61", version)]))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    messages: list = []
    s = _cs_slave(fmus[("MF61", version)], version, messages)
    if version == 2:
        s.enterInitializationMode()
        set_real, get_real, set_int = s.setReal, s.getReal, s.setInteger
    else:
        s.enterInitializationMode(startTime=0.0)
        set_real, get_real, set_int = s.setFloat64, s.getFloat64, s.setInt32
    set_real([vr["Fz"]], [4000.0])
    set_real([vr["kappa"]], [0.05])
    fx = get_real([vr["Fx"]])[0]
    with pytest.raises(fmpy.fmi1.FMICallException):
        set_real([vr["FITTYP"]], [7.0])
    with pytest.raises(fmpy.fmi1.FMICallException):
        set_int([vr["useMode"]], [311])
    assert any(s == 3 and "FITTYP" in m for s, _, m in messages), messages
    assert any(s == 3 and "hundreds digit" in m for s, _, m in messages), messages
    set_real([vr["Fz"]], [4000.0])  # marks the outputs for a new evaluation
    assert get_real([vr["Fx"]])[0] == fx and 1000.0 < fx < 8000.0
    s.terminate()
    s.freeInstance()
