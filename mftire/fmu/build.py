"""Building an FMU: the C sources, the compiler, the platform folders and the zip.

Shared by the steady-state export (:mod:`mftire.fmu.export`) and the transient export
(:mod:`mftire.fmu.transient_export`), which both import from here and not from each other.
"""


import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import warnings
import zipfile
from pathlib import Path

from mftire.errors import MftireError
from mftire.fmu import variables as vt
from mftire.mf import pac2002
from mftire.mf.family import PAC2002_CODE

CSOURCE = Path(__file__).parent / "csource"

#: Hand-written C sources shipped in every FMU (besides the wrapper and generated headers).
CORE_SOURCES = ("mf_eval.c", "mf_eval.h", "mf_model.c", "mf_model.h")

#: The FMI 2.0 functions shared by the steady-state and the transient wrappers (fmi2_model.c, fmi2_transient.c).
FMI2_COMMON_SOURCES = ("fmi2_common.c", "fmi2_common.h")

#: FMI headers taken from fmpy's ``c-code`` directory.
FMI_HEADERS = {
    2: ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h"),
    3: ("fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h"),
}

#: Flags of the shared library build (the maths library is linked explicitly).
CFLAGS = ("-shared", "-fPIC", "-O3", "-std=c99", "-fvisibility=hidden", "-Wall")
LIBS = ("-lm",)


class FMUExportError(MftireError):
    """The FMU could not be built (no C compiler, compile error, unusable .tir)."""


def _fmpy_c_code() -> Path:
    import fmpy

    return Path(fmpy.__file__).parent / "c-code"


def _platform(fmi_version: int) -> tuple[str, str]:
    """(binaries/ sub-directory, shared-library suffix) for this machine."""
    import fmpy

    if sys.platform.startswith("win"):
        raise FMUExportError("export-fmu builds with a POSIX C compiler; Windows binaries are not supported")
    suffix = ".dylib" if sys.platform == "darwin" else ".so"
    return (fmpy.platform if fmi_version == 2 else fmpy.platform_tuple), suffix


def find_compiler(compiler: str | None = None) -> list[str]:
    """The C compiler command: ``compiler``, else ``$CC``, else cc, gcc or clang on PATH.

    Raises :class:`FMUExportError` when none is found.
    """
    candidates = [compiler] if compiler else ([os.environ["CC"]] if os.environ.get("CC") else ["cc", "gcc", "clang"])
    for cand in candidates:
        argv = shlex.split(cand)
        if argv and shutil.which(argv[0]):
            return argv
    raise FMUExportError(
        "no C compiler found (tried " + ", ".join(candidates) + "): the FMU's binary is compiled from its C "
        "sources; install gcc or clang, or set CC"
    )


def model_identifier_for(name: str) -> str:
    """A C identifier (and file name) from a tyre name."""
    ident = re.sub(r"[^A-Za-z0-9_]", "_", name)
    if not ident or not (ident[0].isalpha() or ident[0] == "_"):
        ident = "tyre_" + ident
    return ident


def _load(tir):
    """Flat parameters, a name and the extension configuration from a path, a Tyre or a mapping.

    Checks that the tyre evaluates (with its model extensions, data variables at 0).
    """
    import numpy as np

    from mftire.tyre import Tyre, load

    try:
        if isinstance(tir, Tyre):
            tyre = tir
        elif isinstance(tir, (str, os.PathLike)):
            if not Path(tir).is_file():
                raise FMUExportError(f"{tir}: file not found")
            tyre = load(tir)
        else:
            tyre = Tyre(tir)
    except FMUExportError:
        raise
    except MftireError as exc:
        raise FMUExportError(f"{tir}: cannot be exported: {exc}") from None
    name = Path(tyre.name).stem if tyre.name else "tyre"
    flat = dict(tyre.flat)
    if flat["FITTYP"] == PAC2002_CODE:
        # the camber scaling factors and PAC2002 key mapping are folded in at export (fixed)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            flat = pac2002.prepare(flat)
    try:
        spec = vt.extension_spec(tyre.extensions) if tyre.extensions else None
        vt.variable_table(flat, vt.DEFAULT_USE_MODE, spec)  # data-variable names must not collide
    except MftireError as exc:
        raise FMUExportError(f"{tyre.name}: the model extensions cannot be exported: {exc}") from None
    data = {v: 0.0 for v in tyre.required_variables}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out = tyre.evaluate(flat["FNOMIN"], 0.05, 0.05, 0.0, mode=111, **data)
    except (MftireError, ValueError, TypeError) as exc:
        raise FMUExportError(f"{tyre.name}: cannot be evaluated, so it cannot be exported: {exc}") from None
    bad = [k for k in ("Fx", "Fy", "Mz", "Re") if not np.isfinite(out[k]).all()]
    if bad:
        raise FMUExportError(
            f"{tyre.name}: cannot be evaluated: {', '.join(bad)} not finite at Fz = FNOMIN, kappa = alpha = 0.05"
        )
    return flat, name, spec


def compile_sources(src_dir: Path, out_path: Path, compiler: str | None = None) -> None:
    """Compile every ``.c`` in ``src_dir`` into the shared library ``out_path``."""
    from mftire.fmu.portable import glibc_pin_header

    cc = find_compiler(compiler)
    c_files = sorted(str(p) for p in src_dir.glob("*.c"))
    pins = glibc_pin_header()  # Linux: load on glibc >= 2.17 (mftire/fmu/portable.py); not in the sources
    extra = []
    if pins is not None:
        pin_file = Path(out_path).parent / "mftire_glibc_pins.h"
        pin_file.write_text(pins, encoding="utf-8")
        extra = ["-include", str(pin_file)]
    cmd = [*cc, *CFLAGS, *extra, "-I", str(src_dir), *c_files, "-o", str(out_path), *LIBS]
    try:
        res = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    except OSError as exc:
        raise FMUExportError(f"C compiler {cc[0]!r} could not be run: {exc}") from None
    if res.returncode != 0:
        tail = "\n".join((res.stderr or res.stdout).strip().splitlines()[-15:])
        raise FMUExportError(f"compiling the FMU failed ({' '.join(cc)} exit {res.returncode}):\n{tail}")


def _windows_dll(src: Path, dll: Path) -> Path | None:
    """The Windows DLL when a MinGW-w64 cross compiler is present (else None; a failed build warns)."""
    from mftire.fmu.portable import compile_windows_dll, mingw_compiler

    if mingw_compiler() is None:
        return None
    try:
        compile_windows_dll(src, dll)
    except (RuntimeError, OSError, subprocess.SubprocessError) as exc:
        warnings.warn(f"export-fmu: no Windows DLL: {exc}", stacklevel=3)
        return None
    return dll


def package_fmu(output, xml: str, files: dict[str, str], ident: str, platform: str, suffix: str,
                cc: list[str]) -> Path:  # fmt: skip
    """Compile ``files`` (the ``sources/``) and write the FMU zip ``output`` atomically."""
    from mftire.iotools.atomic import atomic_path

    output = Path(output)
    with tempfile.TemporaryDirectory(prefix="mftire-fmu-") as tmp:
        src = Path(tmp) / "sources"
        src.mkdir()
        for fname, text in files.items():
            (src / fname).write_text(text, encoding="utf-8")
        binary = Path(tmp) / (ident + suffix)
        compile_sources(src, binary, " ".join(shlex.quote(a) for a in cc))
        dll = _windows_dll(src, Path(tmp) / (ident + ".dll"))
        with atomic_path(output) as tmp_out, zipfile.ZipFile(tmp_out, "w", zipfile.ZIP_DEFLATED) as zf:
            zf.writestr("modelDescription.xml", xml)
            for fname in sorted(files):
                zf.writestr(f"sources/{fname}", files[fname])
            zf.write(binary, f"binaries/{platform}/{ident}{suffix}")
            if dll is not None:
                from mftire.fmu.portable import windows_platform

                zf.write(dll, f"binaries/{windows_platform(platform)}/{ident}.dll")
    return output
