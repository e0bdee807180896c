"""The compiled array kernel behind :meth:`mftire.Tyre.evaluate` (and :func:`mftire.mf.solver.evaluate_arrays`).

One C call evaluates a whole batch with the C model (``mftire/mf/c``:
``mf_kernel.c`` includes ``mf_eval.c``, the one C copy of the equations, and adds the
loop over the arrays with the batch semantics of the numpy evaluator).  The numpy modules
of :mod:`mftire.mf` stay the readable reference; ``tests/test_kernel.py`` proves that the
two agree to 1e-12 in every mode, for every model family, with and without model
extensions.

Building
    ``pip install`` compiles the kernel with the system C compiler (``setup.py``: a
    setuptools extension loaded with :mod:`ctypes`, no Python C API, no new dependency).
    In a source checkout, ``python -m mftire.mf.kernel build`` compiles it in place.

Fallback
    Without a compiler the installation still succeeds and the numpy path is used
    (:func:`available` is False, :func:`status` says why).  A library built from other C
    sources than those next to this module (a stale build) is refused the same way.

Choosing the path
    ``backend="numpy"`` (argument of ``Tyre.evaluate`` / ``evaluate_arrays``) or the
    environment variable ``MFTIRE_BACKEND=numpy`` (read at the first evaluation of the
    process) forces the numpy reference;
    ``backend="kernel"`` requires the kernel (an error when it is not available).  The
    default ``"auto"`` takes the kernel when it is available.

The input checks of :mod:`mftire.input_checks`, the model check and the broadcasting stay
in Python; warnings (NaN inputs, clipping, curvature factors) are issued in Python from
what the kernel reports, with the texts of the numpy path.

Scalar calls (latency)
    One operating point given as Python numbers takes :func:`point_function`: the packed
    parameters and a ready ``ctypes`` call are prepared once per parameter set, each call
    writes the inputs into this thread's buffer with one ``struct.pack_into``, makes one
    call of ``mf_kernel_point`` (a batch of one point of ``mf_kernel_evaluate``: the array
    path's numbers bit for bit) and copies the outputs into numpy scalars; the warnings
    are formatted only when the C code reports one.  ``Tyre.evaluate`` calls it directly
    for scalar inputs and all channels (``tests/test_point_path.py``).
"""

from __future__ import annotations

import ctypes
import os
import struct
import sys
import threading
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from mftire.mf import _kernel_build as build
from mftire.mf import spec
from mftire.mf.cheaders import spec_signature
from mftire.mf.extensions import MAX_EXTERNAL, TARGETS
from mftire.mf.inputs import MFLimitWarning
from mftire.parameters import PARAMETERS

#: Package root (the directory holding ``mftire/``).
_ROOT = Path(__file__).resolve().parents[2]
#: Fields of ``MFParams`` in the kernel's generated ``mf_params.h``: the numeric standard parameters.
PARAM_KEYS: tuple[str, ...] = tuple(p.key for p in PARAMETERS if p.unit != "str")
_PARAM_INDEX = {k: i for i, k in enumerate(PARAM_KEYS)}

#: The outputs in the order and with the meaning of MFeval's output matrix (:data:`mftire.mf.spec.OUTPUTS`),
#: the order of mf_kernel.c's outputs; public as :data:`mftire.mf.solver.OUTPUT_NAMES`.
OUTPUTS: tuple[str, ...] = tuple(o.name for o in spec.OUTPUTS)
_OUT_INDEX = {k: i for i, k in enumerate(OUTPUTS)}
_N_IN = len(spec.KERNEL_INPUTS)  # mf_kernel.c MF_N_IN
_IN_INDEX = {k: i for i, k in enumerate(spec.KERNEL_INPUTS)}
_MAX_DATA = MAX_EXTERNAL
_N_TARGETS = len(TARGETS)  # the room in the run-time MFTerm
_TERM_INTS = 2 + _N_TARGETS + 2 + 8 + 2

_lib = None  # the loaded library, False when unavailable
_why = ""  # why it is unavailable


class KernelUnavailableError(RuntimeError):
    """``backend="kernel"`` was asked for but the compiled kernel is not available."""


def _candidates() -> list[Path]:
    """Where a built library may be: next to this module (installed or built in place),
    then in every installed distribution of mftire on the path (a source checkout that
    shadows the installation; its own ``mftire.egg-info``, left by ``pip install .``, lists
    no library, so the first distribution found is not enough)."""
    found = [Path(__file__).resolve().parent / build.LIBRARY]
    try:
        from importlib.metadata import distributions

        for dist in distributions(name="mftire"):
            for f in dist.files or ():
                if f.as_posix() == "mftire/mf/" + build.LIBRARY:
                    path = Path(dist.locate_file(f)).resolve()
                    if path not in found:
                        found.append(path)
    except (ImportError, OSError):  # pragma: no cover - no distribution metadata
        pass
    return found


def load(path: str | os.PathLike | None = None):
    """The kernel library (``ctypes.CDLL``), or None with :func:`status` saying why.

    ``path``: load this library instead of searching (it must have been built from the C
    sources next to this module, e.g. by :func:`mftire.mf._kernel_build.compile_library`).
    """
    global _lib, _why
    if path is None and _lib is not None:
        return _lib or None
    want = build.source_hash(_ROOT)
    tried = []
    for cand in [Path(path)] if path is not None else _candidates():
        if not cand.is_file():
            continue
        try:
            lib = ctypes.CDLL(str(cand))
            lib.mf_kernel_hash.restype = ctypes.c_char_p
            got = lib.mf_kernel_hash().decode()
        except (OSError, AttributeError) as exc:
            tried.append(f"{cand}: {exc}")
            continue
        if got != want:
            tried.append(f"{cand}: built from other C sources (hash {got}, sources {want})")
            continue
        sizes = (ctypes.c_long * 5)()
        lib.mf_kernel_sizes(sizes)
        if tuple(sizes) != (len(PARAM_KEYS), _N_IN, len(OUTPUTS), len(spec.WARNINGS), _TERM_INTS):
            tried.append(f"{cand}: unexpected layout {tuple(sizes)}")
            continue
        lib.mf_kernel_signature.restype = ctypes.c_char_p
        if lib.mf_kernel_signature().decode() != spec_signature():
            tried.append(f"{cand}: outputs, warnings or inputs not those of mftire.mf.spec")
            continue
        f = lib.mf_kernel_evaluate
        vp, ci = ctypes.c_void_p, ctypes.c_int
        f.argtypes = (vp, vp, ci, ci, ctypes.c_long, vp, vp, ci, vp, vp, vp, vp)
        f.restype = ci
        # no argtypes: called with ready ctypes objects only (_pack's pointers, the buffer), which
        # ctypes passes without converting them (the latency of a scalar call)
        lib.mf_kernel_point.argtypes = None
        lib.mf_kernel_point.restype = ci
        _lib, _why = lib, ""
        return lib
    _lib = False
    _why = "; ".join(tried) or (
        "no compiled kernel found (installed without a C compiler, or a source checkout: build it with "
        "`python -m mftire.mf.kernel build`)"
    )
    return None


def available() -> bool:
    """Whether the compiled kernel can be used."""
    return load() is not None


def status() -> str:
    """One line: the kernel in use, or why the numpy path is used."""
    lib = load()
    if lib is None:
        return f"numpy path: {_why}"
    loops = "vectorised lane loops" if lib.mf_kernel_simd() else "scalar loops (built without SIMD)"
    return f"compiled kernel {lib._name} ({loops})"


_env: str | None = None  # MFTIRE_BACKEND, read at the first evaluation


def use_kernel(backend: str | None) -> bool:
    """Whether a call with ``backend`` ("auto", "kernel", "numpy"; None: "auto") runs the kernel.

    The environment variable ``MFTIRE_BACKEND`` (``numpy`` forces the reference path) is read
    once, at the first evaluation of the process.
    """
    global _env
    if backend is None or backend == "auto":
        if _env is None:
            _env = os.environ.get("MFTIRE_BACKEND", "auto")
        if _env == "numpy":
            return False
        return available()
    if backend == "numpy":
        return False
    if backend == "kernel":
        if not available():
            raise KernelUnavailableError(status())
        return True
    raise ValueError(f"backend must be 'auto', 'kernel' or 'numpy', not {backend!r}")


# ----------------------------------------------------------------------------- parameters


def _pack(p: Mapping[str, float], ext) -> tuple:
    """``(keep, params address, terms address or None, n_terms, params pointer, terms pointer
    or None)``: MFParams followed by the numbers of the extension terms, and the run-time term
    table (MFTerm records of mf_ext_gen.h) pointing into it; ``keep`` holds the arrays at those
    addresses, the pointers are the addresses as ``ctypes.c_void_p`` (for mf_kernel_point).
    None when a parameter is not one number (the numpy path evaluates per-point parameter
    arrays)."""
    values = [p[k] for k in PARAM_KEYS]
    if not all(type(v) is float or np.ndim(v) == 0 for v in values):
        return None
    base = [float(v) for v in values]
    if not ext:
        params = np.array(base)
        return params, params.ctypes.data, None, 0, ctypes.c_void_p(params.ctypes.data), None
    from mftire.mf.extensions import BUILTIN_VARIABLES, TARGET_CODES

    builtin = list(BUILTIN_VARIABLES)
    external = ext.external_variables
    numbers: list[float] = []
    rows = []

    def put(value) -> int:
        numbers.append(value)
        return len(base) + len(numbers) - 1

    def var(name: str) -> int:
        return builtin.index(name) if name in builtin else len(builtin) + external.index(name)

    for t in ext.terms:
        two = t.variable2 is not None
        f1 = [put(t.value(n, p)) for n in ("REF", "SCALE", "MIN", "MAX")]
        f2 = [put(t.value(n, p)) for n in ("REF2", "SCALE2", "MIN2", "MAX2")] if two else [f1[0]] * 4
        first = len(base) + len(numbers)
        for k in t.level_keys:
            put(t.numbers[k])
        for k in t.coefficient_keys:
            put(p[k] if k in p else t.numbers.get(k, 0.0))
        tg = [TARGET_CODES[x] if x in TARGET_CODES else _PARAM_INDEX[x] for x in t.targets]
        from mftire.mf.extensions import FORMS

        row = [list(FORMS).index(t.form.name), len(tg), *tg, *([0] * (_N_TARGETS - len(tg)))]
        row += [var(t.variable), var(t.variable2) if two else -1, *f1, *f2, first, t.n_levels]
        rows.append(row)
    if not all(np.ndim(v) == 0 for v in numbers):
        return None
    params, terms = np.array(base + numbers), np.array(rows, dtype=np.intc)
    addresses = params.ctypes.data, terms.ctypes.data
    return (params, terms), *addresses, len(rows), *map(ctypes.c_void_p, addresses)


class FlatParameters(dict):
    """The flat parameters of a :class:`mftire.Tyre` (``Tyre.flat``): a ``dict`` that counts
    its changes, so the kernel packs them once and again only after a change.  Evaluated
    as they are (a PAC2002 set is prepared already, :func:`mftire.mf.pac2002.prepare`)."""

    version = 0

    def __getstate__(self) -> dict:
        # the kernel's caches (addresses, functions) stay behind: a copy or an unpickled set packs again
        return {k: v for k, v in self.__dict__.items() if not k.startswith("_kernel")}

    def _changed(self) -> None:
        self.version = self.__dict__.get("version", 0) + 1

    def __setitem__(self, key, value) -> None:
        super().__setitem__(key, value)
        self._changed()

    def __delitem__(self, key) -> None:
        super().__delitem__(key)
        self._changed()

    def __ior__(self, other):
        self.update(other)
        return self

    def update(self, *args, **kw) -> None:
        super().update(*args, **kw)
        self._changed()

    def setdefault(self, key, default=None):
        self._changed()
        return super().setdefault(key, default)

    def pop(self, *args):
        self._changed()
        return super().pop(*args)

    def popitem(self):
        self._changed()
        return super().popitem()

    def clear(self) -> None:
        super().clear()
        self._changed()


def _packed(p: Mapping[str, float], ext):
    """:func:`_pack` of ``p``, cached on a :class:`FlatParameters` until it changes;
    other mappings are packed at each call."""
    if not isinstance(p, FlatParameters):
        return _pack(p, ext)
    key = (p.version, id(ext))
    cache = p.__dict__.get("_kernel")
    if cache is None or cache[0] != key:
        cache = (key, _pack(p, ext), ext)  # ext kept alive: its id is part of the key
        p.__dict__["_kernel"] = cache
    return cache[1]


# ----------------------------------------------------------------------------- evaluation

_NULL12 = (ctypes.c_void_p * _N_IN)()


def evaluate(
    p: Mapping[str, float],
    Fz,
    kappa,
    alpha,
    gamma,
    phit,
    Vx,
    P,
    omega,
    mode: int,
    ext,
    variables: Mapping[str, object] | None,
    channels: Sequence[str] | None = None,
) -> dict[str, np.ndarray] | None:
    """The outputs ``channels`` (None: all 30) by the kernel; None when this call must take
    the numpy path (inputs the kernel does not take as they are, such as unusual
    broadcasting errors, complex values or variables the extensions do not read: the numpy
    path then raises or evaluates exactly as without the kernel)."""
    lib = load()
    if lib is None:
        return None
    external = ext.external_variables if ext else []
    if (
        isinstance(Fz, _SCALAR)
        and isinstance(kappa, _SCALAR)
        and isinstance(alpha, _SCALAR)
        and isinstance(gamma, _SCALAR)
        and isinstance(phit, _SCALAR)
        and isinstance(Vx, _NONE_OR_SCALAR)
        and isinstance(P, _NONE_OR_SCALAR)
        and isinstance(omega, _NONE_OR_SCALAR)
        and len(variables or ()) == len(external)
        and all(isinstance(variables.get(k), _SCALAR) for k in external)
    ):
        point = _point_function(p, ext)
        if point is None:
            return None
        data = tuple(variables[k] for k in external)
        return point(Fz, kappa, alpha, gamma, phit, Vx, P, omega, mode,
                     None if channels is None or channels == OUTPUTS else channels, external, data, 4)  # fmt: skip
    names = list(variables or {})
    external = ext.external_variables if ext else []
    if any(k not in external for k in names) or any(k not in names for k in external):
        return None
    try:
        if Vx is None:
            Vx = p["LONGVL"]
        arrs = [np.asarray(v, dtype=float) for v in (Fz, kappa, alpha, gamma, phit, Vx)]
        arrs += [np.asarray(variables[k], dtype=float) for k in external]
        shape = np.broadcast_shapes(*(a.shape for a in arrs))
        Pa = None if P is None else np.asarray(P, dtype=float)
        Om = None if omega is None else np.asarray(omega, dtype=float)
        if (Pa is not None and np.broadcast_shapes(Pa.shape, shape) != shape) or (
            Om is not None and np.broadcast_shapes(Om.shape, shape) != shape
        ):
            return None
    except (ValueError, TypeError):
        return None
    n = 1
    for s in shape:
        n *= s
    omega_given = Om is not None and bool(np.any(Om))
    ins = [*arrs[:6], np.float64(p["INFLPRES"]) if Pa is None else Pa, Om if omega_given else np.float64(0.0)]
    slots = [*arrs[6:], *([None] * (_N_IN - 8 - len(external)))]
    keep = []
    ptrs = (ctypes.c_void_p * _N_IN)()
    steps = (ctypes.c_long * _N_IN)()
    for k, a in enumerate(ins + slots):
        if a is None:
            continue
        if a.size == 1:
            a = np.ascontiguousarray(a, dtype=float).reshape(1)
            steps[k] = 0
        else:
            if a.shape != shape or not a.flags.c_contiguous:
                a = np.ascontiguousarray(np.broadcast_to(a, shape))
            steps[k] = 1
        keep.append(a)
        ptrs[k] = a.ctypes.data
    want = OUTPUTS if channels is None else channels
    rows = list(want)
    if "instKya" in rows and "Fy" not in rows:
        rows.append("Fy")  # instKya is the difference of Fy
    block = np.empty((len(rows), n))
    outp = (ctypes.c_void_p * len(OUTPUTS))()
    base = block.ctypes.data
    for r, name in enumerate(rows):
        outp[_OUT_INDEX[name]] = base + r * n * 8
    packed = _packed(p, ext)
    if packed is None:
        return None
    nan = (ctypes.c_long * _N_IN)()
    mask = ctypes.c_ulong(0)
    rc = lib.mf_kernel_evaluate(packed[1], packed[2], packed[3], int(mode), n, ptrs, steps, int(omega_given), outp,
                                None, nan, ctypes.byref(mask))  # fmt: skip
    if rc != 0:  # bad mode or FITTYP: the numpy path raises its own error
        return None
    if any(nan) or mask.value:
        _issue_warnings(p, nan, mask.value, external, omega_given)
    if shape == ():
        return dict(zip(want, block[: len(want), 0], strict=True))
    return {name: block[r].reshape(shape) for r, name in enumerate(want)}


_SCALAR = (float, int)
_NONE_OR_SCALAR = (float, int, type(None))

# mf_kernel_point's buffer (mf_kernel.c): a header (number of terms, of data variables, useMode,
# omega given, channel mask), the inputs, the outputs, the NaN counts, the warning mask; and the
# return code that says that a count or the mask is not 0.
_PT_IN = 5
_PT_OUT = _PT_IN + _N_IN
_PT_NAN = _PT_OUT + len(OUTPUTS)
_PT_WARN = _PT_NAN + _N_IN
_c_double_io = ctypes.c_double * (_PT_WARN + 1)
_PT_REPORT = 16
#: Writes the header and the eight operating-point inputs with one call (``struct`` converts as
#: ctypes does, ``float(x)``; the callers have checked that each is an int or a float).
_put = struct.Struct(f"{_PT_IN + 8}d").pack_into
_ALL = (1 << len(OUTPUTS)) - 1
_TEMPLATE = dict.fromkeys(OUTPUTS)  # copied, then filled: no resizing of a growing dict
_local = threading.local()  # one mf_kernel_point buffer per thread (ctypes releases the GIL)


def _new_buffer() -> tuple:
    """This thread's mf_kernel_point buffer and a numpy view of its outputs (made at its first call)."""
    io = _c_double_io()
    _local.point = io, np.frombuffer(io, count=len(OUTPUTS), offset=_PT_OUT * 8)
    return _local.point


def point_function(p: Mapping[str, float], ext, result: type = dict):
    """A function that evaluates one operating point of the parameters ``p`` with the extensions
    ``ext`` by one C call (the library's ``mf_kernel_point``), or None when the kernel cannot
    (no library, per-point parameters): the latency path of scalar calls.

    What it returns is valid while ``p`` and ``ext`` do not change (it holds their packed form,
    LONGVL, INFLPRES and the limits its warnings name, not ``p``).  Its arguments: ``Fz, kappa,
    alpha, gamma, phit, Vx, P, omega`` (numbers, ints or floats, checked by the caller; ``Vx``,
    ``P``, ``omega`` may be None),
    ``mode``, ``channels`` (output names; None: all), the extension variables' names and
    values ``external``, ``data``, and ``depth``, the ``stacklevel`` that names the caller of
    ``Tyre.evaluate`` from its own caller (where the warnings point, as in the array path).
    It returns ``result`` (``dict``, :class:`mftire.MFResult`) of numpy scalars with the
    array path's values and warnings, or None when the C code refuses the mode or FITTYP (the
    caller then takes the path that raises).
    """
    lib = load()
    packed = None if lib is None else _packed(p, ext)
    if packed is None:
        return None
    fn, c_params, c_terms, n_terms = lib.mf_kernel_point, packed[4], packed[5], packed[3]
    longvl, inflpres = p["LONGVL"], p["INFLPRES"]
    # the limits the warnings name, not p itself: no reference cycle through p's cache
    limits = {w.limit: p[w.limit] for w in spec.WARNINGS if w.limit}
    put, template, local = _put, _TEMPLATE, _local

    def evaluate_point(Fz, kappa, alpha, gamma, phit, Vx, P, omega, mode, channels=None, external=(), data=(),
                       depth=2):  # fmt: skip
        try:
            io, values = local.point
        except AttributeError:
            io, values = _new_buffer()
        omega_given = omega is not None and omega != 0.0
        mask = _ALL if channels is None else sum(1 << _OUT_INDEX[k] for k in channels)
        put(io, 0, n_terms, len(data), mode, omega_given, mask, Fz, kappa, alpha, gamma, phit,
            longvl if Vx is None else Vx, inflpres if P is None else P, omega if omega_given else 0.0)  # fmt: skip
        if data:
            io[_PT_IN + 8 : _PT_IN + 8 + len(data)] = data
        rc = fn(c_params, c_terms, io)
        if rc and rc != _PT_REPORT:
            return None
        # numpy scalars (copies), taken before a warning handler may evaluate again on this thread
        if channels is None:
            out = result(template)
            out.update(zip(OUTPUTS, values, strict=False))  # same length: no end check on the array
        else:
            out = result({k: values[_OUT_INDEX[k]] for k in channels})
        if rc:
            nan = [int(v) for v in io[_PT_NAN:_PT_WARN]]
            _issue_warnings(limits, nan, int(io[_PT_WARN]), external, omega_given, depth + 3)
        return out

    evaluate_point.packed = packed  # the arrays at the addresses the C call reads
    return evaluate_point


def _point_function(p: Mapping[str, float], ext):
    """:func:`point_function` of ``p`` (returning dicts), cached on a :class:`FlatParameters`
    until it changes (or the library does)."""
    if not isinstance(p, FlatParameters):
        return point_function(p, ext)
    key = (p.version, id(ext), id(_lib))
    cache = p.__dict__.get("_kernel_point")
    if cache is None or cache[0] != key:
        cache = (key, point_function(p, ext), ext, _lib)  # ext, _lib kept alive: their ids are in the key
        p.__dict__["_kernel_point"] = cache
    return cache[1]


def _issue_warnings(p, nan, mask: int, external: Sequence[str], omega_given: bool, depth: int = 6) -> None:
    """The warnings of the numpy path (:mod:`mftire.mf.solver`, :mod:`mftire.mf.inputs`), in its order;
    ``depth``: frames up to the caller of ``Tyre.evaluate``."""

    def warn(msg: str) -> None:
        warnings.warn(msg, MFLimitWarning, stacklevel=depth)

    for bit, w in enumerate(spec.WARNINGS):
        if w.input is not None:  # a NaN count per input (omega counted only when given, by the C)
            k = _IN_INDEX[w.input]
            name = w.input if k < 8 else (external[k - 8] if k - 8 < len(external) else None)
            if nan[k] and name is not None and (omega_given or w.input != "omega"):
                warn(w.text.format(n=nan[k], input=name))
        elif mask >> bit & 1:
            warn(w.text.format(limit=w.limit, value=p[w.limit]) if w.limit else w.text)


def build_in_place() -> Path:
    """Compile the kernel next to this module (a source checkout; ``pip install`` does it otherwise)."""
    global _lib
    out = Path(__file__).resolve().parent / build.LIBRARY
    build.compile_library(_ROOT, out)
    _lib = None
    return out


if __name__ == "__main__":  # pragma: no cover - developer command
    if sys.argv[1:] == ["build"]:
        print(build_in_place())
    else:
        print(status())
