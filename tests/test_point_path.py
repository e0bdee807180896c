"""The latency path of scalar calls (``Tyre.evaluate`` -> :func:`mftire.mf.kernel.point_function`
-> ``mf_kernel_point``) keeps the semantics of the array path: the same numbers bit for bit (the
array path at one point: 1-element and 0-d arrays), the same types (an ``MFResult`` of numpy
scalars in the order of ``OUTPUT_NAMES``), the same warnings with the same texts at the same
place (the caller's line), the same errors; it follows changes of the parameters, the extension
set, the library and the backend, and is safe across threads and re-entrant warning handlers.
"""

from __future__ import annotations

import copy
import gc
import math
import pickle
import threading
import warnings
import weakref

import numpy as np
import pytest
from conftest import REFERENCE_TYRES, TIR
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mftire import OUTPUT_NAMES, MftireInputError, Tyre, load, read_tir
from mftire.errors import MftireUnitWarning
from mftire.mf import kernel
from mftire.mf.extensions import SECTION
from mftire.mf.solver import UnsupportedModelError
from mftire.tyre import MFResult

pytestmark = pytest.mark.skipif(not kernel.available(), reason="the compiled kernel is not built")

FILES = {
    "MF52": REFERENCE_TYRES["MF52"],
    "MF61": REFERENCE_TYRES["MF61"],
    "MF62": REFERENCE_TYRES["MF62"],
    "PAC2002": TIR / "chrono_HMMWV_Pac02Tire.tir",
    "JuliaMF62": REFERENCE_TYRES["JuliaMF62"],
}
MODES = (111, 121, 211, 221, 110, 120, 210, 112, 212, 222)
TEMPERATURE = {  # two extension terms: one reads a data variable, one a builtin (the slip speed)
    "EXT1_TARGET": "LMUX LMUY", "EXT1_FORM": "decay", "EXT1_VARIABLE": "Vs", "EXT1_SCALE": 16.7, "EXT1_C1": 0.4,
    "EXT2_TARGET": "LKX LKY FY_OFFSET", "EXT2_FORM": "linear", "EXT2_VARIABLE": "temperature", "EXT2_REF": 50.0,
    "EXT2_SCALE": 25.0, "EXT2_MIN": 0.0, "EXT2_MAX": 90.0, "EXT2_C1": -0.1,
}  # fmt: skip
NAN = float("nan")


def _tyres() -> dict[str, Tyre]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return {k: load(v) for k, v in FILES.items()}


TYRES = _tyres()


def _evaluate(tyre: Tyre, kw: dict):
    """``tyre.evaluate(**kw)`` with every warning recorded as (category, text, file, line): every
    path is called from this one line, so that the warnings' places can be compared."""
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        out = tyre.evaluate(**kw)  # the one line
    return out, [(w.category, str(w.message), w.filename, w.lineno) for w in rec]


def _fresh(tyre: Tyre) -> Tyre:
    """The tyre with its unit warnings not given yet (they are given once per tyre)."""
    tyre.__dict__.pop("_unit_warned", None)
    return tyre


def _as(kw: dict, form) -> dict:
    """The operating-point inputs of ``kw`` as ``form`` (None stays None)."""
    names = ("Fz", "kappa", "alpha", "gamma", "phit", "Vx", "P", "omega")
    return {k: (form(v) if k in names and v is not None else v) for k, v in kw.items()}


def _same_bits(a, b) -> bool:
    return np.asarray(a, dtype=float).tobytes() == np.asarray(b, dtype=float).tobytes()


def _latency_path(tyre: Tyre, kw: dict):
    """``_evaluate(tyre, kw)``, checking that the latency path evaluated (not the array path)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tyre.evaluate(np.array(4000.0), 0.0, 0.0, mode=kw.get("mode", 111))  # the mode is checked once
    real = kernel.evaluate

    def boom(*args, **kwargs):
        raise AssertionError("the latency path was not taken")

    kernel.evaluate = boom
    try:
        return _evaluate(_fresh(tyre), kw)
    finally:
        kernel.evaluate = real


def _check_point(tyre: Tyre, kw: dict) -> None:
    """The latency path against the array path at one point (1-element and 0-d arrays)."""
    if tyre.required_variables:  # the general path, kernel.point_function through kernel.evaluate
        fast, w_fast = _evaluate(_fresh(tyre), kw)
    else:
        fast, w_fast = _latency_path(tyre, kw)
    row, w_row = _evaluate(_fresh(tyre), _as(kw, lambda v: np.array([v], dtype=float)))
    zero_d, w_zero_d = _evaluate(_fresh(tyre), _as(kw, lambda v: np.array(v, dtype=float)))
    assert type(fast) is MFResult and type(zero_d) is MFResult
    assert list(fast) == list(OUTPUT_NAMES) == list(row) == list(zero_d)
    for k in OUTPUT_NAMES:
        assert type(fast[k]) is np.float64 and type(zero_d[k]) is np.float64, k
        assert row[k].shape == (1,), k
        assert _same_bits(fast[k], row[k][0]) and _same_bits(fast[k], zero_d[k]), (k, fast[k], row[k][0])
    assert w_fast == w_row == w_zero_d


def _number(lo: float, hi: float, ints: bool = True):
    parts = [st.floats(lo, hi, allow_nan=False), st.just(NAN), st.just(0.0)]
    if ints:
        parts.append(st.integers(math.ceil(lo), math.floor(hi)))
    return st.one_of(*parts)


@st.composite
def _points(draw):
    name = draw(st.sampled_from(sorted(TYRES)))
    F0 = TYRES[name]["FNOMIN"]
    kw = dict(
        Fz=draw(st.one_of(_number(-0.2 * F0, 2.5 * F0), st.sampled_from([1e-9, 0.02 * F0, 4.0]))),
        kappa=draw(_number(-3.0, 3.0)),
        alpha=draw(_number(-2.0, 2.0)),  # beyond 1.5 rad: the degrees warning
        gamma=draw(_number(-0.6, 0.6, ints=False)),
        phit=draw(_number(-1.0, 1.0, ints=False)),
        Vx=draw(st.one_of(st.none(), _number(-40.0, 40.0), st.sampled_from([0.3, -0.5, 1e-3]))),
        P=draw(st.one_of(st.none(), _number(-1e5, 6e5))),
        omega=draw(st.one_of(st.none(), _number(-200.0, 200.0))),
        mode=draw(st.sampled_from(MODES)),
    )
    return name, kw


@settings(max_examples=250, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_points())
def test_latency_path_is_the_array_path_at_one_point(point):
    name, kw = point
    tyre = TYRES[name]
    _check_point(tyre, kw)
    # and the numpy reference gives the same warnings (its values: tests/test_kernel.py)
    a, wa = _evaluate(_fresh(tyre), kw)
    b, wb = _evaluate(_fresh(tyre), {**kw, "backend": "numpy"})
    assert [w[:2] for w in wa] == [w[:2] for w in wb]
    assert list(a) == list(b) and all(type(v) is np.float64 for v in b.values())


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("name", sorted(FILES))
def test_every_file_and_mode_at_edge_points(name, mode):
    tyre = TYRES[name]
    F0 = tyre["FNOMIN"]
    for kw in (
        dict(Fz=4000.0, kappa=-0.1, alpha=0.05, gamma=0.0, Vx=20.0),
        dict(Fz=0.8 * F0, kappa=0.02, alpha=-0.1, gamma=0.03, phit=0.2, Vx=15.0, P=2.0e5, omega=40.0),
        dict(Fz=-300.0, kappa=NAN, alpha=0.1, Vx=0.0),
        dict(Fz=3.0 * F0, kappa=2.0, alpha=1.2, gamma=-0.5, Vx=-10.0, P=0.0, omega=NAN),
        dict(Fz=F0, kappa=0.1, alpha=0.05, Vx=0.3),
        dict(Fz=int(F0), kappa=0, alpha=0, gamma=0, phit=0, Vx=30, P=250000, omega=0),
    ):
        _check_point(tyre, {**kw, "mode": mode})


def test_the_latency_path_is_taken_and_needs_no_array_path(monkeypatch):
    tyre = load(REFERENCE_TYRES["MF61"])
    ref = tyre.evaluate(4000.0, -0.1, 0.05, gamma=0.0, Vx=20.0)

    def boom(*args, **kw):
        raise AssertionError("the array path was called")

    monkeypatch.setattr(kernel, "evaluate", boom)
    out = tyre.evaluate(Fz=4000.0, kappa=-0.1, alpha=0.05, gamma=0.0, Vx=20.0)
    assert out == ref and tyre._point is not None
    for backend in ("auto", "kernel"):
        assert tyre.evaluate(4000.0, -0.1, 0.05, gamma=0.0, Vx=20.0, backend=backend) == ref
    with pytest.raises(AssertionError, match="array path"):  # channels: the general path
        tyre.evaluate(4000.0, -0.1, 0.05, channels=("Fx",))


def test_calls_with_mode_and_pressure_take_the_latency_path_from_the_first(monkeypatch):
    """``mode=`` (a code never used before in the process) and ``P=``: the latency path serves the first call
    already, with the array path's numbers."""
    from mftire.mf import solver

    tyre = load(REFERENCE_TYRES["MF61"])
    tyre.evaluate(4000.0, 0.0, 0.0)  # the backend is chosen at the first evaluation of the process
    refs = {mode: tyre.evaluate(np.array(4000.0), -0.1, 0.05, Vx=20.0, P=2.1e5, mode=mode) for mode in (221, 212)}
    saved = set(solver.CHECKED_MODES)
    solver.CHECKED_MODES.difference_update({221, 212})

    def boom(*args, **kw):
        raise AssertionError("the array path was called")

    monkeypatch.setattr(kernel, "evaluate", boom)
    try:
        for mode, ref in refs.items():
            out = tyre.evaluate(4000.0, -0.1, 0.05, Vx=20.0, P=2.1e5, mode=mode)
            assert list(out) == list(ref) and all(out[k] == ref[k] or (np.isnan(out[k]) and np.isnan(ref[k]))
                                                  for k in ref)  # fmt: skip
        with pytest.raises(MftireInputError):  # an invalid mode: the general path's error
            tyre.evaluate(4000.0, -0.1, 0.05, mode=311)
    finally:
        solver.CHECKED_MODES.update(saved)


def test_result_is_an_mfresult_of_numpy_scalars():
    tyre = TYRES["MF61"]
    out = tyre.evaluate(4000.0, -0.1, 0.05, Vx=20.0)
    assert type(out) is MFResult and out.units["Fx"] == "N"
    frame = out.to_frame()
    assert frame.shape == (1, 30) and list(frame.columns) == list(OUTPUT_NAMES)
    row = tyre.evaluate(np.array([4000.0]), -0.1, 0.05, Vx=20.0).to_frame()
    assert frame.equals(row)
    assert float(out["Fx"]) < -3000.0  # braking
    out["Fx"] = 0.0  # the caller's own dict: the next call is not affected
    assert tyre.evaluate(4000.0, -0.1, 0.05, Vx=20.0)["Fx"] == row["Fx"][0]


def test_unit_warnings_once_per_tyre_at_the_callers_line():
    """Degrees and kN: one MftireUnitWarning per tyre and cause, where the general path gives it."""
    general = OUTPUT_NAMES  # all channels named: the general path, same outputs
    for kw in (dict(Fz=4.0, kappa=0.0, alpha=0.05), dict(Fz=4000.0, kappa=0.0, alpha=5.0),
               dict(Fz=4.0, kappa=0.0, alpha=-10)):  # fmt: skip
        runs = []
        for channels in (None, general):
            tyre = load(REFERENCE_TYRES["MF61"])
            first = _evaluate(tyre, {**kw, "channels": channels})
            second = _evaluate(tyre, {**kw, "channels": channels})
            runs.append((first, second))
        (f1, f2), (g1, g2) = runs
        assert f1[1] == g1[1] and f2[1] == g2[1]
        assert any(w[0] is MftireUnitWarning for w in f1[1])
        assert not any(w[0] is MftireUnitWarning for w in f2[1])
        assert f1[0] == g1[0]


def test_errors_are_the_general_paths():
    tyre = load(REFERENCE_TYRES["MF61"])
    tyre.evaluate(4000.0, 0.0, 0.0)
    with pytest.raises(TypeError, match="did you mean 'Vx'"):
        tyre.evaluate(4000.0, 0.0, 0.0, vx=20.0)
    for bad in (311, 131, 111.5, "abc"):
        with pytest.raises(MftireInputError):
            tyre.evaluate(4000.0, 0.0, 0.0, mode=bad)
    with pytest.raises(ValueError, match="backend must be"):
        tyre.evaluate(4000.0, 0.0, 0.0, backend="fortran")
    with pytest.raises(MftireInputError, match="not numeric"):
        tyre.evaluate("4 kN", 0.0, 0.0)
    # (MF_05 files evaluate since issue 16: an unsupported FITTYP of a flat mapping is refused instead)
    old = Tyre(dict(tyre.flat, FITTYP=7))
    with pytest.raises(UnsupportedModelError, match="FITTYP 7 is not evaluated"):
        old.evaluate(4000.0, 0.0, 0.0)
    # other scalar types take the general path, with the same numbers
    ref = tyre.evaluate(4000.0, 0.1, 0.05, gamma=0.0)
    for other in (np.float32(0.1), np.int32(1)):
        out = tyre.evaluate(4000.0, float(other), 0.05, gamma=0.0)
        alt = tyre.evaluate(4000.0, other, 0.05, gamma=0.0)
        assert list(alt) == list(out) and all(_same_bits(alt[k], out[k]) for k in out)
    with pytest.raises(TypeError, match="kappa = True is a boolean"):  # a boolean is no slip (issue 24)
        tyre.evaluate(4000.0, True, 0.05, gamma=0.0)
    assert ref == tyre.evaluate(np.float64(4000.0), 0.1, 0.05, gamma=0)


def _extended() -> Tyre:
    params = read_tir(FILES["MF61"])
    for k, v in TEMPERATURE.items():
        params.set(k, v, section=SECTION)
    return Tyre(params, name="ext.tir")


def test_extension_variables_at_one_point():
    tyre = _extended()
    assert tyre.required_variables == ["temperature"]
    for temperature in (20.0, 75, NAN, -40.0):
        _check_point(tyre, dict(Fz=4500.0, kappa=0.05, alpha=-0.04, Vx=12.0, temperature=temperature))
    cold = tyre.evaluate(4500.0, 0.05, -0.04, temperature=0.0)
    hot = tyre.evaluate(4500.0, 0.05, -0.04, temperature=90.0)
    assert abs(float(cold["Fx"]) - float(hot["Fx"])) > 1.0  # the variable is read
    with pytest.raises(MftireInputError, match="temperature"):
        tyre.evaluate(4500.0, 0.05, -0.04)
    with pytest.raises(TypeError, match="did you mean 'temperature'"):
        tyre.evaluate(4500.0, 0.05, -0.04, temprature=20.0)
    # a tyre whose extensions read builtin variables only takes the latency path
    params = read_tir(FILES["MF62"])
    for k, v in TEMPERATURE.items():
        if k.startswith("EXT1"):
            params.set(k, v, section=SECTION)
    builtin = Tyre(params, name="vs.tir")
    _check_point(builtin, dict(Fz=4500.0, kappa=0.2, alpha=0.1, Vx=25.0))


def test_the_state_follows_changes(monkeypatch):
    tyre = load(REFERENCE_TYRES["MF61"])
    base = tyre.evaluate(4000.0, 0.1, 0.05)
    tyre.flat["LMUX"] = 0.5  # a fitter varies the parameters in place
    lower = tyre.evaluate(4000.0, 0.1, 0.05)
    assert abs(float(lower["Fx"])) < 0.7 * abs(float(base["Fx"]))
    _check_point(tyre, dict(Fz=4000.0, kappa=0.1, alpha=0.05))
    tyre.flat.update(LMUX=1.0)
    assert tyre.evaluate(4000.0, 0.1, 0.05) == base
    tyre.flat = dict(tyre.flat, LMUY=0.5)  # a plain dict: the general path (packed at each call)
    plain = tyre.evaluate(4000.0, 0.1, 0.05)
    assert plain["Fx"] == base["Fx"] and plain["Fy"] != base["Fy"]
    assert plain == tyre.evaluate(np.array(4000.0), 0.1, 0.05)
    ext = _extended()
    tyre = load(REFERENCE_TYRES["MF61"])
    tyre.evaluate(4000.0, 0.1, 0.05)
    tyre.extension_set, tyre.required_variables = ext.extension_set, ext.required_variables
    assert tyre.evaluate(4000.0, 0.1, 0.05, temperature=80.0) == ext.evaluate(4000.0, 0.1, 0.05, temperature=80.0)
    # the backend: MFTIRE_BACKEND=numpy read again, the library gone
    tyre = load(REFERENCE_TYRES["MF61"])
    tyre.evaluate(4000.0, 0.1, 0.05)
    ref = tyre.evaluate(4000.0, 0.1, 0.05, backend="numpy")
    monkeypatch.setenv("MFTIRE_BACKEND", "numpy")
    monkeypatch.setattr(kernel, "_env", None)
    assert tyre.evaluate(4000.0, 0.1, 0.05) == ref
    monkeypatch.setattr(kernel, "_env", "auto")
    monkeypatch.setattr(kernel, "_lib", False)
    assert tyre.evaluate(4000.0, 0.1, 0.05) == ref
    with pytest.raises(kernel.KernelUnavailableError):
        tyre.evaluate(4000.0, 0.1, 0.05, backend="kernel")


def test_copies_and_pickles_prepare_their_own():
    tyre = load(REFERENCE_TYRES["MF62"])
    ref = tyre.evaluate(4000.0, 0.1, 0.05)
    for other in (pickle.loads(pickle.dumps(tyre)), copy.deepcopy(tyre), copy.copy(tyre)):
        assert other.evaluate(4000.0, 0.1, 0.05) == ref
    assert tyre.evaluate(4000.0, 0.1, 0.05) == ref


def test_threads_have_their_own_buffer():
    tyre = TYRES["MF62"]
    rng = np.random.default_rng(3)
    x = rng.uniform([1e3, -0.3, -0.2], [8e3, 0.3, 0.2], (400, 3))
    points = [tuple(map(float, row)) for row in x]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = [tyre.evaluate(*x, Vx=25.0) for x in points]
        got: dict[int, list] = {}

        def work(i: int) -> None:
            got[i] = [tyre.evaluate(*x, Vx=25.0) for x in points]

        threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    assert all(got[i] == ref for i in range(4))


def test_a_warning_handler_may_evaluate_again():
    """A warning is issued after the outputs are taken from the thread's buffer."""
    tyre = load(REFERENCE_TYRES["MF61"])
    kw = dict(Fz=4000.0, kappa=0.1, alpha=0.05, Vx=NAN)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = tyre.evaluate(**kw)
    inner = []
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        warnings.showwarning = lambda *a, **k: inner.append(tyre.evaluate(7000.0, -0.2, -0.1, Vx=30.0))
        out = tyre.evaluate(**kw)
    assert inner and out == ref and inner[0] != ref


def test_a_tyre_is_freed_without_the_cycle_collector():
    """The prepared calls hold the packed parameters, not the parameter dict: no reference cycle."""
    tyre = load(REFERENCE_TYRES["MF61"])
    tyre.evaluate(4000.0, 0.1, 0.05)
    tyre.evaluate(4000.0, 0.1, 0.05, channels=("Fx", "Fy"))  # the general path's cached point function
    assert "_kernel_point" in tyre.flat.__dict__ and tyre._point is not None
    refs = weakref.ref(tyre), weakref.ref(tyre.flat)
    gc.disable()
    try:
        del tyre
        assert all(r() is None for r in refs)
    finally:
        gc.enable()
