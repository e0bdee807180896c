"""Build of the compiled array kernel (everything else is in pyproject.toml).

The kernel (mftire/fmu/csource/mf_kernel.c, the FMU's C model looped over arrays) is a
setuptools extension compiled with the system C compiler and loaded with ctypes
(mftire/mf/kernel.py).  It is optional: without a compiler the installation succeeds and
mftire uses its numpy evaluator.
"""

import importlib.util
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

try:  # setuptools >= 65 vendors distutils
    from setuptools.errors import CCompilerError, CompileError, LinkError
except ImportError:  # pragma: no cover
    from distutils.errors import CCompilerError, CompileError, LinkError

ROOT = Path(__file__).resolve().parent
_spec = importlib.util.spec_from_file_location("_kernel_build", ROOT / "mftire" / "mf" / "_kernel_build.py")
build = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(build)

kernel = Extension(
    build.MODULE,
    sources=[str(build.CSOURCE / build.SOURCES[0])],
    depends=[str(build.CSOURCE / s) for s in build.SOURCES[1:]],
    include_dirs=[str(Path(d).relative_to(ROOT)) for d in build.include_dirs(ROOT)],
    define_macros=build.define_macros(ROOT),
    extra_compile_args=list(build.CFLAGS),
    libraries=["m"],
    optional=True,
)



class BuildKernel(build_ext):
    """The kernel is a plain shared library (no PyInit): a file name that is not a module's
    (build.LIBRARY instead of the interpreter's extension suffix), so that nothing
    tries to import it.  It is built with the vectorised lane loops (build.SIMD_CFLAGS,
    build.SIMD_LIBRARIES) where the compiler and C library support them, else without."""

    def build_extension(self, ext):
        if ext.name != build.MODULE:
            return super().build_extension(ext)
        plain = (list(ext.extra_compile_args), list(ext.libraries))
        ext.extra_compile_args = plain[0] + list(build.SIMD_CFLAGS)
        ext.libraries = list(build.SIMD_LIBRARIES) + plain[1]
        try:
            return super().build_extension(ext)
        except (CCompilerError, CompileError, LinkError) as exc:
            print(f"mftire: the vectorised kernel did not build ({exc}); building it without SIMD")
            ext.extra_compile_args, ext.libraries = plain
            return super().build_extension(ext)

    def get_ext_filename(self, fullname):
        name = super().get_ext_filename(fullname)
        if fullname.split(".")[-1] == build.MODULE.split(".")[-1]:
            name = name[: name.rindex(fullname.split(".")[-1])] + build.LIBRARY
        return name


setup(ext_modules=[kernel], cmdclass={"build_ext": BuildKernel})
