"""Portable FMU binaries: an old glibc floor on Linux, a Windows DLL when a MinGW-w64 cross compiler is present.

* **glibc 2.17** (manylinux2014: RHEL 7/8, Ubuntu 18.04): glibc 2.29 gave ``exp``, ``log``, ``pow``,
  ``exp2`` and ``log2`` new symbol versions.  A binary linked on a newer glibc asks for those and does not
  load on an older one.  The FMU build force-includes :func:`glibc_pin_header`, which binds each of them
  to its oldest version (``.symver``), present in every glibc since the architecture's first.  Those
  compatibility entry points compute the same numbers (they wrap the same implementation and differ only
  in the SVID error handling of overflow and domain errors).  Only the FMU build uses the pins; the
  in-process kernel (``mftire.mf._mfkernel``) links against the running glibc and may use libmvec.
* **Windows**: when ``x86_64-w64-mingw32-gcc`` is on PATH at export time, the same sources are also
  compiled into ``binaries/win64/<id>.dll`` (FMI 3: ``x86_64-windows``), statically linked against the
  MinGW runtime.  ``mftire info --fmu`` says whether it is.

:func:`symbol_versions` lists the GLIBC versions a shared library needs (``objdump -T``), for the test.
"""

from __future__ import annotations

import platform
import re
import shutil
import subprocess
import sys
from pathlib import Path

#: Oldest glibc the Linux FMU binaries load on.
GLIBC_FLOOR = (2, 17)

#: libm functions whose default symbol version is newer than GLIBC_FLOOR on a current glibc.
PINNED = ("exp", "log", "pow", "exp2", "log2")

#: The architecture's first glibc symbol version (where the old exp/log/pow live), by platform.machine().
BASE_VERSION = {"x86_64": "GLIBC_2.2.5", "amd64": "GLIBC_2.2.5", "aarch64": "GLIBC_2.17", "arm64": "GLIBC_2.17",
                "ppc64le": "GLIBC_2.17", "s390x": "GLIBC_2.2", "i686": "GLIBC_2.0", "i386": "GLIBC_2.0"}  # fmt: skip

#: Cross compiler of the Windows DLL and its flags.
MINGW = "x86_64-w64-mingw32-gcc"
MINGW_CFLAGS = ("-shared", "-O2", "-std=c99", "-Wall", "-static-libgcc")


def is_glibc() -> bool:
    return sys.platform.startswith("linux") and platform.libc_ver()[0] == "glibc"


def glibc_pin_header() -> str | None:
    """C header text binding :data:`PINNED` to the architecture's base version, or None (not glibc, or an
    architecture without a table entry)."""
    base = BASE_VERSION.get(platform.machine())
    if not is_glibc() or base is None:
        return None
    lines = [
        "/* mftire FMU build: bind libm functions to their oldest glibc symbol version so that the",
        " * binary loads on glibc >= 2.17 (mftire/fmu/portable.py).  Not in the FMU's sources. */",
    ]
    lines += [f'__asm__(".symver {f},{f}@{base}");' for f in PINNED]
    return "\n".join(lines) + "\n"


def mingw_compiler() -> str | None:
    """Path of the MinGW-w64 cross compiler, or None."""
    return shutil.which(MINGW)


def windows_platform(platform_dir: str) -> str:
    """binaries/ sub-directory of the Windows DLL: ``win64`` (FMI 2) or ``x86_64-windows`` (FMI 3), from the
    native platform directory name (FMI 3 names contain a dash)."""
    return "x86_64-windows" if "-" in platform_dir else "win64"


#: The FMU's single translation unit, when its sources have one (it includes the other .c files).
UNITY = "fmu.c"


def translation_units(src_dir: Path) -> list[str]:
    """The ``.c`` files the FMU's binary is compiled from: the single translation unit when there is one,
    else every ``.c`` of ``src_dir``."""
    src_dir = Path(src_dir)
    if (src_dir / UNITY).is_file():
        return [str(src_dir / UNITY)]
    return sorted(str(p) for p in src_dir.glob("*.c"))


def compile_windows_dll(src_dir: Path, out_path: Path) -> None:
    """Compile the FMU's sources in ``src_dir`` into the DLL ``out_path`` with MinGW-w64 (RuntimeError on
    failure)."""
    cc = mingw_compiler()
    if cc is None:
        raise RuntimeError(f"{MINGW} not found")
    c_files = translation_units(src_dir)
    cmd = [cc, *MINGW_CFLAGS, "-I", str(src_dir), *c_files, "-o", str(out_path)]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    if res.returncode != 0:
        raise RuntimeError("MinGW-w64 build failed:\n" + (res.stderr or res.stdout)[-2000:])


def symbol_versions(library: str | Path) -> dict[str, str]:
    """``{symbol: GLIBC_x.y}`` of the dynamic symbols a shared library imports (``objdump -T``)."""
    tool = shutil.which("objdump")
    if tool is None:
        raise RuntimeError("objdump not found")
    out = subprocess.run([tool, "-T", str(library)], capture_output=True, text=True, check=True).stdout
    found = {}
    for line in out.splitlines():
        m = re.search(r"\(?(GLIBC_[0-9.]+)\)?\s+(\S+)\s*$", line)
        if m and "*UND*" in line:
            found[m.group(2)] = m.group(1)
    return found


def version_tuple(v: str) -> tuple[int, ...]:
    return tuple(int(x) for x in v.split("_", 1)[1].split("."))


def build_info(compiler: str) -> dict[str, str]:
    """What an FMU export on this machine produces (``mftire info --fmu``); ``compiler``: the C compiler
    :func:`mftire.fmu.build.find_compiler` finds, or why there is none."""
    cc = compiler
    pins = glibc_pin_header()
    floor = ".".join(map(str, GLIBC_FLOOR))
    mingw = mingw_compiler()
    return {
        "C compiler": cc,
        "native binary": f"{sys.platform} {platform.machine()}",
        "glibc floor": (
            f"{floor} ({', '.join(PINNED)} pinned to {BASE_VERSION[platform.machine()]})"
            if pins
            else "n/a (not glibc, or no pin table for this architecture)"
        ),  # fmt: skip
        "Windows DLL": (
            f"yes, win64 / x86_64-windows ({mingw})"
            if mingw
            else f"no ({MINGW} not on PATH; e.g. apt-get install gcc-mingw-w64-x86-64)"
        ),  # fmt: skip
    }
