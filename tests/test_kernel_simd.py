"""The vectorised lane loops of the compiled kernel (mftire/mf/c/mf_kernel.c).

The kernel evaluates blocks of up to 64 points, each padded to a multiple of 8 lanes with
copies of its first point.  A point's numbers must not depend on where it sits in a batch:
any permutation of a batch gives every point bit for bit the same outputs (except instKya,
a difference between neighbours), whatever the block boundaries.  A single point takes the
scalar path of the FMU's mf_evaluate.  The agreement with the numpy reference (1e-12) is
tests/test_kernel.py's.
"""

from __future__ import annotations

import platform
import shutil
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import DATA, REFERENCE_TYRES, TIR, have_c_compiler
from hypothesis import given, settings
from hypothesis import strategies as st

from mftire import load
from mftire.mf import _kernel_build, kernel
from mftire.mf.solver import OUTPUT_NAMES

FILES = {
    "MF61": REFERENCE_TYRES["MF61"],
    "MF62": REFERENCE_TYRES["MF62"],
    "MF52": REFERENCE_TYRES["MF52"],
    "PAC2002": TIR / "chrono_HMMWV_Pac02Tire.tir",
    "PAC2002-bus": DATA / "tir_wild" / "chrono_CityBus_Pac02Tire.tir",
}
TYRES = {k: load(v) for k, v in FILES.items()}
CHANNELS = [k for k in OUTPUT_NAMES if k != "instKya"]


@pytest.fixture(scope="module", autouse=True)
def kernel_lib(tmp_path_factory):
    if not kernel.available():
        if not have_c_compiler():
            pytest.skip("no C compiler: the kernel cannot be built")
        from pathlib import Path

        root = Path(__file__).resolve().parents[1]
        lib = _kernel_build.compile_library(root, tmp_path_factory.mktemp("kernel") / _kernel_build.LIBRARY)
        assert kernel.load(lib) is not None, kernel.status()
    return kernel.load()


def _points(tyre, n: int, seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    F0 = tyre["FNOMIN"]
    x = dict(
        Fz=rng.uniform(0.2 * F0, 1.8 * F0, n),
        kappa=rng.uniform(-0.6, 0.6, n),
        alpha=rng.uniform(-0.35, 0.35, n),
        gamma=rng.uniform(-0.08, 0.08, n),
        Vx=rng.uniform(-2.0, 40.0, n),  # includes low speed and reversing
        P=rng.uniform(0.8, 1.2, n) * tyre["NOMPRES"],
    )
    x["Fz"][rng.random(n) < 0.05] = -100.0  # lift-off
    x["kappa"][rng.random(n) < 0.03] = np.nan  # NaN inputs become 0 with a warning
    return x


def _eval(tyre, x, mode, channels=None, record=None):
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        out = tyre.evaluate(**x, mode=mode, channels=channels, backend="kernel")
    if record is not None:
        record.extend(sorted(str(w.message) for w in rec))
    return out


@settings(max_examples=25, deadline=None)
@given(
    name=st.sampled_from(sorted(FILES)),
    n=st.integers(2, 200),
    mode=st.sampled_from((111, 121, 211, 110, 221)),
    seed=st.integers(0, 2**31 - 1),
)
def test_a_point_does_not_depend_on_its_place_in_the_batch(name, n, mode, seed):
    """Bit for bit the same outputs for every point after a permutation of the batch (other block
    boundaries, other padding, other neighbours in the lanes)."""
    tyre = TYRES[name]
    x = _points(tyre, n, seed)
    perm = np.random.default_rng(seed + 1).permutation(n)
    wa, wb = [], []
    a = _eval(tyre, x, mode, record=wa)
    b = _eval(tyre, {k: v[perm] for k, v in x.items()}, mode, record=wb)
    for k in CHANNELS:
        np.testing.assert_array_equal(a[k][perm], b[k], err_msg=f"{name} mode {mode} {k}")
    assert wa == wb  # the padding lanes add no warning


@pytest.mark.parametrize("n", (2, 7, 8, 9, 63, 64, 65, 130))
def test_block_boundaries_and_broadcast_inputs(n):
    """Batches around the block (64) and lane (8) sizes, with scalar inputs broadcast: every
    point equals the same point evaluated in a batch of another size."""
    tyre = TYRES["MF61"]
    x = _points(tyre, 300, n)
    x = {k: v[:n] for k, v in x.items()}
    x["gamma"] = 0.02  # a scalar broadcast over the batch
    big = {k: (np.concatenate([v, v[::-1]]) if np.ndim(v) else v) for k, v in x.items()}
    wa, wb = [], []
    a = _eval(tyre, x, 111, record=wa)
    b = _eval(tyre, big, 111, record=wb)
    for k in CHANNELS:
        np.testing.assert_array_equal(a[k], b[k][:n], err_msg=k)
    strip = [w.split(" ", 1)[1] if w[0].isdigit() else w for w in wa]  # NaN counts differ (twice the points)
    assert strip == [w.split(" ", 1)[1] if w[0].isdigit() else w for w in wb]


@pytest.mark.parametrize("name", sorted(FILES))
def test_subsets_of_channels_equal_the_full_evaluation(name):
    """channels= picks a lane loop (forces or all); the numbers are those of the full evaluation."""
    tyre = TYRES[name]
    x = _points(tyre, 150, 7)
    full = _eval(tyre, x, 111)
    for names in (("Fx",), ("Fy",), ("Fx", "Fy"), ("Mz",), ("rho", "Rl", "Cz"), ("Re", "omega"), ("sigmax",)):
        part = _eval(tyre, x, 111, channels=names)
        for k in names:
            np.testing.assert_array_equal(part[k], full[k], err_msg=f"{name} {k}")


def test_built_with_the_vectorised_loops_where_supported():
    """On x86-64 Linux with GCC and glibc the kernel is built with the vectorised lane loops (a
    silent fallback to scalar loops would lose the speed without any test failing otherwise)."""
    if not (sys.platform.startswith("linux") and platform.machine() == "x86_64" and shutil.which("gcc")):
        pytest.skip("the vectorised build is for GCC on x86-64 Linux")
    if not have_c_compiler():
        pytest.skip("no C compiler")
    lib = kernel.load()
    assert lib.mf_kernel_simd() == 1, kernel.status()
    assert "vectorised lane loops" in kernel.status()
    # and the loops really are vector loops: the AVX2 and AVX-512 clones call libmvec's atan (a flag of
    # the build environment, such as Python's -fwrapv, can silently keep GCC from vectorising them)
    binary = Path(lib._name).read_bytes()
    assert b"_ZGVdN4v_atan" in binary and b"_ZGVeN8v_atan" in binary
