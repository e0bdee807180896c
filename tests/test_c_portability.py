"""Portable C (issue 23): the FMU sources compile warning-free with gcc and clang (C99, -pedantic, no C99
complex), pass an MSVC-dialect syntax check (clang's x86_64-pc-windows-msvc target with minimal stub
headers of the C library: what MSVC provides, no <complex.h>), and the Linux binary needs no glibc symbol
version above 2.17.  A Windows DLL is shipped when the MinGW-w64 cross compiler is present.

The compiler checks skip when the compiler is absent (clang is not a dependency of mftire).
"""

from __future__ import annotations

import shutil
import subprocess
import zipfile
from pathlib import Path

import pytest
from conftest import REFERENCE_TYRES, needs_c_compiler

from mftire.fmu import portable

pytestmark = needs_c_compiler

#: Minimal stand-ins of the C library headers MSVC (UCRT) provides, for a syntax check without MSVC.
#: Only declarations that MSVC has; no <complex.h> (MSVC's has no `double complex`).
STUBS = {
    "math.h": """#pragma once
#define HUGE_VAL (__builtin_huge_val())
#define INFINITY (__builtin_inff())
#define NAN (__builtin_nanf(""))
#define isnan(x) __builtin_isnan(x)
#define isinf(x) __builtin_isinf(x)
#define isfinite(x) __builtin_isfinite(x)
#define signbit(x) __builtin_signbit(x)
double acos(double); double asin(double); double atan(double); double atan2(double, double);
double cos(double); double sin(double); double tan(double); double cosh(double); double sinh(double);
double tanh(double); double acosh(double); double asinh(double); double atanh(double); double exp(double);
double expm1(double); double exp2(double); double log(double); double log10(double); double log1p(double);
double log2(double); double pow(double, double); double sqrt(double); double cbrt(double); double hypot(double, double);
double fabs(double); double ceil(double); double floor(double); double round(double); double trunc(double);
double fmod(double, double); double fmax(double, double); double fmin(double, double); double copysign(double, double);
double nextafter(double, double); double ldexp(double, int); double frexp(double, int *);
""",
    "stdio.h": """#pragma once
#include <stddef.h>
#include <stdarg.h>
typedef struct _iobuf FILE;
int printf(const char *, ...); int fprintf(FILE *, const char *, ...); int sprintf(char *, const char *, ...);
int snprintf(char *, size_t, const char *, ...); int vsnprintf(char *, size_t, const char *, va_list);
""",
    "stdlib.h": """#pragma once
#include <stddef.h>
void *malloc(size_t); void *calloc(size_t, size_t); void *realloc(void *, size_t); void free(void *);
double strtod(const char *, char **); long strtol(const char *, char **, int); int abs(int); void abort(void);
""",
    "string.h": """#pragma once
#include <stddef.h>
void *memcpy(void *, const void *, size_t); void *memmove(void *, const void *, size_t);
void *memset(void *, int, size_t); int memcmp(const void *, const void *, size_t); size_t strlen(const char *);
int strcmp(const char *, const char *); int strncmp(const char *, const char *, size_t);
char *strcpy(char *, const char *); char *strncpy(char *, const char *, size_t); char *strchr(const char *, int);
char *strrchr(const char *, int); char *strstr(const char *, const char *); char *strcat(char *, const char *);
""",
}


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    from mftire.fmu.export import export_fmu

    d = tmp_path_factory.mktemp("portable")
    tir = REFERENCE_TYRES["JuliaMF62"]
    out = {
        "fmi2": export_fmu(tir, d / "s2.fmu"),
        "fmi3": export_fmu(tir, d / "s3.fmu", fmi_version=3),
        "transient": export_fmu(tir, d / "t2.fmu", transient=True),
    }
    return {k: Path(v) for k, v in out.items()}


def _sources(fmu: Path, where: Path) -> Path:
    with zipfile.ZipFile(fmu) as z:
        z.extractall(where)
    return where / "sources"


def _compile(argv: list[str], src: Path) -> str:
    units = portable.translation_units(src)
    res = subprocess.run([*argv, "-I", str(src), *units], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr[-3000:]
    return res.stderr


def test_no_c99_complex_in_the_sources():
    package = Path(__file__).resolve().parents[1] / "mftire"
    files = list(package.rglob("*.[ch]"))
    assert any(f.name == "mf_eval.c" for f in files)
    for f in files:
        text = f.read_text()
        for word in ("complex.h", "double complex", "cacos", "ccos", "creal", "cimag", "_Complex"):
            assert word not in text, (f.name, word)


@pytest.mark.parametrize("cc", ["gcc", "clang"])
@pytest.mark.parametrize("kind", ["fmi2", "fmi3", "transient"])
def test_sources_compile_warning_free(fmus, tmp_path, cc, kind):
    if shutil.which(cc) is None:
        pytest.skip(f"{cc} not installed")
    src = _sources(fmus[kind], tmp_path)
    stderr = _compile([cc, "-std=c99", "-pedantic", "-Wall", "-Wextra", "-fsyntax-only"], src)
    assert stderr.strip() == ""


@pytest.mark.parametrize("kind", ["fmi2", "fmi3", "transient"])
def test_msvc_dialect_syntax_check(fmus, tmp_path, kind):
    if shutil.which("clang") is None:
        pytest.skip("clang not installed")
    src = _sources(fmus[kind], tmp_path)
    stubs = tmp_path / "stubs"
    stubs.mkdir()
    for name, text in STUBS.items():
        (stubs / name).write_text(text)
    # the C library is MSVC's (stubs), no GNU headers; variable-length arrays and implicit declarations are
    # errors (MSVC has neither)
    argv = ["clang", "--target=x86_64-pc-windows-msvc", "-fsyntax-only", "-nostdlibinc", "-isystem", str(stubs),
            "-Werror=vla", "-Werror=implicit-function-declaration", "-Wall"]  # fmt: skip
    stderr = _compile(argv, src)
    assert "warning" not in stderr, stderr[-3000:]


@pytest.mark.skipif(not portable.is_glibc(), reason="Linux/glibc only")
def test_linux_binary_loads_on_glibc_2_17(fmus, tmp_path):
    if shutil.which("objdump") is None:
        pytest.skip("objdump not installed")
    for kind, fmu in fmus.items():
        with zipfile.ZipFile(fmu) as z:
            z.extractall(tmp_path / kind)
        so = next((tmp_path / kind / "binaries").glob("*/*.so"))
        versions = portable.symbol_versions(so)
        assert versions, "no versioned imports found: objdump output not understood"
        too_new = {s: v for s, v in versions.items() if portable.version_tuple(v) > portable.GLIBC_FLOOR}
        assert too_new == {}, (kind, too_new)
        assert "exp" in versions and "pow" in versions  # the pinned functions are used


def test_windows_dll_shipped_when_mingw_present(fmus):
    for kind, fmu in fmus.items():
        names = zipfile.ZipFile(fmu).namelist()
        dlls = [n for n in names if n.endswith(".dll")]
        if portable.mingw_compiler() is None:
            assert dlls == []
        else:
            assert dlls == [f"binaries/{'x86_64-windows' if kind == 'fmi3' else 'win64'}/" + Path(dlls[0]).name]
    info = portable.build_info("cc")
    assert info["Windows DLL"].startswith("yes" if portable.mingw_compiler() else "no")


def test_info_fmu_command(capsys):
    from mftire.cli import main

    assert main(["info", "--fmu"]) == 0
    out = capsys.readouterr().out
    assert "Windows DLL" in out and "glibc floor" in out
