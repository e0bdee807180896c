"""How the array kernel (``mf_kernel.c``) is compiled: sources, flags and the source hash.

Standard library only: ``setup.py`` loads this file by path (the package's dependencies
are not installed when the build runs), and :mod:`mftire.mf.kernel` uses it to check that
a library was built from the C sources next to it and to compile one for development
(``python -m mftire.mf.kernel build``).
"""

from __future__ import annotations

import hashlib
import os
import shlex
import shutil
import subprocess
from pathlib import Path

#: The C model directory, relative to the repository / installed package root.
CSOURCE = Path("mftire") / "mf" / "c"
#: The translation unit (it includes mf_eval.c) and every file it reads.
SOURCES = ("mf_kernel.c", "mf_eval.c", "mf_eval.h", "mf_ext.h", "mf_spec_gen.h", "kernel/mf_params.h",
           "kernel/mf_ext_gen.h")
#: Name of the setuptools Extension that builds the kernel (loaded with ctypes: no Python C API) ...
MODULE = "mftire.mf._mfkernel"
#: ... and its file name in mftire/mf/: not a module's suffix, so that nothing imports it.
LIBRARY = "_mfkernel.so.1"
#: Optimisation without changing IEEE results: no errno from libm (lets calls inline and
#: vectorise), no trapping, no contraction into fused multiply-adds (each lane rounds as the
#: scalar C does); no -ffast-math (it would reorder the arithmetic and drop NaN checks, and
#: the kernel must agree with numpy to 1e-12).
#: -fno-wrapv undoes the -fwrapv of Python's own CFLAGS, which setuptools puts first: with it GCC
#: cannot vectorise the lane loops (it must allow the lane index to wrap).
CFLAGS = ("-O3", "-std=c99", "-fno-wrapv", "-fno-math-errno", "-fno-trapping-math", "-ffp-contract=off",
          "-fvisibility=hidden", "-Wall")  # fmt: skip
#: The vectorised lane loops (mf_kernel.c, MF_KERNEL_SIMD): `omp simd` loops, AVX-512/AVX2/x86-64
#: target clones and glibc's vector math library.  GCC on x86-64 Linux; where these flags do not
#: compile or link, the kernel is built without them (plain scalar loops, same results up to
#: the ulps of the math library).
SIMD_CFLAGS = ("-fopenmp-simd", "-DMF_KERNEL_SIMD=1")
SIMD_LIBRARIES = ("mvec",)


def source_hash(root: str | os.PathLike) -> str:
    """SHA-256 (first 16 hex digits) of the kernel's sources and flags under ``root``."""
    h = hashlib.sha256(" ".join(CFLAGS).encode())
    for name in SOURCES:
        h.update(b"\0" + name.encode() + b"\0")
        h.update((Path(root) / CSOURCE / name).read_bytes())
    return h.hexdigest()[:16]


def include_dirs(root: str | os.PathLike) -> list[str]:
    """``kernel/`` (generated headers) first, then the C sources."""
    src = Path(root) / CSOURCE
    return [str(src / "kernel"), str(src)]


def define_macros(root: str | os.PathLike) -> list[tuple[str, str]]:
    return [("MF_KERNEL_HASH", '"' + source_hash(root) + '"')]


def compile_library(root: str | os.PathLike, out: str | os.PathLike, cc: str | None = None) -> Path:
    """Compile the kernel into the shared library ``out`` with the system C compiler
    (``cc`` or ``$CC`` or cc/gcc/clang); raises ``RuntimeError`` when that fails."""
    names = [cc] if cc else ([os.environ["CC"]] if os.environ.get("CC") else ["cc", "gcc", "clang"])
    argv = next((shlex.split(n) for n in names if n and shutil.which(shlex.split(n)[0])), None)
    if argv is None:
        raise RuntimeError("no C compiler found (tried " + ", ".join(names) + ")")
    src = Path(root) / CSOURCE / SOURCES[0]
    defs = [f"-D{k}={v}" for k, v in define_macros(root)]
    incs = [f"-I{d}" for d in include_dirs(root)]
    base = [*argv, "-shared", "-fPIC", *CFLAGS, *defs, *incs, str(src), "-o", str(out)]
    errors = []
    for extra, libs in ((SIMD_CFLAGS, SIMD_LIBRARIES), ((), ())):
        cmd = [*base[:-3], *extra, *base[-3:], *(f"-l{lib}" for lib in libs), "-lm"]
        res = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        if res.returncode == 0:
            return Path(out)
        errors.append(res.stderr[-2000:])
    raise RuntimeError("compiling the kernel failed:\n" + "\n".join(errors))
