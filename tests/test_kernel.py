"""The compiled array kernel (mftire/mf/kernel.py, mftire/mf/c/mf_kernel.c) agrees
with the numpy reference to 1e-12 in every mode, for every model family, with and without
model extensions, at edge inputs, with the same warnings; ``channels=`` and the backend
switch work in both paths.

Tolerance: forces |Δ| <= 1e-12·FNOMIN, moments |Δ| <= 1e-12·FNOMIN·R0, other channels
|Δ| <= 1e-12·max(|numpy|, scale of the channel); instKya, a finite difference between
neighbouring points, within 1e-12 of FNOMIN over the slip-angle step.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import DATA, REFERENCE_TYRES, TIR, have_c_compiler

from mftire import Tyre, load
from mftire.iotools.tir import read_tir
from mftire.mf import _kernel_build, kernel, solver
from mftire.mf.extensions import SECTION
from mftire.mf.solver import OUTPUT_NAMES

ROOT = Path(__file__).resolve().parents[1]
MODES = (111, 121, 211, 221, 110, 120, 210, 112, 212, 222)
FILES = {
    "MF52": REFERENCE_TYRES["MF52"],
    "MF61": REFERENCE_TYRES["MF61"],
    "MF62": REFERENCE_TYRES["MF62"],
    "FSAE": REFERENCE_TYRES["FSAE"],
    "PacejkaBook": REFERENCE_TYRES["PacejkaBook"],
    "JuliaMF62": REFERENCE_TYRES["JuliaMF62"],
    "PAC2002": TIR / "chrono_HMMWV_Pac02Tire.tir",
    "PAC2002-bus": DATA / "tir_wild" / "chrono_CityBus_Pac02Tire.tir",
    "shipped-MF62": ROOT / "tirfiles" / "MagicFormula62_Parameters.tir",
    "shipped-MF52": ROOT / "tirfiles" / "MagicFormula52_Parameters.tir",
}
FORCES = ("Fx", "Fy", "Fz")
MOMENTS = ("Mx", "My", "Mz", "Mzr")
LENGTHS = ("Re", "rho", "2a", "t", "Rl", "2b", "sigmax", "sigmay")


@pytest.fixture(scope="module", autouse=True)
def kernel_lib(tmp_path_factory):
    """The kernel: the installed one, else compiled here (a source checkout); in CI it must exist."""
    if not kernel.available():
        if not have_c_compiler():
            if os.environ.get("CI"):
                pytest.fail("no C compiler in CI: the kernel cannot be built")
            pytest.skip("no C compiler: the kernel cannot be built")
        lib = _kernel_build.compile_library(ROOT, tmp_path_factory.mktemp("kernel") / _kernel_build.LIBRARY)
        assert kernel.load(lib) is not None, kernel.status()
    return kernel.load()


def test_headers_are_generated_from_the_tables():
    """mftire/mf/c/kernel/*.h are the output of the generator (regenerate with
    ``python -m mftire.mf.cheaders``)."""
    from mftire.mf.cheaders import kernel_headers

    d = ROOT / "mftire" / "mf" / "c" / "kernel"
    for name, text in kernel_headers().items():
        assert (d / name).read_text(encoding="utf-8") == text, name


def test_installed_package_uses_the_kernel():
    """After ``pip install .`` (CI) the kernel built by the installation is the one in use, also from
    the source checkout (whose own ``mftire.egg-info`` lists no library)."""
    from importlib.metadata import distributions

    files = [f for d in distributions(name="mftire") for f in (d.files or ())]
    if not files:
        pytest.skip("mftire is not installed")
    if not any(f.as_posix() == "mftire/mf/" + _kernel_build.LIBRARY for f in files):
        pytest.skip("an installation without a built kernel (editable, or no compiler)")
    assert kernel.available(), kernel.status()


def _inputs(tyre: Tyre, n: int, seed: int) -> dict[str, np.ndarray]:
    """Random operating points with the edge cases in front: standstill, reversing, low speed,
    lift-off, zero load, loads and slips beyond the limits, NaN in every input."""
    p = tyre.flat
    F0 = p["FNOMIN"]
    rng = np.random.default_rng(seed)
    x = dict(
        Fz=rng.uniform(0.05 * F0, 2.0 * F0, n),
        kappa=rng.uniform(-0.6, 0.6, n),
        alpha=rng.uniform(-0.4, 0.4, n),
        gamma=rng.uniform(-0.1, 0.1, n),
        phit=rng.uniform(-0.5, 0.5, n),
        Vx=rng.uniform(2.0, 40.0, n),
    )
    x["Vx"][:6] = [0.0, -0.0, 0.3, -0.5, -10.0, p["VXLOW"]]
    x["Fz"][6:10] = [-100.0, 0.0, 1e-9, 5.0 * F0]
    x["kappa"][10:13] = [-1.0, 2.0, -3.0]
    x["alpha"][13:15] = [1.2, -1.4]
    x["gamma"][15:17] = [0.4, -0.4]
    for k, name in enumerate(("Fz", "kappa", "alpha", "gamma", "phit", "Vx")):
        x[name][20 + k] = np.nan
    return x


def _tol(name: str, b: np.ndarray, p) -> np.ndarray:
    F0, R0 = p["FNOMIN"], p["UNLOADED_RADIUS"]
    scale = {**dict.fromkeys(FORCES, F0), **dict.fromkeys(MOMENTS, F0 * R0), **dict.fromkeys(LENGTHS, R0),
             "Kya": F0, "Kxk": F0, "mux": 1.0, "muy": 1.0}.get(name, 0.0)  # fmt: skip
    return 1e-12 * np.maximum(np.abs(b), scale)


def _agree(a: dict, b: dict, p, alpha_c: np.ndarray | None = None) -> None:
    assert list(a) == list(b)
    for k in b:
        A, B = np.asarray(a[k]), np.asarray(b[k])
        assert A.shape == B.shape, k
        nan = np.isnan(B)
        np.testing.assert_array_equal(np.isnan(A), nan, err_msg=f"NaN pattern of {k}")
        inf = np.isinf(B)
        np.testing.assert_array_equal(A[inf], B[inf], err_msg=k)
        ok = ~(nan | inf)
        if k == "instKya":
            if alpha_c is None or B.size < 2:
                tol = _tol("Fy", B, p)
            else:  # dFy/dalpha: the force tolerance over the slip-angle step
                step = np.abs(np.diff(alpha_c.ravel()))
                step = np.append(step, step[-1]).reshape(B.shape)
                with np.errstate(divide="ignore"):
                    tol = 1e-12 * np.abs(B) + 4e-12 * p["FNOMIN"] / step
        else:
            tol = _tol(k, B, p)
        with np.errstate(invalid="ignore"):  # inf - inf where both are inf (compared through `ok`)
            err = np.abs(A - B)
        bad = ok & ~(err <= tol)
        assert not bad.any(), f"{k}: kernel {A[bad][:3]} numpy {B[bad][:3]} (max error {np.max(err[ok]):.3g})"


def _both(tyre: Tyre, **kw):
    """(kernel result, its warnings, numpy result, its warnings); checks that the kernel ran
    (the array path, kernel.evaluate, or the latency path of scalar calls, kernel.point_function)."""
    out, ran = [], []
    real, real_point = kernel.evaluate, kernel.point_function

    def spy(*args, **kwargs):
        res = real(*args, **kwargs)
        ran.append(res is not None)
        return res

    def spy_point(*args, **kwargs):
        f = real_point(*args, **kwargs)

        def counted(*a, **k):
            res = f(*a, **k)
            ran.append(res is not None)
            return res

        return None if f is None else counted

    for backend in ("kernel", "numpy"):
        with warnings.catch_warnings(record=True) as rec:
            warnings.simplefilter("always")
            kernel.evaluate, kernel.point_function = spy, spy_point
            tyre._point = None  # prepared again, through the spy
            tyre.flat.__dict__.pop("_kernel_point", None)
            try:
                res = tyre.evaluate(backend=backend, **kw)
            finally:
                kernel.evaluate, kernel.point_function = real, real_point
                tyre._point = None
                tyre.flat.__dict__.pop("_kernel_point", None)
        out += [res, [(w.category, str(w.message)) for w in rec]]
    assert ran and all(ran), "the kernel path fell back to numpy"
    return out


@pytest.mark.filterwarnings("ignore::mftire.mf.inputs.MFLimitWarning")  # inputs beyond the limits on purpose
@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("name", list(FILES))
def test_kernel_agrees_with_numpy(name, mode):
    tyre = load(FILES[name])
    x = _inputs(tyre, 400, mode)
    a, wa, b, wb = _both(tyre, **x, mode=mode)
    assert wa == wb
    alpha_c = solver.prepare(tyre.flat, **x, P=None, omega=None, mode=mode, variables=None).c.alpha
    _agree(a, b, tyre.flat, alpha_c)


def _every_file() -> list[Path]:
    """Every .tir shipped in tirfiles/ and tests/data that the evaluator evaluates."""
    out = []
    for path in sorted({*ROOT.glob("tirfiles/**/*.tir"), *DATA.glob("**/*.tir")}):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                tyre = load(path)
                tyre.evaluate(tyre["FNOMIN"], 0.0, 0.0, backend="numpy")
        except Exception:  # unreadable, MF_05, broken on purpose: not evaluated by either path
            continue
        out.append(path)
    return out


@pytest.mark.filterwarnings("ignore::mftire.mf.inputs.MFLimitWarning")  # inputs beyond the limits on purpose
@pytest.mark.parametrize("mode", (111, 221, 110, 212))
@pytest.mark.parametrize("path", _every_file(), ids=lambda p: p.name)
def test_kernel_agrees_on_every_shipped_file(path, mode):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tyre = load(path)
    x = _inputs(tyre, 150, mode)
    a, wa, b, wb = _both(tyre, **x, mode=mode)
    assert wa == wb
    _agree(a, b, tyre.flat, solver.prepare(tyre.flat, **x, P=None, omega=None, mode=mode, variables=None).c.alpha)


@pytest.mark.parametrize("mode", (111, 212))
def test_given_speed_pressure_and_spin(mode):
    """omega and P given (with NaN, zeros and non-positive pressures), broadcast from scalars and
    rows, a 2-D batch; and a batch where omega is all zero (estimated)."""
    tyre = load(FILES["MF62"])
    F0, P0 = tyre["FNOMIN"], tyre["INFLPRES"]
    rng = np.random.default_rng(1)
    Fz = rng.uniform(0.2, 1.8, (7, 9)) * F0
    omega = rng.uniform(-20.0, 120.0, (7, 9))
    omega[0, :3] = [0.0, np.nan, -0.0]
    P = rng.uniform(0.7, 1.4, 9) * P0
    P[:3] = [np.nan, 0.0, -1.0]
    for kw in (dict(omega=omega, P=P), dict(omega=np.zeros(9), P=P0), dict(omega=50.0)):
        a, wa, b, wb = _both(tyre, Fz=Fz, kappa=0.05, alpha=rng.uniform(-0.2, 0.2, (7, 1)), gamma=0.02,
                             Vx=rng.uniform(-5, 30, (7, 9)), mode=mode, **kw)  # fmt: skip
        assert wa == wb
        _agree(a, b, tyre.flat)


def test_batch_rolling_radius_iteration_is_the_numpy_one():
    """MFeval's batch semantics: the Re iteration of a batch stops when any point converges,
    so a point's Re depends on the batch -- the kernel reproduces it."""
    tyre = load(FILES["MF61"])
    Vx = np.array([0.0, 35.0])
    single = tyre.evaluate(4000.0, 0.2, 0.0, Vx=35.0)["Re"]
    a, _, b, _ = _both(tyre, Fz=4000.0, kappa=0.2, alpha=0.0, Vx=Vx)
    assert a["Re"][1] == pytest.approx(b["Re"][1], rel=1e-14)
    assert abs(b["Re"][1] - single) > 1e-7  # the batch effect is real
    # the point that sets the batch's count comes last (the kernel's first pass kept the radii of
    # the points from there on only): same values
    a2, _, b2, _ = _both(tyre, Fz=4000.0, kappa=0.2, alpha=0.0, Vx=Vx[::-1], channels=("Re", "omega", "Rl", "Fx"))
    assert a2["Re"][0] == pytest.approx(b2["Re"][0], rel=1e-14) and b2["Re"][0] == pytest.approx(b["Re"][1], rel=1e-14)
    _agree(a2, b2, tyre.flat)


def test_scalars_and_tiny_batches():
    tyre = load(FILES["MF61"])
    a, wa, b, wb = _both(tyre, Fz=4500.0, kappa=-0.07, alpha=0.03, gamma=0.01)
    assert wa == wb
    assert all(isinstance(v, np.float64) for v in a.values())
    assert all(isinstance(v, np.float64) for v in b.values())
    _agree(a, b, tyre.flat)
    assert a["instKya"] == b["instKya"] == 0.0
    for kw in (dict(omega=30.0, P=2.1e5, Vx=12.0, phit=0.1), dict(Vx=float("nan"), omega=0.0, P=-1.0),
               dict(Fz=-5.0, Vx=0.0, gamma=0.5), dict(kappa=float("nan"), Vx=0.2)):  # fmt: skip
        for mode in (111, 212, 110):
            a, wa, b, wb = _both(tyre, **{"Fz": 4500.0, "kappa": -0.07, "alpha": 0.03, **kw}, mode=mode)
            assert wa == wb
            _agree(a, b, tyre.flat)
            a, _, b, _ = _both(tyre, **{"Fz": 4500.0, "kappa": -0.07, "alpha": 0.03, **kw}, channels=("Mz", "instKya"))
            _agree(a, b, tyre.flat)
    for n in (0, 1, 2):
        a, _, b, _ = _both(tyre, Fz=np.full(n, 4000.0), kappa=np.linspace(0, 0.1, n), alpha=0.02)
        _agree(a, b, tyre.flat)
        assert a["Fx"].shape == (n,)


EXTENDED = {
    "EXT1_TARGET": "LMUX LMUY", "EXT1_FORM": "decay", "EXT1_VARIABLE": "Vs", "EXT1_SCALE": 16.7, "EXT1_C1": 0.4,
    "EXT2_TARGET": "LKX LKY LTR", "EXT2_FORM": "linear", "EXT2_VARIABLE": "temperature", "EXT2_REF": 50.0,
    "EXT2_SCALE": 25.0, "EXT2_MIN": 0.0, "EXT2_MAX": 90.0, "EXT2_C1": -0.1,
    "EXT3_TARGET": "FX_OFFSET", "EXT3_FORM": "linear", "EXT3_VARIABLE": "sign_kappa", "EXT3_C1": 0.005,
    "EXT4_TARGET": "LEY FY_OFFSET", "EXT4_FORM": "interaction", "EXT4_VARIABLE": "wear",
    "EXT4_VARIABLE2": "temperature", "EXT4_C1": 0.05, "EXT4_C2": -0.03, "EXT4_SCALE2": 30.0,
    # a table in any order of its levels, linear between them (dfz is continuous here)
    "EXT5_TARGET": "LKYC LMY", "EXT5_FORM": "table", "EXT5_VARIABLE": "dfz", "EXT5_L1": 0.5, "EXT5_L2": -0.5,
    "EXT5_L3": 0.0, "EXT5_C1": -0.1, "EXT5_C2": 0.1, "EXT5_C3": 0.0,
    "EXT6_TARGET": "LRES", "EXT6_FORM": "saturating", "EXT6_VARIABLE": "P", "EXT6_REF": 2.2e5, "EXT6_SCALE": 5e4,
    "EXT6_C1": 0.3, "EXT6_C2": 2.0,
    # the constant part of an offset law (mftire.diagnosis.effects.intercept_term): a one-level table, summed with
    # EXT4's FY_OFFSET; a slip-angle offset growing with temperature (instKya: along the slip angle as given)
    "EXT7_TARGET": "FY_OFFSET", "EXT7_FORM": "table", "EXT7_VARIABLE": "wear", "EXT7_L1": 0.5, "EXT7_C1": 0.01,
    "EXT8_TARGET": "ALPHA_OFFSET", "EXT8_FORM": "linear", "EXT8_VARIABLE": "temperature", "EXT8_REF": 50.0,
    "EXT8_SCALE": 50.0, "EXT8_C1": 0.004,
}  # fmt: skip


@pytest.mark.parametrize("mode", (111, 121, 211, 110, 112, 222))
@pytest.mark.parametrize("base", ("MF61", "MF62", "MF52", "PAC2002"))
def test_kernel_agrees_with_extensions(base, mode):
    params = read_tir(FILES[base])
    for k, v in EXTENDED.items():
        params.set(k, v, section=SECTION)
    tyre = Tyre(params, name="ext.tir")
    x = _inputs(tyre, 300, mode)
    rng = np.random.default_rng(mode)
    temperature = rng.uniform(-20.0, 120.0, 300)
    temperature[30] = np.nan
    a, wa, b, wb = _both(tyre, **x, mode=mode, temperature=temperature, wear=rng.uniform(0.0, 1.0, (1, 300)))
    assert wa == wb
    assert any("'temperature'" in m for _, m in wa)
    _agree(a, b, tyre.flat)
    # a fitter varies the coefficients in the flat dict: the kernel packs them again
    tyre.flat["EXT1_C1"] = 1.5
    a, _, b, _ = _both(tyre, **x, mode=mode, temperature=temperature, wear=0.5)
    _agree(a, b, tyre.flat)


@pytest.mark.filterwarnings("ignore::mftire.mf.inputs.MFLimitWarning")
@pytest.mark.parametrize("backend", ("kernel", "numpy"))
def test_channels_compute_only_what_is_asked(backend):
    tyre = load(FILES["MF61"])
    x = _inputs(tyre, 200, 3)
    full = tyre.evaluate(**x, backend=backend)
    for names in (("Fx",), ("Fy", "instKya"), ("instKya",), ("Mz", "Re", "omega"), ("Cz", "2a", "sigmay"), "My"):
        part = tyre.evaluate(**x, channels=names, backend=backend)
        assert list(part) == ([names] if isinstance(names, str) else list(names))
        for k in part:
            np.testing.assert_array_equal(part[k], full[k], err_msg=k)
    # what is not asked is not computed: a lateral curvature factor above 1 warns only with Fy
    flat = dict(tyre.flat, PEY1=1.5, PEY2=0.0, PEY3=0.0, PEY4=0.0, PEY5=0.0)
    hot = Tyre(flat)
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        hot.evaluate(4000.0, 0.1, 0.1, channels=("Fx", "Re"), backend=backend)
        assert not any("Ey over limit" in str(w.message) for w in rec)
        hot.evaluate(4000.0, 0.1, 0.1, channels="Fy", backend=backend)
        assert any("Ey over limit" in str(w.message) for w in rec)
    with pytest.raises(ValueError, match="unknown output channel.*'FX'"):
        tyre.evaluate(4000.0, 0.0, 0.0, channels=("FX",), backend=backend)


def test_backend_switch(monkeypatch):
    tyre = load(FILES["MF61"])
    ref = tyre.evaluate(4000.0, 0.1, 0.05, backend="numpy")

    def boom(*args, **kw):
        raise AssertionError("the kernel was called")

    monkeypatch.setattr(kernel, "evaluate", boom)
    monkeypatch.setattr(kernel, "point_function", boom)  # the latency path of scalar calls
    monkeypatch.setenv("MFTIRE_BACKEND", "numpy")
    monkeypatch.setattr(kernel, "_env", None)  # read again, as at the start of a process
    assert tyre.evaluate(4000.0, 0.1, 0.05) == ref  # the environment forces numpy
    with pytest.raises(AssertionError, match="the kernel was called"):
        tyre.evaluate(4000.0, 0.1, 0.05, backend="kernel")
    monkeypatch.delenv("MFTIRE_BACKEND")
    kernel._env = None
    with pytest.raises(AssertionError, match="the kernel was called"):
        tyre.evaluate(4000.0, 0.1, 0.05)
    with pytest.raises(ValueError, match="backend must be"):
        tyre.evaluate(4000.0, 0.1, 0.05, backend="fortran")
    monkeypatch.setattr(kernel, "_lib", False)
    monkeypatch.setattr(kernel, "_why", "no compiled kernel found (test)")
    assert tyre.evaluate(4000.0, 0.1, 0.05) == ref  # the documented fallback
    with pytest.raises(kernel.KernelUnavailableError, match="no compiled kernel found"):
        tyre.evaluate(4000.0, 0.1, 0.05, backend="kernel")


def test_stale_library_is_refused(monkeypatch, kernel_lib):
    """A library built from other C sources than those shipped is not used."""
    monkeypatch.setattr(kernel, "_lib", None)
    monkeypatch.setattr(kernel, "_why", "")
    monkeypatch.setattr(_kernel_build, "source_hash", lambda root: "0123456789abcdef")
    assert kernel.load(kernel_lib._name) is None
    assert "built from other C sources" in kernel.status()


def test_errors_are_the_numpy_ones():
    tyre = load(FILES["MF61"])
    for backend in ("kernel", "numpy"):
        with pytest.raises(Exception, match="cannot be broadcast") as e:
            tyre.evaluate(np.ones(3) * 4000, np.zeros(4), 0.0, backend=backend)
        with pytest.raises(Exception, match="useMode|mode") as e2:
            tyre.evaluate(4000.0, 0.0, 0.0, mode=131, backend=backend)
        if backend == "kernel":
            first = (type(e.value), str(e.value), type(e2.value), str(e2.value))
    assert first == (type(e.value), str(e.value), type(e2.value), str(e2.value))
    assert set(OUTPUT_NAMES) == set(kernel.OUTPUTS) and OUTPUT_NAMES == kernel.OUTPUTS


def test_per_point_parameters_take_the_numpy_path():
    """A scaling factor given per point (an array in ``Tyre.flat``, as validation/make_rig_file.py
    does) is evaluated by the numpy path, which broadcasts parameters."""
    tyre = load(FILES["MF61"])
    x = _inputs(tyre, 60, 4)
    tyre.flat["LMUX"] = np.linspace(0.5, 1.5, 60)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a, b = tyre.evaluate(**x), tyre.evaluate(**x, backend="numpy")
    for k in b:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)
    assert np.ptp(a["mux"][30:]) > 0.1
