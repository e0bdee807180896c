"""Shared test fixtures: paths to the data shipped in tests/data."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from mftire.fmu import portable
from mftire.fmu.export import FMUExportError, find_compiler

DATA = Path(__file__).parent / "data"
TIR = DATA / "tir"
MFEVAL = DATA / "mfeval"

#: Reference tyre labels -> .tir file (see tests/data/mfeval/README.md)
REFERENCE_TYRES = {
    "MF52": TIR / "MagicFormula52_Parameters.tir",
    "MF61": TIR / "mfeval" / "MagicFormula61_Paramerters.tir",
    "MF62": TIR / "mfeval" / "MagicFormula62_Paramerters.tir",
    "PacejkaBook": TIR / "mfeval" / "PacejkaBook_Defaults.tir",
    "FSAE": TIR / "mfeval" / "FSAE_Defaults.tir",
    "JuliaMF61": TIR / "MagicFormula61_Parameters.tir",
    "JuliaMF62": TIR / "MagicFormula62_Parameters.tir",
}


@pytest.fixture(scope="session")
def mf61_path() -> Path:
    return REFERENCE_TYRES["MF61"]


@pytest.fixture(scope="session")
def mf62_path() -> Path:
    return REFERENCE_TYRES["MF62"]


@pytest.fixture()
def in_tmp(tmp_path: Path):
    cwd = os.getcwd()
    os.chdir(tmp_path)
    yield tmp_path
    os.chdir(cwd)


_MINGW_COMPILER = portable.mingw_compiler  # the real one, whatever a test module patched

#: Test modules that check the Windows DLL of an exported FMU (binaries/win64, binaries/x86_64-windows).
WINDOWS_DLL_MODULES = {"test_c_portability"}


@pytest.fixture(scope="module", autouse=True)
def _no_windows_dll(request):
    """FMUs exported in this process by the other test modules carry no cross-compiled Windows DLL.

    ``export_fmu`` also builds ``binaries/win64`` when the MinGW-w64 cross compiler is on PATH (a few seconds
    per FMU, most of an export's time); no test outside :data:`WINDOWS_DLL_MODULES` loads or checks that DLL,
    and a failed DLL build only warns, so building it there proves nothing.  tests/test_c_portability.py
    keeps the cross compiler and checks the DLL of every FMU kind.  Module scope, autouse: active before the
    module's own (module-scoped) fixtures export their FMUs.  Subprocesses (CLI runs, Dask workers) are not
    affected, nor is the session's quick demo (:func:`quick_demo`)."""
    if request.module.__name__.rsplit(".", 1)[-1] in WINDOWS_DLL_MODULES:
        yield
        return
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(portable, "mingw_compiler", lambda: None)
        yield


@pytest.fixture(scope="session")
def quick_demo(tmp_path_factory) -> tuple[Path, str, str]:
    """``mftire demo --quick --output local`` run once for the session, from a folder of its own (a relative
    output, as a user runs it): (the output folder, what the run printed on stdout, on stderr).
    tests/test_demo.py checks this run; tests/test_dask_cluster.py compares a run on a Dask cluster with it.

    Once for the whole session, not once per pytest-xdist worker: its users are in two modules that may run on
    different workers, and the run is 95-130 CPU-seconds.  Under xdist the first worker to need it runs it in the
    session's common temporary folder while holding a lock there; the others wait for the lock and read its
    output, exit code and printed text (the pytest-xdist docs' recipe, with ``fcntl``).  The tests only read
    the output folder."""
    try:
        import fcntl
    except ImportError:  # not POSIX (Windows): each worker that needs it runs its own
        fcntl = None
    if os.environ.get("PYTEST_XDIST_WORKER") is None or fcntl is None:  # one process: its own temporary folder
        here = tmp_path_factory.mktemp("quick_demo")
        _quick_demo_in(here)
    else:
        shared = tmp_path_factory.getbasetemp().parent  # the session's folder, common to its workers
        with open(shared / "quick_demo.lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file is closed, also if this worker dies
            here = shared / "quick_demo"
            if not (here / "rc").exists():
                if here.exists():  # a run that did not finish (its worker was stopped): start again
                    import shutil

                    shutil.rmtree(here)
                here.mkdir()
                _quick_demo_in(here)
    rc = int((here / "rc").read_text())
    out, err = ((here / name).read_text(encoding="utf-8") for name in ("stdout", "stderr"))
    assert rc == 0, err
    return here / "local", out, err


def _quick_demo_in(here: Path) -> None:
    """:func:`quick_demo`'s run in the folder ``here``: its output folder ``local``, and its exit code and printed
    text in the files ``rc``, ``stdout`` and ``stderr`` there (what :func:`quick_demo` reads and checks)."""
    import contextlib
    import io

    from mftire.cli import main

    out, err = io.StringIO(), io.StringIO()
    cwd = os.getcwd()
    os.chdir(here)
    rc = 1
    try:  # the demo as a user runs it: its FMU with the Windows DLL when the cross compiler is there
        with pytest.MonkeyPatch.context() as mp, contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            mp.setattr(portable, "mingw_compiler", _MINGW_COMPILER)
            rc = main(["demo", "--quick", "--output", "local"])
    except Exception:
        import traceback

        err.write(traceback.format_exc())
    finally:
        os.chdir(cwd)
        (here / "stdout").write_text(out.getvalue(), encoding="utf-8")
        (here / "stderr").write_text(err.getvalue(), encoding="utf-8")
        (here / "rc").write_text(str(rc))  # last: its presence says the run is over


def load_validation(name: str):
    """The script ``validation/<name>.py`` as a module (registered in ``sys.modules`` under ``name``)."""
    import importlib.util
    import sys

    path = Path(__file__).resolve().parents[1] / "validation" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


def have_c_compiler() -> bool:
    """True when a C compiler for FMU binaries is on PATH."""
    try:
        find_compiler()
    except FMUExportError:
        return False
    return True


@pytest.fixture()
def _c_compiler():
    """FMU tests need a C compiler: outside CI they are skipped without one; in CI (``CI``
    set) they fail, because the FMU is part of the product."""
    if not have_c_compiler():
        msg = "no C compiler (cc, gcc or clang) on PATH: FMU binaries cannot be built"
        if os.environ.get("CI"):
            pytest.fail(msg)
        pytest.skip(msg)


#: Marker for tests that build FMU binaries (see :func:`_c_compiler`).
needs_c_compiler = pytest.mark.usefixtures("_c_compiler")


def turn_slip_nan_departure(p, mode: int, channel: str, gamma):
    """Where MFeval's Mz is NaN and ours finite by design (mftire/mf/aligning.py, "MFeval
    departure"): turn slip on, and no camber torque stiffness (QDZ8·QDZ9 = QDZ10 = 0 and
    QDZ11·gamma = 0), so MFeval's spin-moment ratio is infinite."""
    import numpy as np

    if mode % 10 != 2 or channel not in ("Mz", "Mzr"):
        return np.zeros(np.shape(gamma), dtype=bool)
    return (p["QDZ8"] * p["QDZ9"] == 0) & (p["QDZ10"] == 0) & ((p["QDZ11"] == 0) | (np.asarray(gamma) == 0))
